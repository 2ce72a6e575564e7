"""Checkpoints: round trip, slim/half copies, precise errors, the helmsman wrapper."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import (
    FORMAT,
    VERSION,
    Checkpoint,
    CheckpointError,
    NonFiniteWeightsError,
    PolicyHelmsman,
    load_agent,
    load_checkpoint,
    load_helmsman,
    save_checkpoint,
    slim_copy,
)
from learning.experiments.setups import get_setup
from usvsim.helm.protocol import Helmsman
from usvsim.helm.registry import helmsman_kinds
from usvsim.task.batch import action_space
from usvsim.task.observations import observation_space
from usvsim.task.vector_env import PoleAvoidanceVectorEnv


def _agent(setup_name: str, seed: int = 3) -> tuple[Any, Checkpoint]:
    setup = get_setup(setup_name)
    agent = get_algorithm(setup.algorithm).make_agent(
        observation_space(setup.observation), action_space(setup.action), setup.run_config(seed)
    )
    env = PoleAvoidanceVectorEnv(8, observation=setup.observation, action=setup.action)
    obs, _ = env.reset(seed=0)
    agent.normalizer.update(obs)  # non-trivial statistics to round-trip
    ckpt = Checkpoint.from_agent(
        agent, setup, train_args={"seed": seed}, validation={"iteration": 0, "successes": 2}
    )
    return agent, ckpt


def _obs(setup_name: str, n: int = 6) -> Any:
    setup = get_setup(setup_name)
    env = PoleAvoidanceVectorEnv(n, observation=setup.observation, action=setup.action)
    return env.reset(seed=11)[0]


@pytest.mark.parametrize("name", ["rl-gaussian-positional", "rl-categorical-radar"])
def test_round_trip_gives_identical_actions(tmp_path: Path, name: str) -> None:
    agent, ckpt = _agent(name)
    save_checkpoint(ckpt, tmp_path / "a.pt")
    loaded = load_checkpoint(tmp_path / "a.pt", expected_setup=name)
    assert (loaded.setup, loaded.slim, loaded.weights_dtype) == (name, False, "float32")
    assert loaded.validation == {"iteration": 0, "successes": 2}
    assert loaded.git_revision != ""
    again = load_agent(loaded)
    obs = _obs(name)
    np.testing.assert_array_equal(again.act(obs), agent.act(obs))
    np.testing.assert_array_equal(again.values(obs), agent.values(obs))
    raw = torch.load(tmp_path / "a.pt", weights_only=True)
    assert (raw["format"], raw["version"]) == (FORMAT, VERSION)


def test_slim_copy_acts_the_same_and_is_smaller(tmp_path: Path) -> None:
    name = "rl-categorical-positional"
    agent, ckpt = _agent(name)
    save_checkpoint(ckpt, tmp_path / "full.pt")
    save_checkpoint(slim_copy(ckpt), tmp_path / "slim.pt")
    full_size = (tmp_path / "full.pt").stat().st_size
    slim_size = (tmp_path / "slim.pt").stat().st_size
    assert slim_size < 0.6 * full_size  # no critic (Adam's moments are still empty here)
    slim = load_agent(load_checkpoint(tmp_path / "slim.pt"))
    obs = _obs(name)
    np.testing.assert_array_equal(slim.act(obs), agent.act(obs))


def test_half_precision_copy_halves_the_policy(tmp_path: Path) -> None:
    name = "rl-gaussian-radar"
    agent, ckpt = _agent(name)
    save_checkpoint(slim_copy(ckpt), tmp_path / "f32.pt")
    save_checkpoint(slim_copy(ckpt, half=True), tmp_path / "f16.pt")
    ratio = (tmp_path / "f16.pt").stat().st_size / (tmp_path / "f32.pt").stat().st_size
    assert 0.45 < ratio < 0.55
    half = load_checkpoint(tmp_path / "f16.pt")
    assert half.weights_dtype == "float16"
    restored = load_agent(half)
    assert all(p.dtype == torch.float32 for p in restored.policy.parameters())
    obs = _obs(name)
    np.testing.assert_allclose(restored.act(obs), agent.act(obs), atol=2e-3)


def test_helmsman_declares_its_kinds(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-categorical-radar")
    save_checkpoint(slim_copy(ckpt), tmp_path / "my-policy.pt")
    helmsman = load_helmsman(tmp_path / "my-policy.pt")
    assert isinstance(helmsman, PolicyHelmsman) and isinstance(helmsman, Helmsman)
    assert helmsman_kinds(helmsman) == ("radar+goal", "categorical")
    assert helmsman.name == "my-policy"
    helmsman.reset(6)
    actions = helmsman.act(_obs("rl-categorical-radar"))
    assert actions.shape == (6,) and actions.dtype.kind in "iu"


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(CheckpointError, match="no such checkpoint file"):
        load_checkpoint(tmp_path / "nope.pt")


def test_truncated_file_is_reported_as_corrupt(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-positional")
    save_checkpoint(ckpt, tmp_path / "a.pt")
    data = (tmp_path / "a.pt").read_bytes()
    (tmp_path / "a.pt").write_bytes(data[: len(data) // 2])
    with pytest.raises(CheckpointError, match="corrupt or truncated"):
        load_checkpoint(tmp_path / "a.pt")


def test_garbage_file_is_reported_as_corrupt(tmp_path: Path) -> None:
    (tmp_path / "a.pt").write_bytes(b"this is not a checkpoint at all")
    with pytest.raises(CheckpointError, match="not a readable checkpoint"):
        load_checkpoint(tmp_path / "a.pt")


def test_foreign_torch_file_is_not_a_checkpoint(tmp_path: Path) -> None:
    torch.save({"weights": torch.zeros(3)}, tmp_path / "a.pt")
    with pytest.raises(CheckpointError, match="not a usvsim checkpoint"):
        load_checkpoint(tmp_path / "a.pt")


def test_newer_version_is_refused(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-positional")
    data = ckpt.to_dict()
    data["version"] = VERSION + 1
    torch.save(data, tmp_path / "a.pt")
    with pytest.raises(CheckpointError, match=f"version {VERSION + 1} is not supported"):
        load_checkpoint(tmp_path / "a.pt")


def test_wrong_setup_names_both_observation_kinds(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-radar")
    save_checkpoint(ckpt, tmp_path / "a.pt")
    with pytest.raises(
        CheckpointError, match=r"observation 'radar\+goal'.*expected .*'positional'"
    ):
        load_checkpoint(tmp_path / "a.pt", expected_setup="rl-gaussian-positional")


def test_observation_kind_that_does_not_match_the_weights(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-positional")
    ckpt.observation = "radar+goal"  # a file claiming another observation than its network's
    save_checkpoint(ckpt, tmp_path / "a.pt")
    with pytest.raises(CheckpointError, match="observation space does not match"):
        load_checkpoint(tmp_path / "a.pt")


def test_weights_of_the_wrong_shape(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-positional")
    policy = dict(ckpt.agent["policy"])
    policy["head.weight"] = torch.zeros(3, 3)
    ckpt.agent = {**ckpt.agent, "policy": policy}
    save_checkpoint(ckpt, tmp_path / "a.pt")
    with pytest.raises(CheckpointError, match="weights do not fit"):
        load_agent(load_checkpoint(tmp_path / "a.pt"), tmp_path / "a.pt")


def test_non_finite_policy_is_never_saved_and_old_file_survives(tmp_path: Path) -> None:
    _, ckpt = _agent("rl-gaussian-positional")
    save_checkpoint(ckpt, tmp_path / "a.pt")
    before = (tmp_path / "a.pt").read_bytes()
    policy = dict(ckpt.agent["policy"])
    policy["head.bias"] = torch.full_like(policy["head.bias"], float("nan"))
    ckpt.agent = {**ckpt.agent, "policy": policy}
    with pytest.raises(NonFiniteWeightsError, match="non-finite weights"):
        save_checkpoint(ckpt, tmp_path / "a.pt")
    assert (tmp_path / "a.pt").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.pt"]  # no temporary left over


MODELS = Path(__file__).resolve().parents[3] / "usvsim" / "models"
SHIPPED = sorted(MODELS.glob("*.pt"))  # every shipped model has its models.json entry


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_model_reproduces_its_recorded_validation(path: Path) -> None:
    import json

    from usvsim.evaluation.episodes import evaluate, validation_episodes

    recorded = json.loads((MODELS / "models.json").read_text())["models"][path.stem]
    setup = recorded["setup"]  # the model's name says what it is; its setup how it was trained
    rl = setup.startswith("rl-")  # expected_setup knows the RL setups only
    ckpt = load_checkpoint(path, expected_setup=setup if rl else None)
    assert ckpt.setup == setup and recorded["card"]["former_names"] == [setup]
    # slim copies: float16 radar CNNs ~2.8 MB; the traffic models keep float32 (5.7 MB), as
    # float16 weights moved a traffic file's COLREG validation (benchmarks/ship_traffic.py)
    assert ckpt.slim and path.stat().st_size < 6_000_000
    helmsman = load_helmsman(path)
    records = evaluate(
        helmsman, validation_episodes(), observation=ckpt.observation, action=ckpt.action
    )
    expected = recorded["evaluation"]["validation"]
    assert sum(r.success for r in records) == expected["successes"]
    # float32 sums differ in the last bits with the thread count: centimetres, not outcomes
    assert min(r.min_pole_distance_m for r in records) == pytest.approx(
        expected["min_pole_distance_m"], abs=0.01
    )


def test_config_from_dict_rebuilds_nested_configs_and_refuses_unknown_keys() -> None:
    import dataclasses

    from learning.algorithms.base import config_from_dict
    from learning.algorithms.trpo import TRPOConfig

    config = get_setup("rl-gaussian-radar").run_config(seed=4)
    again = config_from_dict(TRPOConfig, _plain_lists(dataclasses.asdict(config)))
    assert again == config and again.network.hidden == (400, 300)
    with pytest.raises(ValueError, match="unknown TRPOConfig keys \\['max_kll'\\]"):
        config_from_dict(TRPOConfig, {"max_kll": 0.01})


def _plain_lists(d: dict[str, Any]) -> dict[str, Any]:
    """Tuples as lists, as a checkpoint stores them."""
    return {
        k: _plain_lists(v) if isinstance(v, dict) else list(v) if isinstance(v, tuple) else v
        for k, v in d.items()
    }


@pytest.mark.parametrize("name", ["rl-gaussian-radar", "il-categorical-radar"])
def test_flat_setup_params_of_older_checkpoints_read_as_the_composed_setup(name: str) -> None:
    import json

    from learning.experiments.il_setups import IL_SETUPS
    from learning.experiments.setups import SETUPS, setup_from_params, setup_params

    # setup_params as the models shipped until 2026-12 (commit eb82cea) stored them: flat,
    # written before setups held their algorithm's config
    flat = json.loads((Path(__file__).parent / "data" / "flat_setup_params.json").read_text())
    params = flat[name]
    assert "algorithm_config" not in params
    base = {**SETUPS, **IL_SETUPS}[name]
    assert setup_from_params(base, params) == base
    from usvsim.helm.registry import model_path

    ckpt = load_checkpoint(model_path(name))  # the setup's shipped model, by its former name
    assert ckpt.algorithm == "trpo"
    assert setup_from_params(base, ckpt.setup_params) == base
    assert setup_from_params(base, setup_params(base)) == base
    with pytest.raises(ValueError, match="unknown setup fields"):
        setup_from_params(base, {**setup_params(base), "bogus": 1})


def test_new_checkpoints_name_their_algorithm(tmp_path: Path) -> None:
    from learning.algorithms.registry import ALGORITHMS, get_algorithm

    _, ckpt = _agent("rl-gaussian-positional")
    save_checkpoint(ckpt, tmp_path / "a.pt")
    raw = torch.load(tmp_path / "a.pt", weights_only=True)
    assert raw["algorithm"] == "trpo" and raw["setup_params"]["algorithm"] == "trpo"
    assert list(ALGORITHMS) == ["trpo", "ppo"]
    with pytest.raises(ValueError, match="unknown algorithm 'sac'"):
        get_algorithm("sac")
    raw["algorithm"] = "sac"
    torch.save(raw, tmp_path / "b.pt")
    with pytest.raises(CheckpointError, match="unknown algorithm 'sac'"):
        load_checkpoint(tmp_path / "b.pt")


def test_a_ppo_checkpoint_round_trips_through_the_registry(tmp_path: Path) -> None:
    agent, ckpt = _agent("rl-gaussian-positional-ppo")
    assert ckpt.algorithm == "ppo" and type(agent).__name__ == "PPOAgent"
    save_checkpoint(ckpt, tmp_path / "p.pt")
    loaded = load_agent(load_checkpoint(tmp_path / "p.pt"))
    obs = np.random.default_rng(0).normal(size=(5, *agent.observation_space.shape))
    assert type(loaded).__name__ == "PPOAgent"
    np.testing.assert_array_equal(loaded.act(obs), agent.act(obs))
