"""The goal mark (usvsim.task.goal_mark): where the goal's circle lands in the radar grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.task.goal_mark import (
    MARK,
    MARK_BLOCK,
    GoalMarkVectorEnv,
    goal_mark_images,
    goal_polar,
    marked_space,
    with_goal_mark,
)
from usvsim.task.observations import GOAL_STANDARDIZATION
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.radar import RadarConfig, pixel_index

CFG = RadarConfig()


def _goal(range_m: float, bearing_deg: float) -> np.ndarray:
    return GOAL_STANDARDIZATION.apply(np.array([[range_m, math.radians(bearing_deg)]]))


def _cells(mark: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = np.nonzero(mark[0, 0])
    return rows, cols


def test_goal_polar_inverts_the_observation_standardisation() -> None:
    r, b = goal_polar(_goal(123.4, -37.0))
    assert abs(r[0] - 123.4) < 1e-4 and abs(math.degrees(b[0]) + 37.0) < 1e-5


def test_a_goal_ahead_marks_its_circle_around_its_own_cell() -> None:
    mark = goal_mark_images(_goal(50.0, 0.0))
    assert mark.shape == (1, 1, 50, 119) and mark.dtype == np.uint8
    assert set(np.unique(mark)) == {0, MARK}
    rows, cols = _cells(mark)
    own_row, own_col = pixel_index(50.0, 0.0)
    assert mark[0, 0, own_row, own_col] == MARK
    # the rows of 40-60 m (4 m each), the columns symmetric about the centre (59)
    assert rows.min() == 10 and rows.max() == 14
    assert sorted(cols - 59) == sorted(59 - cols)
    # every marked cell's centre within the 10 m circle: its area over a cell's at 50 m
    cell_area = 4.0 * 50.0 * (2 * CFG.half_fov_rad / CFG.n_cols)
    assert abs(rows.size - math.pi * 100.0 / cell_area) / rows.size < 0.25


def test_a_goal_to_starboard_marks_the_columns_to_starboard() -> None:
    _, cols = _cells(goal_mark_images(_goal(30.0, 40.0)))
    _, own_col = pixel_index(30.0, math.radians(40.0))
    assert cols.min() > 59 and own_col in cols


def test_a_goal_beyond_the_image_is_marked_where_it_leaves_it() -> None:
    rows, cols = _cells(goal_mark_images(_goal(600.0, -30.0)))
    assert rows.max() == CFG.n_rows - 1  # the last row, at its bearing
    _, col = pixel_index(199.0, math.radians(-30.0))
    assert col in cols and cols.max() < 59
    for bearing, edge in ((170.0, CFG.n_cols - 1), (-170.0, 0), (190.0, 0)):
        _, cols = _cells(goal_mark_images(_goal(60.0, bearing)))
        assert edge in cols  # behind the boat: the outermost column on its side


def test_a_goal_at_the_boat_marks_the_nearest_rows() -> None:
    rows, _ = _cells(goal_mark_images(_goal(0.0, 0.0)))
    assert rows.min() == 0 and rows.max() <= 2


def test_the_space_and_a_batch_gain_one_channel() -> None:
    env = OpenWaterVectorEnv(3, observation="radar+goal")
    space = marked_space(env.single_observation_space)
    assert space["radar"].shape == (2, 50, 119)
    obs, _ = env.reset(seed=0)
    marked = with_goal_mark(obs)
    assert np.array_equal(marked["radar"][:, :1], obs["radar"])
    assert np.array_equal(marked["radar"][:, 1:], goal_mark_images(obs["goal"]))
    with pytest.raises(ValueError, match="radar\\+goal"):
        marked_space(OpenWaterVectorEnv(1, observation="scene").single_observation_space)


def test_the_wrapper_marks_observations_and_final_observations() -> None:
    plain = OpenWaterVectorEnv(6, observation="radar+goal")
    env = GoalMarkVectorEnv(OpenWaterVectorEnv(6, observation="radar+goal"))
    assert env.single_observation_space["radar"].shape == (2, 50, 119)
    a, _ = plain.reset(seed=3)
    b, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(80):
        act = rng.uniform(-1, 1, (6, 1))
        a, *_, info_a = plain.step(act)
        b, *_, info = env.step(act)
        assert np.array_equal(b["radar"][:, 0], a["radar"][:, 0])
        assert np.array_equal(b["radar"][:, 1:], goal_mark_images(a["goal"]))
        for i, row in enumerate(info.get("final_obs", [])):
            if row is not None:
                ended += 1
                base = info_a["final_obs"][i]
                assert row["radar"].shape == (2, 50, 119)
                assert np.array_equal(row["radar"][0], base["radar"][0])
                assert np.array_equal(row["radar"][1], goal_mark_images(base["goal"][None])[0, 0])
    assert ended > 0


def test_marking_in_blocks_is_marking_at_once() -> None:
    """A batch larger than one block is marked as ``goal_mark_images`` marks it whole."""
    rng = np.random.default_rng(3)
    n = MARK_BLOCK + 37
    obs = {
        "radar": rng.integers(0, 256, (n, 1, 50, 119), dtype=np.uint8),
        "goal": rng.normal(0.0, 1.0, (n, 2)).astype(np.float32),
    }
    marked = with_goal_mark(obs)["radar"]
    assert marked.shape == (n, 2, 50, 119) and marked.dtype == np.uint8
    assert np.array_equal(marked[:, :1], obs["radar"])
    assert np.array_equal(marked[:, 1:], goal_mark_images(obs["goal"], RadarConfig()))
