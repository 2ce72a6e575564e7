"""Wind, waves and the heading notch of usvsim.vessel.weather (issue 38): physics with numbers.

Hand values use usv105's windage (A_F = 7.25 m², A_L = 16.5 m², c_x = 0.70, c_y = 0.825,
c_n = 0.125) and ρ_a = 1.225 kg/m³.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import freqz, lfilter, welch

from usvsim.common.errors import UserError
from usvsim.vessel.model import build_force_dynamics
from usvsim.vessel.vessels import USV105
from usvsim.vessel.weather.filters import design_notch
from usvsim.vessel.weather.waves import (
    RHO_WATER,
    USV105_WATERLINE,
    G,
    SeaState,
    WaterlinePolygon,
    encounter_frequency,
    jonswap,
    jonswap_peak,
    mean_drift_force,
    sea_state_from_code,
    wave_displacement,
    wave_motion_init,
    wave_motion_step,
    wave_response,
)
from usvsim.vessel.weather.wind import (
    USV105_WINDAGE,
    GustParams,
    draw_wind,
    gust_step,
    wind_forces,
)

Q10 = 0.5 * 1.225 * 10.0**2  # Pa, dynamic pressure of a 10 m/s wind


def _at_rest(n: int) -> np.ndarray:
    return np.zeros((n, 3))


def test_wind_force_scales_with_relative_speed_squared() -> None:
    directions = np.linspace(0.0, 2 * math.pi, 7)
    f1 = wind_forces(_at_rest(7), np.zeros(7), np.full(7, 6.0), directions)
    f2 = wind_forces(_at_rest(7), np.zeros(7), np.full(7, 12.0), directions)
    np.testing.assert_allclose(f2, 4.0 * f1, rtol=1e-12, atol=1e-9)
    # relative wind: a boat running at 5 m/s into a 5 m/s head wind feels 10 m/s
    moving = wind_forces(np.array([[5.0, 0.0, 0.0]]), [0.0], [5.0], [math.pi])
    assert moving[0, 0] == pytest.approx(-Q10 * 0.70 * 7.25, rel=1e-12)


def test_wind_direction_dependence_at_0_90_180_degrees() -> None:
    # wind blowing towards south (on the bow), east (on the port beam), north (from astern), and
    # towards south-west (on the starboard bow, γ = -45°) for a boat at rest heading north
    f = wind_forces(
        _at_rest(4), np.zeros(4), np.full(4, 10.0), [math.pi, math.pi / 2, 0.0, -0.75 * math.pi]
    )
    assert f[0, 0] == pytest.approx(-310.84375, rel=1e-9)  # -Q c_x A_F: pushed astern
    assert f[1, 1] == pytest.approx(833.765625, rel=1e-9)  # +Q c_y A_L: pushed to starboard
    assert f[2, 0] == pytest.approx(310.84375, rel=1e-9)  # pushed ahead
    np.testing.assert_allclose(
        [f[0, 1], f[0, 2], f[1, 0], f[1, 2], f[2, 1], f[2, 2]], 0.0, atol=1e-9
    )
    # γ = -45°: C_N = c_n sin(-90°) = -c_n: the bow turns away from the wind (to port)
    assert f[3, 2] == pytest.approx(-Q10 * 0.125 * 16.5 * 10.5, rel=1e-9)  # -1326.4 N m


def test_boat_at_rest_drifts_downwind_at_the_wind_damping_balance() -> None:
    """Beam wind of 10 m/s from the west: sway drift where ½ρ_a c_y A_L (V - v)² = D v².

    At u = r = 0 usv105's sway damping is -(Y_v |v| / U_ref + Y_|v|v) |v| v (Y_v scales with
    U_r / 3 m/s), so D = 2800.1 / 3 + 1325 = 2258.4 N s²/m², k = √(8.338 / 2258.4) = 0.0608 and
    v* = k V / (1 + k) = 0.573 m/s. The sway-yaw coupling N_v turns the boat a little; the wind
    moment c_n sin 2γ holds it beam-on, so the drift must land within 3 % of v*.
    """
    f = build_force_dynamics(USV105)
    damping = -(USV105.Y_v / USV105.linear_ref_speed_mps + USV105.Y_vv)
    k = math.sqrt(0.5 * 1.225 * USV105_WINDAGE.c_y * USV105_WINDAGE.lateral_area_m2 / damping)
    v_star = k * 10.0 / (1.0 + k)
    assert v_star == pytest.approx(0.573, abs=0.001)

    def rates(x: np.ndarray) -> np.ndarray:
        tau = wind_forces(x[None, 3:6], [x[2]], [10.0], [math.pi / 2])[0]
        return np.asarray(f(x, tau, [0.0, 0.0])).ravel()

    x, dt = np.zeros(6), 0.2
    for _ in range(int(400 / dt)):
        k1 = rates(x)
        k2 = rates(x + 0.5 * dt * k1)
        k3 = rates(x + 0.5 * dt * k2)
        k4 = rates(x + dt * k3)
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    east_speed = math.sin(x[2]) * x[3] + math.cos(x[2]) * x[4]  # m/s, over ground
    assert east_speed == pytest.approx(v_star, rel=0.03)
    assert abs(math.degrees(x[2])) < 10.0  # still near beam-on


def test_gusts_have_the_designed_spread_and_correlation_time() -> None:
    rng = np.random.default_rng(5)
    gusts = GustParams(intensity=0.1, time_constant_s=10.0)
    state = draw_wind(rng, 200, (10.0, 10.0), 0.0, gusts)
    series = []
    for _ in range(2000):
        state = gust_step(state, rng, 1.0, gusts)
        series.append(state.gust_mps)
    g = np.array(series)  # (T, N)
    assert g.std() == pytest.approx(1.0, rel=0.05)  # σ_g = 0.1 * 10 m/s
    rho10 = np.mean(g[10:] * g[:-10]) / g.var()
    assert rho10 == pytest.approx(math.exp(-1.0), abs=0.03)


def test_wave_response_filter_matches_jonswap_peak_and_variance() -> None:
    resp = wave_response([1.88], [8.8])
    w0, lam, kw = resp.omega0[0], resp.damping[0], resp.gain[0]
    omega = np.linspace(1e-3, 40.0, 400_000)
    h2 = (kw * omega) ** 2 / ((w0**2 - omega**2) ** 2 + (2 * lam * w0 * omega) ** 2)
    assert np.trapezoid(h2, omega) == pytest.approx(1.88**2 / 16, rel=0.01)
    assert h2.max() == pytest.approx(jonswap(w0, 1.88, 8.8)[()], rel=1e-4)
    assert lam == pytest.approx(0.1024, abs=0.001)  # JONSWAP γ = 3.3


def test_jonswap_peak_is_the_spectrum_at_its_peak_frequency() -> None:
    """The closed form S(ω_p) equals JONSWAP evaluated at ω_p = 2π/T_p, and it is the maximum
    of S over a fine frequency grid (the spectrum peaks at ω_p)."""
    hs, tp = np.array([0.3, 1.0, 1.88, 4.0]), np.array([3.0, 7.5, 8.8, 12.4])
    wp = 2 * math.pi / tp
    np.testing.assert_allclose(jonswap_peak(hs, tp), jonswap(wp, hs, tp), rtol=1e-13)
    np.testing.assert_allclose(jonswap_peak(hs, tp, 1.0), jonswap(wp, hs, tp, 1.0), rtol=1e-13)
    grid = np.linspace(0.05, 6.0, 200_001)
    top = jonswap(grid[None, :], hs[:, None], tp[:, None]).max(axis=1)
    np.testing.assert_allclose(jonswap_peak(hs, tp), top, rtol=1e-6)


def test_simulated_elevation_spectrum_matches_jonswap() -> None:
    """Sea state 4 (H_s 1.88 m, T_p 8.8 s): 32 boats × 4096 s at 2 Hz, Welch's PSD."""
    sea = sea_state_from_code(4)
    n, dt = 32, 0.5
    resp = wave_response(np.full(n, sea.hs_m), np.full(n, sea.tp_s))
    rng = np.random.default_rng(11)
    x = wave_motion_init(rng, resp)
    eta = np.empty((8192, n))
    for i in range(eta.shape[0]):
        x = wave_motion_step(x, rng, resp, dt)
        eta[i] = x[:, 1]
    freq_hz, psd = welch(eta, fs=1 / dt, nperseg=1024, axis=0)
    psd_w = psd.mean(axis=1) / (2 * math.pi)  # m² s/rad
    omega = 2 * math.pi * freq_hz
    omega_peak = omega[np.argmax(psd_w)]
    assert omega_peak == pytest.approx(2 * math.pi / 8.8, rel=0.05)
    grid = np.linspace(0.05, 15.0, 20_000)
    hs_jonswap = 4.0 * math.sqrt(np.trapezoid(jonswap(grid, 1.88, 8.8), grid))
    hs_sim = 4.0 * math.sqrt(np.trapezoid(psd_w, omega))
    assert hs_sim == pytest.approx(hs_jonswap, rel=0.10)
    assert 4.0 * eta.std() == pytest.approx(1.88, rel=0.10)


