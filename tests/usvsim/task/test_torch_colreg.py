"""The COLREG reward terms in torch (usvsim.task.torch_colreg, issue 41 on the device) against
the NumPy terms (usvsim.task.colreg_reward): the pieces on random geometries, and the torch
open-water env's rewards on COLREG episodes against ``OpenWaterVectorEnv(colreg_reward=...)``."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.colreg_geometry import classify_encounter, encounter_kinematics
from usvsim.task.colreg_params import ColregParams
from usvsim.task.colreg_reward import COLREG_TERMS, ColregReward, ColregRewardWeights, own_motion
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, OpenWaterVectorEnv, mix_families
from usvsim.task.torch_colreg import (
    TorchColregReward,
    classify_encounter_torch,
    encounter_kinematics_torch,
    own_motion_torch,
)
from usvsim.task.torch_openwater import TorchOpenWaterEnv

W = ColregRewardWeights()
T = torch.as_tensor


def test_geometry_equals_the_numpy_functions() -> None:
    rng = np.random.default_rng(0)
    own, tgt = rng.uniform(-500, 500, (64, 1, 2)), rng.uniform(-500, 500, (64, 5, 2))
    chi, chi_t = rng.uniform(-4, 4, (64, 1)), rng.uniform(-4, 4, (64, 5))
    u, u_t = rng.uniform(0, 5, (64, 1)), rng.uniform(0, 5, (64, 5))
    u_t[:, 0] = u[:, 0]  # equal speeds: the overtaking tests' boundary
    # target 1: 300 m dead ahead on a reciprocal course (head-on)
    tgt[:, 1] = own[:, 0] + 300.0 * np.stack([np.cos(chi[:, 0]), np.sin(chi[:, 0])], -1)
    chi_t[:, 1] = chi[:, 0] + np.pi
    want = encounter_kinematics(own, chi, u, tgt, chi_t, u_t)
    got = encounter_kinematics_torch(T(own), T(chi), T(u), T(tgt), T(chi_t), T(u_t))
    for name in vars(want):
        np.testing.assert_allclose(getattr(got, name).numpy(), getattr(want, name), atol=1e-9,
                                   rtol=1e-12, err_msg=name)  # fmt: skip
    p = ColregParams()
    roles = classify_encounter(want.bearing_rad, want.aspect_rad, u, u_t, p)
    got_roles = classify_encounter_torch(T(want.bearing_rad), T(want.aspect_rad), T(u), T(u_t), p)
    np.testing.assert_array_equal(got_roles.numpy(), roles)
    assert len(set(roles.ravel().tolist())) == 5  # every role among the draws


def test_own_motion_equals_the_numpy_function() -> None:
    rng = np.random.default_rng(1)
    traj = np.cumsum(rng.normal(0, 0.3, (16, 20, 13)), axis=1)
    end = rng.integers(0, 20, 16)
    end[:3] = [0, 1, 19]  # the period's first, second and last steps
    want = own_motion(traj, end + 1, 0.1)
    got = own_motion_torch(T(traj[..., 0]), T(traj[..., 1]), T(end), 0.1)
    for w, g in zip(want, got, strict=True):
        np.testing.assert_allclose(g.numpy(), w, rtol=1e-13, atol=1e-13)


def test_terms_equal_the_numpy_terms_decision_after_decision() -> None:
    """Ten boats meeting three vessels each over 60 decisions, some restarting midway: every
    term and the encounter memory as the NumPy class's."""
    rng = np.random.default_rng(2)
    n, k, dt = 10, 3, 2.0
    cpu, dev = ColregReward(W, n), TorchColregReward(W, n, k, torch.device("cpu"), torch.float64)
    v_p0 = rng.uniform(-400, 400, (n, k, 2))
    v_vel = rng.uniform(-3, 3, (n, k, 2))
    ok = rng.random((n, k)) < 0.8
    own, chi = np.zeros((n, 2)), rng.uniform(-np.pi, np.pi, n)
    fired = dict.fromkeys(COLREG_TERMS, 0)
    for step in range(60):
        chi = chi + rng.normal(0.0, 0.15, n)  # a helmsman's wandering course
        own = own + 6.0 * np.stack([np.cos(chi), np.sin(chi)], 1)
        v_pos = v_p0 + v_vel * dt * step
        args = (own, chi, np.full(n, 3.0), v_pos, v_vel, ok)
        want = cpu(*args, dt)
        got = dev(*(T(a) for a in args), dt)
        for name in COLREG_TERMS:
            np.testing.assert_allclose(got[name].numpy(), getattr(want, name), atol=1e-9,
                                       err_msg=f"{name} at decision {step}")  # fmt: skip
            fired[name] += int(np.count_nonzero(getattr(want, name)))
        np.testing.assert_array_equal(dev.role.numpy(), cpu.role)
        np.testing.assert_allclose(got["total"].numpy(), want.total, atol=1e-9)
        if step == 30:
            boats = np.array([1, 4, 7])
            cpu.reset(boats)
            dev.reset(T(np.isin(np.arange(n), boats)))
    assert all(fired[t] > 0 for t in ("cpa", "starboard", "stand_on")), fired


