"""The pole-avoidance scenario: parameters, episode specifications, start geometry, noise streams.

The task is the reference study's (Vedeler 2019, ``shared/reference/table-4-1.md``): one pole is
the obstacle of an episode; the boat starts 50-100 m from it at a uniform bearing, heading at it;
the goal lies 220 m from the start on the start→pole line, beyond the pole.

Geometry (NED, ``x_N`` north, ``y_E`` east, angles clockwise from north)::

    start = pole + d (cos β, sin β)               β: bearing of the start seen from the pole
    ψ0    = ssa(β + π + δ)                        δ: heading offset (0 in the study)
    goal  = start + D (cos(β + π), sin(β + π))    D = 220 m, so the goal is D - d beyond the pole

An episode is fully determined by its :class:`EpisodeSpec` (and the helmsman's actions): the
spec carries the seed of the episode's own sensor-noise stream (:class:`BoatNoise`). That is what
makes a batch of N boats equal N single environments, and an evaluation independent of how its
episodes are batched.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.noise_kernel import load_kernel as load_noise_kernel

NoiseBackend = Literal["auto", "compiled", "numpy"]

__all__ = [
    "BoatNoise",
    "EpisodeGeometry",
    "EpisodeSpec",
    "Scenario",
    "draw_episode",
    "draw_episodes",
    "episode_geometry",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Scenario:
    """Parameters of the pole-avoidance task (the study's values unless stated).

    Only the episode's own pole exists in an episode (as in the study, where each episode picks
    one of the site's two poles as *the* obstacle). The default poles are 707 m apart, more than
    twice ``area_radius_m``, so the other pole can never be reached inside the area anyway.
    """

    poles_ne: tuple[tuple[float, float], ...] = ((0.0, 0.0), (500.0, 500.0))
    # m, [x_N, y_E] of the fixed poles; usvsim's choice (the study's site had two poles)
    pole_radius_m: float = 1.0  # m, usvsim default (issue 3)
    start_distance_range_m: tuple[float, float] = (50.0, 100.0)  # m, study: uniform [50, 100]
    heading_offset_range_rad: tuple[float, float] = (0.0, 0.0)
    # rad, initial heading minus the bearing to the pole, uniform; study: 0 (pointing at the pole)
    goal_distance_m: float = 220.0  # m, start→goal, on the start→pole line; study
    goal_radius_m: float = 10.0  # m, goal reached within this distance; study
    safety_distance_m: float = 10.0  # m, success needs the pole never closer than this; study
    speed_mps: float = 3.0  # m/s, constant surge reference; usvsim default (study: not given)
    max_heading_change_rad: float = math.radians(30.0)  # rad, |action| bound; study
    decision_period_s: float = 2.0  # s, one action per period; study
    dt_s: float = 0.1  # s, plant step; study
    time_limit_s: float = 150.0
    # s, truncation; 220 m straight at 3 m/s takes 73 s, so an expert-like detour has > 2× margin
    area_radius_m: float = 250.0
    # m, "left the area" when farther than this from the episode's pole (start ≤ 100 m, goal
    # ≤ 170 m from it): truncation, not a failure mode the reward must teach

    def __post_init__(self) -> None:
        if len(self.poles_ne) < 1 or any(len(p) != 2 for p in self.poles_ne):
            raise ValueError(f"poles_ne must hold one or more (x_N, y_E) pairs: {self.poles_ne}")
        lo, hi = self.start_distance_range_m
        if not 0 < lo <= hi:
            raise ValueError(f"start_distance_range_m must satisfy 0 < lo <= hi, got {lo, hi}")
        hlo, hhi = self.heading_offset_range_rad
        if not -math.pi <= hlo <= hhi <= math.pi:
            raise ValueError(f"heading_offset_range_rad must lie in [-π, π], got {hlo, hhi}")
        for name in (
            "pole_radius_m",
            "goal_distance_m",
            "goal_radius_m",
            "speed_mps",
            "max_heading_change_rad",
            "decision_period_s",
            "dt_s",
            "time_limit_s",
            "area_radius_m",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"Scenario.{name} must be finite and > 0, got {value!r}")
        if self.goal_distance_m <= hi:
            raise ValueError(
                "goal_distance_m must exceed the largest start distance "
                "(the goal lies beyond the pole)"
            )
        ratio = self.decision_period_s / self.dt_s
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError("decision_period_s must be an integer multiple of dt_s")

    @property
    def steps_per_decision(self) -> int:
        """Plant steps per decision (20 for the study's 2 s / 0.1 s)."""
        return round(self.decision_period_s / self.dt_s)

    @property
    def max_decisions(self) -> int:
        """Decisions before the time limit truncates an episode (75 by default)."""
        return math.ceil(self.time_limit_s / self.decision_period_s - 1e-9)


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything that defines one episode (the helmsman's actions aside).

    ``start_bearing_rad`` is the bearing of the start seen from the pole (so the boat's bearing to
    the pole is that plus π); ``noise_seed`` seeds the episode's sensor-noise stream.
    """

    pole_index: int
    start_distance_m: float  # m
    start_bearing_rad: float  # rad, clockwise from north, [0, 2π)
    heading_offset_rad: float = 0.0  # rad
    noise_seed: int = 0


def draw_episode(rng: np.random.Generator, scenario: Scenario) -> EpisodeSpec:
    """Draw one episode: pole, distance, bearing, heading offset, noise seed, in that order."""
    pole = int(rng.integers(len(scenario.poles_ne)))
    distance = float(rng.uniform(*scenario.start_distance_range_m))
    bearing = float(rng.uniform(0.0, 2.0 * math.pi))
    offset = float(rng.uniform(*scenario.heading_offset_range_rad))
    seed = int(rng.integers(2**63))
    return EpisodeSpec(pole, distance, bearing, offset, seed)


def draw_episodes(rng: np.random.Generator, scenario: Scenario, n: int) -> tuple[EpisodeSpec, ...]:
    """``n`` episodes drawn one after the other from ``rng`` (see :func:`draw_episode`)."""
    return tuple(draw_episode(rng, scenario) for _ in range(n))


@dataclass(frozen=True)
class EpisodeGeometry:
    """Start geometry of N episodes: ``pole_ne`` (N, 2) m, ``start_eta`` (N, 3), ``goal_ne``."""

    pole_ne: FloatArray
    start_eta: FloatArray
    goal_ne: FloatArray


def episode_geometry(scenario: Scenario, specs: Sequence[EpisodeSpec]) -> EpisodeGeometry:
    """Pole, start pose and goal of each episode (equations in the module docstring).

    Raises
    ------
    ValueError
        If a spec names a pole that does not exist or has a non-finite or non-positive distance.
    """
    n_poles = len(scenario.poles_ne)
    index = [s.pole_index for s in specs]
    d, beta, offset = (
        np.array(
            [(s.start_distance_m, s.start_bearing_rad, s.heading_offset_rad) for s in specs],
            dtype=float,
        )
        .reshape(-1, 3)
        .T
    )
    pole_index = np.asarray(index, dtype=np.intp)
    bad_pole = (pole_index < 0) | (pole_index >= n_poles)
    bad_distance = ~(np.isfinite(d) & (d > 0))
    if bad_pole.any() or bad_distance.any():  # report the first bad spec, as a loop would
        s = specs[int(np.argmax(bad_pole | bad_distance))]
        if not 0 <= s.pole_index < n_poles:
            raise ValueError(f"pole_index {s.pole_index} out of range for {n_poles} poles")
        raise ValueError(f"start_distance_m must be finite and > 0, got {s.start_distance_m}")
    poles = np.asarray(scenario.poles_ne, dtype=float)[pole_index]
    out = np.stack([np.cos(beta), np.sin(beta)], axis=-1)  # unit vector pole → start
    start = poles + d[:, None] * out
    psi0 = ssa(beta + math.pi + offset)
    goal = start - scenario.goal_distance_m * out
    return EpisodeGeometry(
        pole_ne=poles.reshape(-1, 2),
        start_eta=np.column_stack([start.reshape(-1, 2), psi0]),
        goal_ne=goal.reshape(-1, 2),
    )


class BoatNoise:
    """One random stream per boat, served through the ``Generator.normal`` interface.

    The navigation filter draws its sensor noise for all N boats at once, ``normal(loc, scale,
    size=(N, ...))``. This object answers such a call with row i taken from boat i's own
    ``numpy.random.Generator`` (seeded from the episode's ``noise_seed``), so each episode's noise
    depends on its own history only: a batch of N boats equals N single environments, and an
    evaluation gives the same records however its episodes are batched.

    Boat i is served exactly the sequence ``Generator(noise_seed).standard_normal(∞)``, in order,
    whatever the draw sizes and the batch around it: numbers are buffered per boat (refilled in
    chunks, keeping the unread tail) and handed out in blocks gathered once for all boats, so a
    draw is usually a slice. The only Python loop over boats is over the few whose buffer runs
    out (every ~``width / 60`` decisions) and over reset boats.

    :meth:`for_boats` restricts the next draws to a subset (e.g. the boats being reset).

    ``backend``: ``"compiled"`` draws every boat's numbers in one C call from its PCG64 state
    (:mod:`usvsim.task.noise_kernel`: the same numbers, checked against NumPy when it loads,
    about 6 ns a number against NumPy's 16 ns, no buffers, no loop over boats); ``"numpy"`` is
    the buffered path above; ``"auto"`` (default) takes the compiled one where it builds.
    """

    def __init__(
        self, n_boats: int, width: int = 1024, block: int = 64, backend: NoiseBackend = "auto"
    ) -> None:
        if backend not in ("auto", "compiled", "numpy"):
            raise ValueError(f"backend must be 'auto', 'compiled' or 'numpy', got {backend!r}")
        self._kernel = None if backend == "numpy" else load_noise_kernel()
        if backend == "compiled" and self._kernel is None:
            raise RuntimeError(
                "BoatNoise: the compiled noise kernel is unavailable here (no C compiler or "
                "no NumPy libnpyrandom); use backend='auto' or 'numpy'"
            )
        # compiled path: each boat's PCG64 state, (N, 4) uint64; seeded boats marked
        self._states = np.zeros((n_boats, 4), dtype=np.uint64)
        self._seeded = np.zeros(n_boats, dtype=bool)
        self._all_seeded = False  # once every boat has a stream, draws skip the per-boat check
        self._states_at = self._states.ctypes.data
        self._gens: list[np.random.Generator | None] = [None] * n_boats
        self._buf = np.zeros((n_boats, 0 if self._kernel else width))  # NumPy path's buffers
        self._cursor = np.full(n_boats, width, dtype=np.int64)  # next unread number per boat
        self._block_cols = block
        self._all: NDArray[np.intp] = np.arange(n_boats)
        self._idx = self._all
        self._idx_at = self._all.ctypes.data  # address of _idx as int64, for the kernel
        self._block: FloatArray | None = None  # gathered numbers of the served boats
        self._pos = 0  # numbers of the block already served
        self._windows: dict[int, FloatArray] = {}  # m -> view (N, width - m + 1, m) of _buf

    def seed(self, boats: NDArray[np.intp], seeds: Sequence[int]) -> None:
        """Restart the streams of ``boats`` from ``seeds`` (one per boat)."""
        self._commit()
        boats = np.asarray(boats, dtype=np.intp)
        if self._kernel is not None:
            if len(seeds) != boats.size:
                raise ValueError(f"need one seed per boat ({boats.size}), got {len(seeds)}")
            self._kernel.seed(boats, list(seeds), self._states)
            self._seeded[boats] = True
            self._all_seeded = bool(self._seeded.all())
            return
        for i, s in zip(boats.tolist(), seeds, strict=True):
            self._gens[i] = np.random.default_rng(s)
        self._cursor[boats] = self._buf.shape[1]

    def for_boats(self, boats: NDArray[np.intp] | None) -> BoatNoise:
        """Serve the following draws to ``boats`` only (``None``: all boats); returns self."""
        self._commit()
        self._idx = self._all if boats is None else np.asarray(boats, dtype=np.intp)
        if self._kernel is not None:
            if boats is not None:
                self._idx = np.ascontiguousarray(self._idx, dtype=np.int64)
            self._idx_at = self._idx.ctypes.data
        return self

    def _commit(self) -> None:
        """Mark the served part of the current block as read."""
        if self._block is not None:
            self._cursor[self._idx] += self._pos
            self._block, self._pos = None, 0

    def _gather(self, m: int) -> FloatArray:
        """The next ``m`` unread numbers of every served boat, (n, m), without reading them."""
        if m > self._buf.shape[1]:
            old, self._buf = self._buf, np.zeros((self._buf.shape[0], 2 * m))
            self._windows.clear()
            self._refill(self._all[[g is not None for g in self._gens]], old)
        idx, width = self._idx, self._buf.shape[1]
        cursor = self._cursor[idx]
        if np.any(cursor + m > width):
            self._refill(idx[cursor + m > width], self._buf)
            cursor = self._cursor[idx]
        windows = self._windows.get(m)
        if windows is None:  # windows[i, c] is the view buf[i, c : c + m]
            if len(self._windows) >= 16:  # draw sizes are few in practice: bound the cache
                self._windows.clear()
            step_row, step_col = self._buf.strides
            windows = self._windows[m] = np.lib.stride_tricks.as_strided(
                self._buf,
                shape=(self._buf.shape[0], width - m + 1, m),
                strides=(step_row, step_col, step_col),
                writeable=False,
            )
        return windows[idx, cursor]

    def _refill(self, boats: NDArray[np.intp], old: FloatArray) -> None:
        """Move each boat's unread tail (in ``old``) to the front, the rest from its generator."""
        for i, c in zip(boats.tolist(), self._cursor[boats].tolist(), strict=True):
            gen = self._gens[i]
            if gen is None:
                raise RuntimeError(f"BoatNoise: boat {i} has no seeded stream")
            n_tail = old.shape[1] - c
            self._buf[i, :n_tail] = old[i, c:]  # overlapping rows are copied safely by NumPy
            gen.standard_normal(out=self._buf[i, n_tail:])
        self._cursor[boats] = 0

    def standard_normal(self, size: int | tuple[int, ...]) -> FloatArray:
        """Standard normals of shape ``size``; ``size[0]`` must be the number of served boats."""
        shape = (size,) if isinstance(size, (int, np.integer)) else tuple(size)
        if len(shape) == 0 or shape[0] != self._idx.size:
            raise ValueError(
                f"BoatNoise serves {self._idx.size} boats; a draw of shape {shape} "
                "must have that many rows"
            )
        m = math.prod(shape[1:])
        if self._kernel is not None:
            if not self._all_seeded and not self._seeded[self._idx].all():
                i = int(self._idx[np.argmin(self._seeded[self._idx])])
                raise RuntimeError(f"BoatNoise: boat {i} has no seeded stream")
            out = self._kernel.draw_at(self._idx.size, self._idx_at, self._states_at, m)
            return out.reshape(shape)
        if self._block is None or self._pos + m > self._block.shape[1]:
            self._commit()
            self._block = self._gather(max(m, self._block_cols))
        out = self._block[:, self._pos : self._pos + m]
        self._pos += m
        return out.reshape(shape)

    def normal(
        self, loc: float = 0.0, scale: float = 1.0, size: int | tuple[int, ...] | None = None
    ) -> FloatArray:
        """``loc + scale · standard_normal(size)`` (the ``numpy.random.Generator.normal`` call)."""
        if size is None:
            raise ValueError("BoatNoise.normal needs a size whose first axis is the boats")
        return loc + scale * self.standard_normal(size)

    def random(self, size: tuple[int, ...]) -> FloatArray:
        """Uniform [0, 1) numbers of shape ``size`` (boats first): ``Φ(z)`` of standard normals."""
        from scipy.special import ndtr  # lazily: the torch path imports this module without SciPy

        return ndtr(self.standard_normal(size))