def test_wave_displacement_follows_the_surface_orbit() -> None:
    """Along-wave displacement std = H_s / 4 (stationary: var(ω₀ x₁) = var(x₂) = m₀), none across;
    yaw zero in beam seas and largest at 45°."""
    n = 64
    resp = wave_response(np.full(n, 0.88), np.full(n, 7.5))
    rng = np.random.default_rng(2)
    x = wave_motion_init(rng, resp)
    direction = np.full(n, 0.4)
    beam, quartering, along, across = [], [], [], []
    for _ in range(2000):
        x = wave_motion_step(x, rng, resp, 0.5)
        d = wave_displacement(x, resp, direction, direction - math.pi / 2)
        along.append(d[:, 0] * math.cos(0.4) + d[:, 1] * math.sin(0.4))
        across.append(-d[:, 0] * math.sin(0.4) + d[:, 1] * math.cos(0.4))
        beam.append(d[:, 2])
        quartering.append(wave_displacement(x, resp, direction, direction - math.pi / 4)[:, 2])
    assert np.std(along) == pytest.approx(0.88 / 4, rel=0.05)
    np.testing.assert_allclose(across, 0.0, atol=1e-12)
    np.testing.assert_allclose(beam, 0.0, atol=1e-12)
    k0 = (2 * math.pi / 7.5) ** 2 / G  # 1/m, peak wave number
    assert np.std(quartering) == pytest.approx(k0 * 0.88 / 4, rel=0.05)  # 0.0157 rad = 0.9°