def _run_pair(family: object, n: int, decisions: int, seed: int) -> dict[str, float]:
    """Both envs with the COLREG reward, the same seed and the same actions (to the goal plus
    noise); asserts flags equal every step; returns the summed |terms| and the worst gap."""
    cpu = OpenWaterVectorEnv(n, observation="scene", family=family, colreg_reward=W)  # type: ignore[arg-type]
    dev = TorchOpenWaterEnv(n, family=family, per_boat=40, noise="replay", colreg_reward=W,
                            observation_dtype="float64")  # fmt: skip
    o_cpu, _ = cpu.reset(seed=seed)
    dev.reset(seed=seed)
    rng = np.random.default_rng(seed)
    seen = {"gap": 0.0, **dict.fromkeys(COLREG_TERMS, 0.0)}
    for _ in range(decisions):
        a = np.clip(o_cpu[:, 1] / np.radians(30.0) + rng.normal(0, 0.5, n), -1, 1)[:, None]
        o_cpu, r_cpu, te, tr, i_cpu = cpu.step(a)
        _, r_dev, te_d, tr_d, i_dev = dev.step(T(a))
        np.testing.assert_array_equal(te_d.numpy(), te)
        np.testing.assert_array_equal(tr_d.numpy(), tr)
        gaps = [np.abs(r_dev.numpy() - r_cpu).max()]
        for name in COLREG_TERMS:
            key = f"reward_colreg_{name}"
            gaps.append(np.abs(i_dev[key].numpy() - i_cpu[key]).max())
            seen[name] += float(np.abs(i_cpu[key]).sum())
        seen["gap"] = max(seen["gap"], *map(float, gaps))
    return seen


def test_env_colreg_rewards_equal_the_cpu_env() -> None:
    """The COLREG members (Imazu- and trafficgen-like) with the open-water family: rewards and
    every term as the CPU env's; the terms that fire in both are not all zero."""
    fam = mix_families(OPEN_WATER_FAMILY, COLREG_FAMILY, 0.7, prefix="colreg-")
    seen = _run_pair(fam, 8, 120, seed=5)
    assert seen["gap"] <= 1e-8, seen
    assert seen["cpa"] > 0 and seen["starboard"] > 0, seen


@pytest.mark.slow
def test_env_colreg_rewards_equal_the_cpu_env_on_the_colreg_family_alone() -> None:
    seen = _run_pair(COLREG_FAMILY, 16, 200, seed=11)
    assert seen["gap"] <= 1e-8, seen
    assert sum(seen[t] > 0 for t in COLREG_TERMS) >= 4, seen


def test_env_without_the_option_has_no_colreg_entries() -> None:
    env = TorchOpenWaterEnv(2, family=COLREG_FAMILY, per_boat=2)
    env.reset(seed=0)
    _, _, _, _, info = env.step(torch.zeros((2, 1), dtype=torch.float64))
    assert not any(k.startswith("reward_colreg") for k in info)
