"""GAIL: reward forms, action normalisation, absorbing states, the discriminator, learning."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import torch
from gymnasium import spaces

from learning.algorithms.rollout import RolloutCollector
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.imitation.demonstrations import load_recordings, quality_check
from learning.imitation.discriminator import cat_obs
from learning.imitation.gail import (
    GAILConfig,
    GAILTrainer,
    normalize_actions,
    reward_from_logits,
    train_gail,
)
from learning.imitation.preprocess import ExpertData, expert_data
from usvsim.evaluation.episodes import validation_episodes
from usvsim.evaluation.likeness import expert_reference, helmsman_likeness
from usvsim.task.batch import action_space
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def expert() -> ExpertData:
    kept = [r for r in load_recordings().recordings if not quality_check(r)]
    return expert_data(kept, "positional", "gaussian")


def test_reward_forms_match_their_definitions() -> None:
    f = torch.linspace(-6.0, 6.0, 13)
    d = torch.sigmoid(f)
    torch.testing.assert_close(reward_from_logits(f, "-log(1-D)"), -torch.log(1 - d))
    torch.testing.assert_close(reward_from_logits(f, "log_d"), torch.log(d))
    torch.testing.assert_close(reward_from_logits(f, "logit"), torch.log(d) - torch.log(1 - d))
    with pytest.raises(ValueError, match="reward must be one of"):
        GAILConfig(reward="wasserstein")


def test_actions_are_normalised_to_the_heading_change_fraction() -> None:
    cat = normalize_actions(np.array([0, 10, 20, 40]), action_space("categorical"))
    np.testing.assert_allclose(cat[:, 0], [-1.0, -0.5, 0.0, 1.0])
    gauss = normalize_actions(np.array([[-1.7], [0.25], [3.0]]), action_space("gaussian"))
    np.testing.assert_allclose(gauss[:, 0], [-1.0, 0.25, 1.0])


def _random_batch(n_envs: int = 8, steps: int = 64):  # type: ignore[no-untyped-def]
    env = PoleAvoidanceVectorEnv(n_envs)
    rng = np.random.default_rng(0)

    def act(obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a = rng.uniform(-1.0, 1.0, (n_envs, 1)).astype(np.float32)
        return a, np.zeros(n_envs, dtype=np.float32)

    return env, RolloutCollector(env, seed=0).collect(act, steps)


@pytest.mark.slow
def test_discriminator_separates_expert_from_random_in_500_updates(expert: ExpertData) -> None:
    env, batch = _random_batch()
    cfg = GAILConfig(disc_steps=500, disc_minibatch=128, disc_lr=1e-3)
    gail = GAILTrainer(env.single_observation_space, env.single_action_space, expert, cfg)
    ends = np.zeros((*batch.rewards.shape, 2), dtype=bool)
    obs, az, _, _ = gail.policy_samples(batch, ends)
    gail.update_discriminator(obs, az)
    d_expert = torch.sigmoid(gail.logits(gail.expert_obs, gail.expert_az))
    d_random = torch.sigmoid(gail.logits(obs, az))
    # AUC: the chance that an expert pair scores above a random-behaviour pair
    auc = float((d_expert[:, None] > d_random[None, :]).float().mean())
    assert auc >= 0.97
    assert float((d_expert > 0.5).float().mean()) >= 0.9
    assert float((d_random < 0.5).float().mean()) >= 0.85


def test_absorbing_states_add_the_discounted_value_of_the_end(expert: ExpertData) -> None:
    env, batch = _random_batch(4, 8)
    space_o, space_a = env.single_observation_space, env.single_action_space
    with_abs = GAILTrainer(space_o, space_a, expert, GAILConfig(absorbing=True))
    without = GAILTrainer(space_o, space_a, expert, GAILConfig(absorbing=False))
    without.disc.load_state_dict(with_abs.disc.state_dict())
    batch.terminated[:] = False
    batch.terminated[2, 1] = batch.terminated[5, 3] = True
    ends = np.zeros((8, 4, 2), dtype=bool)
    ends[2, 1, 0] = True  # goal
    ends[5, 3, 1] = True  # collision
    gamma = 0.99
    diff = with_abs.rewards(batch, ends, gamma) - without.rewards(batch, ends, gamma)
    z = torch.tensor([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    r_abs = reward_from_logits(with_abs.logits(torch.zeros(2, 4), z), "-log(1-D)").numpy()
    expected = np.zeros((8, 4))
    expected[2, 1], expected[5, 3] = gamma / (1 - gamma) * r_abs
    np.testing.assert_allclose(diff, expected, rtol=1e-5, atol=1e-5)


def test_expert_data_gets_one_goal_absorbing_sample_per_run(expert: ExpertData) -> None:
    gail = GAILTrainer(
        spaces.Box(-np.inf, np.inf, (4,), dtype=np.float32),
        action_space("gaussian"),
        expert,
        GAILConfig(),
    )
    n_runs = int(expert.last.sum())
    assert gail.expert_az.shape[0] == len(expert) + n_runs
    np.testing.assert_array_equal(gail.expert_az[-n_runs:].numpy(), [[0.0, 1.0, 0.0]] * n_runs)


def test_gradient_penalty_of_a_unit_gradient_discriminator_is_zero(expert: ExpertData) -> None:
    env, batch = _random_batch(4, 8)
    gail = GAILTrainer(env.single_observation_space, env.single_action_space, expert, GAILConfig(
        disc_hidden=()))  # fmt: skip
    with torch.no_grad():  # f(x) = w·x + b with ‖w‖ = 1
        w = torch.zeros_like(gail.disc.head.weight)
        w[0, 0] = 1.0
        gail.disc.head.weight.copy_(w)
    obs, az, _, _ = gail.policy_samples(batch, np.zeros((8, 4, 2), dtype=bool))
    gp = gail._gradient_penalty(obs[:16], az[:16], cat_obs([obs[16:32]]), az[16:32])
    assert float(gp.detach()) == pytest.approx(0.0, abs=1e-6)


def _gail_run(expert: ExpertData, iterations: int, seed: int = 0):  # type: ignore[no-untyped-def]
    cfg = TRPOConfig(seed=seed, iterations=iterations, num_envs=16, steps_per_env=64, max_kl=0.02)
    log: list[float] = []
    agent = train_gail(
        GAILConfig(),
        cfg,
        lambda n: PoleAvoidanceVectorEnv(n),
        expert,
        callback=lambda s, a: log.append(s.update.mean_reward) and None,
    )
    return agent, log


@pytest.mark.slow
def test_same_seed_same_run(expert: ExpertData) -> None:
    _, a = _gail_run(expert, 2, seed=3)
    _, b = _gail_run(expert, 2, seed=3)
    assert a == b


@pytest.mark.slow
def test_short_gail_run_makes_the_policy_more_expert_like(expert: ExpertData, greedy: type) -> None:
    reference = expert_reference(validation_episodes(), n_samples=4)
    untrained = TRPOAgent(
        spaces.Box(-np.inf, np.inf, (4,), dtype=np.float32),
        action_space("gaussian"),
        TRPOConfig(),
    )
    before = helmsman_likeness(greedy(untrained), reference=reference)
    agent, _ = _gail_run(expert, 40)
    after = helmsman_likeness(greedy(agent), reference=reference)
    assert after.path_distance_m < 0.7 * before.path_distance_m
    assert math.isfinite(after.action_distance_deg)


def test_cloned_cnn_policy_keeps_its_batchnorm_statistics() -> None:
    """After cloning, a trainer's refresh of the BatchNorm statistics on the same states
    leaves the policy's actions as they were (the statistics were settled)."""
    from learning.algorithms.networks import refresh_batchnorm
    from learning.imitation.gail import behavioral_cloning
    from usvsim.task.observations import observation_space

    kept = [r for r in load_recordings().recordings if not quality_check(r)][:3]
    data = expert_data(kept, "radar+goal", "gaussian")
    agent = TRPOAgent(observation_space("radar+goal"), action_space("gaussian"), TRPOConfig())
    behavioral_cloning(agent, data, GAILConfig(bc_epochs=3))
    before = agent.act(data.obs)
    refresh_batchnorm(agent.policy, agent.policy_input(data.obs))
    np.testing.assert_allclose(agent.act(data.obs), before, atol=0.02)


