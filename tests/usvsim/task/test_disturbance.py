"""Per-episode disturbances of the batch simulator: speed, current, GNSS faults (issue 16)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.special import ndtri

from usvsim.helm.protocol import StraightAheadHelmsman
from usvsim.task.batch import PoleAvoidanceBatch
from usvsim.task.disturbance import BoatDisturbances, EpisodeDisturbance
from usvsim.task.gnss_fault_kernel import load_gnss_fault_kernel
from usvsim.task.scenario import EpisodeSpec
from usvsim.vessel.autopilot import IDLE_DRAG_FRACTION, IDLE_THRUST_FRACTION
from usvsim.vessel.model import damping_forces
from usvsim.vessel.plant import Plant
from usvsim.vessel.vessels import get_vessel

SPEC = EpisodeSpec(0, 80.0, 0.0, 0.0, noise_seed=7)  # start 80 m north of the pole, heading south


def _run(dists, specs=None, steps=10):
    specs = specs or [SPEC] * len(dists)
    batch = PoleAvoidanceBatch(len(specs))
    batch.reset(None, specs, dists)
    helm = StraightAheadHelmsman()
    helm.reset(len(specs))
    out = []
    for _ in range(steps):
        res = batch.step(helm.act(None))
        out.append(res)
    return batch, out


def test_default_boat_reaches_1_5_mps_from_cruise():
    plant = Plant("default")
    state = plant.initial_state(np.zeros((1, 3)), 3.0)
    _, traj = plant.step(state, np.zeros(1), 1.5, n_steps=900)  # 90 s
    assert abs(traj[0, -1, 3] - 1.5) < 0.01  # the old fixed 5 % idle thrust held it at ~2.2 m/s


def test_idle_thrust_at_cruise_is_the_fixed_fraction():
    v = get_vessel("default")
    drag3 = float(damping_forces(v, ca.DM([3.0, 0.0, 0.0]))[0])
    assert IDLE_DRAG_FRACTION * drag3 > IDLE_THRUST_FRACTION * v.actuation.a1_max  # unchanged


def test_current_per_boat_drifts_only_that_boat():
    east = EpisodeDisturbance(current_speed_mps=0.5, current_direction_rad=math.pi / 2)
    batch, _ = _run([None, east], steps=10)  # 20 s
    y = batch.state.x[:, 1]
    # same noise streams: the autopilot holds heading, not course, so the second boat drifts
    # east with the current, 0.5 m/s x 20 s = 10 m, beside the calm one
    assert 8.5 < y[1] - y[0] < 11.0


def test_speed_per_boat():
    _, out = _run([EpisodeDisturbance(speed_mps=2.0), EpisodeDisturbance(speed_mps=4.0)], steps=5)
    u = out[-1].trajectory[:, -1, 3]
    assert u[0] == pytest.approx(2.0, abs=0.05) and u[1] == pytest.approx(4.0, abs=0.05)


def test_no_disturbance_equals_undisturbed_call():
    _, a = _run([None, None], steps=4)
    _, b = _run([EpisodeDisturbance(), None], steps=4)  # active but calm: same numbers
    np.testing.assert_array_equal(a[-1].trajectory, b[-1].trajectory)
    np.testing.assert_array_equal(a[-1].est_pos_ne, b[-1].est_pos_ne)


def test_boat_does_not_depend_on_its_neighbours():
    noisy = EpisodeDisturbance(gnss_noise_scale=3.0, gnss_outlier_probability=0.2, seed=3)
    other = EpisodeDisturbance(speed_mps=2.0, gnss_dropout_start_s=4.0, gnss_dropout_duration_s=9.0)
    _, alone = _run([noisy], steps=6)
    _, mixed = _run([other, noisy], steps=6)
    np.testing.assert_array_equal(alone[-1].est_pos_ne[0], mixed[-1].est_pos_ne[1])


def _position_error(dist, steps=15):
    _, out = _run([dist], steps=steps)
    true = np.array([r.trajectory[0, -1, :2] for r in out])
    est = np.array([r.est_pos_ne[0] for r in out])
    return np.hypot(*(est - true).T)


def test_gnss_noise_scale_raises_estimate_error():
    e1 = _position_error(None)
    e3 = _position_error(EpisodeDisturbance(gnss_noise_scale=3.0))
    assert np.sqrt(np.mean(e3**2)) > 2.0 * np.sqrt(np.mean(e1**2))


def test_gnss_outliers_raise_estimate_error():
    e1 = _position_error(None)
    eo = _position_error(EpisodeDisturbance(gnss_outlier_probability=0.3, seed=1))
    assert eo.max() > 2.0 * e1.max()


def test_dropout_freezes_gnss_updates():
    # with GNSS silent for the whole run, the filter dead-reckons: its position estimate drifts
    # from the noisy-GNSS one (same normals otherwise)
    e_drop = _position_error(
        EpisodeDisturbance(gnss_dropout_start_s=0.0, gnss_dropout_duration_s=1e9), steps=15
    )
    e1 = _position_error(None, steps=15)
    assert not np.allclose(e_drop, e1)
    assert np.all(np.isfinite(e_drop))


def test_bad_disturbance_is_refused():
    with pytest.raises(ValueError, match="current_speed_mps"):
        EpisodeDisturbance(current_speed_mps=-1.0)
    with pytest.raises(ValueError, match="speed_mps"):
        EpisodeDisturbance(speed_mps=0.0)


def _perturbed_reference(dist, normals, gnss_index, z):
    """The GNSS columns scaled element by element (the definition): noise scale, times the
    outlier scale where the boat's draw z < Φ⁻¹(p); boats without faults untouched."""
    out = normals.copy()
    drawing = list(np.flatnonzero(dist.active & (dist.outlier_p > 0)))
    for i in range(normals.shape[0]):
        if not (dist.active[i] and (dist.noise_scale[i] != 1.0 or dist.outlier_p[i] > 0)):
            continue
        for k, col in enumerate(gnss_index):
            s = dist.noise_scale[i]
            if i in drawing and z[drawing.index(i), k] < ndtri(dist.outlier_p[i]):
                s = s * dist.outlier_scale[i]
            out[i, col] = normals[i, col] * s
    return out


