"""The compiled scene distances against the NumPy reference."""

from __future__ import annotations

import numpy as np
import pytest

from usvsim.evaluation.stress import select_sets, stress_episodes
from usvsim.task import scene_distances
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.scene_distances import (
    MAX_KERNEL_DISCS,
    PackedDiscs,
    load_distance_kernel,
    nearest_and_hits,
)

pytestmark = pytest.mark.skipif(load_distance_kernel() is None, reason="no C compiler")


def _random_discs(rng: np.random.Generator, n: int, k: int, m: int) -> PackedDiscs:
    turn = rng.uniform(-0.02, 0.02, (n, m))
    turn[:, :1] = 0.0  # straight-line vessels too (the |ω t| < 1e-9 branch)
    return PackedDiscs(
        rng.uniform(-200.0, 200.0, (n, k, 2)), rng.uniform(0.5, 25.0, (n, k)),
        rng.random((n, k)) < 0.7, rng.uniform(-200.0, 200.0, (n, m, 2)),
        rng.uniform(-np.pi, np.pi, (n, m)), rng.uniform(0.0, 5.0, (n, m)), turn,
        rng.uniform(1.0, 6.0, (n, m)), rng.random((n, m)) < 0.7,
    )  # fmt: skip


@pytest.mark.parametrize(("k", "m"), [(6, 3), (4, 0), (0, 3), (0, 0)])
def test_compiled_equals_the_numpy_reference(k: int, m: int) -> None:
    rng = np.random.default_rng(k * 10 + m)
    n, steps = 300, 20
    discs = _random_discs(rng, n, k, m)
    traj = rng.uniform(-220.0, 220.0, (n, steps, 13))  # positions in the first two columns
    t = rng.uniform(0.0, 300.0, (n, 1)) + 0.1 * np.arange(1, steps + 1)
    d_ref, hit_ref = nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="numpy")
    d, hit = nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="compiled")
    np.testing.assert_array_equal(hit, hit_ref)
    np.testing.assert_array_equal(np.isinf(d), np.isinf(d_ref))
    fin = np.isfinite(d_ref)
    np.testing.assert_allclose(d[fin], d_ref[fin], rtol=1e-12, atol=0.0)
    if m == 0:  # no trigonometry: the same bits
        np.testing.assert_array_equal(d, d_ref)
    if k == m == 0:
        assert np.isinf(d).all() and not hit.any()


def test_hits_and_nearest_at_their_thresholds() -> None:
    """A boat exactly on a collision threshold and two discs tied within rounding: the cheap
    pre-test must hand both to the exact ``hypot``."""
    half_beam = 1.2
    discs = PackedDiscs(
        np.array([[[0.0, 0.0], [0.0, 3e-12]]]), np.array([[5.0, 5.0]]),
        np.array([[True, True]]), np.zeros((1, 0, 2)), np.zeros((1, 0)), np.zeros((1, 0)),
        np.zeros((1, 0)), np.zeros((1, 0)), np.zeros((1, 0), dtype=bool),
    )  # fmt: skip
    edge = 5.0 + half_beam
    pos = np.array([[[edge, 0.0], [np.nextafter(edge, 0.0), 0.0], [3.0, 4.0]]])
    t = np.zeros((1, 3))
    d_ref, hit_ref = nearest_and_hits(pos, t, discs, 1.0, half_beam, backend="numpy")
    d, hit = nearest_and_hits(pos, t, discs, 1.0, half_beam, backend="compiled")
    np.testing.assert_array_equal(hit, hit_ref)
    np.testing.assert_array_equal(d, d_ref)
    assert hit[0].tolist() == [False, True, True]