@pytest.mark.slow
def test_il_run_validates_checkpoints_and_resumes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from learning.experiments.checkpoint import load_checkpoint, load_helmsman
    from learning.experiments.il_setups import get_il_setup
    from learning.experiments.train_il import train_il

    base = get_il_setup("il-gaussian-positional")
    setup = base.replace(
        validate_every=1,
        gail=dataclasses.replace(base.gail, bc_epochs=1),
        algorithm_config=dataclasses.replace(base.algorithm_config, num_envs=4, steps_per_env=16),
    )
    first = train_il(setup, tmp_path, iterations=2, log=lambda _: None)
    assert [h["iteration"] for h in first.history] == [1, 2]
    resumed = train_il(setup, tmp_path, iterations=3, resume=True, log=lambda _: None)
    assert [h["iteration"] for h in resumed.history] == [1, 2, 3]
    latest = load_checkpoint(tmp_path / "latest.pt")
    assert latest.setup == "il-gaussian-positional" and int(latest.agent["iteration"]) == 3
    spent = float(resumed.history[-1]["wall_time_s"])  # a budget counts the whole run: spent
    again = train_il(setup, tmp_path, iterations=6, resume=True, time_budget_s=spent,
                     log=lambda _: None)  # fmt: skip
    assert [h["iteration"] for h in again.history] == [1, 2, 3, 4]
    assert again.stop_reason == "time budget"
    assert int(load_checkpoint(tmp_path / "latest.pt").agent["iteration"]) == 4
    helmsman = load_helmsman(tmp_path / "best.pt")
    assert (helmsman.observation, helmsman.action) == ("positional", "gaussian")


