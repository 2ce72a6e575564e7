"""Rover parameters derived for the usvsim vessels (usvsim.mavlink.rover_params).

The Must-show: the shipped usv105 file, in usvsim's own model of ArduPilot's steering cascade
(the ``rover`` autopilot, AR_AttitudeControl's structure), with the loop closed through
``sitl-physics`` (PWM out by the file's SERVO ranges, JSON state back) at 3 m/s, turns 60°
within 5° in ≤ 10 s and oscillates < 2° afterwards.
"""

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from usvsim.cli.main import main
from usvsim.mavlink.rover_params import (
    autopilot_config,
    derive_rover_tuning,
    parameter_file,
    read_parameter_file,
    shipped_parameter_file,
)
from usvsim.mavlink.sitl_physics import JsonPhysics, ServoFrame, ServoMapping
from usvsim.vessel.autopilot import NC, NG, AutopilotConfig, control_law, design_autopilot
from usvsim.vessel.model import NX
from usvsim.vessel.vessels import VESSELS, get_vessel

FRAME_HZ = 50  # physics frames per second (ArduPilot SITL sends one per loop)
CONTROL_DT_S = 0.1  # the cascade's step (the plant's 10 Hz autopilot)


@pytest.mark.parametrize("name", list(VESSELS))
def test_shipped_files_are_what_the_derivation_gives(name: str) -> None:
    """Regenerate with parameter_file(derive_rover_tuning(name)) when the model changes."""
    shipped = read_parameter_file(shipped_parameter_file(name))
    derived = read_parameter_file(parameter_file(derive_rover_tuning(name)))
    assert shipped.keys() == derived.keys()
    for key, value in derived.items():  # the last printed digit may differ between platforms
        assert shipped[key] == pytest.approx(value, rel=2e-3, abs=1e-3), key


def config_from_file(values: dict[str, float]) -> AutopilotConfig:
    """usvsim's rover cascade with a .parm file's ATC_STR_* (I = 0 stands as 1e-6)."""
    return AutopilotConfig(
        kind="rover",
        cruise_speed_mps=values["CRUISE_SPEED"],
        rover_ang_p=values["ATC_STR_ANG_P"],
        rover_rate_ff=values["ATC_STR_RAT_FF"],
        rover_rate_p=values["ATC_STR_RAT_P"],
        rover_rate_i=max(values["ATC_STR_RAT_I"], 1e-6),
        rover_rate_imax=values["ATC_STR_RAT_IMAX"],
        rover_rate_max=math.radians(values["ATC_STR_RAT_MAX"]),
        rover_acc_max=math.radians(values["ATC_STR_ACC_MAX"]),
    )


def pwm(value: float, lo: float, trim: float, hi: float) -> int:
    """ArduPilot's angle-type output: ±1 → MAX / MIN around TRIM, whole µs."""
    v = max(-1.0, min(1.0, value))
    return round(trim + v * ((hi - trim) if v >= 0 else (trim - lo)))


def heading_step_through_sitl_physics(
    values: dict[str, float], step_deg: float, seconds: float
) -> tuple[np.ndarray, np.ndarray]:
    """Heading (deg) of the loop cascade → PWM → JsonPhysics → JSON state → cascade."""
    vessel = get_vessel("default")
    act = vessel.actuation
    cfg = config_from_file(values)
    gains = design_autopilot(vessel, cfg).gains_vector()
    x, c, cmd, g = ca.SX.sym("x", NX), ca.SX.sym("c", NC), ca.SX.sym("cmd", 2), ca.SX.sym("g", NG)
    law = ca.Function("law", [x, c, cmd, g], list(control_law(vessel, "rover", x, c, cmd, g, 0.1)))
    steer_range = tuple(values[f"SERVO1_{k}"] for k in ("MIN", "TRIM", "MAX"))
    throttle_range = tuple(values[f"SERVO3_{k}"] for k in ("MIN", "TRIM", "MAX"))
    mapping = ServoMapping(1, 3, steer_range, throttle_range)  # type: ignore[arg-type]
    physics = JsonPhysics(vessel, mapping=mapping)
    speed = values["CRUISE_SPEED"]
    physics.x[3] = speed  # cruising straight at 3 m/s, as the plant's tests start
    physics.x[6] = float(physics.vessel.actuation.a1_max) * values["CRUISE_THROTTLE"] / 100.0
    ctrl = np.zeros(NC)
    state = np.array(physics.x)
    frame, times, headings = 0, [], []
    for _ in range(round(seconds / CONTROL_DT_S)):
        a_cmd, ctrl_next = law(state, ctrl, [math.radians(step_deg), speed], gains)
        ctrl = np.asarray(ctrl_next).ravel()
        a = np.asarray(a_cmd).ravel()
        pwm_out = [1500] * 16
        pwm_out[0] = pwm(a[1] / act.a2_max, *steer_range)
        pwm_out[2] = pwm(a[0] / act.a1_max, *throttle_range)
        for _ in range(round(FRAME_HZ * CONTROL_DT_S)):
            reply = json.loads(physics.handle(ServoFrame(FRAME_HZ, frame, tuple(pwm_out))))
            frame += 1
        psi = reply["attitude"][2]
        vn, ve = reply["velocity"][0], reply["velocity"][1]
        u = vn * math.cos(psi) + ve * math.sin(psi)
        v = -vn * math.sin(psi) + ve * math.cos(psi)
        n_, e_ = reply["position"][0], reply["position"][1]
        state = np.array([n_, e_, psi, u, v, reply["imu"]["gyro"][2], *physics.x[6:8]])
        times.append(reply["timestamp"])
        headings.append(math.degrees(psi))
    return np.array(times), np.array(headings)


