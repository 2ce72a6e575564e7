"""GAIL with a discriminator that sees the true scene while the policy sees the radar
(``GAILConfig.disc_observation="scene"``): the env's privileged observation, its place in the
rollout, what the discriminator reads, and the setup and CLI rules."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import torch

from learning.algorithms.rollout import RolloutCollector
from learning.cli.train import TrainArgs, run
from learning.experiments.il_setups import get_il_setup
from learning.imitation.discriminator import SCENE_INFO_KEY, SCENE_WIDTH
from learning.imitation.gail import GAILAgent, GAILConfig, GAILTrainer, end_kinds
from learning.imitation.preprocess import ExpertData
from usvsim.task.observations import observation_space
from usvsim.task.openwater_env import OpenWaterVectorEnv

torch.set_num_threads(1)


def _random_actions(env: OpenWaterVectorEnv, seed: int = 0):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)

    def act(obs):  # type: ignore[no-untyped-def]
        a = rng.uniform(-1.0, 1.0, (env.num_envs, 1)).astype(np.float32)
        return a, np.zeros(env.num_envs, dtype=np.float32)

    return act


def test_the_env_gives_the_scene_form_of_the_returned_observation_autoresets_included() -> None:
    env = OpenWaterVectorEnv(8, observation="scene", info_observation="scene")
    collector = RolloutCollector(env, seed=3, obs_info_keys=(SCENE_INFO_KEY,))
    ended = 0
    for _ in range(3):  # autoresets inside batches and episodes running across them
        batch = collector.collect(_random_actions(env), 40)
        assert isinstance(batch.obs, np.ndarray)
        np.testing.assert_array_equal(batch.aux[SCENE_INFO_KEY], batch.obs)
        ended += int(batch.episode_end.sum())
    assert ended > 0  # the SAME_STEP autoreset rows were checked too


def test_a_radar_env_gives_the_scene_beside_the_image() -> None:
    env = OpenWaterVectorEnv(4, observation="radar+goal", info_observation="scene")
    scene = OpenWaterVectorEnv(4, observation="scene")
    obs, info = env.reset(seed=5)
    ref, _ = scene.reset(seed=5)
    assert isinstance(obs, dict) and set(obs) == {"radar", "goal"}
    np.testing.assert_array_equal(info[SCENE_INFO_KEY], ref)
    actions = np.full((4, 1), 0.3, dtype=np.float32)
    for _ in range(5):
        _, _, _, _, info = env.step(actions)
        ref, *_ = scene.step(actions)
        np.testing.assert_array_equal(info[SCENE_INFO_KEY], ref)


def test_bad_info_observation_and_a_missing_key_are_named() -> None:
    with pytest.raises(ValueError, match="info_observation must be None or one of"):
        OpenWaterVectorEnv(2, observation="scene", info_observation="sonar")  # type: ignore[arg-type]
    with pytest.raises(KeyError, match="has no 'observation_scene'"):
        RolloutCollector(OpenWaterVectorEnv(2), seed=0, obs_info_keys=(SCENE_INFO_KEY,))


def _synthetic_expert(n: int = 64) -> ExpertData:
    rng = np.random.default_rng(0)
    radar = observation_space("radar+goal")
    image = rng.integers(0, 255, (n, *radar["radar"].shape), dtype=np.uint8)
    goal = rng.normal(size=(n, 2)).astype(np.float32)
    scene = np.zeros((n, SCENE_WIDTH), dtype=np.float32)
    scene[:, 0] = rng.uniform(20.0, 200.0, n)  # goal range, m
    last = np.zeros(n, dtype=bool)
    last[[31, 63]] = True
    return ExpertData(
        obs={"radar": image, "goal": goal},
        actions=rng.uniform(-1, 1, (n, 1)).astype(np.float32),
        heading_change_rad=np.zeros(n),
        episode=np.repeat([0, 1], n // 2),
        last=last,
        tracks=(),
        disc_obs=scene,
    )


def test_the_scene_discriminator_reads_the_scene_and_never_the_image() -> None:
    env = OpenWaterVectorEnv(4, observation="radar+goal", info_observation="scene")
    cfg = GAILConfig(disc_observation="scene")
    trainer = GAILTrainer(
        env.single_observation_space, env.single_action_space, _synthetic_expert(), cfg
    )
    first = next(iter(trainer.disc.parameters()))
    assert first.shape[1] == SCENE_WIDTH + 3  # scene ⊕ action ⊕ two absorbing flags: an MLP
    collector = RolloutCollector(
        env, seed=1, info_keys=GAILAgent.info_keys, obs_info_keys=(SCENE_INFO_KEY,)
    )
    batch = collector.collect(_random_actions(env), 6)
    ends = end_kinds(batch)
    r = trainer.rewards(batch, ends, 0.99)
    assert isinstance(batch.obs, dict)
    batch.obs["radar"][:] = 255 - batch.obs["radar"]  # another image, the same scene
    np.testing.assert_array_equal(trainer.rewards(batch, ends, 0.99), r)
    batch.aux[SCENE_INFO_KEY][..., 0] += 50.0  # the goal 50 m further off
    assert not np.allclose(trainer.rewards(batch, ends, 0.99), r)
    obs, az, _, _ = trainer.policy_samples(batch, ends)
    assert obs.shape == (int(batch.valid.sum()), SCENE_WIDTH) and az.shape[1] == 3


def test_the_scene_discriminator_needs_scene_data_and_an_open_water_setup() -> None:
    env = OpenWaterVectorEnv(2, observation="radar+goal")
    expert = dataclasses.replace(_synthetic_expert(), disc_obs=None)
    with pytest.raises(ValueError, match="needs the expert's scene observations"):
        GAILTrainer(
            env.single_observation_space,
            env.single_action_space,
            expert,
            GAILConfig(disc_observation="scene"),
        )
    with pytest.raises(ValueError, match="disc_observation must be one of"):
        GAILConfig(disc_observation="radar")  # type: ignore[arg-type]
    pole = get_il_setup("il-gaussian-radar")
    with pytest.raises(ValueError, match="needs task='open-water'"):
        pole.replace(gail=dataclasses.replace(pole.gail, disc_observation="scene"))


def test_the_agent_asks_the_rollout_for_the_scene() -> None:
    env = OpenWaterVectorEnv(2, observation="radar+goal")
    setup = get_il_setup("il-gaussian-radar-ow")

    def agent(view: str) -> GAILAgent:
        gail = dataclasses.replace(setup.gail, disc_observation=view)
        space_o, space_a = env.single_observation_space, env.single_action_space
        return GAILAgent(space_o, space_a, setup.algorithm_config, gail, _synthetic_expert())

    assert agent("scene").obs_info_keys == (SCENE_INFO_KEY,)
    assert agent("policy").obs_info_keys == ()
    # the shipped recipes: the Gaussian radar setup's D sees the scene, the categorical's the image
    assert setup.gail.disc_observation == "scene"
    assert get_il_setup("il-categorical-radar-ow").gail.disc_observation == "policy"


def _args(out: Path, **kw: object) -> TrainArgs:
    base: dict[str, object] = dict(
        setup="il-gaussian-radar-ow", iterations=1, n_envs=2, out=str(out), quiet=True, threads=1
    )
    base.update(kw)
    return TrainArgs(**base)  # type: ignore[arg-type]


def test_disc_observation_option_is_for_new_open_water_il_runs(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="--disc-observation must be one of policy, scene"):
        run(_args(tmp_path / "a", disc_observation="radar"))
    with pytest.raises(SystemExit, match="for the il-\\*-ow setups"):
        run(_args(tmp_path / "b", setup="il-gaussian-radar", disc_observation="scene"))
    with pytest.raises(SystemExit, match="for the il-\\*-ow setups"):
        run(_args(tmp_path / "c", setup="rl-gaussian-radar-ow", disc_observation="scene"))
    with pytest.raises(SystemExit, match="--resume keeps the run's own"):
        run(_args(tmp_path / "d", disc_observation="scene", resume=True))
    assert not any(tmp_path.rglob("*.pt"))
