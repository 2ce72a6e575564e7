"""Per-episode disturbances of the batch simulator: cruise speed, current, GNSS quality.

The study's task runs every boat of a batch at one speed reference, in one current (the
plant's), with one sensor model (:class:`usvsim.nav.models.NavConfig`). An
:class:`EpisodeDisturbance` changes these for one episode;
:meth:`usvsim.task.batch.PoleAvoidanceBatch.reset` takes one per reset boat. A boat reset without
one runs exactly as before (same numbers: the study's path is not touched).

GNSS faults (applied to the standard normals the batch feeds the navigation filter, so the
filter's own noise model stays the nominal one, as on a real boat whose receiver degrades):

* noise scale ``k``: every GNSS position and velocity error is ``k`` times the nominal one;
* outliers: each fix, with probability ``p``, has its error ``outlier_scale`` times larger
  (a multipath / jump fix; the filter is not told);
* dropout: no fix arrives during ``[start, start + duration)`` s of the episode (the filter
  dead-reckons on gyro and compass).

Outlier draws come from the episode's own stream (seeded by ``seed``), so a boat's draws do not
depend on the batch around it.

Weather (issue 38): ``weather`` (:class:`usvsim.task.weather_draw.Weather`) steps the boat in
wind and waves (:mod:`usvsim.vessel.weather_plant`). :class:`BoatDisturbances` keeps each boat's
per-episode weather inputs (N, 33) (:data:`usvsim.vessel.weather_plant.WEATHER_INPUTS` from
``wind_mean``), filled on reset by :meth:`BoatDisturbances.start_weather` through
:meth:`usvsim.vessel.weather_plant.WeatherPlant.initial_state`; the gust and wave motion start
from their stationary distributions drawn from the episode's own noise stream (so a boat's
weather does not depend on the batch around it either). A boat without weather gets the calm
rows: every weather term is an exact zero.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.special import ndtri

from usvsim.task.gnss_fault_kernel import load_gnss_fault_kernel
from usvsim.task.scenario import BoatNoise
from usvsim.task.weather_draw import CALM, Weather, sea_conditions
from usvsim.vessel.plant import PlantState
from usvsim.vessel.weather_plant import NWS, WeatherPlant

__all__ = ["BoatDisturbances", "EpisodeDisturbance"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class EpisodeDisturbance:
    """What differs in one episode from the study's calm, clean setting (module docstring)."""

    speed_mps: float | None = None  # m/s, surge reference; None: the scenario's (3 m/s)
    current_speed_mps: float = 0.0  # m/s, irrotational current over ground
    current_direction_rad: float = 0.0  # rad, direction the current flows towards (NED)
    gnss_noise_scale: float = 1.0  # -, multiplies the GNSS position and velocity errors
    gnss_outlier_probability: float = 0.0  # -, per fix
    gnss_outlier_scale: float = 10.0  # -, an outlier fix's error in nominal σ multiples
    gnss_dropout_start_s: float = math.inf  # s, episode time the outage starts
    gnss_dropout_duration_s: float = 0.0  # s
    seed: int = 0  # seeds the outlier draws
    weather: Weather | None = None  # wind and waves (module docstring); None: calm, as today

    def __post_init__(self) -> None:
        if self.speed_mps is not None and not (
            math.isfinite(self.speed_mps) and self.speed_mps > 0
        ):
            raise ValueError(f"speed_mps must be finite and > 0, got {self.speed_mps}")
        if not (math.isfinite(self.current_speed_mps) and self.current_speed_mps >= 0):
            raise ValueError(
                f"current_speed_mps must be finite and >= 0, got {self.current_speed_mps}"
            )
        if not math.isfinite(self.current_direction_rad):
            raise ValueError("current_direction_rad must be finite")
        if not (math.isfinite(self.gnss_noise_scale) and self.gnss_noise_scale >= 0):
            raise ValueError(
                f"gnss_noise_scale must be finite and >= 0, got {self.gnss_noise_scale}"
            )
        if not 0.0 <= self.gnss_outlier_probability <= 1.0:
            raise ValueError("gnss_outlier_probability must lie in [0, 1]")
        if not (math.isfinite(self.gnss_outlier_scale) and self.gnss_outlier_scale >= 1):
            raise ValueError("gnss_outlier_scale must be finite and >= 1")
        if math.isnan(self.gnss_dropout_start_s) or self.gnss_dropout_duration_s < 0:
            raise ValueError("gnss_dropout_start_s must not be NaN; duration must be >= 0")

    @property
    def gnss_faulty(self) -> bool:
        """True when the GNSS normals need changing (scale or outliers)."""
        return self.gnss_noise_scale != 1.0 or self.gnss_outlier_probability > 0