def test_encounter_frequency_rises_in_head_seas_and_falls_in_following_seas() -> None:
    w = 2 * math.pi / 7.5  # rad/s, sea state 3's peak
    we = encounter_frequency(w, 3.0, [math.pi, math.pi / 2, 0.0])
    np.testing.assert_allclose(we, [w + w**2 * 3.0 / G, w, w - w**2 * 3.0 / G], rtol=1e-12)
    assert we[0] == pytest.approx(1.0524, abs=1e-4)  # 26 % above ω = 0.8378 rad/s


def test_calm_sea_has_no_motion_and_no_drift() -> None:
    calm = sea_state_from_code(0)
    resp = wave_response([calm.hs_m], [calm.tp_s])
    rng = np.random.default_rng(0)
    x = wave_motion_step(wave_motion_init(rng, resp), rng, resp, 0.1)
    np.testing.assert_array_equal(x, 0.0)
    np.testing.assert_array_equal(mean_drift_force([0.0], [0.0], [0.0], [0.0]), 0.0)


def test_mean_drift_pushes_down_wave() -> None:
    headings = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
    f = mean_drift_force(np.full(16, 1.88), np.full(16, 8.8), np.full(16, 0.3), headings)
    rel = 0.3 - headings
    along = f[:, 0] * np.cos(rel) + f[:, 1] * np.sin(rel)  # N, along the wave direction
    assert np.all(along > 0.0)
    # ∝ H_s²: twice the wave height, four times the force
    f2 = mean_drift_force(np.full(16, 3.76), np.full(16, 8.8), np.full(16, 0.3), headings)
    np.testing.assert_allclose(f2, 4.0 * f, rtol=1e-12)


def test_mean_drift_equals_the_total_reflection_reference_in_short_waves() -> None:
    """A very deep wall reflects everything: beam seas on the port side give
    Y = ρ g m₀ (7.5 m side + 3.473 m bow face × n_y² |n_y|, n_y = 0.8638) = ρ g m₀ × 9.738 m
    (Faltinsen 1990, ½ ρ g ζ_a² per metre of wall in regular waves)."""
    deep = WaterlinePolygon(USV105_WATERLINE.vertices, draft_m=200.0)
    f = mean_drift_force([0.88], [7.5], [math.pi / 2], [0.0], waterline=deep)[0]
    reference = RHO_WATER * G * 0.88**2 / 16 * 9.738  # N, 4739 N
    assert f[1] == pytest.approx(reference, rel=0.03)
    # the real 0.55 m draft lets sea state 3's long waves (λ_p = 88 m) pass under: 0.3-3 % of it
    real = mean_drift_force([0.88], [7.5], [math.pi / 2], [0.0])[0]
    assert 0.003 * reference < real[1] < 0.03 * reference


def test_same_seed_same_weather() -> None:
    def episode(seed: int) -> np.ndarray:
        rng = np.random.default_rng(seed)
        wind = draw_wind(rng, 4, (2.0, 12.0))
        resp = wave_response(np.full(4, 0.88), np.full(4, 7.5))
        x = wave_motion_init(rng, resp)
        out = []
        for _ in range(50):
            wind = gust_step(wind, rng, 0.1)
            x = wave_motion_step(x, rng, resp, 0.1)
            out.append(np.concatenate([wind.speed_mps, wind.direction_rad, x.ravel()]))
        return np.array(out)

    np.testing.assert_array_equal(episode(3), episode(3))
    assert not np.allclose(episode(3), episode(4))


