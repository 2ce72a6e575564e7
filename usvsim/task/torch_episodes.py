"""Episodes and sensor noise of the pole-avoidance task for the torch environment.

:class:`usvsim.task.torch_env.TorchPoleAvoidanceEnv` starts every episode on the device, at
every step, for all boats at once (the finished ones take it): it needs the next episode of
each boat and the standard normals of its sensors as tensors, without asking the host.

Episodes (:class:`EpisodeStarts`, all (N,) or (N, 2) tensors), two sources:

- ``"numpy"``: the CPU environment's own draws. At reset, boat i's first ``episodes_per_boat``
  episodes are drawn on the host exactly as :class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`
  draws them (:func:`usvsim.task.scenario.draw_episode` from a generator seeded ``seed + i``,
  geometry by :func:`usvsim.task.scenario.episode_geometry`) and kept on the device as a table;
  a boat that has used its table goes on with device draws. Same seed → the same episodes as the
  CPU environment (a Python loop over boats at reset only: for tests and small N).
- ``"device"``: drawn on the device from a seeded ``torch.Generator``: the same distributions as
  :func:`usvsim.task.scenario.draw_episode` (pole uniform, start distance, bearing and heading
  offset uniform) and the same geometry (:func:`episode_geometry_torch`), other numbers.

Noise (standard normals), two sources:

- :class:`DeviceNoise`: ``torch.randn`` from a seeded ``torch.Generator`` on the device;
- :class:`ReplayNoise` (test mode): each episode's own NumPy stream
  (:class:`usvsim.task.scenario.BoatNoise`, seeded by the episode's ``noise_seed``), number for
  number what the CPU environment's sensors draw. It reads which boats restarted back to the
  host every step: for equality tests, not for speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np
import torch

from usvsim.nav.torch_nav import FIX_DRAWS, torch_ssa
from usvsim.task.scenario import (
    BoatNoise,
    EpisodeSpec,
    Scenario,
    draw_episode,
    episode_geometry,
)

__all__ = [
    "DeviceNoise",
    "EpisodeSource",
    "EpisodeStarts",
    "NoiseSource",
    "OutlierDraws",
    "ReplayNoise",
    "TorchEpisodes",
    "episode_geometry_torch",
    "faulty_sensor_inputs",
    "gnss_slots",
]

EpisodeSource = Literal["numpy", "device"]


@dataclass(frozen=True)
class EpisodeStarts:
    """The next episode of each of N boats, on the device.

    ``pole_ne``, ``goal_ne`` (N, 2) m; ``start_eta`` (N, 3) [x_N, y_E, ψ0] (m, m, rad);
    ``start_distance_m`` (N,); ``noise_seed`` (N,) int64 (the NumPy stream of a table episode,
    -1 for a device draw).
    """

    pole_ne: torch.Tensor
    start_eta: torch.Tensor
    goal_ne: torch.Tensor
    start_distance_m: torch.Tensor
    noise_seed: torch.Tensor


def episode_geometry_torch(
    scenario: Scenario,
    poles_ne: torch.Tensor,
    pole_index: torch.Tensor,
    distance_m: torch.Tensor,
    bearing_rad: torch.Tensor,
    offset_rad: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """:func:`usvsim.task.scenario.episode_geometry` on tensors (N,): pole (N, 2), start pose
    (N, 3) and goal (N, 2), the same equations in the same order (inputs are not checked);
    ``poles_ne`` (P, 2) is ``scenario.poles_ne`` on the device."""
    pole = poles_ne[pole_index]
    out = torch.stack([torch.cos(bearing_rad), torch.sin(bearing_rad)], dim=-1)
    start = pole + distance_m[:, None] * out
    psi0 = torch_ssa(bearing_rad + math.pi + offset_rad)
    goal = start - scenario.goal_distance_m * out
    return pole, torch.cat([start, psi0[:, None]], dim=1), goal


class TorchEpisodes:
    """Each boat's next episode (:class:`EpisodeStarts`), from the table or from device draws.

    Parameters
    ----------
    scenario : Scenario
    n_boats : int
    source : "numpy" | "device"
        See the module docstring.
    episodes_per_boat : int
        Table length per boat for ``"numpy"``.
    device, dtype
        Where the tensors live.
    """

    def __init__(
        self,
        scenario: Scenario,
        n_boats: int,
        source: EpisodeSource,
        episodes_per_boat: int,
        device: torch.device,
        dtype: torch.dtype,
    ) -> None:
        if source not in ("numpy", "device"):
            raise ValueError(f"episodes must be 'numpy' or 'device', got {source!r}")
        if episodes_per_boat < 1:
            raise ValueError(f"episodes_per_boat must be >= 1, got {episodes_per_boat}")
        self.scenario, self.n, self.source = scenario, n_boats, source
        self.k = episodes_per_boat if source == "numpy" else 0
        self.device, self.dtype = device, dtype
        self._gen = torch.Generator(device=device)
        self._table: EpisodeStarts | None = None
        self._rows = torch.arange(n_boats, device=device)
        self._poles = torch.tensor(scenario.poles_ne, dtype=dtype, device=device)

    def seed(self, seed: int) -> None:
        """Restart the draws: boat i's table from ``default_rng(seed + i)`` (NumPy source) and
        the device generator from ``seed``."""
        self._gen.manual_seed(int(seed) % 2**63)
        if self.source == "numpy":
            self._table = self._numpy_table(int(seed))

    def _numpy_table(self, seed: int) -> EpisodeStarts:
        """The first k episodes of every boat, (N, k, ...) (the CPU vector env's draws:
        gymnasium's ``seeding.np_random(s)`` is ``default_rng(s)``)."""
        specs: list[EpisodeSpec] = []
        for i in range(self.n):  # reset only: the CPU draws are one Generator per boat
            rng = np.random.default_rng(seed + i)
            specs.extend(draw_episode(rng, self.scenario) for _ in range(self.k))
        geo = episode_geometry(self.scenario, specs)

        def put(a: np.ndarray) -> torch.Tensor:
            t = torch.as_tensor(a, dtype=self.dtype, device=self.device)
            return t.reshape(self.n, self.k, *a.shape[1:])

        return EpisodeStarts(
            pole_ne=put(geo.pole_ne),
            start_eta=put(geo.start_eta),
            goal_ne=put(geo.goal_ne),
            start_distance_m=put(np.array([s.start_distance_m for s in specs])),
            noise_seed=torch.as_tensor(
                [s.noise_seed for s in specs], dtype=torch.int64, device=self.device
            ).reshape(self.n, self.k),
        )

    def _uniform(self, lo: float, hi: float) -> torch.Tensor:
        u = torch.rand(self.n, generator=self._gen, dtype=self.dtype, device=self.device)
        return lo + (hi - lo) * u

    def drawn(self) -> EpisodeStarts:
        """N fresh episodes from the device generator."""
        sc = self.scenario
        pole_index = torch.randint(
            len(sc.poles_ne), (self.n,), generator=self._gen, device=self.device
        )
        distance = self._uniform(*sc.start_distance_range_m)
        bearing = self._uniform(0.0, 2.0 * math.pi)
        offset = self._uniform(*sc.heading_offset_range_rad)
        pole, eta, goal = episode_geometry_torch(
            sc, self._poles, pole_index, distance, bearing, offset
        )
        seeds = torch.full((self.n,), -1, dtype=torch.int64, device=self.device)
        return EpisodeStarts(pole, eta, goal, distance, seeds)

    def next(self, used: torch.Tensor) -> EpisodeStarts:
        """Each boat's episode number ``used`` (N,) int64 (0 for its first): from the table where
        it has one, else a device draw (drawn for every boat, kept where the table has ended)."""
        fresh = self.drawn()
        if self._table is None:
            return fresh
        t = self._table
        take = (self._rows, used.clamp(max=self.k - 1))
        inside = used < self.k

        def pick(table: torch.Tensor, drawn: torch.Tensor) -> torch.Tensor:
            mask = inside.view(-1, *([1] * (drawn.ndim - 1)))
            return torch.where(mask, table[take], drawn)

        return EpisodeStarts(
            pick(t.pole_ne, fresh.pole_ne),
            pick(t.start_eta, fresh.start_eta),
            pick(t.goal_ne, fresh.goal_ne),
            pick(t.start_distance_m, fresh.start_distance_m),
            pick(t.noise_seed, fresh.noise_seed),
        )


class NoiseSource(Protocol):
    """Standard normals for the sensors of N boats (see the module docstring)."""

    def seed(self, seed: int) -> None: ...

    def fix_normals(self, restart: torch.Tensor, noise_seed: torch.Tensor) -> torch.Tensor:
        """(N, 7) normals of a first fix for the boats ``restart`` (N,) bool (other rows
        unused); ``noise_seed`` (N,) int64: each restarting episode's stream."""
        ...

    def decision_normals(self, m: int) -> torch.Tensor:
        """(N, m) normals: every boat's next m draws."""
        ...

    def weather_normals(self, boats: torch.Tensor, m: int) -> torch.Tensor:
        """(N, m) normals of the weather plant for the boats ``boats`` (N,) bool (those in a
        weather episode; the rows of the others are unused or multiplied by zero), drawn after
        this step's other draws."""
        ...


class DeviceNoise:
    """``torch.randn`` on the device from a seeded generator."""

    def __init__(self, n_boats: int, device: torch.device, dtype: torch.dtype) -> None:
        self.n, self.device, self.dtype = n_boats, device, dtype
        self._gen = torch.Generator(device=device)

    def seed(self, seed: int) -> None:
        self._gen.manual_seed(int(seed) % 2**63 + 1)  # not the episodes' stream

    def fix_normals(self, restart: torch.Tensor, noise_seed: torch.Tensor) -> torch.Tensor:
        return self.decision_normals(FIX_DRAWS)

    def decision_normals(self, m: int) -> torch.Tensor:
        return torch.randn((self.n, m), generator=self._gen, dtype=self.dtype, device=self.device)

    def weather_normals(self, boats: torch.Tensor, m: int) -> torch.Tensor:
        return self.decision_normals(m)


class ReplayNoise:
    """Each episode's NumPy noise stream, as the CPU environment draws it (test mode)."""

    def __init__(self, n_boats: int, device: torch.device, dtype: torch.dtype) -> None:
        self.n, self.device, self.dtype = n_boats, device, dtype
        self._noise = BoatNoise(n_boats)

    def seed(self, seed: int) -> None:
        """Nothing to do: each episode's stream is seeded by its own ``noise_seed``."""

    def fix_normals(self, restart: torch.Tensor, noise_seed: torch.Tensor) -> torch.Tensor:
        idx = np.flatnonzero(restart.cpu().numpy())
        seeds = noise_seed.cpu().numpy()[idx]
        if np.any(seeds < 0):
            raise RuntimeError(
                "ReplayNoise replays the NumPy episodes only (episodes='numpy'); a boat has "
                "used its table of episodes (raise episodes_per_boat)"
            )
        out = np.zeros((self.n, FIX_DRAWS))
        if idx.size:
            self._noise.seed(idx, [int(s) for s in seeds])
            out[idx] = self._noise.for_boats(idx).standard_normal((idx.size, FIX_DRAWS))
            self._noise.for_boats(None)
        return torch.as_tensor(out, dtype=self.dtype, device=self.device)

    def decision_normals(self, m: int) -> torch.Tensor:
        out = self._noise.for_boats(None).standard_normal((self.n, m))
        return torch.as_tensor(out, dtype=self.dtype, device=self.device)

    def weather_normals(self, boats: torch.Tensor, m: int) -> torch.Tensor:
        """The next m draws of the streams of ``boats`` (as ``PoleAvoidanceBatch`` draws its
        weather boats' innovations and start), zeros for the others (their streams untouched)."""
        idx = np.flatnonzero(boats.cpu().numpy())
        out = np.zeros((self.n, m))
        if idx.size:
            out[idx] = self._noise.for_boats(idx).standard_normal((idx.size, m))
            self._noise.for_boats(None)
        return torch.as_tensor(out, dtype=self.dtype, device=self.device)


class OutlierDraws:
    """The standard normals of each decision's GNSS outlier draws, G per boat (the open-water
    episodes' outlier faults): from a seeded generator on the device, or (``replay``, test
    mode) from each episode's own NumPy stream (its ``outlier_seed``), seeded on the host as
    the CPU batch seeds it; only the boats whose episode has outliers draw from theirs."""

    def __init__(
        self, n_boats: int, device: torch.device, dtype: torch.dtype, replay: bool
    ) -> None:
        self.n, self.device, self.dtype = n_boats, device, dtype
        self._gen = torch.Generator(device=device)
        self._streams = BoatNoise(n_boats) if replay else None
        self._drawing = np.zeros(n_boats, dtype=bool)  # replay: boats drawing outliers (host)

    def seed(self, seed: int) -> None:
        self._gen.manual_seed(int(seed) % 2**63 + 2)  # not the episodes' or the sensors'

    def start(self, boats: torch.Tensor, outlier_seed: np.ndarray, probability: np.ndarray) -> None:
        """Replay: seed the streams of ``boats`` (N,) bool starting episodes with seeds
        ``outlier_seed`` (N,) and outlier probabilities ``probability`` (N,), host arrays;
        nothing to do on the device."""
        if self._streams is None:
            return
        idx = np.flatnonzero(boats.cpu().numpy())
        if idx.size:
            self._streams.seed(idx, [int(s) for s in outlier_seed[idx]])
            self._drawing[idx] = probability[idx] > 0

    def normals(self, g: int) -> torch.Tensor:
        """(N, g) normals of this decision (zeros for replayed boats without outliers)."""
        if self._streams is None:
            return torch.randn(
                (self.n, g), generator=self._gen, dtype=self.dtype, device=self.device
            )
        z = np.zeros((self.n, g))
        drawing = np.flatnonzero(self._drawing)
        if drawing.size:
            z[drawing] = self._streams.for_boats(drawing).standard_normal((drawing.size, g))
            self._streams.for_boats(None)
        return torch.as_tensor(z, dtype=self.dtype, device=self.device)


def gnss_slots(layout: Any) -> list[tuple[int, int]]:
    """(plant step j, input e) of every GNSS error among a decision's filter inputs
    (``layout``: :class:`usvsim.task.torch_env.ClosedLoop`'s; the CPU batch's
    ``gnss_index``)."""
    return [(j, e) for j, cols in enumerate(layout.index) for e in range(1, 5) if cols[e] >= 0]


def faulty_sensor_inputs(
    layout: Any, slots: list[tuple[int, int]], normals: torch.Tensor, gnss: torch.Tensor,
    outlier_normals: torch.Tensor, time_s: torch.Tensor,
) -> list[tuple[Any, ...]]:  # fmt: skip
    """The filter's per-step inputs of one decision with the open-water episodes' GNSS faults
    (``BoatDisturbances.perturb_normals`` and the dropout mask): ``normals`` (N, draws) the
    decision's standard normals, ``gnss`` (N, 6) each boat's fault row (the episode table's),
    ``outlier_normals`` (N, G) the outlier draws of the G ``slots`` (:func:`gnss_slots`),
    ``time_s`` (N, T) the episode time at each plant step."""
    scale, threshold, outlier_scale = gnss[:, 0:1], gnss[:, 1:2], gnss[:, 2:3]
    factor = torch.where(outlier_normals < threshold, scale * outlier_scale, scale)  # (N, G)
    available = ~((time_s >= gnss[:, 3:4]) & (time_s < gnss[:, 4:5]))
    es = [list(e) for e in layout.step_inputs(normals)]
    for g, (j, k) in enumerate(slots):  # the GNSS entries of a decision
        es[j][k] = normals[:, layout.index[j][k]] * factor[:, g]
    for j in range(len(es)):
        if layout.gps[j]:
            es[j][6] = es[j][6] * available[:, j].to(normals.dtype)
    return [tuple(e) for e in es]
