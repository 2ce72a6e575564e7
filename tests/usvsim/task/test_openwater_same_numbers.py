"""The open-water env's numbers do not change when its step is made faster (issue 40, CPU).

A recorded reference (``data/openwater_reference.npz``, written by this module run as a script
before the step was optimised): for a fixed seed, 32 boats and 60 decision steps of
``OpenWaterVectorEnv`` with random actions (autoresets included), per step the rewards,
terminations and truncations in full and a SHA-256 digest of the observations, of every
``info`` array and of the ``final_obs`` rows. The current env must reproduce every one of them
bit for bit. The compiled kernels are built with ``-ffp-contract=off`` and the reference was
recorded on x86-64 Linux (glibc libm): another libm's ``sin``/``cos`` could differ in the last
bit; regenerate then with ``python tests/usvsim/task/test_openwater_same_numbers.py``. The
radar+goal digests were recorded again when padding slots stopped taking missed-return draws
(``usvsim.task.scene_radar``; its rewards, terminations and truncations unchanged).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from usvsim.task.openwater_env import OpenWaterVectorEnv

REFERENCE = Path(__file__).parent / "data" / "openwater_reference.npz"
N_BOATS, N_STEPS, SEED = 32, 60, 7
# (name, observation, action, reward horizon, info observation)
CASES: tuple[tuple[str, Any, Any, Any, Any], ...] = (
    ("scene", "scene", "gaussian", "episode", None),
    ("radar_goal", "radar+goal", "gaussian", "fixed", "scene"),
    ("positional", "positional", "categorical", "fixed", None),
)


def _digest(value: Any) -> bytes:
    """SHA-256 of an observation (array, dict of arrays, or object array of them)."""
    h = hashlib.sha256()

    def feed(v: Any) -> None:
        if isinstance(v, dict):
            for key in sorted(v):
                h.update(key.encode())
                feed(v[key])
        elif isinstance(v, np.ndarray) and v.dtype == object:
            for item in v:
                h.update(b"none" if item is None else b"row")
                if item is not None:
                    feed(item)
        else:
            a = np.ascontiguousarray(v)
            h.update(str(a.dtype).encode() + str(a.shape).encode())
            h.update(a.tobytes())

    feed(value)
    return h.digest()


def record(observation: Any, action: Any, horizon: Any, info_obs: Any) -> dict[str, np.ndarray]:
    """The per-step figures of one case (module docstring)."""
    env = OpenWaterVectorEnv(
        N_BOATS, observation=observation, action=action, reward_horizon=horizon,
        info_observation=info_obs,
    )  # fmt: skip
    env.action_space.seed(SEED)
    obs, info = env.reset(seed=SEED)
    digests = [_digest(obs), _digest(info)]
    rewards, terms, truncs = [], [], []
    for _ in range(N_STEPS):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        rewards.append(reward)
        terms.append(terminated)
        truncs.append(truncated)
        digests.append(_digest(obs))
        plain = {k: v for k, v in info.items() if k not in ("final_obs", "final_info")}
        digests.append(_digest(plain))
        digests.append(_digest(info.get("final_obs", np.zeros(0))))
        digests.append(_digest(info.get("final_info", {})))
    return {
        "reward": np.asarray(rewards),
        "terminated": np.asarray(terms),
        "truncated": np.asarray(truncs),
        "digests": np.frombuffer(b"".join(digests), dtype=np.uint8).reshape(-1, 32),
    }


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_same_numbers_as_the_recorded_reference(case):
    name, *args = case
    ref = np.load(REFERENCE)
    now = record(*args)
    assert ref[f"{name}_terminated"].any() or ref[f"{name}_truncated"].any()  # resets happen
    for key, value in now.items():
        expected = ref[f"{name}_{key}"]
        assert value.dtype == expected.dtype and value.shape == expected.shape, key
        differs = value.reshape(len(value), -1) != expected.reshape(len(expected), -1)
        mismatch = np.flatnonzero(np.any(differs, axis=1))
        assert mismatch.size == 0, f"{name} {key}: first differing row {mismatch[:5]}"


if __name__ == "__main__":
    arrays = {}
    for name, *args in CASES:
        for key, value in record(*args).items():
            arrays[f"{name}_{key}"] = value
    REFERENCE.parent.mkdir(exist_ok=True)
    np.savez_compressed(REFERENCE, **arrays)
    print(f"written {REFERENCE} ({REFERENCE.stat().st_size} bytes)")
