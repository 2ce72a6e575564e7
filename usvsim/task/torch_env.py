"""The pole-avoidance task as batched tensor code on any torch device (positional and radar).

:class:`TorchPoleAvoidanceEnv` is :class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv` (autoreset
``SAME_STEP``) with everything of a step on the device: the plant (:mod:`usvsim.vessel.
torch_plant`, generated from the CasADi plant), the sensors and Kalman filter (:mod:`usvsim.nav.
torch_nav`, generated from the CasADi filter), the judge (goal, collision, area, time limit at
every 0.1 s plant step, as :meth:`usvsim.task.batch.PoleAvoidanceBatch.step`), the study's reward,
the observation and the restart of finished boats. No host round trip and no Python loop over
boats per step; ``device="torch-cpu"`` or ``"cuda"`` runs the same code.

One decision step of N boats (T = 20 plant steps of 0.1 s)::

    Δψ     = action → heading change (rad)                        (N,)
    ψ_ref  = ssa(ψ̂ + Δψ)                 ψ̂: estimated heading at the decision
    T × [ plant step (autopilot, RK4) ; sensors + Kalman filter ]
    done   : from the true positions at every plant step
    reward : from the true distances at the period's end (or the first goal / collision step)
    obs    : from the estimate: [r_pole, φ_pole, r_goal, φ_goal] (m, rad), or the radar image
             (and the standardised goal vector) (:mod:`usvsim.task.torch_observations`)
    restart: boats whose episode ended start their next one (obs is the new episode's first)

Equality with the CPU environment: with ``episodes="numpy"`` (the CPU env's episode draws) and
``noise="replay"`` (each episode's NumPy noise stream, test mode) a ``float64`` run on
``torch-cpu`` gives the CPU env's flags and times exactly and its observations and rewards to
rounding: within 1e-9 over the first decisions, then drifting apart slowly (2e-7 m over 160
decisions), as the closed loop amplifies last-bit differences (torch's ``sin`` and ``cos``, the
C kernel's fused multiply-adds); the CPU env's CasADi-VM backend differs from its C kernel by as
much (``benchmarks/torch_env_equality.py``, ``docs/guide/gpu.md``).
The defaults (``episodes="device"``, ``noise="device"``) draw both on the device: the same
distributions, other numbers.

Returns of :meth:`~TorchPoleAvoidanceEnv.step` (tensors on the device):

==================  ==========  =================================================================
name                shape       meaning
==================  ==========  =================================================================
obs                 (N, 4)      positional, ``observation_dtype`` (float32 like the CPU env);
                                radar: (N, 1, 50, 119) uint8; radar+goal: a dict of both; after a
                                restart the new episode's first observation
reward              (N,)        the study's reward (:class:`usvsim.task.reward.GaussianReward`)
terminated          (N,) bool   goal reached or collision
truncated           (N,) bool   time limit or out of the area, not terminated
info                dict        ``final_obs`` the last observation of every boat before a
                                restart, and the CPU env's info entries (``reward_pole``,
                                ``distance_to_pole_m``, ``is_success``, ``time_s``, …) as (N,)
==================  ==========  =================================================================

Actions are those of the CPU env (gaussian (N, 1) in [-1, 1] → ±30°, categorical (N,) in 0..40)
and are not range-checked here (a check would wait for the device): the CPU env checks them.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import torch

from usvsim.nav.torch_nav import (
    NoiseLayout,
    TorchNavKernel,
    load_nav_kernel,
    noise_layout,
    started_nav_state,
    torch_ssa,
)
from usvsim.task.radar import RadarConfig
from usvsim.task.reward import GaussianReward
from usvsim.task.scenario import Scenario
from usvsim.task.torch_episodes import (
    DeviceNoise,
    EpisodeSource,
    NoiseSource,
    ReplayNoise,
    TorchEpisodes,
)
from usvsim.task.torch_observations import (
    TORCH_OBSERVATIONS,
    RadarGrid,
    TorchObservation,
    radar_image,
    relative_polar_torch,
    select_rows,
    standardized_goal,
)
from usvsim.task.torch_scene import gaussian_reward_torch
from usvsim.vessel.torch_plant import DTYPES, TorchPlant

__all__ = [
    "ClosedLoop",
    "TorchPoleAvoidanceEnv",
    "check_options",
    "compiled_substep",
    "plant_and_filter",
    "torch_heading_change",
]

Columns = tuple[torch.Tensor, ...]
N_CATEGORIES = 41  # usvsim.task.batch.N_CATEGORIES (study: 0 → -30°, 20 → 0°, 40 → +30°)


class TorchPoleAvoidanceEnv:
    """``num_envs`` boats on the pole-avoidance task, stepped on a torch device (module docstring).

    Parameters
    ----------
    num_envs : int
    device : "torch-cpu" | "cuda" | "cuda:K"
    dtype : "float64" | "float32"
        Number type of the simulation.
    action : "gaussian" | "categorical"
    observation : "positional" | "radar" | "radar+goal"
        As the CPU env's (:mod:`usvsim.task.torch_observations`).
    radar : RadarConfig, optional
        Image geometry; clutter and intensity noise are not drawn on the device (refused).
    observation_dtype : "float32" | "float64"
        float32 as the CPU env; float64 keeps the simulation's numbers (tests).
    scenario : Scenario, optional
    reward : GaussianReward, optional
    nav : NavConfig, optional
        Default: the committed filter; another one is generated (needs CasADi).
    episodes : "device" | "numpy"
        Where episodes come from (:mod:`usvsim.task.torch_episodes`).
    episodes_per_boat : int
        Table length of ``episodes="numpy"``.
    noise : "device" | "replay"
        Sensor noise from a device generator, or each episode's NumPy stream (test mode: needs
        ``episodes="numpy"``; reads the restarted boats back to the host every step).
    compile : bool
        Run a plant step + filter step through ``torch.compile`` (for a GPU: one fused kernel
        instead of ~800 small ones per plant step; the first step compiles, which takes a
        while); ``compile_backend`` is its backend (``"eager"`` only traces: a dry run).
    """

    def __init__(
        self,
        num_envs: int,
        *,
        device: str = "torch-cpu",
        dtype: str = "float64",
        action: Literal["gaussian", "categorical"] = "gaussian",
        observation: str = "positional",
        observation_dtype: str = "float32",
        radar: RadarConfig | None = None,
        scenario: Scenario | None = None,
        reward: GaussianReward | None = None,
        nav: Any = None,
        episodes: EpisodeSource = "device",
        episodes_per_boat: int = 8,
        noise: Literal["device", "replay"] = "device",
        compile: bool = False,
        compile_backend: str = "inductor",
    ) -> None:
        check_options(num_envs, action, observation_dtype, noise)
        if observation not in TORCH_OBSERVATIONS:
            raise ValueError(
                f"observation must be one of {TORCH_OBSERVATIONS} on torch, got {observation!r}"
            )
        self.radar = radar or RadarConfig()
        if self.radar.clutter_probability > 0 or self.radar.noise_amplitude > 0:
            raise ValueError("radar clutter and intensity noise are not drawn by the torch env")
        self._radar_grid: RadarGrid | None = None
        if noise == "replay" and episodes != "numpy":
            raise ValueError("noise='replay' replays the NumPy episodes: needs episodes='numpy'")
        self.reward = reward or GaussianReward()
        if not isinstance(self.reward, GaussianReward):
            raise ValueError("the torch env computes the GaussianReward only")
        self.num_envs = n = num_envs
        self.action_kind = action
        self.observation_kind = observation
        self.scenario = sc = scenario or Scenario()
        loop = ClosedLoop.build(sc, nav, device, dtype)
        self.plant, self.nav, self.T, self.layout = loop.plant, loop.nav, loop.T, loop.layout
        self.device, self.dtype = self.plant.device, self.plant.dtype
        self.observation_dtype = DTYPES[observation_dtype]
        self.episodes = TorchEpisodes(sc, n, episodes, episodes_per_boat, self.device, self.dtype)
        noise_cls = ReplayNoise if noise == "replay" else DeviceNoise
        self.noise: NoiseSource = noise_cls(n, self.device, self.dtype)
        self._collision_m = sc.pole_radius_m + self.plant.vessel.half_beam_m
        self._speed = torch.tensor(sc.speed_mps, dtype=self.dtype, device=self.device)
        start = self.plant.initial_state(np.zeros((1, 3)), sc.speed_mps)  # x and c at ψ = 0
        self._x0, self._c0 = start.x[0], start.c[0]
        self._steps = torch.arange(self.T, device=self.device)
        zeros = torch.zeros(n, dtype=self.dtype, device=self.device)
        self._s = torch.zeros((self.plant.kernel.ns, n), dtype=self.dtype, device=self.device)
        self._n = torch.zeros((15, n), dtype=self.dtype, device=self.device)
        self.pole_ne = torch.zeros((n, 2), dtype=self.dtype, device=self.device)
        self.goal_ne = torch.zeros((n, 2), dtype=self.dtype, device=self.device)
        self._min_pole, self._t_goal = zeros.clone(), zeros.clone()
        self._n_decisions = torch.zeros(n, dtype=torch.int64, device=self.device)
        self._started = torch.zeros(n, dtype=torch.int64, device=self.device)  # episodes begun
        self._ready = False
        # numbers shared by all boats: 0-d tensors, built once
        self._gains = self._shared(self.plant.kernel.gains)
        self._current = self._shared(self.plant.current)
        self._substep: Callable[..., tuple[Columns, Columns]] = (
            compiled_substep(compile_backend) if compile else plant_and_filter
        )

    # ----------------------------------------------------------------------------- state
    @property
    def state(self) -> torch.Tensor:
        """True plant state [x, c] of all boats (N, 13) (never for observations)."""
        return self._s.T.clone()

    @property
    def single_observation_space(self) -> Any:
        """The CPU env's single-boat observation space (a gymnasium space: needs gymnasium)."""
        from usvsim.task.observations import observation_space

        return observation_space(self.observation_kind, self.radar)  # type: ignore[arg-type]

    @property
    def single_action_space(self) -> Any:
        """The CPU env's single-boat action space (:func:`single_action_space`)."""
        return single_action_space(self.action_kind)

    @property
    def estimate(self) -> tuple[torch.Tensor, torch.Tensor]:
        """Navigation estimate now: position (N, 2) m and heading (N,) rad."""
        return self._n[0:2].T.clone(), self._n[8].clone()

    # ----------------------------------------------------------------------------- reset
    @torch.no_grad()
    def reset(self, *, seed: int | None = None) -> tuple[TorchObservation, dict[str, torch.Tensor]]:
        """Start every boat's first episode; ``seed`` seeds the episode and noise draws (boat i's
        NumPy episodes from ``seed + i``, as the CPU env)."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        self.episodes.seed(seed)
        self.noise.seed(seed)
        self._started.zero_()
        everyone = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
        obs = self._restart(everyone, self._observe())
        self._ready = True
        return obs, {"pole_ne": self.pole_ne.clone(), "goal_ne": self.goal_ne.clone()}

    def _restart(self, boats: torch.Tensor, obs: TorchObservation) -> TorchObservation:
        """Start the next episode of ``boats`` (N,) bool, everything selected on the device;
        returns ``obs`` with those boats' rows their first observation."""
        ep = self.episodes.next(self._started)
        self._started += boats
        psi = torch_ssa(ep.start_eta[:, 2])
        x = self._x0[:, None].expand(-1, self.num_envs).clone()
        x[0], x[1], x[2] = ep.start_eta[:, 0], ep.start_eta[:, 1], psi
        c = self._c0[:, None].expand(-1, self.num_envs).clone()
        if self.plant.kind == "pid":  # usvsim.vessel.autopilot.initial_controller_state
            c[0], c[1] = psi, x[5]
        nav = started_nav_state(self.nav, x, self.noise.fix_normals(boats, ep.noise_seed))
        rows = boats[None, :]
        self._s = torch.where(rows, torch.cat([x, c]), self._s)
        self._n = torch.where(rows, nav, self._n)
        col = boats[:, None]
        self.pole_ne = torch.where(col, ep.pole_ne, self.pole_ne)
        self.goal_ne = torch.where(col, ep.goal_ne, self.goal_ne)
        self._min_pole = torch.where(boats, ep.start_distance_m, self._min_pole)
        self._t_goal = torch.where(boats, math.inf, self._t_goal)
        self._n_decisions = torch.where(boats, 0, self._n_decisions)
        return select_rows(boats, self._observe(), obs)

    def _observe(self) -> TorchObservation:
        """The observation of every boat from its estimate (module docstring)."""
        pos, psi = self._n[0:2].T, self._n[8]
        r, b = relative_polar_torch(pos, psi, torch.stack([self.pole_ne, self.goal_ne], dim=1))
        if self.observation_kind == "positional":
            obs = torch.stack([r[:, 0], b[:, 0], r[:, 1], b[:, 1]], 1)
            return obs.to(self.observation_dtype)
        if self._radar_grid is None:
            self._radar_grid = RadarGrid.build(self.radar, self.dtype, self.device)
        image = radar_image(r[:, 0], b[:, 0], self.scenario.pole_radius_m, self._radar_grid)
        if self.observation_kind == "radar":
            return image
        return {"radar": image, "goal": standardized_goal(r[:, 1], b[:, 1])}

    # ----------------------------------------------------------------------------- step
    def heading_change_rad(self, actions: Any) -> torch.Tensor:
        """Heading changes Δψ (N,) rad of batched actions (as the CPU env maps them)."""
        return torch_heading_change(
            self.action_kind, actions, self.num_envs, self.scenario.max_heading_change_rad,
            self.device, self.dtype,
        )  # fmt: skip

    def _shared(self, values: tuple[float, ...]) -> Columns:
        return tuple(torch.tensor(values, dtype=self.dtype, device=self.device).unbind(0))

    @torch.no_grad()
    def step(
        self, actions: Any
    ) -> tuple[TorchObservation, torch.Tensor, torch.Tensor, torch.Tensor, dict[str, Any]]:
        """One decision step of every boat, finished boats restarted (module docstring)."""
        if not self._ready:
            raise RuntimeError("call reset() before step()")
        sc, T = self.scenario, self.T
        dpsi = self.heading_change_rad(actions)
        w = (torch_ssa(self._n[8] + dpsi), self._speed, *self._current)
        plant_step, nav_step, nx = self.plant.kernel.step, self.nav.step, self.plant.kernel.nx
        es = self.layout.step_inputs(self.noise.decision_normals(self.layout.draws))
        s, n = tuple(self._s.unbind(0)), tuple(self._n.unbind(0))
        xs, ys = [], []
        for j in range(T):  # the plant steps of one decision
            s, n = self._substep(plant_step, nav_step, nx, s, n, w, self._gains, es[j])
            xs.append(s[0])
            ys.append(s[1])
        self._s, self._n = torch.stack(s), torch.stack(n)
        self._n_decisions += 1
        x_n, y_e = torch.stack(xs, 1), torch.stack(ys, 1)  # true positions (N, T)
        d_pole = torch.hypot(x_n - self.pole_ne[:, 0:1], y_e - self.pole_ne[:, 1:2])
        dx_goal, dy_goal = x_n - self.goal_ne[:, 0:1], y_e - self.goal_ne[:, 1:2]
        hit = d_pole < self._collision_m
        in_goal = torch.hypot(dx_goal, dy_goal) <= sc.goal_radius_m
        collision, reached = hit.any(1), in_goal.any(1)
        terminated = reached | collision
        steps = self._steps[None, :]
        end = torch.where(
            terminated, torch.where(hit | in_goal, steps, T).amin(1), T - 1
        )  # a terminated episode ends at its first event step
        upto_end = torch.where(steps > end[:, None], math.inf, d_pole)
        self._min_pole = torch.minimum(self._min_pole, upto_end.amin(1))
        first_goal = torch.where(in_goal, steps, T).amin(1)
        t_first = ((self._n_decisions - 1) * T + first_goal + 1).to(self.dtype) * sc.dt_s
        self._t_goal = torch.where(reached & torch.isinf(self._t_goal), t_first, self._t_goal)
        at_end = end[:, None]
        d_pole_end = d_pole.gather(1, at_end)[:, 0]
        d_goal_end = torch.hypot(dx_goal.gather(1, at_end)[:, 0], dy_goal.gather(1, at_end)[:, 0])
        out_of_area = d_pole_end > sc.area_radius_m
        time_limit = self._n_decisions >= sc.max_decisions
        pole, goal = self._reward_terms(d_pole_end, d_goal_end)
        truncated = (time_limit | out_of_area) & ~terminated
        obs = self._observe()
        info = {
            "final_obs": obs,
            "reward_pole": pole,
            "reward_goal": goal,
            "heading_change_rad": dpsi,
            "distance_to_pole_m": d_pole_end,
            "distance_to_goal_m": d_goal_end,
            "min_distance_to_pole_m": self._min_pole,
            "reached_goal": reached,
            "collision": collision,
            "out_of_area": out_of_area,
            "time_limit": time_limit,
            "is_success": reached & ~collision & (self._min_pole >= sc.safety_distance_m),
            "time_s": self._n_decisions.to(self.dtype) * sc.decision_period_s,
            "time_to_goal_s": self._t_goal,
        }
        obs = self._restart(terminated | truncated, obs)
        return obs, pole + goal, terminated, truncated, info

    def _reward_terms(
        self, d_pole_m: torch.Tensor, d_goal_m: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """:class:`usvsim.task.reward.GaussianReward` on tensors, the same operations."""
        r = self.reward
        return gaussian_reward_torch(
            r.pole_weight, r.pole_sigma_m, r.goal_weight, r.goal_sigma_m, d_pole_m, d_goal_m
        )


def torch_heading_change(
    kind: str,
    actions: Any,
    num_envs: int,
    max_rad: float,
    device: torch.device,
    dtype: torch.dtype,
) -> torch.Tensor:
    """Heading changes Δψ (N,) rad of batched actions, as the CPU env maps them (gaussian (N, 1)
    → ±``max_rad``, categorical (N,) 0..40); shapes and kinds checked, values not (a check
    would wait for the device)."""
    a = torch.as_tensor(actions, device=device)
    if kind == "gaussian":
        if tuple(a.shape) != (num_envs, 1) or not a.is_floating_point():
            raise ValueError(
                f"gaussian actions must be floats of shape ({num_envs}, 1), got "
                f"{a.dtype} {tuple(a.shape)}"
            )
        return a[:, 0].to(dtype) * max_rad
    if tuple(a.shape) != (num_envs,) or a.is_floating_point():
        raise ValueError(
            f"categorical actions must be integers of shape ({num_envs},), got "
            f"{a.dtype} {tuple(a.shape)}"
        )
    centre = (N_CATEGORIES - 1) // 2
    return (a.to(dtype) - centre) * (max_rad / centre)


def check_options(num_envs: int, action: str, observation_dtype: str, noise: str) -> None:
    """The arguments every torch env takes, checked: a one-line ``ValueError`` naming the
    argument and what it allows."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
    if action not in ("gaussian", "categorical"):
        raise ValueError(f"action must be 'gaussian' or 'categorical', got {action!r}")
    if observation_dtype not in DTYPES:
        raise ValueError(f"observation_dtype must be one of {list(DTYPES)}")
    if noise not in ("device", "replay"):
        raise ValueError(f"noise must be 'device' or 'replay', got {noise!r}")


@dataclass(frozen=True)
class ClosedLoop:
    """What a torch env steps its boats with: the generated plant, the filter kernel, the plant
    steps per decision ``T`` and the noise layout of a decision's steps (the CPU batch's clock:
    decision k covers plant steps kT + 1 .. kT + T)."""

    plant: TorchPlant
    nav: TorchNavKernel
    T: int
    layout: NoiseLayout

    @classmethod
    def build(cls, scenario: Scenario, nav: Any, device: str, dtype: str) -> ClosedLoop:
        """For ``scenario``'s plant step and decision period on ``device`` in ``dtype``; ``nav``
        a :class:`usvsim.nav.models.NavConfig` (None: the default filter).

        Raises ``ValueError`` where the filter's step is not the plant's or a decision does not
        span whole sensor cycles."""
        plant = TorchPlant("default", dt_s=scenario.dt_s, device=device, dtype=dtype)
        kernel = load_nav_kernel(nav)
        if abs(kernel.dt_s - scenario.dt_s) > 1e-12:
            raise ValueError(f"NavConfig.dt_s {kernel.dt_s} != Scenario.dt_s {scenario.dt_s}")
        T = scenario.steps_per_decision
        if T % kernel.cycle_steps:
            raise ValueError("a decision must span whole sensor cycles (GNSS and compass)")
        return cls(plant, kernel, T, noise_layout(kernel, 1, T))


def single_action_space(action_kind: str) -> Any:
    """The CPU env's single-boat action space of ``action_kind`` (a gymnasium space: needs
    gymnasium; built here, not by ``usvsim.task.batch.action_space``, whose module needs CasADi;
    tested equal)."""
    from gymnasium import spaces

    if action_kind == "categorical":
        return spaces.Discrete(N_CATEGORIES)
    return spaces.Box(-1.0, 1.0, (1,), dtype=np.float32)


def plant_and_filter(
    plant_step: Callable[..., Columns],
    nav_step: Callable[..., Columns],
    nx: int,
    s: Columns,
    n: Columns,
    w: Columns,
    g: Columns,
    e: tuple[Any, ...],
) -> tuple[Columns, Columns]:
    """One plant step (``plant_step(s, w, g)``, the generated closed-loop step), then the
    sensors and the filter (``nav_step``) on the new true plant state (its first ``nx``)."""
    s = plant_step(s, w, g)
    return s, nav_step(n, s[:nx], e)


def stack_columns(columns: tuple[Any, ...], ref: torch.Tensor) -> torch.Tensor:
    """Columns (each (N,), a 0-d tensor or a number: broadcast, the same numbers) stacked into
    one fresh (K, N) tensor like ``ref``: what a compiled substep takes, so that one graph serves
    every plant step. Passed as separate columns, the mix of 0-d entries (a silent sensor, the
    firing flags), column views at varying storage offsets and fresh tensors made a new
    compilation for nearly every plant step of a decision (8 or more), and after torch's limit
    of 8 the step fell back to eager."""
    return torch.stack([torch.broadcast_to(torch.as_tensor(c, dtype=ref.dtype, device=ref.device),
                                           ref.shape) for c in columns])  # fmt: skip


def _stacked_plant_and_filter(
    plant_step: Callable[..., Columns], nav_step: Callable[..., Columns], nx: int,
    s: torch.Tensor, n: torch.Tensor, w: torch.Tensor, g: Columns, e: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:  # fmt: skip
    s_next, n_next = plant_and_filter(plant_step, nav_step, nx, tuple(s.unbind(0)),
                                      tuple(n.unbind(0)), tuple(w.unbind(0)), g,
                                      tuple(e.unbind(0)))  # fmt: skip
    return torch.stack(s_next), torch.stack(n_next)


@functools.cache
def compiled_substep(backend: str = "inductor") -> Callable[..., tuple[Columns, Columns]]:
    """:func:`plant_and_filter` through ``torch.compile`` with ``backend`` (shape-generic: one
    compilation serves every N), its inputs stacked (:func:`stack_columns`) so that one graph
    serves every plant step; made once per process and backend. Same arguments and results."""
    compiled = torch.compile(_stacked_plant_and_filter, dynamic=True, backend=backend)

    def substep(
        plant_step: Callable[..., Columns], nav_step: Callable[..., Columns], nx: int,
        s: Columns, n: Columns, w: Columns, g: Columns, e: tuple[Any, ...],
    ) -> tuple[Columns, Columns]:  # fmt: skip
        ref = s[0]
        s_t, n_t = compiled(plant_step, nav_step, nx, stack_columns(s, ref),
                            stack_columns(n, ref), stack_columns(w, ref), g,
                            stack_columns(e, ref))  # fmt: skip
        return tuple(s_t.unbind(0)), tuple(n_t.unbind(0))

    return substep
