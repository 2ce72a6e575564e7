"""The vessel commands: ``usvsim demo`` (design report and plant plots), ``usvsim manoeuvre``
(manoeuvring trials) and ``usvsim perf``."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from usvsim.common.errors import UserError
from usvsim.common.options import bounds

__all__ = ["DemoArgs", "ManoeuvreArgs", "PerfArgs", "run_demo", "run_manoeuvre", "run_perf"]


@dataclass(frozen=True)
class DemoArgs:
    """Print the vessel and autopilot design and save plant plots (PNG)."""

    vessel: str = "default"  # vessel preset: default (= usv105), loe-default, viknes830, ...
    autopilot: str = "pid"  # pid | rover | rover-tuned
    out: str = "usvsim-results/plant"  # folder for the PNG plots


# the highest --speed of usvsim manoeuvre as a multiple of a vessel's cruise speed: every hull's
# trials stay finite up to 5x (measured; cybership2's model diverges at 40x)
MAX_SPEED_OVER_CRUISE = 5.0


@dataclass(frozen=True)
class ManoeuvreArgs:
    """Standard manoeuvring trials (turning circle, zig-zags, stopping) against IMO MSC.137(76)."""

    vessel: str = "all"  # vessel preset, or all
    speed: float = field(  # approach speed, m/s; 0: each vessel's cruise speed
        default=0.0, metadata=bounds(gt=0.0, le=20.0, zero_ok=True)
    )
    out: str = "usvsim-results/manoeuvre"  # folder for the table (Markdown) and the PNG plots
    # mean wind speed, m/s (gusts 10 %); 0: none. Weather uses usv105's windage and waterline
    wind: float = field(default=0.0, metadata=bounds(ge=0.0, le=40.0))
    # direction the wind blows from, deg clockwise from north (the approach course); 90: beam
    wind_dir: float = field(default=90.0, metadata=bounds(ge=0.0, lt=360.0))
    # WMO sea state code 0-8 (Bales 1983 H_s, T_p); waves come from the wind's direction
    sea_state: int = field(default=0, metadata=bounds(ge=0, le=8))
    seed: int = field(default=0, metadata=bounds(ge=0))  # gusts and wave motion

    def weather(self) -> Any:
        """The trials' :class:`usvsim.evaluation.manoeuvre.TrialWeather`, None in calm water."""
        if self.wind == 0.0 and self.sea_state == 0:
            return None
        from usvsim.evaluation.manoeuvre import TrialWeather

        return TrialWeather(self.wind, self.wind_dir, self.sea_state, seed=self.seed)

    def check(self) -> None:
        from usvsim.vessel.vessels import VESSELS, get_vessel, vessel_names

        if self.vessel != "all" and self.vessel not in vessel_names():
            known = ", ".join(["all", *vessel_names()])
            raise UserError(f"--vessel must be one of {known}, not {self.vessel!r}")
        if not isinstance(self.sea_state, int) or not 0 <= self.sea_state <= 8:
            raise UserError(f"--sea-state must be an integer code 0-8, got {self.sea_state!r}")
        if self.weather() is not None and self.vessel == "all":
            raise UserError(
                "--wind and --sea-state need one --vessel (the weather loads use usv105's "
                "windage and waterline), not all"
            )
        chosen = VESSELS.values() if self.vessel == "all" else [get_vessel(self.vessel)]
        for v in chosen:  # the hull models hold near their cruise speed; far above it they blow up
            top = MAX_SPEED_OVER_CRUISE * v.cruise_speed_mps
            if self.speed > top:
                raise UserError(
                    f"--speed must be <= {top:g} m/s for {v.name} ({MAX_SPEED_OVER_CRUISE:g} x its "
                    f"cruise speed {v.cruise_speed_mps:g} m/s), got {self.speed:g}; "
                    "choose one --vessel or a lower --speed"
                )


@dataclass(frozen=True)
class PerfArgs:
    """Measure plant (and environment) throughput."""

    json: bool = False  # print JSON only (stdout)
    seconds: float = field(default=1.0, metadata=bounds(gt=0, le=3600))  # per figure, s
    env: bool = True  # also measure the environments (--no-env: the plant only)
    profile: bool = False  # only profile decision steps: where a step's time goes
    # plant backend measured beside the C kernel: cpu (the C kernel only), torch-cpu, cuda
    device: Literal["cpu", "torch-cpu", "cuda"] = "cpu"

    def check(self) -> None:
        if self.device != "cpu":  # cuda without a GPU: one line, before any measuring
            from usvsim.vessel.torch_plant import torch_device

            torch_device(self.device)


def _autopilot_config(name: str) -> Any:
    from usvsim.vessel.autopilot import AutopilotConfig

    try:
        return AutopilotConfig.from_name(name)
    except ValueError as err:
        raise SystemExit(f"usvsim: {err}") from None