@pytest.mark.parametrize("backend", ["auto", "numpy"])
def test_perturb_normals_scales_each_gnss_entry_as_defined(backend):
    rng = np.random.default_rng(4)
    n, m = 12, 30
    items = [
        None,
        EpisodeDisturbance(gnss_noise_scale=2.5, seed=1),
        EpisodeDisturbance(gnss_outlier_probability=0.3, seed=2),
        EpisodeDisturbance(gnss_noise_scale=0.5, gnss_outlier_probability=0.6, seed=3),
        EpisodeDisturbance(seed=4),
    ] * 2 + [None, EpisodeDisturbance(gnss_noise_scale=3.0, gnss_outlier_probability=0.9, seed=5)]
    twins = []
    for _ in range(2):
        d = BoatDisturbances(n, 3.0, (0.0, 0.0))
        d.set(np.arange(n), items)
        twins.append(d)
    normals = rng.standard_normal((n, m))
    gnss_index = np.array([1, 4, 5, 9, 20, 29])
    drawing = np.flatnonzero(twins[1].active & (twins[1].outlier_p > 0))
    z = twins[1]._noise.for_boats(drawing).standard_normal((drawing.size, gnss_index.size))
    got = twins[0].perturb_normals(normals, gnss_index, backend=backend)
    want = _perturbed_reference(twins[1], normals, gnss_index, z)
    assert np.array_equal(got, want)
    ratio = got[:, gnss_index] / normals[:, gnss_index]
    assert np.any(ratio[3] == 0.5) and np.any(ratio[3] == 0.5 * 10.0)  # noise, and outliers
    others = np.setdiff1d(np.arange(m), gnss_index)
    assert np.array_equal(got[:, others], normals[:, others])


def test_gnss_fault_kernel_builds_here():
    """The C path is the one the tests above exercise with backend="auto" on this machine."""
    assert load_gnss_fault_kernel() is not None
