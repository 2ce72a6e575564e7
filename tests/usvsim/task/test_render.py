"""Rendering: frame shapes and content, passive rendering, human mode, videos (GIF, RecordVideo)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from PIL import Image

import usvsim
from usvsim.task import render as render_module
from usvsim.task.env import PoleAvoidanceEnv
from usvsim.task.render import RenderConfig, tile_frames, write_video
from usvsim.task.scenario import EpisodeSpec
from usvsim.task.vector_env import PoleAvoidanceVectorEnv
from usvsim.vessel.plant import Plant

HULL = np.array([245, 150, 40], dtype=np.uint8)
TRAIL = np.array([30, 90, 200], dtype=np.uint8)
POLE = np.array([40, 40, 40], dtype=np.uint8)


@pytest.fixture(scope="module")
def plant():
    return Plant()


def _count(frame: np.ndarray, colour: np.ndarray) -> int:
    return int(np.all(frame == colour, axis=-1).sum())


@pytest.mark.parametrize(
    ("observation", "shape"),
    [("positional", (400, 400, 3)), ("radar", (504, 400, 3)), ("radar+goal", (504, 400, 3))],
)
def test_rgb_array_frames_have_the_documented_shape(observation, shape, plant):
    env = PoleAvoidanceEnv(observation, render_mode="rgb_array", plant=plant)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == shape and frame.dtype == np.uint8
    vec = PoleAvoidanceVectorEnv(3, observation, render_mode="rgb_array", plant=plant)
    vec.reset(seed=0)
    frames = vec.render()
    assert isinstance(frames, tuple) and len(frames) == 3
    assert all(f.shape == shape and f.dtype == np.uint8 for f in frames)
    small = PoleAvoidanceEnv(render_mode="rgb_array", render_config=RenderConfig(size_px=128))
    small.reset(seed=0)
    assert small.render().shape == (128, 128, 3)


def test_frame_shows_boat_pole_and_a_growing_trail(plant):
    env = PoleAvoidanceEnv(render_mode="rgb_array", plant=plant)
    spec = EpisodeSpec(pole_index=0, start_distance_m=80.0, start_bearing_rad=0.0)
    env.reset(options={"episode": spec})
    first = env.render()
    for _ in range(5):
        env.step(np.array([0.3], dtype=np.float32))
    later = env.render()
    # the 10.5 m × 3.5 m hull at ~0.7 m/px: tens of pixels; the pole at the viewport's scale
    assert 20 < _count(first, HULL) < 200 and 20 < _count(later, HULL) < 200
    assert _count(first, POLE) >= 9
    assert _count(later, TRAIL) > _count(first, TRAIL) + 30  # 10 s at 3 m/s ≈ 30 m ≈ 40 px
    # started north of the pole (bearing 0) heading south at it: down the frame (north up)
    rows_first = np.nonzero(np.all(first == HULL, axis=-1))[0].mean()
    rows_later = np.nonzero(np.all(later == HULL, axis=-1))[0].mean()
    assert rows_later > rows_first + 20


def test_rendering_does_not_change_the_episode(plant):
    plain = PoleAvoidanceEnv(plant=plant)
    drawn = PoleAvoidanceEnv(render_mode="rgb_array", plant=plant)
    first_plain, _ = plain.reset(seed=3)
    first_drawn, _ = drawn.reset(seed=3)
    np.testing.assert_array_equal(first_plain, first_drawn)
    for k in range(20):
        act = np.array([0.5 * np.sin(k)], dtype=np.float32)
        ra, rb = plain.step(act), drawn.step(act)
        drawn.render()
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[1:4] == rb[1:4]
        if ra[2] or ra[3]:
            break


def test_render_needs_a_render_mode_and_bad_modes_raise(plant):
    env = PoleAvoidanceEnv(plant=plant)
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="render_mode"):
        env.render()
    with pytest.raises(ValueError, match=r"render_mode must be None or one of \('human', "):
        PoleAvoidanceEnv(render_mode="ansi", plant=plant)


def test_human_mode_shows_frames_and_returns_none(plant, monkeypatch):
    shown: list[np.ndarray] = []
    monkeypatch.setattr(render_module.HumanWindow, "show", lambda self, f: shown.append(f))
    env = PoleAvoidanceEnv(render_mode="human", plant=plant)
    env.reset(seed=0)
    env.step(np.zeros(1, dtype=np.float32))
    assert env.render() is None
    assert len(shown) == 3 and shown[0].shape == (400, 400, 3)  # reset, step, render
    vec = PoleAvoidanceVectorEnv(4, render_mode="human", plant=plant)
    vec.reset(seed=0)
    assert shown[-1].shape == (800, 800, 3)  # 4 frames tiled 2 × 2


def test_human_window_draws_with_the_agg_backend():
    import matplotlib

    matplotlib.use("Agg")
    window = render_module.HumanWindow(fps=5)
    frame = np.zeros((64, 80, 3), dtype=np.uint8)
    window.show(frame)
    window.show(frame + 1)
    assert window._image.get_array().shape == (64, 80, 3)
    window.close()


def test_check_env_with_rendering():
    # check_env re-makes the env from its spec (deep-copied kwargs): no shared plant here
    env = gym.make(usvsim.ENV_ID, observation="radar+goal", render_mode="rgb_array")
    check_env(env.unwrapped)
    assert env.metadata["render_fps"] == 5


def test_gif_has_one_frame_per_decision(tmp_path, plant):
    env = PoleAvoidanceEnv(render_mode="rgb_array", plant=plant)
    env.reset(seed=1)
    frames = [env.render()]
    for _ in range(6):
        env.step(np.zeros(1, dtype=np.float32))
        frames.append(env.render())
    path = write_video(frames, tmp_path / "episode.gif", fps=5)
    with Image.open(path) as gif:
        assert gif.n_frames == 7 and gif.size == (400, 400)
        assert gif.info["duration"] == 200
    with pytest.raises(ValueError, match=r"\.gif or \.mp4"):
        write_video(frames, tmp_path / "episode.avi")


def test_record_video_writes_an_mp4(tmp_path, plant):
    pytest.importorskip("moviepy")
    env = gym.make(usvsim.ENV_ID, render_mode="rgb_array", plant=plant)
    folder = tmp_path / "videos"
    env = gym.wrappers.RecordVideo(env, str(folder), episode_trigger=lambda e: e == 0)
    env.reset(seed=0)
    done, steps = False, 0
    while not done:
        _, _, terminated, truncated, _ = env.step(np.zeros(1, dtype=np.float32))
        done, steps = terminated or truncated, steps + 1
    env.close()
    videos = list(folder.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 2_000
    import imageio.v3 as iio

    meta = iio.immeta(videos[0], plugin="pyav") if _has_pyav() else iio.immeta(videos[0])
    assert meta["fps"] == 5
    assert steps >= 5


@pytest.mark.filterwarnings("ignore:.*autoreset mode is same-step")  # documented: see render()
def test_vector_record_video_takes_the_frame_tuple(tmp_path, plant):
    pytest.importorskip("moviepy")
    vec = PoleAvoidanceVectorEnv(2, render_mode="rgb_array", plant=plant)
    folder = tmp_path / "videos"
    env = gym.wrappers.vector.RecordVideo(
        vec, str(folder), step_trigger=lambda s: s == 0, video_length=10, record_first_only=True
    )
    env.reset(seed=0)
    for _ in range(12):
        env.step(np.zeros((2, 1), dtype=np.float32))
    env.close()
    videos = list(folder.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 2_000


def _has_pyav() -> bool:
    try:
        import av  # noqa: F401
    except ImportError:
        return False
    return True


def test_tile_frames_grid():
    frames = [np.full((10, 20, 3), k, dtype=np.uint8) for k in range(1, 6)]
    tiled = tile_frames(frames)
    assert tiled.shape == (20, 60, 3)  # 5 frames: 3 columns, 2 rows
    assert tiled[15, 25, 0] == 5 and tiled[15, 45, 0] == 0  # the sixth cell is empty
