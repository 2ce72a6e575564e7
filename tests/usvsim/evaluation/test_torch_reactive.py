"""Reactive targets on the torch open-water env (usvsim.evaluation.torch_reactive, issue 41's
-colreg-reactive on the device) against the CPU env's (TrainingReactiveTargets): with the
episodes' noise replayed, the same targets' courses, trajectories, rewards and flags."""

from __future__ import annotations

import numpy as np
import torch

from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets
from usvsim.evaluation.torch_reactive import DeviceReactiveTargets
from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.colreg_reward import ColregRewardWeights
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.torch_openwater import TorchOpenWaterEnv


def test_reactive_targets_on_the_device_equal_the_cpu_env() -> None:
    n, seed, w = 8, 4, ColregRewardWeights()
    cpu = OpenWaterVectorEnv(n, observation="scene", family=COLREG_FAMILY, colreg_reward=w,
                             on_decision=TrainingReactiveTargets())  # fmt: skip
    dev = TorchOpenWaterEnv(n, family=COLREG_FAMILY, per_boat=40, noise="replay",
                            colreg_reward=w, on_decision=DeviceReactiveTargets(),
                            observation_dtype="float64")  # fmt: skip
    o_cpu, _ = cpu.reset(seed=seed)
    dev.reset(seed=seed)
    rng = np.random.default_rng(seed)
    worst = {"position_m": 0.0, "reward": 0.0, "obs_float32_steps": 0.0}
    altered, ended = 0, 0
    before = cpu.sim.v_course.copy()
    for _ in range(150):
        a = np.clip(o_cpu[:, 1] / np.radians(30.0) + rng.normal(0, 0.5, n), -1, 1)[:, None]
        o_cpu, r_cpu, te, tr, _ = cpu.step(a)
        o_dev, r_dev, te_d, tr_d, _ = dev.step(torch.as_tensor(a))
        np.testing.assert_array_equal(te_d.numpy(), te)
        np.testing.assert_array_equal(tr_d.numpy(), tr)
        ok, m = cpu.sim.vessel_ok, cpu.sim.v_course.shape[1]
        np.testing.assert_array_equal(dev.discs.vessel_ok[:, :m].numpy(), ok)
        course = dev.discs.vessel_course_rad[:, :m].numpy()
        np.testing.assert_allclose(course[ok], cpu.sim.v_course[ok], atol=1e-9)
        going_on = ~(te | tr)[:, None] & ok & (before.shape[1] == m)
        if going_on.any():  # a target steered off its course this decision (same episode)
            altered += int((np.abs(cpu.sim.v_course - before)[going_on] > 1e-6).sum())
        before = cpu.sim.v_course.copy()
        obs32 = o_dev.numpy().astype(np.float32)  # the CPU env's observations are float32
        steps = np.abs(o_cpu - obs32) / np.spacing(np.maximum(np.abs(o_cpu), np.abs(obs32)))
        for key, value in (
            ("position_m", np.abs(cpu.sim.inner.state.x[:, :2] - dev.state.numpy()[:, :2]).max()),
            ("reward", np.abs(r_cpu - r_dev.numpy()).max()),
            ("obs_float32_steps", steps.max()),
        ):
            worst[key] = max(worst[key], float(value))
        ended += int((te | tr).sum())
    assert worst["position_m"] <= 1e-6 and worst["reward"] <= 1e-8, worst
    assert worst["obs_float32_steps"] <= 1.0, worst  # identical or one rounding apart
    assert ended >= n  # restarts happened: the hook's reset path ran
    assert altered >= 10  # the targets did react