def test_a_nan_position_gives_nan_as_in_numpy() -> None:
    rng = np.random.default_rng(2)
    discs = _random_discs(rng, 8, 4, 2)
    traj, t = rng.uniform(-200.0, 200.0, (8, 5, 2)), np.zeros((8, 5))
    traj[3, 2] = np.nan
    want = nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="numpy")
    got = nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="compiled")
    np.testing.assert_array_equal(got[1], want[1])
    np.testing.assert_array_equal(np.isnan(got[0]), np.isnan(want[0]))
    assert np.isnan(got[0][3, 2]) == bool(discs.static_ok[3].any() or discs.vessel_ok[3].any())


def test_more_discs_than_the_kernel_takes_run_in_numpy() -> None:
    rng = np.random.default_rng(1)
    discs = _random_discs(rng, 4, MAX_KERNEL_DISCS, 1)
    traj, t = rng.uniform(-200.0, 200.0, (4, 5, 2)), np.zeros((4, 5))
    want = nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="numpy")
    got = nearest_and_hits(traj, t, discs, 1.0, 1.2)
    np.testing.assert_array_equal(got[0], want[0])
    with pytest.raises(ValueError, match="more than 64 discs"):
        nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="compiled")
    with pytest.raises(ValueError, match="backend must be"):
        nearest_and_hits(traj, t, discs, 1.0, 1.2, backend="fast")  # type: ignore[arg-type]


def _run_everything(n: int, decisions: int) -> list[dict[str, np.ndarray]]:
    (stress_set,) = select_sets(["everything"])
    sim = OpenWaterBatch(n, observation="positional")
    sim.reset(None, list(stress_episodes(stress_set, n)))
    rng = np.random.default_rng(3)
    fields = ("min_distance_m", "collision", "terminated", "is_success")
    return [
        {f: getattr(step, f) for f in fields}
        for step in (sim.step(rng.uniform(-1.0, 1.0, (n, 1))) for _ in range(decisions))
    ]


def test_open_water_records_are_the_same_with_the_numpy_distances(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The "everything" stress set, 64 boats, 40 decisions: every step's minimum distance,
    collisions and outcomes with the compiled distances and with the NumPy reference."""
    compiled = _run_everything(64, 40)
    monkeypatch.setattr(scene_distances, "load_distance_kernel", lambda: None)
    reference = _run_everything(64, 40)
    assert any(r["collision"].any() for r in reference)  # the comparison sees collisions
    for got, want in zip(compiled, reference, strict=True):
        for name, value in want.items():
            np.testing.assert_allclose(got[name], value, rtol=1e-12, err_msg=name)


@pytest.mark.parametrize(("k", "m"), [(6, 3), (4, 0), (0, 3), (0, 0)])
def test_compiled_judge_equals_the_numpy_reference(k: int, m: int) -> None:
    """The compiled period judge against the NumPy reference, on paths that hit discs and pass
    through goals (and a NaN position), bit for bit."""
    rng = np.random.default_rng(100 + k * 10 + m)
    n, steps = 400, 20
    discs = _random_discs(rng, n, k, m)
    start = rng.uniform(-150.0, 150.0, (n, 1, 2))
    traj = np.zeros((n, steps, 13))
    traj[:, :, :2] = start + np.cumsum(rng.uniform(-6.0, 6.0, (n, steps, 2)), axis=1)
    goal = traj[:, rng.integers(steps), :2] + rng.uniform(-15.0, 15.0, (n, 2))
    traj[7, 5, 0] = np.nan
    t = rng.uniform(0.0, 300.0, (n, 1)) + 0.1 * np.arange(1, steps + 1)
    args = (traj, t, discs, goal, 1.0, 1.2, 10.0)
    ref = scene_distances.judge_period(*args, backend="numpy")
    got = scene_distances.judge_period(*args, backend="compiled")
    assert ref.reached_goal.any() and not ref.reached_goal.all()
    if k or m:
        assert ref.collision.any() and not ref.collision.all()
    for name in ("nearest_m", "collision", "reached_goal", "end_step", "first_goal_step",
                 "distance_to_obstacle_m", "distance_to_goal_m"):  # fmt: skip
        a, b = getattr(ref, name), getattr(got, name)
        assert a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)
