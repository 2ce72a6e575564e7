"""Reactive targets in training (usvsim.evaluation.colreg_rollout.TrainingReactiveTargets as the
open-water env's on_decision hook, issue 41)."""

from __future__ import annotations

import numpy as np

from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets, run_encounters
from usvsim.helm.registry import make_helmsman
from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.openwater_env import OpenWaterVectorEnv, draw_family


def test_env_targets_are_steered_as_the_suites_reactive_targets() -> None:
    """Boats that start together: the env's targets take the courses the suite's do."""
    episodes = draw_family(COLREG_FAMILY, 7, 6)
    suite = run_encounters(make_helmsman("los"), episodes, reactive_targets=True)
    assert suite.schedule is not None
    env = OpenWaterVectorEnv(6, family=COLREG_FAMILY, on_decision=TrainingReactiveTargets())
    obs, _ = env.reset(seed=0, options={"episodes": list(episodes)})
    helm = make_helmsman("los")
    helm.reset(6)
    turned = 0
    for k in range(12):  # every episode lasts longer
        obs, _, term, trunc, _ = env.step(helm.act(obs))
        assert not (term | trunc).any()
        k_slots = suite.schedule[k + 1][1].shape[1]
        np.testing.assert_array_equal(env.sim.v_course[:, :k_slots], suite.schedule[k + 1][1])
        turned += int(np.any(env.sim.v_course != suite.schedule[0][1]))
    assert turned > 0  # some target did react


def test_env_with_reactive_targets_is_reproducible_across_autoresets() -> None:
    ends = []

    def run() -> list[np.ndarray]:
        env = OpenWaterVectorEnv(
            4, observation="scene", family=COLREG_FAMILY, on_decision=TrainingReactiveTargets()
        )
        env.reset(seed=3)
        rng = np.random.default_rng(0)
        out = []
        for _ in range(120):
            obs, reward, term, trunc, _ = env.step(rng.uniform(-1, 1, (4, 1)))
            out.append(np.concatenate([reward, obs.ravel()]))
            ends.append(int((term | trunc).sum()))
        return out

    a, b = run(), run()
    assert sum(ends) >= 2  # autoresets happened in each run
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
