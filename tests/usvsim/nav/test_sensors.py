"""Tests of usvsim.nav.sensors: noise statistics, rate schedule, compass wrapping, input checks."""

from __future__ import annotations

import numpy as np
import pytest

from usvsim.common.angles import ssa
from usvsim.nav.sensors import (
    SensorConfig,
    period_steps,
    sample_compass,
    sample_gps,
    sample_gyro,
    sample_gyro_bias,
    sensor_fires,
)

N_SAMPLES = 200_000
# Relative standard error of a sample std is 1/sqrt(2 n) = 0.16 % here; 2 % is > 10 sigma.
STD_RTOL = 0.02


def test_default_config_values() -> None:
    cfg = SensorConfig()
    assert cfg.gps_sigma_m == 1.5
    assert cfg.gps_rate_hz == 5.0
    assert cfg.compass_sigma_rad == pytest.approx(np.deg2rad(1.0), rel=1e-15)
    assert cfg.compass_rate_hz == 10.0
    assert cfg.gyro_sigma_radps > 0.0
    assert cfg.gyro_bias_sigma_radps > 0.0


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("gps_sigma_m", 0.0),
        ("gps_sigma_m", -1.0),
        ("gps_rate_hz", float("nan")),
        ("compass_sigma_rad", float("inf")),
        ("compass_rate_hz", "10"),
        ("gyro_sigma_radps", True),
        ("gyro_bias_sigma_radps", -1e-3),
    ],
)
def test_config_rejects_bad_values(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"SensorConfig.{field} must be"):
        SensorConfig(**{field: value})  # type: ignore[arg-type]


def test_config_is_frozen() -> None:
    cfg = SensorConfig()
    with pytest.raises(AttributeError):
        cfg.gps_sigma_m = 2.0  # type: ignore[misc]


def test_period_steps_at_plant_step() -> None:
    assert period_steps(5.0, 0.1) == 2
    assert period_steps(10.0, 0.1) == 1
    assert period_steps(1.0, 0.1) == 10


def test_period_steps_rejects_non_integer_period() -> None:
    with pytest.raises(ValueError, match="integer multiple"):
        period_steps(3.0, 0.1)


def test_period_steps_rejects_sensor_faster_than_plant() -> None:
    with pytest.raises(ValueError, match="faster than the plant rate"):
        period_steps(40.0, 0.1)


def test_sensor_fires_schedule() -> None:
    gps = [sensor_fires(k, 5.0, 0.1) for k in range(6)]
    compass = [sensor_fires(k, 10.0, 0.1) for k in range(6)]
    assert gps == [True, False, True, False, True, False]
    assert compass == [True] * 6


@pytest.mark.parametrize("bad", [-1, 1.0, True, "3"])
def test_sensor_fires_rejects_bad_step_index(bad: object) -> None:
    with pytest.raises(ValueError, match="step_index"):
        sensor_fires(bad, 5.0, 0.1)  # type: ignore[arg-type]


def test_gps_noise_statistics() -> None:
    cfg = SensorConfig()
    pos = np.tile([[100.0, -50.0]], (N_SAMPLES, 1))
    err = sample_gps(pos, np.random.default_rng(0), cfg) - pos
    assert err.shape == (N_SAMPLES, 2)
    np.testing.assert_allclose(err.std(axis=0), cfg.gps_sigma_m, rtol=STD_RTOL)
    # mean within 5 standard errors of zero; axes uncorrelated
    assert np.all(np.abs(err.mean(axis=0)) < 5 * cfg.gps_sigma_m / np.sqrt(N_SAMPLES))
    assert abs(np.corrcoef(err.T)[0, 1]) < 0.01


def test_compass_noise_statistics() -> None:
    cfg = SensorConfig()
    psi = np.full(N_SAMPLES, 0.3)
    err = ssa(sample_compass(psi, np.random.default_rng(1), cfg) - psi)
    assert err.std() == pytest.approx(cfg.compass_sigma_rad, rel=STD_RTOL)
    assert abs(err.mean()) < 5 * cfg.compass_sigma_rad / np.sqrt(N_SAMPLES)


def test_compass_wraps_across_pi() -> None:
    cfg = SensorConfig()
    # true heading just below +pi, and an unwrapped 3*pi - 0.01 (same direction)
    psi = np.concatenate(
        [np.full(N_SAMPLES // 2, np.pi - 0.01), np.full(N_SAMPLES // 2, 3 * np.pi - 0.01)]
    )
    z = sample_compass(psi, np.random.default_rng(2), cfg)
    assert z.min() >= -np.pi and z.max() < np.pi
    # P(noise > 0.01 rad = 0.573 sigma) = 0.283 of the readings cross to the negative side
    frac_negative = np.mean(z < 0.0)
    assert frac_negative == pytest.approx(0.283, abs=0.01)
    assert ssa(z - psi).std() == pytest.approx(cfg.compass_sigma_rad, rel=STD_RTOL)


def test_gyro_statistics() -> None:
    cfg = SensorConfig()
    r = np.full(N_SAMPLES, 0.1)
    bias = np.full(N_SAMPLES, 0.002)
    err = sample_gyro(r, bias, np.random.default_rng(3), cfg) - r
    assert err.mean() == pytest.approx(0.002, abs=5 * cfg.gyro_sigma_radps / np.sqrt(N_SAMPLES))
    assert err.std() == pytest.approx(cfg.gyro_sigma_radps, rel=STD_RTOL)


def test_gyro_bias_statistics() -> None:
    cfg = SensorConfig()
    b = sample_gyro_bias(N_SAMPLES, np.random.default_rng(4), cfg)
    assert b.shape == (N_SAMPLES,)
    assert b.std() == pytest.approx(cfg.gyro_bias_sigma_radps, rel=STD_RTOL)


def test_same_seed_same_samples() -> None:
    cfg = SensorConfig()
    pos = np.zeros((8, 2))
    a = sample_gps(pos, np.random.default_rng(7), cfg)
    b = sample_gps(pos, np.random.default_rng(7), cfg)
    c = sample_gps(pos, np.random.default_rng(8), cfg)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_inputs_raise(bad: float) -> None:
    cfg, rng = SensorConfig(), np.random.default_rng(0)
    pos = np.zeros((3, 2))
    pos[1, 0] = bad
    with pytest.raises(ValueError, match="pos_ne contains NaN or inf"):
        sample_gps(pos, rng, cfg)
    with pytest.raises(ValueError, match="psi contains NaN or inf"):
        sample_compass(np.array([0.0, bad]), rng, cfg)
    with pytest.raises(ValueError, match="bias contains NaN or inf"):
        sample_gyro(np.zeros(2), np.array([bad, 0.0]), rng, cfg)


def test_wrong_shapes_raise() -> None:
    cfg, rng = SensorConfig(), np.random.default_rng(0)
    with pytest.raises(ValueError, match=r"pos_ne must have shape \(N, 2\), got \(3, 3\)"):
        sample_gps(np.zeros((3, 3)), rng, cfg)
    with pytest.raises(ValueError, match=r"psi must have shape \(N,\), got \(3, 1\)"):
        sample_compass(np.zeros((3, 1)), rng, cfg)
    with pytest.raises(ValueError, match="bias must have the shape of r"):
        sample_gyro(np.zeros(3), np.zeros(4), rng, cfg)
    with pytest.raises(ValueError, match="n_boats must be a non-negative integer"):
        sample_gyro_bias(-1, rng, cfg)
