"""A boat's radar image is its own: the same alone as beside batch-mates with wider scenes.

The batch pads every boat's statics and vessels to the widest scene among its boats; the padding
slots must take no missed-return draw (``usvsim.task.scene_radar``'s module docstring), in the C
kernel, the NumPy path and the torch twin.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from usvsim.task import scene_radar
from usvsim.task.openwater import OpenWaterEpisode, RadarQuality, Vessel
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.scenario import EpisodeSpec
from usvsim.task.scene_radar import RadarDegradation, RadarStreams, render_scene
from usvsim.task.scene_radar_kernel import load_kernel
from usvsim.task.torch_openwater import TorchOpenWaterEnv
from usvsim.task.torch_openwater_episodes import pack_episodes

DECISIONS = 12
MISSED = RadarQuality(missed_probability=0.5, speckle=0.3, noise_amplitude=10.0)


def _episode(obstacles: tuple[tuple[float, float, float], ...], n_vessels: int, seed: int):
    """The boat starts 60 m south of the anchor heading north (a pole 25 m east of its line);
    vessels cross ahead from the west, clear of it within the decisions run."""
    vessels = tuple(
        Vessel(x0_n=30.0 + 25.0 * i, y0_e=-40.0, course_rad=math.pi / 2, speed_mps=2.0)
        for i in range(n_vessels)
    )
    return OpenWaterEpisode(
        anchor_ne=(0.0, 0.0),
        start=EpisodeSpec(
            pole_index=0, start_distance_m=60.0, start_bearing_rad=math.pi, noise_seed=seed
        ),
        goal_ne=(160.0, 0.0),
        obstacles=((0.0, 25.0, 1.0), *obstacles),
        vessels=vessels,
        radar=MISSED,
        radar_seed=seed,
    )


# the boat watched: one pole, one vessel; its mate: four more statics and two vessels
OWN = _episode((), 1, seed=11)
MATE = _episode(((60.0, 20.0, 8.0), (90.0, -15.0, 1.0), (120.0, 25.0, 12.0), (40.0, 60.0, 1.0)),
                2, seed=12)  # fmt: skip


def _cpu_images(episodes: list[OpenWaterEpisode], boat: int) -> np.ndarray:
    """Boat ``boat``'s radar images (DECISIONS + 1, 50, 119), heading straight on."""
    sim = OpenWaterBatch(len(episodes), observation="radar")
    frames = [sim.reset(None, episodes)[boat, 0]]
    for _ in range(DECISIONS):
        frames.append(sim.step(np.zeros((len(episodes), 1))).observation[boat, 0])
    return np.stack(frames)


def _torch_images(episodes: list[OpenWaterEpisode], boat: int) -> np.ndarray:
    env = TorchOpenWaterEnv(len(episodes), table=pack_episodes(episodes), per_boat=1,
                            noise="replay", observation="radar")  # fmt: skip
    frames = [env.reset(seed=0)[0][boat, 0].numpy()]
    for _ in range(DECISIONS):
        obs = env.step(torch.zeros((len(episodes), 1), dtype=torch.float64))[0]
        frames.append(obs[boat, 0].numpy())
    return np.stack(frames)


def test_padding_slots_take_no_missed_return_draw() -> None:
    """render_scene: invalid slots inserted before and between a boat's discs change nothing
    (both backends, many frames at p_miss 0.5: before the fix every image after a gap moved)."""
    n, rng = 64, np.random.default_rng(3)
    rho, phi = rng.uniform(20.0, 150.0, (n, 3)), rng.uniform(-1.5, 1.5, (n, 3))
    r, ok = rng.uniform(1.0, 15.0, (n, 3)), np.ones((n, 3), bool)
    q = RadarDegradation(*(np.full(n, x) for x in (0.0, 0.0, 0.5, 0.0)))
    streams = RadarStreams(n)
    streams.seed(list(range(n)), list(range(100, 100 + n)))
    keys = streams.frame_keys(np.arange(n))
    slots = [0, 3, 4, 6]  # discs 0..2 at slots 3, 4, 6 of 7
    wide = [np.zeros((n, 7)) for _ in range(3)]
    for a, w in zip((rho, phi, r), wide, strict=True):
        w[:, slots[1:]] = a
    wide[0][:, slots[0]] = 50.0  # a padding slot with a disc's numbers, not valid
    ok_wide = np.zeros((n, 7), bool)
    ok_wide[:, slots[1:]] = True
    backends = ["numpy"] + (["compiled"] if load_kernel() is not None else [])
    for backend in backends:
        tight = render_scene(rho, phi, r, ok, None, q, keys, backend=backend)  # type: ignore[arg-type]
        padded = render_scene(*wide, ok_wide, None, q, keys, backend=backend)  # type: ignore[arg-type]
        np.testing.assert_array_equal(padded, tight, err_msg=backend)
    shown = tight.reshape(n, -1).any(axis=1)
    assert 0 < shown.sum() < n  # the misses do drop whole images' discs


@pytest.mark.parametrize("backend", ["auto", "numpy"])
def test_a_boat_alone_and_beside_a_wider_mate_sees_the_same_images(
    backend: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The CPU batch (C kernel, and the NumPy path with the kernel withheld): a boat's images
    over 12 decisions equal bit for bit whether it runs alone or after a mate with four more
    statics and another vessel (its vessel's draw was the slot's, 5 rather than 1)."""
    if backend == "numpy":
        monkeypatch.setattr(scene_radar, "load_kernel", lambda: None)
    alone = _cpu_images([OWN], 0)
    beside = _cpu_images([MATE, OWN], 1)
    np.testing.assert_array_equal(beside, alone)
    assert alone.any(axis=(1, 2)).all()  # something is seen in every frame


def test_the_torch_env_draws_the_same_images_alone_and_beside_a_mate() -> None:
    """The torch env (table padded to the mate's scene): the boat's images equal its images
    alone, and those equal the CPU batch's, pixel for pixel."""
    alone = _torch_images([OWN], 0)
    np.testing.assert_array_equal(_torch_images([MATE, OWN], 1), alone)
    np.testing.assert_array_equal(alone, _cpu_images([OWN], 0))


def test_the_vessels_misses_show_in_the_images() -> None:
    """The vessel is in view and missed in some frames, seen in others: the comparisons above
    test its draws, not an empty image."""
    clean = OpenWaterBatch(1, observation="radar")
    episode = _episode((), 1, seed=11)
    no_vessel = OpenWaterBatch(1, observation="radar")
    plain = [clean.reset(None, [episode])[0, 0]]
    bare = [no_vessel.reset(None, [_episode((), 0, seed=11)])[0, 0]]
    for _ in range(DECISIONS):
        plain.append(clean.step(np.zeros((1, 1))).observation[0, 0])
        bare.append(no_vessel.step(np.zeros((1, 1))).observation[0, 0])
    # the same stream with and without the vessel: frames differ where the vessel is drawn
    differs = [not np.array_equal(a, b) for a, b in zip(plain, bare, strict=True)]
    assert 0 < sum(differs) < len(differs)
