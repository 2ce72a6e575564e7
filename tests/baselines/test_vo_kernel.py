"""The compiled ``vo`` terms (:mod:`baselines.vo_kernel`) against the NumPy reference: bit for
bit on random scenes (the kernel skips tests that cannot change a result, so near misses matter).
"""

from __future__ import annotations

import numpy as np
import pytest

from baselines.velocity_obstacle import VOConfig, VOHelmsman, vo_course
from baselines.vo_kernel import load_vo_kernel
from usvsim.task.observations import SCENE_FEATURES, SCENE_K

pytestmark = pytest.mark.skipif(load_vo_kernel() is None, reason="no C compiler")


def _scenes(n: int, seed: int) -> np.ndarray:
    """``n`` random scene observations: 0-8 obstacles 5-400 m away, 60 % of them moving up to
    8 m/s, radii 1, 5 or 20 m; own speed 0-5 m/s with some sway."""
    rng = np.random.default_rng(seed)
    o = np.zeros((n, 4 + SCENE_FEATURES * SCENE_K), dtype=np.float32)
    o[:, 0], o[:, 1] = rng.uniform(50, 500, n), rng.uniform(-np.pi, np.pi, n)
    o[:, 2], o[:, 3] = rng.uniform(0, 5, n), rng.uniform(-1, 1, n)
    n_obstacles = rng.integers(0, SCENE_K + 1, n)
    ranges = np.sort(rng.uniform(5, 400, (n, SCENE_K)), axis=1)
    for j in range(SCENE_K):
        slot = o[:, 4 + SCENE_FEATURES * j : 4 + SCENE_FEATURES * (j + 1)]
        moving = rng.random(n) < 0.6
        slot[:, 0], slot[:, 1] = ranges[:, j], rng.uniform(-np.pi, np.pi, n)
        slot[:, 2] = rng.choice([1.0, 5.0, 20.0], n)
        slot[:, 3] = np.where(moving, rng.uniform(-8, 8, n), -o[:, 2])  # relative velocity
        slot[:, 4] = np.where(moving, rng.uniform(-8, 8, n), -o[:, 3])
        slot[:, 5] = 1.0
        slot[j >= n_obstacles] = 0.0
    return o


@pytest.mark.parametrize(
    "config", [VOConfig(), VOConfig(w_shortfall=2.0, w_static_starboard=0.5)], ids=["vo", "expert"]
)
def test_compiled_equals_numpy_bit_for_bit(config: VOConfig) -> None:
    rng = np.random.default_rng(7)
    obs = _scenes(2000, 1)
    previous = np.where(rng.random(2000) < 0.5, np.nan, rng.uniform(-3, 3, 2000))
    margin = rng.uniform(0, 10, 2000)
    ref = vo_course(config, obs, previous, margin, backend="numpy")
    fast = vo_course(config, obs, previous, margin, backend="compiled")
    np.testing.assert_array_equal(fast[0], ref[0])
    np.testing.assert_array_equal(fast[1], ref[1])
    assert 0.1 < ref[1].mean() < 0.9  # the scenes do block courses: the terms are exercised


def test_helmsman_backends_act_alike_over_decisions() -> None:
    obs = _scenes(500, 2)
    actions = []
    for backend in ("numpy", "compiled"):
        h = VOHelmsman(backend=backend)
        h.reset(500)
        actions.append([h.act(obs[np.roll(np.arange(500), k)]) for k in range(3)])
    np.testing.assert_array_equal(np.array(actions[0]), np.array(actions[1]))


def test_no_obstacles_nothing_blocked() -> None:
    obs = _scenes(4, 3)
    obs[:, 4:] = 0.0
    fast, avoiding = vo_course(VOConfig(), obs, np.full(4, np.nan), backend="compiled")
    np.testing.assert_array_equal(fast, vo_course(VOConfig(), obs, np.full(4, np.nan))[0])
    assert not avoiding.any()


def test_acting_for_some_boats_equals_their_rows_and_keeps_the_others_memory() -> None:
    obs = _scenes(300, 4)
    full, some = VOHelmsman(), VOHelmsman()
    full.reset(300)
    some.reset(300)
    rows = np.flatnonzero(np.random.default_rng(5).random(300) < 0.4)
    for k in range(3):  # the memory (previous choice) carries between decisions
        step = obs[np.roll(np.arange(300), 7 * k)]
        expected = full.act(step)[rows]
        np.testing.assert_array_equal(some.act(step[rows], rows), expected)
    assert full.last_avoiding is not None and some.last_avoiding is not None
    np.testing.assert_array_equal(some.last_avoiding[rows], full.last_avoiding[rows])
    assert not some.last_avoiding[np.setdiff1d(np.arange(300), rows)].any()
    with pytest.raises(ValueError, match="boats in"):
        some.act(obs[:2], np.array([0, 300]))


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_an_empty_batch_gives_empty_courses(backend: str) -> None:
    obs = np.zeros((0, 4 + SCENE_K * SCENE_FEATURES))
    course, avoiding = vo_course(VOConfig(), obs, np.zeros(0), backend=backend)  # type: ignore[arg-type]
    assert course.shape == avoiding.shape == (0,)