class BoatDisturbances:
    """Per-boat disturbance state of a batch: what :meth:`PoleAvoidanceBatch.step` hands the plant.

    Boats start undisturbed; :meth:`set` gives reset boats their episode's disturbance (or clears
    it). :meth:`inputs` returns ``(speed, current, gnss_available)`` for one decision period, with
    ``None`` wherever every boat is undisturbed, so the study's call is made unchanged.
    """

    def __init__(self, n_boats: int, speed_mps: float, current: tuple[float, float]) -> None:
        self._default_speed = speed_mps
        self._default_current = current
        self.speed_mps = np.full(n_boats, speed_mps)
        self.current = np.tile(np.asarray(current, dtype=float), (n_boats, 1))  # (N, 2)
        self.noise_scale = np.ones(n_boats)
        self.outlier_p = np.zeros(n_boats)
        self.outlier_scale = np.ones(n_boats)
        self.dropout = np.full((n_boats, 2), np.inf)  # [start, end) s
        self.active = np.zeros(n_boats, dtype=bool)
        self._noise = BoatNoise(n_boats)
        # per-boat weather (module docstring): which boats have it, their episodes' weather and
        # the weather plant's per-episode inputs (N, 33), allocated by the first start_weather
        self.weather_active = np.zeros(n_boats, dtype=bool)
        self._weather: list[Weather] = [CALM] * n_boats
        self.weather_inputs: FloatArray | None = None

    def set(self, boats: NDArray[np.intp], items: Sequence[EpisodeDisturbance | None]) -> None:
        """Give ``boats`` their disturbances (``None``: the study's calm, clean setting)."""
        boats = np.asarray(boats, dtype=np.intp)
        if len(items) != boats.size:
            raise ValueError(f"need one disturbance (or None) per reset boat ({boats.size})")
        calm = EpisodeDisturbance()
        for i, d in zip(boats.tolist(), items, strict=True):
            e = calm if d is None else d
            self.speed_mps[i] = self._default_speed if e.speed_mps is None else e.speed_mps
            if d is None:
                self.current[i] = self._default_current
            else:
                self.current[i] = (e.current_speed_mps, e.current_direction_rad)
            self.noise_scale[i] = e.gnss_noise_scale
            self.outlier_p[i] = e.gnss_outlier_probability
            self.outlier_scale[i] = e.gnss_outlier_scale
            self.dropout[i] = (
                e.gnss_dropout_start_s,
                e.gnss_dropout_start_s + e.gnss_dropout_duration_s,
            )
            self.active[i] = d is not None
            self.weather_active[i] = d is not None and d.weather is not None
            self._weather[i] = CALM if d is None or d.weather is None else d.weather
        given = [k for k, d in enumerate(items) if d is not None]
        if given:
            self._noise.seed(boats[given], [items[k].seed for k in given])  # type: ignore[union-attr]

    @staticmethod
    def brings_weather(items: Sequence[EpisodeDisturbance | None] | None) -> bool:
        """True when one of ``items`` has a weather (the batch then needs the weather plant)."""
        return any(d is not None and d.weather is not None for d in items or ())

    def start_calm_weather(
        self, plant: WeatherPlant, eta: FloatArray, speed_mps: FloatArray
    ) -> FloatArray:
        """Every boat's calm weather input rows and states (N, 8) at ``eta`` (N, 3) and
        ``speed_mps`` (N,): the batch's switch to the weather plant; no episode stream draws."""
        n = self.speed_mps.size
        calm = plant.initial_state(  # no sea: the filter is off for these boats
            eta, sea_conditions([CALM] * n), speed_mps, wave_filter=False
        )
        self.weather_inputs = calm.inputs.copy()
        return calm.m

    def start_weather(
        self,
        plant: WeatherPlant,
        boats: NDArray[np.intp],
        eta: FloatArray,
        speed_mps: FloatArray,
        episode_noise: Callable[[NDArray[np.intp]], Any],
        calm: PlantState | None = None,
    ) -> FloatArray:
        """The weather states (len(boats), 8) of ``boats`` starting at ``eta`` (len(boats), 3)
        at ``speed_mps`` (len(boats),), and their weather input rows set (module docstring).

        ``episode_noise(b)`` serves standard normals row by row from boats ``b``'s own streams
        (the batch's :class:`usvsim.task.scenario.BoatNoise`): the stationary gust and wave
        motion of the boats with weather are drawn from it; boats without draw nothing from
        their streams (their draws, from the plant's generator, are multiplied by zero).
        Boats in a calm sea (H_s = 0) skip the wave filter's Riccati solutions: their filter is
        off and its gains zero either way (:func:`usvsim.vessel.weather_plant.weather_inputs`).
        ``calm``: the boats' ``Plant.initial_state(eta, speed_mps)`` where the caller has it.
        """
        boats = np.asarray(boats, dtype=np.intp)
        if self.weather_inputs is None:
            raise RuntimeError("start_calm_weather first: the boats' weather rows are not set")
        if boats.size == 0:
            return np.zeros((0, NWS))
        # one start for all: the episodes' own streams draw the gust and wave starts of the
        # boats with weather, the plant's generator those of the others (multiplied by zero)
        windy = np.flatnonzero(self.weather_active[boats])
        draws = _SplitDraws(
            episode_noise(boats[windy]) if windy.size else None, windy, plant.rng, boats.size
        )
        conditions = sea_conditions([self._weather[b] for b in boats.tolist()])
        state = plant.initial_state(eta, conditions, speed_mps, rng=draws, calm=calm)  # type: ignore[arg-type]
        self.weather_inputs[boats] = state.inputs
        return state.m

    def inputs(
        self, episode_time_s: FloatArray, dt_s: float, n_steps: int
    ) -> tuple[FloatArray | None, FloatArray | None, NDArray[np.bool_] | None]:
        """Speed (N,), current (N, 2) and GNSS availability (N, T) of the next period, or None.

        ``episode_time_s`` (N,): each boat's episode time at the period's start.
        """
        if not self.active.any():
            return None, None, None
        t = episode_time_s[:, None] + dt_s * np.arange(1, n_steps + 1)  # (N, T) at each step
        dropped = (t >= self.dropout[:, 0:1]) & (t < self.dropout[:, 1:2])
        return self.speed_mps, self.current, (~dropped if dropped.any() else None)

    def perturb_normals(
        self,
        normals: FloatArray,
        gnss_index: NDArray[np.intp],
        backend: Literal["auto", "numpy"] = "auto",
    ) -> FloatArray:
        """``normals`` (N, M) with the GNSS columns ``gnss_index`` scaled (noise, outliers);
        in one C call (:mod:`usvsim.task.gnss_fault_kernel`) where it builds, else (or with
        ``backend="numpy"``, the reference) in NumPy: the same numbers."""
        active = self.active
        faulty = active & ((self.noise_scale != 1.0) | (self.outlier_p > 0))
        if gnss_index.size == 0 or not faulty.any():
            return normals
        drawing = np.flatnonzero(active & (self.outlier_p > 0))
        z = np.empty((0, gnss_index.size))
        if drawing.size:
            # one draw per GNSS error entry, from the boat's own stream: every boat with
            # outliers draws every period, so its draws do not depend on its neighbours. The
            # draw is a standard normal z, an outlier where Φ(z) < p, i.e. z < Φ⁻¹(p) (Φ is
            # monotone: one quantile per boat instead of Φ of every draw)
            z = self._noise.for_boats(drawing).standard_normal((drawing.size, gnss_index.size))
            self._noise.for_boats(None)
        threshold = np.full(faulty.size, -np.inf)
        threshold[drawing] = ndtri(self.outlier_p[drawing])
        kernel = load_gnss_fault_kernel() if backend == "auto" else None
        out = normals.copy()
        if kernel is not None and normals.dtype == np.float64 and normals.flags.c_contiguous:
            rows = np.flatnonzero(faulty)
            draw_row = np.full(faulty.size, -1, dtype=np.int64)  # boat -> its row of z
            draw_row[drawing] = np.arange(drawing.size)
            arrays = [
                np.ascontiguousarray(a, dtype=dtype)
                for a, dtype in ((rows, np.int64), (gnss_index, np.int64),
                                 (self.noise_scale, np.float64),
                                 (self.outlier_scale, np.float64), (draw_row[rows], np.int64),
                                 (z, np.float64), (threshold, np.float64))
            ]  # fmt: skip
            kernel(
                rows.size, normals.shape[1], gnss_index.size,
                *(a.ctypes.data for a in arrays), out.ctypes.data,
            )  # fmt: skip
            return out
        # (N, G) scales; a boat without faults is scaled by exactly 1 (x · 1 = x in IEEE
        # arithmetic, so its columns keep their bits)
        scale = np.repeat(np.where(faulty, self.noise_scale, 1.0)[:, None], gnss_index.size, 1)
        if drawing.size:
            rows_ = scale[drawing]
            jump = z < threshold[drawing, None]
            scale[drawing] = np.where(jump, rows_ * self.outlier_scale[drawing, None], rows_)
        out[:, gnss_index] = normals[:, gnss_index] * scale
        return out


class _SplitDraws:
    """Standard normals for ``n`` boats: the rows ``rows`` from ``episode`` (their streams, in
    the order asked), the others from ``other`` (a generator), as separate draws would give."""

    def __init__(self, episode: Any, rows: NDArray[np.intp], other: Any, n: int) -> None:
        self.episode, self.rows, self.other = episode, rows, other
        rest = np.ones(n, dtype=bool)
        rest[rows] = False
        self.others = np.flatnonzero(rest)

    def standard_normal(self, size: int | tuple[int, ...]) -> FloatArray:
        shape = (size,) if isinstance(size, (int, np.integer)) else tuple(size)
        out = np.empty(shape)
        if self.rows.size:
            out[self.rows] = self.episode.standard_normal((self.rows.size, *shape[1:]))
        if self.others.size:
            out[self.others] = self.other.standard_normal((self.others.size, *shape[1:]))
        return out
