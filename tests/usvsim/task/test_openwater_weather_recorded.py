"""OpenWater-v0 in weather steps its boats through ``NavigatedPlant.run_recorded`` (only
``[x, c]`` written per plant step, the packed state at the last): the episodes are those of the
full-trajectory path it replaced, bit for bit (issue 38)."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
import pytest

from usvsim import OPEN_WATER_ENV_ID
from usvsim.nav.navplant import NavigatedPlant
from usvsim.task.openwater_env import weather_family
from usvsim.task.weather_draw import WEATHER_SETS
from usvsim.vessel.codegen import BatchStepper


def _full_trajectory_path(navplant: NavigatedPlant) -> None:
    """Step ``navplant`` as before run_recorded: a default stepper writing every packed state of
    every plant step, the caller keeping [x, c] per step and a copy of the last packed state."""
    full = BatchStepper(navplant.step_function, navplant._stepper.kernel)
    navplant._stepper = full
    closed_loop = navplant.layout.closed_loop

    def run_recorded(*args: Any) -> tuple[np.ndarray, np.ndarray]:
        packed = navplant.run(*args)
        return packed[:, :, closed_loop], packed[:, -1].copy()

    navplant.run_recorded = run_recorded  # type: ignore[method-assign]


@pytest.mark.parametrize(
    ("n_boats", "n_steps", "ranges"),
    [(64, 300, None), (128, 150, WEATHER_SETS["sea-state-4"])],
)
def test_weather_episodes_equal_the_full_trajectory_path(
    n_boats: int, n_steps: int, ranges: Any
) -> None:
    def rollout(full: bool) -> list[tuple[np.ndarray, ...]]:
        env = gymnasium.make_vec(
            OPEN_WATER_ENV_ID,
            num_envs=n_boats,
            observation="scene",
            family=weather_family(ranges=ranges),
        )
        obs, _ = env.reset(seed=7)
        inner = env.unwrapped.sim.inner
        assert inner.in_weather
        if full:
            _full_trajectory_path(inner._navplant)
        actions = np.random.default_rng(1).uniform(-1.0, 1.0, (n_steps, n_boats, 1))
        out = [(obs,)]
        for a in actions:
            obs, reward, terminated, truncated, _ = env.step(a.astype(np.float32))
            out.append((obs, reward, terminated, truncated))
        out.append((inner._s,))
        return out

    fast, slow = rollout(False), rollout(True)
    assert any(r[2].any() or r[3].any() for r in fast[1:-1])  # autoresets happened
    for a, b in zip(fast, slow, strict=True):
        for x, y in zip(a, b, strict=True):
            assert np.array_equal(x, y)
