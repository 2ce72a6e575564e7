"""The vessel in wind and waves with its actuators commanded directly (no usvsim autopilot).

:class:`usvsim.vessel.weather_plant.WeatherPlant` closes the loop with usvsim's heading
autopilot inside its compiled step. A vehicle whose actuators are commanded from outside (an
ArduPilot SITL frame in ``usvsim sitl-physics``, motors off in ``usvsim sitl``) needs the same
weather open loop: :class:`OpenLoopWeather` steps N boats by one RK4 step of the vessel model
(:func:`usvsim.vessel.model.build_dynamics` with ``weather``) with the command held and the
environmental load τ_env (wind excess + wave drift, :mod:`usvsim.vessel.weather.loads`)
evaluated at the step's start and held over it, as the weather plant does; then advances the
gust and the first-order wave motion with the weather plant's exact discretisation, read from the
same per-boat inputs (:func:`usvsim.vessel.weather_plant.weather_inputs`: ``gust_a``,
``gust_gain``, Φ and L at the step ``dt_s``), driven by standard normals of the caller's
generator. The wave filter's states (the autopilot's, unused open loop) restart on the compass
and gyro, as at :meth:`WeatherPlant.initial_state`, so the autopilot can take over after it.

Shapes: plant states ``x`` (N, 8), weather states ``m`` (N, 8) (:data:`WEATHER_STATES`),
inputs (N, 33) (:data:`WEATHER_INPUTS` from ``wind_mean``), commands (N, 2).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.vessel.model import NX, build_dynamics, rk4_expr
from usvsim.vessel.vessels import VesselParams
from usvsim.vessel.weather.loads import (
    USV105_HULL,
    WeatherHull,
    relative_drift_loads,
    relative_trig,
    relative_wind_loads,
)
from usvsim.vessel.weather.observer import OBSERVER_STATES
from usvsim.vessel.weather_plant import WEATHER_INPUTS, sensed_offsets

__all__ = ["OpenLoopWeather"]

_COL = {name: i - 4 for i, name in enumerate(WEATHER_INPUTS)}  # columns of the inputs (N, 33)
# what the step function reads of them, in this order
_LOAD_INPUTS = ("wind_cos", "wind_sin", "drift_pressure", "wave_cos", "wave_sin")


class OpenLoopWeather:
    """One open-loop step of N boats of ``vessel`` over ``dt_s`` in their weather (module
    docstring); ``hull`` the windage and waterline (default usv105's, as the weather plant)."""

    def __init__(self, vessel: VesselParams, dt_s: float, hull: WeatherHull = USV105_HULL) -> None:
        self.vessel = vessel
        self.dt_s = float(dt_s)
        x, a = ca.SX.sym("x", NX), ca.SX.sym("a", 2)
        current, wind = ca.SX.sym("current", 2), ca.SX.sym("wind")  # [V_c, β_c]; V_w ≥ 0 m/s
        q = ca.SX.sym("q", len(_LOAD_INPUTS))
        trig = (ca.cos(x[2]), ca.sin(x[2]))
        tau = relative_wind_loads(
            hull, x[3:6], wind, *relative_trig(q[0], q[1], *trig)
        ) + relative_drift_loads(hull, q[2], *relative_trig(q[3], q[4], *trig))
        f = build_dynamics(vessel, weather=True)
        x_next = rk4_expr(f, x, a, ca.vertcat(current, tau), self.dt_s)
        self._step = ca.Function("open_loop_weather", [x, a, current, wind, q], [x_next])
        self._maps: dict[int, ca.Function] = {1: self._step}  # N boats per call

    def step(
        self,
        x: NDArray[np.float64],
        a_cmd: NDArray[np.float64],
        current: tuple[float, float],
        m: NDArray[np.float64],
        inputs: NDArray[np.float64],
        rng: np.random.Generator,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(x_next, m_next) after one step; ``current`` (m/s, rad towards); ``inputs`` built
        for this step ``dt_s`` (their Φ, L and gust factors are per step). ψ is not wrapped
        (as :func:`usvsim.vessel.model.build_rk4_step`)."""
        n = x.shape[0]
        wind = np.maximum(inputs[:, _COL["wind_mean"]] + m[:, 0], 0.0)
        q = inputs[:, [_COL[k] for k in _LOAD_INPUTS]]
        cur = np.broadcast_to(np.asarray(current, dtype=float)[:, None], (2, n))
        if n not in self._maps:
            self._maps[n] = self._step.map(n)
        x_next = np.asarray(self._maps[n](x.T, a_cmd.T, cur, wind[None, :], q.T)).T
        e = rng.standard_normal((n, 3))
        col = {k: inputs[:, _COL[k]] for k in ("gust_a", "gust_gain", "l00", "l10", "l11")}
        phi = [inputs[:, _COL[k]] for k in ("phi00", "phi01", "phi10", "phi11")]
        m_next = np.zeros_like(m)
        m_next[:, 0] = col["gust_a"] * m[:, 0] + col["gust_gain"] * e[:, 0]
        m_next[:, 1] = phi[0] * m[:, 1] + phi[1] * m[:, 2] + col["l00"] * e[:, 1]
        m_next[:, 2] = phi[2] * m[:, 1] + phi[3] * m[:, 2] + col["l10"] * e[:, 1]
        m_next[:, 2] += col["l11"] * e[:, 2]
        # the wave filter restarts on the compass and gyro (WeatherPlant.initial_state)
        sensed = sensed_offsets(x_next, m_next, inputs)
        obs = {k: 3 + i for i, k in enumerate(OBSERVER_STATES)}
        m_next[:, obs["psi"]] = x_next[:, 2] + sensed[:, 2]
        m_next[:, obs["r"]] = x_next[:, 5]
        return x_next, m_next