def test_cloning_in_raw_minibatches_is_cloning_the_normalised_set() -> None:
    """The warm start normalises each minibatch (and each BatchNorm chunk) as it uses it: the
    cloned weights and statistics equal, bit for bit, those of normalising every observation
    first (the computation before, kept here as the reference), at a fraction of the memory."""
    import copy

    from learning.algorithms.networks import refresh_batchnorm
    from learning.imitation.discriminator import index_obs
    from learning.imitation.gail import behavioral_cloning
    from usvsim.task.observations import observation_space

    kept = [r for r in load_recordings().recordings if not quality_check(r)][:8]
    data = expert_data(kept, "radar+goal", "gaussian")
    config = GAILConfig(bc_epochs=2, bc_minibatch=64)
    agent = TRPOAgent(observation_space("radar+goal"), action_space("gaussian"), TRPOConfig())
    reference = copy.deepcopy(agent)
    behavioral_cloning(agent, data, config)

    reference.normalizer.update(data.obs)
    obs = reference.policy_input(data.obs)
    actions = torch.as_tensor(data.actions)
    opt = torch.optim.Adam(reference.policy.parameters(), lr=config.bc_lr)
    for _ in range(config.bc_epochs):
        for _ in range(8):
            refresh_batchnorm(reference.policy, obs)
        perm = torch.randperm(len(data), generator=reference.generator)
        for i in range(0, len(data), config.bc_minibatch):
            idx = perm[i : i + config.bc_minibatch]
            loss = -reference.policy(index_obs(obs, idx)).log_prob(actions[idx]).mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
    for _ in range(8):
        refresh_batchnorm(reference.policy, obs)
    got, want = agent.policy.state_dict(), reference.policy.state_dict()
    assert len(data) > 256  # BatchNorm refreshed in more than one chunk
    for key in want:
        assert torch.equal(got[key], want[key]), key
