"""The torch weather step (generated) against the compiled C weather plant it is generated from."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from usvsim.vessel.plant import NS, Plant
from usvsim.vessel.torch_codegen import (
    DEFAULT_WEATHER_KERNEL_PATH,
    default_weather_kernel_source,
)
from usvsim.vessel.torch_plant import load_weather_kernel
from usvsim.vessel.weather_plant import (
    NWS,
    SeaConditions,
    WeatherPlant,
    sensed_offsets,
)

N_BOATS, SEGMENTS, SEGMENT_STEPS = 8, 12, 50  # 600 steps of 0.1 s: a 60 s episode


def _conditions() -> SeaConditions:
    """Eight boats' weather: calm, wind alone, waves alone, both, from several sides."""
    wind = np.array([0.0, 10.0, 0.0, 8.0, 14.0, 5.0, 12.0, 0.0])
    hs = np.array([0.0, 0.0, 1.88, 0.88, 1.88, 3.25, 0.3, 0.88])
    return SeaConditions(
        wind_speed_mps=wind,
        wind_dir_rad=np.linspace(-3.0, 3.0, N_BOATS),
        gust_intensity=np.full(N_BOATS, 0.1),
        hs_m=hs,
        tp_s=np.where(hs > 0, np.array([7.5, 7.5, 8.8, 7.5, 8.8, 9.7, 7.5, 7.5]), 10.0),
        wave_dir_rad=np.linspace(2.5, -2.5, N_BOATS),
    )


def _episode(seed: int = 0) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The C weather plant's trajectory (N, 600, 21) from boats at random poses and speeds in
    :func:`_conditions`, references redrawn every 5 s; its start (N, 21), inputs (N, 33) and
    per-segment references and innovations (for the torch run)."""
    plant = WeatherPlant(Plant("default"), seed=seed, innovations="normal")
    rng = np.random.default_rng(seed)
    eta = np.column_stack(
        [rng.uniform(-100.0, 100.0, (N_BOATS, 2)), rng.uniform(-np.pi, np.pi, N_BOATS)]
    )
    state = plant.initial_state(eta, _conditions(), rng.uniform(1.0, 5.0, N_BOATS))
    start = np.concatenate([state.x, state.c, state.m], axis=1)
    parts, segments = [], []
    for _ in range(SEGMENTS):
        refs = np.stack([rng.uniform(-np.pi, np.pi, N_BOATS), rng.uniform(1.0, 6.0, N_BOATS)])
        twin = np.random.default_rng()  # the innovations the plant draws next, for the torch run
        twin.bit_generator.state = plant.rng.bit_generator.state
        segments.append((refs, twin.standard_normal((N_BOATS, SEGMENT_STEPS, 3))))
        state, traj = plant.step(state, refs[0], refs[1], SEGMENT_STEPS, weather_states=True)
        parts.append(traj)
    return np.concatenate(parts, axis=1), start, [state.inputs, *segments]  # type: ignore[list-item]


def _torch_episode(start: np.ndarray, inputs: np.ndarray, segments: list, dtype: torch.dtype):
    kernel = load_weather_kernel()
    gains = Plant("default").gains
    s = tuple(torch.as_tensor(start.T, dtype=dtype))
    w_weather = tuple(torch.as_tensor(inputs.T, dtype=dtype))
    g = tuple(torch.as_tensor(gains, dtype=dtype).unbind(0))  # shared: 0-d tensors
    zero = torch.zeros(N_BOATS, dtype=dtype)
    out = []
    for refs, e in segments:
        w = (
            torch.as_tensor(refs[0], dtype=dtype),
            torch.as_tensor(refs[1], dtype=dtype),
            zero,
            zero,
            *w_weather,
        )
        et = torch.as_tensor(e, dtype=dtype)
        for j in range(SEGMENT_STEPS):
            s = kernel.step(s, w, g, (et[:, j, 0], et[:, j, 1], et[:, j, 2]))
            out.append(torch.stack(s, 1))
    return torch.stack(out, 1).to(torch.float64).numpy(), kernel


@pytest.fixture(scope="module")
def runs() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c_traj, start, (inputs, *segments) = _episode()
    t64, _ = _torch_episode(start, inputs, segments, torch.float64)
    t32, _ = _torch_episode(start, inputs, segments, torch.float32)
    return c_traj, t64, t32


def _heading_gap(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs((a[..., 2] - b[..., 2] + np.pi) % (2 * np.pi) - np.pi).max())


def test_committed_weather_kernel_is_what_the_generator_writes_today() -> None:
    assert DEFAULT_WEATHER_KERNEL_PATH.read_text() == default_weather_kernel_source()


def test_float64_reproduces_the_c_weather_plant(runs: tuple[np.ndarray, ...]) -> None:
    c_traj, t64, _ = runs
    assert np.abs(c_traj[..., 3:6]).max() > 0.5  # the boats move and turn
    assert np.abs(c_traj[..., NS + 1 : NS + 3]).max() > 0.01  # the waves move them
    assert np.abs(c_traj[:, :, 0:2] - t64[:, :, 0:2]).max() < 1e-6  # m
    assert _heading_gap(c_traj, t64) < 1e-8  # rad
    assert np.abs(c_traj[:, :, NS:] - t64[:, :, NS:]).max() < 1e-6  # gust, waves, filter


def test_float32_stays_within_its_stated_tolerance(runs: tuple[np.ndarray, ...]) -> None:
    c_traj, _, t32 = runs
    assert np.abs(c_traj[:, :, 0:2] - t32[:, :, 0:2]).max() < 0.5  # m over 60 s
    assert _heading_gap(c_traj, t32) < 0.02  # rad


def test_sensed_offsets_equal_numpy() -> None:
    c_traj, _start, (inputs, *_) = _episode(seed=1)
    kernel = load_weather_kernel()
    last = c_traj[:, -1]
    want = sensed_offsets(last[:, :8], last[:, NS : NS + NWS], inputs)
    s = tuple(torch.as_tensor(last.T))
    w = (*(torch.zeros(N_BOATS, dtype=torch.float64),) * 4, *torch.as_tensor(inputs.T))
    got = torch.stack(kernel.sensed_offsets(s, w), 1).numpy()
    assert np.abs(want).max() > 1e-3
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
