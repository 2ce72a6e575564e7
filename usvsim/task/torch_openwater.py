"""The open-water task (``usvsim/OpenWater-v0``) as batched tensor code on any torch device.

:class:`TorchOpenWaterEnv` is :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` (autoreset
``SAME_STEP``; the ``scene``, ``positional``, ``radar`` and ``radar+goal`` observations) with
everything of a step on the device: the plant in
each episode's current at its cruise speed (:mod:`usvsim.vessel.torch_plant`, generated from the
CasADi plant), the sensors and Kalman filter with the episode's GNSS faults (noise scale,
outliers, dropout; :mod:`usvsim.nav.torch_nav`, generated from the CasADi filter), the moving
vessels, the judge at every 0.1 s plant step against every disc, the reward, the horizon, the
``scene`` observation (:mod:`usvsim.task.torch_scene`) or the radar image of every disc with the
episode's radar degradation (:mod:`usvsim.task.torch_scene_radar`: the CPU image pixel for pixel,
from the same counter-based draws of each boat's frame key) and the restart of finished boats.
No host round trip (but an ``on_decision`` hook's, e.g. reactive targets) and no Python loop
over boats, discs or vessels per step.

Episodes are the CPU family's draws, packed on the host and copied to the device
(:mod:`usvsim.task.torch_openwater_episodes`): with the same seed the same episodes as the CPU
env (``per_boat`` per boat, then the table cycles). Where the table has weather (e.g.
``family=weather_family()`` or a weather stress set), every boat steps in the weather plant
(:mod:`usvsim.task.torch_weather`: wind, gusts, wave drift and first-order wave motion, the wave
filter, the sensors displaced by the waves), as the CPU batch does once an episode brings
weather; each episode's weather inputs are computed on the host when the table is packed.

One decision step of N boats (T = 20 plant steps of 0.1 s), as ``OpenWaterBatch.step``::

    ψ_ref  = ssa(ψ̂ + Δψ)                          ψ̂: estimated heading
    GNSS   : normals × scale (× outlier scale where z < Φ⁻¹(p)), fix flags × (not in dropout)
    T × [ plant step (autopilot, RK4, current; in weather: wind, waves, wave filter) ;
          sensors (+ wave motion) + Kalman filter ]
    judge  : every disc (vessels where they are) at every plant step: collision, goal,
             pole-equivalent distances |p − c| − R + 1 m
    reward : GaussianReward at the period's end (or the first goal / collision step)
    obs    : scene, from the estimate and the discs at the period's end
    restart: boats whose episode ended take their next table row

Noise: ``noise="device"`` draws the sensor normals, the outlier draws and the weather's
innovations from seeded ``torch.Generator`` s; ``noise="replay"`` (test mode) replays each
episode's NumPy streams (its ``noise_seed`` and its disturbance's ``seed``) number for number as
the CPU env draws them, reading the restarted boats back to the host every step.

Returns of :meth:`~TorchOpenWaterEnv.step`, tensors on the device: obs (N, 52) (``scene``,
``observation_dtype``; ``radar``: (N, 1, 50, 119) uint8; ``radar+goal``: a dict of the image and
the standardised goal (N, 2) float32), reward (N,), terminated (N,) bool, truncated (N,) bool,
info (the CPU env's per-boat entries as (N,) tensors, and ``final_obs``: every boat's
observation before the restarts).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Literal

import numpy as np
import torch

from usvsim.nav.torch_nav import started_nav_state, torch_ssa
from usvsim.task.colreg_reward import ColregRewardWeights
from usvsim.task.radar import RadarConfig
from usvsim.task.reward import GaussianReward
from usvsim.task.scenario import Scenario
from usvsim.task.scene_radar import MAX_DISCS
from usvsim.task.torch_colreg import TorchColregReward
from usvsim.task.torch_env import (
    ClosedLoop,
    check_options,
    compiled_substep,
    plant_and_filter,
    single_action_space,
    torch_heading_change,
)
from usvsim.task.torch_episodes import (
    DeviceNoise,
    NoiseSource,
    OutlierDraws,
    ReplayNoise,
    faulty_sensor_inputs,
    gnss_slots,
)
from usvsim.task.torch_observations import (
    TorchObservation,
    relative_polar_torch,
    select_rows,
    standardized_goal,
)
from usvsim.task.torch_openwater_episodes import OpenWaterTable, family_table
from usvsim.task.torch_scene import (
    TorchDiscs,
    fixed_horizon_torch,
    gaussian_reward_torch,
    judge_period_torch,
    nearest_and_hits_torch,
    positional_torch,
    scene_observation_torch,
)
from usvsim.task.torch_scene_radar import (
    FRAME_DRAWS,
    GOLDEN,
    SceneRadarGrid,
    render_scene_torch,
)
from usvsim.task.torch_weather import (
    compiled_weather_substep,
    weather_start_states,
    weather_substep,
)
from usvsim.vessel.torch_plant import DTYPES, load_weather_kernel

__all__ = ["TORCH_OPENWATER_OBSERVATIONS", "TorchOpenWaterEnv"]

#: The observation kinds the torch open-water env builds.
TORCH_OPENWATER_OBSERVATIONS = ("scene", "positional", "radar", "radar+goal")
_HORIZON_REF_S = 20_000.0  # s, OpenWaterVectorEnv's reference horizon K_ref · 2 s
Columns = tuple[torch.Tensor, ...]


class TorchOpenWaterEnv:
    """``num_envs`` boats on open-water episodes, stepped on a torch device (module docstring).

    Parameters
    ----------
    num_envs : int
    family : ScenarioMixture | OpenWaterScenario, optional
        Drawn at every ``reset(seed=...)`` as the CPU env draws (default ``OPEN_WATER_FAMILY``;
        needs the CPU family's modules, i.e. CasADi). Not with ``table``.
    table : OpenWaterTable, optional
        Fixed episodes (e.g. :func:`usvsim.task.torch_openwater_episodes.load_table`): boat i's
        k-th episode is row ``(i · per_boat + k) mod E``.
    per_boat : int
        Episodes per boat drawn at reset (``family``), or the row stride of ``table``.
    device : "torch-cpu" | "cuda" | "cuda:K"
    dtype : "float64" | "float32"
    action : "gaussian" | "categorical"
    observation : "scene" | "positional" | "radar" | "radar+goal"
    observation_dtype : "float32" | "float64"
        float32 as the CPU env; float64 keeps the simulation's numbers (tests).
    reward_horizon : "episode" | "fixed"
        As ``OpenWaterVectorEnv`` (``"fixed"``: each episode's own time limit against K_ref).
    gamma : float
    noise : "device" | "replay"
    scenario : Scenario, optional
        Decision period, plant step, goal radius, safety distance (default the study's).
    reward : GaussianReward, optional
    colreg_reward, info_observation ("scene"), on_decision : optional
        As ``OpenWaterVectorEnv``'s: the COLREG terms (:mod:`usvsim.task.torch_colreg`),
        ``info["observation_scene"]`` of the observation returned, and a hook with
        ``reset(env, boats)`` at restarts and ``steer(env, time_s)`` after the reward that may
        replace ``env.discs``' vessel motion (:mod:`usvsim.evaluation.torch_reactive`).
    compile : bool
        A plant + filter step through ``torch.compile`` (``compile_backend``; for a GPU).
    """

    def __init__(
        self,
        num_envs: int,
        *,
        family: Any = None,
        table: OpenWaterTable | None = None,
        per_boat: int = 8,
        device: str = "torch-cpu",
        dtype: str = "float64",
        action: Literal["gaussian", "categorical"] = "gaussian",
        observation: str = "scene",
        observation_dtype: str = "float32",
        reward_horizon: Literal["episode", "fixed"] = "episode",
        gamma: float = 0.99,
        noise: Literal["device", "replay"] = "device",
        scenario: Scenario | None = None,
        reward: GaussianReward | None = None,
        colreg_reward: ColregRewardWeights | None = None,
        on_decision: Any = None,
        info_observation: str | None = None,
        compile: bool = False,
        compile_backend: str = "inductor",
    ) -> None:
        check_options(num_envs, action, observation_dtype, noise)
        if observation not in TORCH_OPENWATER_OBSERVATIONS:
            raise ValueError(
                f"observation must be one of {TORCH_OPENWATER_OBSERVATIONS} on the torch "
                f"open-water env, got {observation!r}"
            )
        if reward_horizon not in ("episode", "fixed"):
            raise ValueError(f"reward_horizon must be 'episode' or 'fixed', got {reward_horizon!r}")
        if family is not None and table is not None:
            raise ValueError("give family or table, not both")
        if per_boat < 1:
            raise ValueError(f"per_boat must be >= 1, got {per_boat}")
        if info_observation not in (None, "scene"):
            raise ValueError(f"info_observation must be None or 'scene', got {info_observation!r}")
        self.reward = reward or GaussianReward()
        if not isinstance(self.reward, GaussianReward):
            raise ValueError("the torch open-water env computes the GaussianReward only")
        self.num_envs = n = num_envs
        self.action_kind, self.observation_kind = action, observation
        self.reward_horizon, self.gamma = reward_horizon, float(gamma)
        self.family, self._fixed_table, self.per_boat = family, table, per_boat
        self.scenario = sc = replace(scenario or Scenario(), area_radius_m=1e9)
        loop = ClosedLoop.build(sc, None, device, dtype)
        self.plant, self.nav, self.T, self.layout = loop.plant, loop.nav, loop.T, loop.layout
        self.device, self.dtype = self.plant.device, self.plant.dtype
        self.observation_dtype = DTYPES[observation_dtype]
        # the GNSS columns of a decision's normals, step by step (the CPU batch's gnss_index)
        self._gnss_slots = gnss_slots(self.layout)
        self._replay = noise == "replay"
        self.noise: NoiseSource = (ReplayNoise if self._replay else DeviceNoise)(
            n, self.device, self.dtype
        )
        self._outliers = OutlierDraws(n, self.device, self.dtype, self._replay)
        self._half_beam = self.plant.vessel.half_beam_m
        self._ref_decisions = replace(sc, time_limit_s=_HORIZON_REF_S).max_decisions
        self._steps = torch.arange(1, self.T + 1, device=self.device)
        self._rows = torch.arange(n, device=self.device)
        self._radar_grid = SceneRadarGrid(RadarConfig(), self.dtype, self.device)
        gains = torch.tensor(self.plant.kernel.gains, dtype=self.dtype, device=self.device)
        self._gains = tuple(gains.unbind(0))  # shared by all boats: 0-d tensors, built once
        self._substep = compiled_substep(compile_backend) if compile else plant_and_filter
        self._compile_backend = compile_backend if compile else None
        self._weather: Any = None  # the weather kernel, where the table has weather
        self._colreg_weights, self.on_decision = colreg_reward, on_decision
        self.info_observation = info_observation
        self._colreg: TorchColregReward | None = None  # built with the table (its vessel slots)
        self._ready = False

    # ----------------------------------------------------------------------------- tables
    def _upload(self, table: OpenWaterTable) -> None:
        """The table's arrays on the device, and each row's start state (plant, controller)."""
        self._table = table.on_device(self.device, self.dtype)
        self._weather = None
        if table.in_weather:
            self._weather = load_weather_kernel(self.plant.vessel, None, self.plant.dt_s)
        self._table_np = table
        most = int((table.statics_ok.sum(axis=1) + table.vessels_ok.sum(axis=1)).max())
        if most > MAX_DISCS:
            raise ValueError(f"a boat sees at most {MAX_DISCS} discs, an episode has {most}")
        self._degraded = bool((table.radar > 0).any())  # the table's images need draws
        start = self.plant.initial_state(table.start_eta, table.speed_mps)
        self._table["x0"], self._table["c0"] = start.x, start.c
        self._n_rows = table.n_episodes
        if self._colreg_weights is not None:
            slots = table.vessels.shape[1]
            self._colreg = TorchColregReward(
                self._colreg_weights, self.num_envs, slots, self.device, self.dtype
            )

    # ----------------------------------------------------------------------------- reset
    @torch.no_grad()
    def reset(self, *, seed: int | None = None) -> tuple[TorchObservation, dict[str, torch.Tensor]]:
        """Start every boat's first episode; ``seed`` seeds the episode draw (boat i from
        ``seed + i``, as the CPU env) and the device noise."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        if self._fixed_table is not None:
            if not self._ready:
                self._upload(self._fixed_table)
        else:
            from usvsim.task.openwater_env import OPEN_WATER_FAMILY

            family = OPEN_WATER_FAMILY if self.family is None else self.family
            self._upload(family_table(family, seed, self.num_envs, self.per_boat))
        self.noise.seed(seed)
        self._outliers.seed(seed)
        n, dev, dt = self.num_envs, self.device, self.dtype
        states = self.plant.kernel.ns + (0 if self._weather is None else self._weather.nws)
        self._s = torch.zeros((states, n), dtype=dt, device=dev)
        self._n = torch.zeros((15, n), dtype=dt, device=dev)
        self._row = torch.zeros(n, dtype=torch.int64, device=dev)
        self._started = torch.zeros(n, dtype=torch.int64, device=dev)
        self._n_dec = torch.zeros(n, dtype=torch.int64, device=dev)
        self._min_d = torch.zeros(n, dtype=dt, device=dev)
        self._t_goal = torch.zeros(n, dtype=dt, device=dev)
        self._frame = torch.zeros(n, dtype=torch.int64, device=dev)  # radar frames this episode
        self.discs = self._discs_of(self._row)
        everyone = torch.ones(n, dtype=torch.bool, device=dev)
        obs = self._restart(everyone, self._observe(advance=None))
        self._ready = True
        info = {"goal_ne": self._take("goal_ne").clone()}
        if self.info_observation is not None:
            info["observation_scene"] = self._scene()
        return obs, info

    def _take(self, name: str) -> torch.Tensor:
        """Table field ``name`` at every boat's current row."""
        return self._table[name][self._row]

    def _discs_of(self, rows: torch.Tensor) -> TorchDiscs:
        t = self._table
        st, ve = t["statics"][rows], t["vessels"][rows]
        return TorchDiscs(
            st[..., 0:2], st[..., 2], t["statics_ok"][rows],
            ve[..., 0:2], ve[..., 2], ve[..., 3], ve[..., 4], ve[..., 5], t["vessels_ok"][rows],
        )  # fmt: skip

    def _restart(self, boats: torch.Tensor, obs: TorchObservation) -> TorchObservation:
        """Start the next episode of ``boats`` (N,) bool; returns ``obs`` with those boats'
        rows their first observation."""
        t = self._table
        row = (self._rows * self.per_boat + self._started) % self._n_rows
        self._started += boats
        self._row = torch.where(boats, row, self._row)
        x0, c0 = t["x0"][row].T, t["c0"][row].T
        nav = started_nav_state(self.nav, x0, self.noise.fix_normals(boats, t["noise_seed"][row]))
        start = [x0, c0]
        if self._weather is not None:  # after the filter's draws, as the CPU batch
            z = self.noise.weather_normals(boats & t["windy"][row], 3)
            w_in = t["weather"][row].T
            start.append(
                weather_start_states(self._weather, x0, c0, w_in, t["weather_start"][row], z)
            )
        if self._replay:  # the host's copy of the rows, only where the streams are replayed
            rows = row.cpu().numpy()
            tab = self._table_np
            self._outliers.start(boats, tab.outlier_seed[rows], tab.gnss[rows, 5])
        self._s = torch.where(boats[None, :], torch.cat(start), self._s)
        self._n = torch.where(boats[None, :], nav, self._n)
        self.discs = self.discs.where(boats, self._discs_of(row))
        zero_t = torch.zeros((self.num_envs, 1), dtype=self.dtype, device=self.device)
        d0, _ = nearest_and_hits_torch(x0[0][:, None], x0[1][:, None], zero_t, self.discs, 1.0,
                                       self._half_beam)  # fmt: skip
        self._min_d = torch.where(boats, d0[:, 0], self._min_d)
        self._t_goal = torch.where(boats, math.inf, self._t_goal)
        self._n_dec = torch.where(boats, 0, self._n_dec)
        self._frame = torch.where(boats, 0, self._frame)
        if self._colreg is not None:
            self._colreg.reset(boats)
        if self.on_decision is not None:
            self.on_decision.reset(self, boats)
        return select_rows(boats, self._observe(advance=boats), obs)

    # ----------------------------------------------------------------------------- observe
    def _observe(self, advance: torch.Tensor | None) -> TorchObservation:
        """Every boat's observation from its estimate and the discs now; a radar image draws
        each boat's current frame, and the boats ``advance`` (N,) bool (None: none) move on to
        their next frame (``OpenWaterBatch._observe`` draws one frame per observation)."""
        if self.observation_kind == "scene":
            return self._scene()
        t_s = self._n_dec.to(self.dtype) * self.scenario.decision_period_s
        centres, _ = self.discs.at(t_s)
        pos, psi, goal = self._n[0:2].T, self._n[8], self._take("goal_ne")
        if self.observation_kind == "positional":
            obs = positional_torch(pos, psi, goal, centres, self.discs.radii_all, self.discs.ok_all)
            return obs.to(self.observation_dtype)
        r, b = relative_polar_torch(pos, psi, centres)
        degradation = keys = None
        if self._degraded:
            degradation = self._take("radar")
            keys = self._take("radar_base") + GOLDEN * (self._frame * FRAME_DRAWS)
        if advance is not None:
            self._frame = self._frame + advance
        image = render_scene_torch(
            r, b, self.discs.radii_all, self.discs.ok_all, self._radar_grid, degradation, keys
        )
        if self.observation_kind == "radar":
            return image
        r_g, b_g = relative_polar_torch(pos, psi, goal[:, None, :])
        return {"radar": image, "goal": standardized_goal(r_g[:, 0], b_g[:, 0])}

    def _scene(self) -> torch.Tensor:
        """Every boat's ``scene`` observation from its estimate and the discs now."""
        centres, velocity = self.discs.at(
            self._n_dec.to(self.dtype) * self.scenario.decision_period_s
        )
        obs = scene_observation_torch(
            self._n[0:2].T, self._n[8], self._n[2:4].T, self._take("goal_ne"), centres,
            self.discs.radii_all, velocity, self.discs.ok_all,
        )  # fmt: skip
        return obs.to(self.observation_dtype)

    # ----------------------------------------------------------------------------- step
    @torch.no_grad()
    def step(
        self, actions: Any
    ) -> tuple[TorchObservation, torch.Tensor, torch.Tensor, torch.Tensor, dict[str, Any]]:
        """One decision step of every boat, finished boats restarted (module docstring)."""
        if not self._ready:
            raise RuntimeError("call reset() before step()")
        sc, T = self.scenario, self.T
        dpsi = torch_heading_change(
            self.action_kind, actions, self.num_envs, sc.max_heading_change_rad, self.device,
            self.dtype,
        )  # fmt: skip
        cur = self._take("current")
        w: Columns = (torch_ssa(self._n[8] + dpsi), self._take("speed_mps"), cur[:, 0], cur[:, 1])
        t_plant = (self._n_dec.to(self.dtype) * sc.decision_period_s)[:, None] + (
            sc.dt_s * self._steps.to(self.dtype)
        )  # (N, T) episode time at each plant step
        es = faulty_sensor_inputs(
            self.layout, self._gnss_slots, self.noise.decision_normals(self.layout.draws),
            self._take("gnss"), self._outliers.normals(len(self._gnss_slots)), t_plant,
        )  # fmt: skip
        s, n = tuple(self._s.unbind(0)), tuple(self._n.unbind(0))
        xs, ys = [], []
        if self._weather is None:
            for j in range(T):  # the plant steps of one decision
                s, n = self._substep(self.plant.kernel.step, self.nav.step,
                                     self.plant.kernel.nx, s, n, w, self._gains, es[j])  # fmt: skip
                xs.append(s[0])
                ys.append(s[1])
        else:  # after the sensors' draws, as the CPU batch: gust, wave motion ×2 a step
            k = self._weather
            ew = self.noise.weather_normals(self._take("windy"), 3 * T).T
            w = (*w, *self._take("weather").T.unbind(0))
            step = (weather_substep if self._compile_backend is None
                    else compiled_weather_substep(self._compile_backend))  # fmt: skip
            for j in range(T):
                e_w = (ew[3 * j], ew[3 * j + 1], ew[3 * j + 2])
                s, n = step(k.step, k.sensed_offsets, self.nav.step, self.plant.kernel.nx, s, n,
                            w, self._gains, e_w, es[j])  # fmt: skip
                xs.append(s[0])
                ys.append(s[1])
        self._s, self._n = torch.stack(s), torch.stack(n)
        x_n, y_e = torch.stack(xs, 1), torch.stack(ys, 1)
        t_s = (self._n_dec[:, None] * T + self._steps[None, :]).to(self.dtype) * sc.dt_s
        goal = self._take("goal_ne")
        judged = judge_period_torch(x_n, y_e, t_s, self.discs, goal, 1.0, self._half_beam,
                                    sc.goal_radius_m)  # fmt: skip
        reached, collision = judged.reached_goal, judged.collision
        terminated = reached | collision
        self._min_d = torch.minimum(self._min_d, judged.nearest_m)
        first = (self._n_dec * T + judged.first_goal_step + 1).to(self.dtype) * sc.dt_s
        self._t_goal = torch.where(reached & torch.isinf(self._t_goal), first, self._t_goal)
        self._n_dec += 1
        end = judged.end_step[:, None]
        area = self._take("area")
        out_of_area = (
            torch.hypot(
                x_n.gather(1, end)[:, 0] - area[:, 0], y_e.gather(1, end)[:, 0] - area[:, 1]
            )
            > area[:, 2]
        )
        limit = self._take("time_limit_s")
        time_s = self._n_dec.to(self.dtype) * sc.decision_period_s
        time_limit = time_s >= limit - 1e-9
        truncated = (time_limit | out_of_area) & ~terminated
        r = self.reward
        pole, goal_term = gaussian_reward_torch(
            r.pole_weight, r.pole_sigma_m, r.goal_weight, r.goal_sigma_m,
            judged.distance_to_obstacle_m, judged.distance_to_goal_m,
        )  # fmt: skip
        reward, extra = pole + goal_term, dict[str, torch.Tensor]()
        if self._colreg is not None:
            start_s = time_s - sc.decision_period_s
            terms = self._colreg.of_period(x_n, y_e, judged.end_step, self.discs, start_s,
                                           sc.dt_s, sc.decision_period_s)  # fmt: skip
            reward = reward + terms["total"]
            extra = {f"reward_colreg_{k}": v for k, v in terms.items() if k != "total"}
            extra["reward_colreg"] = terms["total"]
        if self.reward_horizon == "fixed":
            reward, terminated, truncated = fixed_horizon_torch(
                reward, terminated, truncated, out_of_area, time_s, limit, self._ref_decisions,
                sc.decision_period_s, self.gamma,
            )  # fmt: skip
        if self.on_decision is not None:
            self.on_decision.steer(self, time_s)
        obs = self._observe(advance=torch.ones_like(terminated))
        info = {
            "final_obs": obs,
            "reward_pole": pole,
            "reward_goal": goal_term,
            "heading_change_rad": dpsi,
            "distance_to_obstacle_m": judged.distance_to_obstacle_m,
            "distance_to_goal_m": judged.distance_to_goal_m,
            "min_distance_m": self._min_d.clone(),
            "reached_goal": reached,
            "collision": collision,
            "out_of_area": out_of_area,
            "time_limit": time_limit,
            "is_success": reached & ~collision & (self._min_d >= sc.safety_distance_m),
            "time_s": time_s,
            "time_to_goal_s": self._t_goal.clone(),
            **extra,
        }
        obs = self._restart(terminated | truncated, obs)
        if self.info_observation is not None:  # of the observation returned (after restarts)
            info["observation_scene"] = self._scene()
        return obs, reward, terminated, truncated, info

    # ----------------------------------------------------------------------------- state
    @property
    def state(self) -> torch.Tensor:
        """True plant state [x, c] of all boats (N, 13) (never for observations)."""
        return self._s[: self.plant.kernel.ns].T.clone()

    @property
    def single_observation_space(self) -> Any:
        """The CPU env's single-boat observation space (gymnasium; see ``single_action_space``)."""
        from usvsim.task.observations import observation_space

        return observation_space(self.observation_kind)  # type: ignore[arg-type]

    @property
    def single_action_space(self) -> Any:
        return single_action_space(self.action_kind)

    @property
    def estimate(self) -> tuple[torch.Tensor, torch.Tensor]:
        """Navigation estimate now: position (N, 2) m and heading (N,) rad."""
        return self._n[0:2].T.clone(), self._n[8].clone()