def run_demo(args: DemoArgs) -> int:
    from tqdm import tqdm

    from usvsim.vessel.autopilot import design_report
    from usvsim.vessel.plant import Plant
    from usvsim.vessel.vessels import get_vessel

    try:
        vessel = get_vessel(args.vessel)
    except ValueError as err:
        raise SystemExit(f"usvsim: {err}") from None
    plant = Plant(vessel, autopilot=_autopilot_config(args.autopilot))
    print(design_report(vessel, plant.design, plant.dt_s))
    print(f"plant fast path: {plant.backend}")
    from usvsim.evaluation.manoeuvre import run_trials, trials_summary

    print(trials_summary(run_trials(vessel)) + "  (usvsim manoeuvre: all trials)")
    _print_wave_filter(vessel, plant)
    from usvsim.evaluation import plant_plots

    out = Path(args.out)
    steps: list[tuple[str, Callable[[], Any]]] = [
        ("turning_circle.png", lambda: plant_plots.turning_circle_figure(plant)),
        ("heading_steps.png", lambda: plant_plots.heading_step_figure(plant)),
        ("bode.png", lambda: plant_plots.bode_figure(plant)),
        ("kalman_vs_gps.png", lambda: plant_plots.kalman_figure()),
    ]
    import matplotlib.pyplot as plt

    from usvsim.common.fileio import atomic_savefig

    for name, make in tqdm(steps, desc="plots", unit="plot", file=sys.stderr):
        fig = make()
        atomic_savefig(fig, out / name, dpi=120)
        plt.close(fig)
    print(f"plots written to {out}/: " + ", ".join(name for name, _ in steps))
    return 0


# hulls shorter than this are model scale (cybership2: 1.255 m): sea state 4 would swamp them
MIN_WAVE_FILTER_LENGTH_M = 5.0


def _print_wave_filter(vessel: Any, plant: Any) -> None:
    """The autopilot's wave filter: its design and what it does in sea state 4 (issue 38)."""
    if vessel.length_m < MIN_WAVE_FILTER_LENGTH_M:
        print(f"wave filter: not shown for a model-scale hull ({vessel.length_m:g} m)")
        return
    import numpy as np

    from usvsim.evaluation.manoeuvre import TrialWeather, wave_filter_activity
    from usvsim.vessel.weather_plant import WeatherPlant, wave_filter_design

    weather = TrialWeather(0.0, 45.0, 4)
    state = WeatherPlant(plant).initial_state(np.zeros((1, 3)), weather.conditions(1))
    print(wave_filter_design(state, plant.design))
    off, on = wave_filter_activity(vessel, plant.cruise_speed_mps, weather, n=8, seconds=120.0)
    print(
        f"  sea state 4, heading kept with the waves 45° off the quarter: nozzle RMS "
        f"{off.rms_deg:.1f}° → {on.rms_deg:.1f}°, its rate {off.rate_rms_deg_s:.1f} → "
        f"{on.rate_rms_deg_s:.1f} °/s, heading error {off.heading_error_rms_deg:.2f}° → "
        f"{on.heading_error_rms_deg:.2f}° (8 boats × 120 s; usvsim manoeuvre --vessel "
        f"{vessel.name} --sea-state 4: 16 × 300 s)"
    )


def run_manoeuvre(args: ManoeuvreArgs) -> int:
    import matplotlib.pyplot as plt
    from tqdm import tqdm

    from usvsim.common.fileio import check_writable_dir, staged_dir
    from usvsim.common.interrupt import check_interrupt
    from usvsim.evaluation import manoeuvre
    from usvsim.evaluation.plant_plots import manoeuvre_figure
    from usvsim.vessel.vessels import VESSELS, get_vessel

    args.check()
    names = sorted(VESSELS) if args.vessel == "all" else [get_vessel(args.vessel).name]
    out = Path(args.out)
    check_writable_dir(args.out, "--out")  # before the trials, not after them
    reports = []
    for name in tqdm(names, desc="trials", unit="vessel", file=sys.stderr):
        check_interrupt()  # Ctrl-C / SIGTERM even if a CasADi call swallowed it
        weather = args.weather()
        speed = args.speed or None
        reports.append(
            manoeuvre.run_trials(VESSELS[name], speed)
            if weather is None
            else manoeuvre.run_trials(VESSELS[name], speed, weather)
        )
    table = manoeuvre.trials_table(reports)
    # one unit (Ctrl-C, SIGTERM or a crash leaves the previous table and plots as they were)
    with staged_dir(out, "manoeuvre") as staging:
        for report in reports:
            fig = manoeuvre_figure(report)
            fig.savefig(staging / f"manoeuvre_{report.vessel}.png", dpi=110)
            plt.close(fig)
        (staging / "manoeuvre.md").write_text(table + "\n")
    print(table)
    print(f"written to {out}/: manoeuvre.md, " + ", ".join(f"manoeuvre_{n}.png" for n in names))
    return 0


