"""TRPO learns pole avoidance (positional), and the same seed gives the same training curve."""

from __future__ import annotations

import dataclasses

import torch

from learning.setups import get_setup
from learning.train_cli import validate
from learning.trpo import IterationStats, TRPOAgent, train
from usvsim.evaluate import RandomHelmsman, evaluate, validation_episodes

TIMES = {"rollout_time_s", "update_time_s", "wall_time_s"}


def _curve(stats: list[IterationStats]) -> list[dict[str, object]]:
    return [{k: v for k, v in dataclasses.asdict(s).items() if k not in TIMES} for s in stats]


def _train(name: str, iterations: int, seed: int = 0) -> tuple[TRPOAgent, list[IterationStats]]:
    setup = get_setup(name)
    stats: list[IterationStats] = []

    def record(s: IterationStats, agent: TRPOAgent) -> bool:
        stats.append(s)
        return False

    torch.set_num_threads(2)
    agent = train(setup.trpo_config(seed, iterations), setup.make_vector_env, callback=record)
    return agent, stats


def test_short_positional_run_beats_the_random_policy() -> None:
    setup = get_setup("rl-gaussian-positional")
    random_records = evaluate(
        RandomHelmsman("gaussian", seed=0),
        validation_episodes(),
        observation=setup.observation,
        action=setup.action,
    )
    random_successes = sum(r.success for r in random_records)
    # 12 iterations x 2048 decisions: ~5 s on 2 cores; measured 15/15 from iteration 10 (seed 0)
    agent, stats = _train(setup.name, 12)
    learned = validate(agent, setup)
    assert random_successes <= 3
    assert learned["successes"] >= random_successes + 9
    assert stats[-1].mean_return > stats[0].mean_return


def test_same_seed_same_training_curve_on_pole_avoidance() -> None:
    _, first = _train("rl-categorical-positional", 3, seed=5)
    _, again = _train("rl-categorical-positional", 3, seed=5)
    _, other = _train("rl-categorical-positional", 3, seed=6)
    assert _curve(first) == _curve(again)
    assert _curve(first) != _curve(other)