def step_figures(t: np.ndarray, psi: np.ndarray, target: float) -> tuple[float, float, float]:
    """(time after which |ψ − target| ≤ 5° for good, overshoot, peak-to-peak oscillation after
    the first extremum that follows; 0 when the approach is monotone)."""
    outside = np.nonzero(np.abs(psi - target) > 5.0)[0]
    if outside.size and outside[-1] == len(t) - 1:
        return math.inf, float(psi.max() - target), math.nan  # never settles
    t5 = 0.0 if outside.size == 0 else float(t[outside[-1] + 1])
    after = psi[t >= t5]
    turning = np.nonzero(np.diff(np.sign(np.diff(after))))[0]
    osc = 0.0 if turning.size == 0 else float(np.ptp(after[turning[0] + 1 :]))
    return t5, float(psi.max() - target), osc


def test_shipped_usv105_parameters_turn_60_degrees_through_sitl_physics() -> None:
    values = read_parameter_file(shipped_parameter_file("usv105"))
    t, psi = heading_step_through_sitl_physics(values, 60.0, 40.0)
    t5, overshoot, osc = step_figures(t, psi, 60.0)
    print(
        f"\n60° step: within 5° at {t5:.1f} s, overshoot {overshoot:.2f}°, oscillation {osc:.2f}°"
    )
    assert t5 <= 10.0  # measured 7.4 s
    assert osc < 2.0  # measured 1.3° (the one overshoot, then settled)
    assert abs(psi[-1] - 60.0) < 0.5


def test_ardupilot_defaults_fail_the_same_step() -> None:
    """rover.parm's FF 0.75 / P 0.2 / ANG_P 2 (no speed scaling) in the same loop."""
    values = read_parameter_file(shipped_parameter_file("usv105"))
    values.update(ATC_STR_RAT_FF=0.75, ATC_STR_RAT_P=0.2, ATC_STR_RAT_I=0.2, ATC_STR_ANG_P=2.0)
    values.update(ATC_STR_RAT_MAX=120.0, ATC_STR_ACC_MAX=120.0)
    t, psi = heading_step_through_sitl_physics(values, 60.0, 40.0)
    t5, overshoot, _ = step_figures(t, psi, 60.0)
    assert t5 > 10.0 and overshoot > 10.0


def test_rover_tuned_is_the_derived_usv105_cascade() -> None:
    derived = autopilot_config(derive_rover_tuning("usv105"))
    tuned = AutopilotConfig.rover_tuned()
    for name in ("rover_ang_p", "rover_rate_ff", "rover_rate_p", "rover_rate_i"):
        assert getattr(tuned, name) == pytest.approx(getattr(derived, name)), name
    for name in ("rover_rate_max", "rover_acc_max", "rover_rate_imax"):
        assert getattr(tuned, name) == pytest.approx(getattr(derived, name)), name


def test_design_figures_and_the_file_format() -> None:
    t = derive_rover_tuning("usv105")
    assert t.rate_phase_margin_deg > 60.0 and t.heading_phase_margin_deg >= 60.0
    assert t.rate_crossover_radps == pytest.approx(1.25)  # 1 / (4 (0.15 s + 0.05 s))
    values = read_parameter_file(parameter_file(t))
    assert values["FRAME_CLASS"] == 2 and values["MOT_SPD_SCA_BASE"] == 0
    assert (values["SERVO1_MIN"], values["SERVO1_MAX"]) == (1000, 2000)
    assert values["WP_SPEED"] == values["CRUISE_SPEED"] == 3.0
    with pytest.raises(ValueError, match="line 1: expected 'NAME VALUE'"):
        read_parameter_file("ATC_STR_ANG_P\n")


def test_write_params_writes_the_shipped_file(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "boat.parm"
    assert main(["sitl-physics", "--write-params", str(out), "--vessel", "loe-default"]) == 0
    assert out.read_text() == shipped_parameter_file("loe-default")
    assert "--add-param-file=" in capsys.readouterr().out