@pytest.mark.parametrize(
    ("make", "allowed"),
    [
        (lambda: SeaState(hs_m=-1.0, tp_s=8.0), "[0, 14] m"),
        (lambda: SeaState(hs_m=15.0, tp_s=8.0), "[0, 14] m"),
        (lambda: SeaState(hs_m=1.0, tp_s=0.5), "[1, 25] s"),
        (lambda: sea_state_from_code(9), "0-8"),
        (lambda: sea_state_from_code("3"), "0-8"),  # type: ignore[arg-type]
        (lambda: draw_wind(np.random.default_rng(0), 2, (50.0, 60.0)), "[0, 40] m/s"),
        (lambda: draw_wind(np.random.default_rng(0), 2, (-1.0, 5.0)), "[0, 40] m/s"),
        (lambda: draw_wind(np.random.default_rng(0), 2, (8.0, 3.0)), "low <= high"),
        (lambda: GustParams(intensity=0.9), "[0, 0.5]"),
        (lambda: design_notch(0.8, 0.0), "[1, 60] dB"),
        (lambda: design_notch(40.0, 20.0, 0.1), "rad/s"),
    ],
)
def test_bad_weather_arguments_raise_one_line_user_error(make, allowed: str) -> None:
    with pytest.raises(UserError) as err:
        make()
    message = str(err.value)
    assert "\n" not in message and allowed in message


def test_heading_notch_attenuates_the_wave_band_and_passes_low_frequencies() -> None:
    w0, dt = 2 * math.pi / 7.5, 0.1
    notch = design_notch(w0, attenuation_db=20.0, dt_s=dt)
    _, h = freqz(notch.b, notch.a, worN=[w0 * dt, 0.1 * w0 * dt, 0.0])
    gain_db = 20 * np.log10(np.abs(h))
    assert gain_db[0] == pytest.approx(-20.0, abs=0.01)  # prewarped: exact at ω₀
    assert gain_db[1] > -0.2  # a slow heading change passes (ω₀ / 10)
    assert gain_db[2] == pytest.approx(0.0, abs=1e-6)  # unit DC gain
    # a heading ramp plus 2° waves at ω₀: the waves drop to ≤ 0.2° after the filter settles
    t = np.arange(0.0, 600.0, dt)
    slow = 0.002 * t
    psi = slow + math.radians(2.0) * np.sin(w0 * t)
    out = lfilter(notch.b, notch.a, psi)
    tail = slice(len(t) // 2, None)
    residual = out[tail] - slow[tail]
    assert np.ptp(residual - residual.mean()) / 2 < math.radians(0.2)


def test_cascaded_low_pass_adds_its_corner_and_keeps_the_notch() -> None:
    w0, wf, dt = 2 * math.pi / 7.5, 2.0, 0.1
    f = design_notch(w0, 20.0, dt, lowpass_rad_s=wf)
    _, h = freqz(f.b, f.a, worN=[w0 * dt, wf * dt, 0.0, 3.0])
    notch_at_wf = abs(complex(-(wf**2) + w0**2, 2 * f.zeta * w0 * wf) / complex(w0, wf) ** 2)
    gain_db = 20 * np.log10(np.abs(h))
    lp_at_w0 = -10 * math.log10(1 + (w0 / wf) ** 2)  # dB, continuous low-pass at ω₀
    assert gain_db[0] == pytest.approx(-20.0 + lp_at_w0, abs=0.05)
    # low-pass exact at ω_f (prewarped there); the notch, prewarped at ω₀, is off by 0.017 dB
    assert gain_db[1] == pytest.approx(20 * math.log10(notch_at_wf) - 3.0103, abs=0.03)
    assert gain_db[2] == pytest.approx(0.0, abs=1e-9)
    assert gain_db[3] < -30.0  # 30 rad/s (sensor noise) is cut


def test_drift_pressure_interpolation_equals_the_integral() -> None:
    """p_d = H_s² p_d(1 m, T_p) with the latter a spline in ln T_p: within 2e-8 of the
    trapezoid integral over 4000 random seas (1000 of them at T_p 1-1.5 s, where p_d changes
    fastest); measured 1.2e-8. Calm seas give 0; a period outside 1-25 s is integrated."""
    from usvsim.vessel.weather.waves import drift_pressure, drift_pressure_direct

    rng = np.random.default_rng(0)
    hs = rng.uniform(0.0, 14.0, 4000)
    tp = np.r_[rng.uniform(1.0, 25.0, 3000), rng.uniform(1.0, 1.5, 1000)]
    hs[:10] = 0.0
    fast, direct = drift_pressure(hs, tp), drift_pressure_direct(hs, tp)
    assert np.all(fast[:10] == 0.0)
    assert np.max(np.abs(fast[10:] - direct[10:]) / direct[10:]) < 2e-8
    np.testing.assert_array_equal(
        drift_pressure([1.0], [30.0]), drift_pressure_direct([1.0], [30.0])
    )