def run_perf(args: PerfArgs) -> int:
    from usvsim.evaluation.perf import run_perf as measure

    if args.seconds <= 0:
        raise SystemExit("usvsim perf: --seconds must be > 0")
    if args.profile:
        from usvsim.evaluation.perf import profile_steps

        return _print_profile(profile_steps(max(args.seconds, 1.0)), args.json)
    result = measure(args.seconds, env=args.env, device=args.device)
    if args.env and args.device != "cpu":  # the study task's env on the torch device too
        from usvsim.task.torch_env_speed import torch_env_rates

        result["torch_env"] = torch_env_rates(args.device, seconds=args.seconds)
        from usvsim.task.torch_openwater_speed import torch_openwater_rates

        result["torch_openwater"] = torch_openwater_rates(args.device, seconds=args.seconds)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    plant = result["plant"]
    print(
        f"plant ({plant['backend']}): boat-substeps/s "
        + ", ".join(f"{k}: {v:,}" for k, v in plant["boat_substeps_per_s"].items())
    )
    print(
        f"  per-boat Python loop: {plant['per_boat_python_loop_boat_substeps_per_s']:,}/s; "
        f"batched N=1024 is {plant['batched_N1024_over_loop']}x faster"
    )
    kernels = plant["kernels_N=1024_boat_substeps_per_s"]
    print(
        f"  kernels at N=1024, same run (load {plant['load_average_1min']}): "
        + ", ".join(f"{k}: {v:,}/s" for k, v in kernels.items())
        + f"; soa is {plant['soa_over_scalar']}x scalar, {plant['soa_over_casadi_map']}x casadi_map"
    )
    torch_plant = result.get("torch_plant")
    if torch_plant:
        ratios = torch_plant["over_C_kernel_N=1024"]
        print(
            f"torch plant ({torch_plant['device']}, same run, load "
            f"{torch_plant['load_average_1min']}): boat-substeps/s "
            + ", ".join(
                f"{k}: {v:,}" + (f" ({ratios[k]}x C)" if k in ratios else "")
                for k, v in torch_plant["boat_substeps_per_s"].items()
            )
        )
    torch_env = result.get("torch_env")
    if torch_env:
        over = torch_env["over_C_path"]
        print(
            f"torch env, study task positional ({torch_env['device']}, same run, load "
            f"{torch_env['load_average_1min']}): env steps/s "
            + "; ".join(
                f"{n} "
                + ", ".join(
                    f"{k}: {v:,}" + (f" ({over[n][k]}x C)" if k in over[n] else "")
                    for k, v in row.items()
                )
                for n, row in torch_env["env_steps_per_s"].items()
            )
        )
    torch_ow = result.get("torch_openwater")
    if torch_ow:
        over = torch_ow["over_C_path"]
        print(
            f"torch env, open water ({torch_ow['device']}, same run, load "
            f"{torch_ow['load_average_1min']}): decision steps/s "
            + "; ".join(
                f"{n} "
                + ", ".join(
                    f"{k}: {v:,}" + (f" ({over[n][k]}x C)" if k in over[n] else "")
                    for k, v in row.items()
                )
                for n, row in torch_ow["decision_steps_per_s"].items()
            )
        )
    env = result.get("env", {})
    targets = env.get("targets", {})
    for key, value in env.get("decision_steps_per_s", {}).items():
        bar = f" (target {targets[key]:,})" if key in targets else ""
        print(f"env {key}: {value:,} decision steps/s{bar}")
    if "sensor_noise" in env:
        print(f"env sensor noise: {env['sensor_noise']} (usvsim.task.noise_kernel)")
    for key, value in result.get("open_water", {}).get("decision_steps_per_s", {}).items():
        print(f"open-water {key}: {value:,} decision steps/s")
    for kind, fig in result.get("everything_set", {}).get("decision_steps_per_s", {}).items():
        print(
            f"everything set {kind} N=256: {fig['everything N=256']:,} decision steps/s, "
            f"{fig['ratio']:.2f} of the study task's {fig['study task N=256']:,}"
        )
    radar = result.get("scene_radar", {})
    if radar:
        print(
            "scene radar images (N=256, degraded): "
            + ", ".join(f"{k}: {v:,}" for k, v in radar.items() if k.endswith("images/s"))
            + (f"; compiled is {radar['compiled_over_numpy']}x NumPy" if len(radar) == 3 else "")
        )
    return 0


def _print_profile(result: dict[str, Any], as_json: bool) -> int:
    if as_json:
        print(json.dumps(result, indent=2))
        return 0
    for workload, fig in result.items():
        print(
            f"{workload} (N=256): {fig['ms_per_step']:.2f} ms per step under the profiler "
            f"({fig['decision_steps_per_s_profiled']:,} decision steps/s)"
        )
        for row in fig["top"]:
            print(
                f"  {row['share']:6.1%}  {row['ms_per_step']:7.3f} ms  "
                f"{row['calls_per_step']:8.2f} calls  {row['function']}"
            )
    return 0
