"""Top-view frames of the pole-avoidance task, drawn with NumPy (``render_mode="rgb_array"``).

A frame is an ``(H, W, 3) uint8`` RGB image of one boat's episode: ``(S, S, 3)`` with
``S = RenderConfig.size_px`` (400), and for radar observations ``(S + 2 H_r + 4, S, 3)``
(``(504, 400, 3)`` with the default 50-row radar image). The map is north up, east to the
right, over a square that holds the start, the pole and the goal with a 30 m margin (about
0.7 m per pixel for the default scenario)::

    ───────────  time bar: episode time / time limit
    · · · · ·    grid every 50 m
    ●  ◯         the pole (dark) inside its safety circle (red ring, Scenario.safety_distance_m)
    ◎            the goal: a green disc of Scenario.goal_radius_m
    ───          the trail: the TRUE position at every 0.1 s plant step
    ⬠            the boat: hull outline (length × beam of the vessel) at its TRUE heading
    ▭            for radar observations, the last radar image (2× scale) in a strip below the map

Everything is drawn by array operations on small bounding boxes (no plotting library), so a
frame costs a fraction of a millisecond to a few milliseconds: cheap enough to record every
step (``usvsim perf``-style figures in the README). :class:`TopView` keeps the trails of N
boats; :func:`write_video` writes frames as GIF (Pillow) or MP4 (moviepy);
:class:`HumanWindow` shows frames in a matplotlib window (``render_mode="human"``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.fileio import atomic_open
from usvsim.task.scenario import Scenario

__all__ = ["RENDER_MODES", "HumanWindow", "RenderConfig", "TopView", "tile_frames", "write_video"]

RENDER_MODES: tuple[str, ...] = ("human", "rgb_array")
FloatArray = NDArray[np.float64]
Frame = NDArray[np.uint8]

_WATER = (232, 242, 250)
_GRID = (212, 226, 238)
_POLE = (40, 40, 40)
_SAFETY = (214, 60, 60)
_GOAL = (150, 215, 160)
_GOAL_EDGE = (40, 150, 70)
_TRAIL = (30, 90, 200)
_HULL = (245, 150, 40)
_HULL_EDGE = (60, 40, 20)
_BAR = (120, 120, 140)


@dataclass(frozen=True)
class RenderConfig:
    """Frame geometry (pixels and metres)."""

    size_px: int = 400  # px, frames are (size_px, size_px, 3)
    margin_m: float = 30.0  # m, around the start, pole and goal
    grid_m: float = 50.0  # m, grid spacing
    fps: int = 5  # frames per second of recorded video (one frame per 2 s decision: 10× speed)

    def __post_init__(self) -> None:
        if self.size_px < 64:
            raise ValueError(f"size_px must be at least 64, got {self.size_px}")


class TopView:
    """Trails and viewports of N boats, and their frames.

    Parameters
    ----------
    n_boats : int
    scenario : Scenario
        Radii (pole, safety, goal) and the episode's length (trail capacity).
    length_m, beam_m : float
        Hull outline of the vessel (m).
    config : RenderConfig, optional
    """

    def __init__(
        self,
        n_boats: int,
        scenario: Scenario,
        length_m: float,
        beam_m: float,
        config: RenderConfig | None = None,
    ) -> None:
        self.config = config or RenderConfig()
        self.scenario = scenario
        self.n_boats = n_boats
        capacity = scenario.max_decisions * scenario.steps_per_decision + 1
        self._trail = np.zeros((n_boats, capacity, 2))
        self._count = np.zeros(n_boats, dtype=np.intp)
        self._origin = np.zeros((n_boats, 2))  # (north of the top edge, east of the left edge) m
        self._scale = np.ones(n_boats)  # m per pixel
        self._water_row = np.tile(np.array(_WATER, dtype=np.uint8), (self.config.size_px, 1))
        # hull outline in body coordinates (x forward, y starboard), m: a pointed bow
        L, B = length_m, beam_m
        self._hull = np.array(
            [[L / 2, 0.0], [L / 6, B / 2], [-L / 2, B / 2], [-L / 2, -B / 2], [L / 6, -B / 2]]
        )

    def reset(
        self,
        boats: NDArray[np.intp],
        start_ne: FloatArray,
        pole_ne: FloatArray,
        goal_ne: FloatArray,
    ) -> None:
        """Start the trails of ``boats`` at ``start_ne`` (k, 2) and fit their viewports."""
        pts = np.stack([start_ne, pole_ne, goal_ne], axis=1)  # (k, 3, 2)
        lo, hi = pts.min(axis=1), pts.max(axis=1)
        centre, half = (lo + hi) / 2, (hi - lo).max(axis=1) / 2 + self.config.margin_m
        self._scale[boats] = 2 * half / self.config.size_px
        self._origin[boats, 0] = centre[:, 0] + half
        self._origin[boats, 1] = centre[:, 1] - half
        self._trail[boats, 0] = start_ne
        self._count[boats] = 1

    def record(self, positions_ne: FloatArray, n_new: NDArray[np.intp]) -> None:
        """Append the first ``n_new[i]`` of ``positions_ne[i]`` ((N, T, 2) m) to each trail."""
        cap = self._trail.shape[1]
        cols = np.minimum(self._count[:, None] + np.arange(positions_ne.shape[1]), cap - 1)
        self._trail[np.arange(self.n_boats)[:, None], cols] = positions_ne
        self._count = np.minimum(self._count + n_new, cap)

    def frame(
        self,
        boat: int,
        eta: NDArray[np.float64],
        pole_ne: NDArray[np.float64],
        goal_ne: NDArray[np.float64],
        time_s: float,
        radar: NDArray[np.uint8] | None = None,
    ) -> Frame:
        """The frame of ``boat``: true pose ``eta`` = [x_N, y_E, ψ] (m, m, rad), its pole and
        goal (m), the episode time (s), and optionally a radar image (H_r, W_r) uint8."""
        cfg, sc = self.config, self.scenario
        S = cfg.size_px
        strip = 0 if radar is None else 2 * radar.shape[-2] + 4
        full = np.empty((S + strip, S, 3), dtype=np.uint8)
        img = full[:S]
        img[:] = self._water_row  # a whole row per copy: ~50× faster than a colour tuple
        scale, (top, left) = self._scale[boat], self._origin[boat]

        def px(ne: NDArray[np.float64]) -> NDArray[np.float64]:
            """(..., 2) [north, east] m → (..., 2) [row, col] px."""
            return np.stack([(top - ne[..., 0]) / scale, (ne[..., 1] - left) / scale], axis=-1)

        g, span = cfg.grid_m, S * scale
        north = np.arange(math.ceil((top - span) / g) * g, top, g)  # grid lines, m
        east = np.arange(math.ceil(left / g) * g, left + span, g)
        rows, cols = ((top - north) / scale).astype(int), ((east - left) / scale).astype(int)
        img[rows[(rows >= 0) & (rows < S)], :] = _GRID
        img[:, cols[(cols >= 0) & (cols < S)]] = _GRID
        goal_px, pole_px = px(goal_ne), px(pole_ne)
        _disc(img, goal_px, sc.goal_radius_m / scale, _GOAL)
        _ring(img, goal_px, sc.goal_radius_m / scale, 1.0, _GOAL_EDGE)
        _ring(img, pole_px, sc.safety_distance_m / scale, 1.0, _SAFETY)
        _disc(img, pole_px, max(sc.pole_radius_m / scale, 2.5), _POLE)
        _polyline(img, px(self._trail[boat, : self._count[boat]]), _TRAIL)
        c, s = math.cos(eta[2]), math.sin(eta[2])
        hull_ne = eta[:2] + self._hull @ np.array([[c, s], [-s, c]])  # body → NED
        hull_px = px(hull_ne)
        _fill_polygon(img, hull_px, _HULL)
        _polyline(img, np.vstack([hull_px, hull_px[:1]]), _HULL_EDGE)
        done = min(max(time_s / sc.time_limit_s, 0.0), 1.0)
        img[0:3, : round(done * S)] = _BAR
        if radar is not None:
            _radar_strip(full[S:], radar)
        return full


def _bbox(img: Frame, centre: NDArray[np.float64], r: float) -> tuple[slice, slice, Any, Any]:
    S0, S1 = img.shape[:2]
    r0, r1 = max(int(centre[0] - r - 1), 0), min(int(centre[0] + r + 2), S0)
    c0, c1 = max(int(centre[1] - r - 1), 0), min(int(centre[1] + r + 2), S1)
    yy, xx = np.ogrid[r0:r1, c0:c1]
    return slice(r0, r1), slice(c0, c1), yy + 0.5 - centre[0], xx + 0.5 - centre[1]


def _disc(img: Frame, centre: NDArray[np.float64], r: float, colour: tuple[int, ...]) -> None:
    rs, cs, dy, dx = _bbox(img, centre, r)
    img[rs, cs][dy**2 + dx**2 <= r**2] = colour


def _ring(
    img: Frame, centre: NDArray[np.float64], r: float, width: float, colour: tuple[int, ...]
) -> None:
    rs, cs, dy, dx = _bbox(img, centre, r + width)
    d = np.sqrt(dy**2 + dx**2)
    img[rs, cs][np.abs(d - r) <= width / 2 + 0.25] = colour


def _polyline(img: Frame, pts: NDArray[np.float64], colour: tuple[int, ...]) -> None:
    """Pixels along the segments between consecutive points (K, 2) [row, col], ~1 px apart."""
    if len(pts) == 0:
        return
    samples = pts  # the points themselves; segments longer than 1 px are filled in below
    if len(pts) > 1:
        seg = np.diff(pts, axis=0)
        long = np.flatnonzero(np.abs(seg).max(axis=1) > 1.0)  # a trail's 0.1 s steps are not
        if long.size:
            seg = seg[long]
            n = np.ceil(np.abs(seg).max(axis=1)).astype(np.intp) + 1  # samples per segment
            start = np.repeat(np.arange(long.size), n)
            frac = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
            step = (frac / np.repeat(n - 1, n))[:, None]
            samples = np.vstack([pts, pts[long][start] + seg[start] * step])
    rc = np.floor(samples).astype(np.intp)
    ok = (rc[:, 0] >= 0) & (rc[:, 0] < img.shape[0]) & (rc[:, 1] >= 0) & (rc[:, 1] < img.shape[1])
    img[rc[ok, 0], rc[ok, 1]] = colour


def _fill_polygon(img: Frame, poly: NDArray[np.float64], colour: tuple[int, ...]) -> None:
    """Even-odd fill of a polygon (K, 2) [row, col] over its bounding box."""
    r0, c0 = np.maximum(np.floor(poly.min(axis=0)).astype(int), 0)
    r1 = min(int(np.ceil(poly[:, 0].max())) + 1, img.shape[0])
    c1 = min(int(np.ceil(poly[:, 1].max())) + 1, img.shape[1])
    if r1 <= r0 or c1 <= c0:
        return
    yy, xx = np.mgrid[r0:r1, c0:c1] + 0.5
    a, b = poly, np.roll(poly, -1, axis=0)
    y, x = yy[..., None], xx[..., None]
    crosses = (a[:, 0] > y) != (b[:, 0] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 1] + (y - a[:, 0]) * (b[:, 1] - a[:, 1]) / (b[:, 0] - a[:, 0])
    inside = np.count_nonzero(crosses & (x < x_cross), axis=-1) % 2 == 1
    img[r0:r1, c0:c1][inside] = colour


def _radar_strip(strip: Frame, radar: NDArray[np.uint8]) -> None:
    """The radar image, 2× nearest-neighbour, centred on a dark strip (2 H_r + 4 rows)."""
    im = np.asarray(radar).reshape(radar.shape[-2:])
    big = np.repeat(np.repeat(im, 2, axis=0), 2, axis=1)[:, : strip.shape[1] - 4]
    strip[:] = _HULL_EDGE
    c0 = (strip.shape[1] - big.shape[1]) // 2
    strip[2 : 2 + big.shape[0], c0 : c0 + big.shape[1]] = big[:, :, None]


def tile_frames(frames: Sequence[Frame]) -> Frame:
    """Frames of equal shape side by side in a near-square grid (black where none)."""
    n = len(frames)
    if n == 0:
        raise ValueError("tile_frames needs at least one frame")
    h, w, c = frames[0].shape
    cols = math.ceil(math.sqrt(n))
    rows = math.ceil(n / cols)
    out = np.zeros((rows * h, cols * w, c), dtype=np.uint8)
    for k, f in enumerate(frames):
        r, q = divmod(k, cols)
        out[r * h : (r + 1) * h, q * w : (q + 1) * w] = f
    return out


class HumanWindow:
    """A matplotlib window that shows frames as they come (``render_mode="human"``).

    Uses whatever matplotlib backend is active; with a non-interactive one (Agg, on a machine
    without a display) nothing is shown and nothing fails.
    """

    def __init__(self, fps: int) -> None:
        self.fps = fps
        self._fig: Any = None
        self._image: Any = None

    def show(self, frame: Frame) -> None:
        import matplotlib.pyplot as plt

        if self._fig is None or not plt.fignum_exists(self._fig.number):
            self._fig, ax = plt.subplots(figsize=(frame.shape[1] / 100, frame.shape[0] / 100))
            ax.set_axis_off()
            self._fig.subplots_adjust(0, 0, 1, 1)
            self._image = ax.imshow(frame)
        else:
            self._image.set_data(frame)
        self._fig.canvas.draw_idle()
        self._fig.canvas.flush_events()
        if plt.get_backend().lower() != "agg":
            plt.pause(1.0 / self.fps)

    def close(self) -> None:
        if self._fig is not None:
            import matplotlib.pyplot as plt

            plt.close(self._fig)
            self._fig = None


def write_video(frames: Sequence[Frame], path: str | os.PathLike[str], fps: int = 5) -> Path:
    """Write ``frames`` ((H, W, 3) uint8 each) to ``path``: ``.gif`` (Pillow) or ``.mp4``
    (moviepy, ``pip install usvsim[video]``), atomically. Returns the path.

    Raises
    ------
    ValueError
        On no frames or another suffix; ``ImportError`` naming the extra if moviepy is missing.
    """
    out = Path(path)
    if not frames:
        raise ValueError("write_video needs at least one frame")
    suffix = out.suffix.lower()
    if suffix == ".gif":
        from PIL import Image

        images = [Image.fromarray(np.asarray(f, dtype=np.uint8)) for f in frames]
        with atomic_open(out, "wb") as fh:
            images[0].save(
                fh,
                format="GIF",
                save_all=True,
                append_images=images[1:],
                duration=round(1000 / fps),
                loop=0,
            )
        return out
    if suffix == ".mp4":
        try:
            from moviepy.video.io.ImageSequenceClip import ImageSequenceClip
        except ImportError as err:
            raise ImportError(
                "MP4 needs moviepy: pip install 'usvsim[video]' (or write a .gif)"
            ) from err
        tmp = out.with_name(f".{out.stem}.tmp{os.getpid()}.mp4")
        try:
            clip = ImageSequenceClip([np.asarray(f) for f in frames], fps=fps)
            clip.write_videofile(str(tmp), logger=None)
            os.replace(tmp, out)
        finally:
            tmp.unlink(missing_ok=True)
        return out
    raise ValueError(f"video path must end in .gif or .mp4, got {out.name!r}")
