"""The batched plant: vessel model + heading autopilot + speed control, N boats per call.

One plant step (dt_s, default 0.1 s) of one boat is the CasADi Function built by
:func:`build_closed_loop_step`: the digital autopilot samples the state, computes the actuator
command (held over the step), then the vessel ODE is integrated with one RK4 step. The batched
path (:class:`usvsim.vessel.codegen.BatchStepper`) evaluates exactly this function for all boats.

Shapes (N boats, T steps):

===============  ============  ==========================================================
name             shape         content
===============  ============  ==========================================================
state.x          (N, 8)        [x_N, y_E, ψ, u, v, r, a1, a2] (see :mod:`usvsim.vessel.model`)
state.c          (N, 5)        controller state (see :mod:`usvsim.vessel.autopilot`)
psi_ref_rad      (N,)          heading reference (rad)
speed_ref_mps    (N,)          surge speed reference (m/s)
trajectory       (N, T, 13)    [x, c] after each step
===============  ============  ==========================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.common.angles import ssa, ssa_casadi
from usvsim.vessel.autopilot import (
    NC,
    NG,
    AutopilotConfig,
    AutopilotDesign,
    AutopilotKind,
    control_law,
    design_autopilot,
    initial_controller_state,
)
from usvsim.vessel.codegen import Backend, BatchStepper
from usvsim.vessel.model import NX, build_dynamics, rk4_expr, surge_trim
from usvsim.vessel.sx_eval import numpy_function
from usvsim.vessel.vessels import VesselParams, get_vessel

__all__ = ["NS", "Plant", "PlantState", "build_closed_loop_step"]

NS = NX + NC  # closed-loop state size per boat


def build_closed_loop_step(vessel: VesselParams, kind: AutopilotKind, dt_s: float) -> ca.Function:
    """``step(s[13], w[4], g[NG]) -> s_next[13]``: autopilot update then one RK4 plant step.

    ``s = [x, c]``; ``w = [ψ_ref (rad), U_ref (m/s), V_c (m/s), β_c (rad)]`` per boat;
    ``g`` the autopilot gains (:meth:`AutopilotDesign.gains_vector`).
    """
    f = build_dynamics(vessel)
    s = ca.SX.sym("s", NS)
    w = ca.SX.sym("w", 4)
    g = ca.SX.sym("g", NG)
    x, c = s[:NX], s[NX:]
    a_cmd, c_next = control_law(vessel, kind, x, c, w[0:2], g, dt_s)
    x_next = rk4_expr(f, x, a_cmd, w[2:4], dt_s)
    x_next[2] = ssa_casadi(x_next[2])
    return ca.Function(
        "usv_cl_step", [s, w, g], [ca.vertcat(x_next, c_next)], ["s", "w", "g"], ["s_next"]
    )


@dataclass(frozen=True)
class PlantState:
    """State of N boats: plant ``x`` (N, 8) and autopilot ``c`` (N, 5)."""

    x: NDArray[np.float64]
    c: NDArray[np.float64]

    @property
    def eta(self) -> NDArray[np.float64]:
        """[x_N, y_E, ψ] (N, 3) in m, m, rad."""
        return self.x[:, 0:3]

    @property
    def nu(self) -> NDArray[np.float64]:
        """[u, v, r] (N, 3) in m/s, m/s, rad/s."""
        return self.x[:, 3:6]

    @property
    def n_boats(self) -> int:
        return int(self.x.shape[0])


def _as_vector(name: str, value: ArrayLike, n: int) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have shape ({n},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf: {arr[~np.isfinite(arr)][:5]}")
    return arr


class Plant:
    """N boats of one vessel type with their autopilots, stepped together.

    Parameters
    ----------
    vessel : VesselParams or str
        A vessel or the name of a preset (:func:`usvsim.vessel.vessels.get_vessel`).
    autopilot : AutopilotConfig, optional
        Design choices; default :class:`AutopilotConfig` (PID at the vessel's cruise speed).
    dt_s : float
        Plant step (s), default 0.1.
    current : (speed m/s, direction rad)
        Irrotational ocean current in NED, direction it flows towards; default none.
    backend : "auto" | "compiled" | "casadi"
        Fast path (see :mod:`usvsim.vessel.codegen`).
    """

    def __init__(
        self,
        vessel: VesselParams | str = "default",
        autopilot: AutopilotConfig | None = None,
        dt_s: float = 0.1,
        current: tuple[float, float] = (0.0, 0.0),
        backend: Backend = "auto",
    ) -> None:
        self.vessel = get_vessel(vessel) if isinstance(vessel, str) else vessel
        if not (np.isfinite(dt_s) and 0 < dt_s <= 1.0):
            raise ValueError(f"dt_s must be in (0, 1] s, got {dt_s}")
        if len(current) != 2 or not np.all(np.isfinite(current)) or current[0] < 0:
            raise ValueError(f"current must be (speed >= 0 m/s, direction rad), got {current}")
        self.dt_s = float(dt_s)
        self.current = (float(current[0]), float(current[1]))
        self.design: AutopilotDesign = design_autopilot(self.vessel, autopilot)
        self.kind: AutopilotKind = self.design.config.kind
        self.step_function = build_closed_loop_step(self.vessel, self.kind, self.dt_s)
        self.gains = self.design.gains_vector()
        self._stepper = BatchStepper(self.step_function, backend)
        u = ca.SX.sym("u")
        self._surge_drag = ca.Function("drag", [u], [surge_trim(self.vessel, u)])
        # the same numbers for a handful of boats without a CasADi call (usvsim.vessel.sx_eval)
        self._surge_drag_numpy = numpy_function(self._surge_drag)
        self._trim_a1: dict[float, float] = {}  # surge trim per speed (m/s), see trim_actuator

    @property
    def backend(self) -> str:
        """The fast path in use: ``compiled`` or ``casadi``."""
        return self._stepper.backend

    @property
    def kernel(self) -> str:
        """The kernel in use: ``soa``, ``scalar`` (compiled) or ``casadi``."""
        return self._stepper.kernel

    @property
    def cruise_speed_mps(self) -> float:
        """The design speed: the autopilot config's, else the vessel's (m/s)."""
        return self.design.cruise_speed_mps

    def trim_actuator(self, speed_mps: NDArray[np.float64]) -> NDArray[np.float64]:
        """Actuator values (N, 2) that hold surge speed ``speed_mps`` (N,) on a straight course.

        Batches reset boats at one speed over and over: a speed seen before is looked up instead
        of evaluating the drag again (an element-wise function: the same numbers either way).
        """
        speed = np.asarray(speed_mps, dtype=float)
        a1: NDArray[np.float64]
        first = float(speed[0]) if speed.size else 0.0
        if first in self._trim_a1 and np.all(speed == first):
            a1 = np.full(speed.shape, self._trim_a1[first])
        elif first != 0.0 and np.all(speed == first) and len(self._trim_a1) < 16:
            # ±0 excluded: a dict cannot tell them apart
            self._trim_a1[first] = float(np.asarray(self._surge_drag(first)).item())
            a1 = np.full(speed.shape, self._trim_a1[first])
        elif self._surge_drag_numpy is not None:
            a1 = self._surge_drag_numpy(speed)
        else:
            # a function of one scalar called with a (1, N) row evaluates element-wise
            a1 = np.asarray(self._surge_drag(speed[None, :])).ravel()
        act = self.vessel.actuation
        return np.stack([np.clip(a1, act.a1_min, act.a1_max), np.zeros_like(a1)], axis=1)

    def initial_state(self, eta: ArrayLike, speed_mps: ArrayLike | None = None) -> PlantState:
        """Boats at poses ``eta`` (N, 3) [m, m, rad] moving straight ahead at ``speed_mps``."""
        eta = np.asarray(eta, dtype=float)
        if eta.ndim != 2 or eta.shape[1] != 3:
            raise ValueError(f"eta must have shape (N, 3), got {eta.shape}")
        if not np.all(np.isfinite(eta)):
            raise ValueError("eta contains NaN or inf")
        n = eta.shape[0]
        speed = _as_vector(
            "speed_mps", self.cruise_speed_mps if speed_mps is None else speed_mps, n
        )
        x = np.zeros((n, NX))
        x[:, 0:2] = eta[:, 0:2]
        x[:, 2] = ssa(eta[:, 2])
        x[:, 3] = speed
        x[:, 6:8] = self.trim_actuator(speed)
        return PlantState(x=x, c=initial_controller_state(self.kind, x[:, 2], x[:, 5]))

    def step(
        self,
        state: PlantState,
        psi_ref_rad: ArrayLike,
        speed_ref_mps: ArrayLike | None = None,
        n_steps: int = 1,
    ) -> tuple[PlantState, NDArray[np.float64]]:
        """Advance all boats ``n_steps`` plant steps with references held constant.

        Returns the new state and the trajectory (N, n_steps, 13) of [x, c] after each step.
        """
        n = state.n_boats
        if state.x.shape != (n, NX) or state.c.shape != (n, NC):
            raise ValueError(
                f"state arrays must be (N, {NX}) and (N, {NC}), got "
                f"{state.x.shape} and {state.c.shape}"
            )
        if not (np.all(np.isfinite(state.x)) and np.all(np.isfinite(state.c))):
            raise ValueError("plant state contains NaN or inf")
        if not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
            raise ValueError(f"n_steps must be a positive integer, got {n_steps!r}")
        psi_ref = _as_vector("psi_ref_rad", psi_ref_rad, n)
        speed = _as_vector(
            "speed_ref_mps", self.cruise_speed_mps if speed_ref_mps is None else speed_ref_mps, n
        )
        w = np.empty((n, 4))
        w[:, 0] = psi_ref
        w[:, 1] = speed
        w[:, 2] = self.current[0]
        w[:, 3] = self.current[1]
        s0 = np.concatenate([state.x, state.c], axis=1)
        traj = self._stepper.run(s0, w, self.gains, int(n_steps))
        last = traj[:, -1, :]
        return PlantState(x=last[:, :NX].copy(), c=last[:, NX:].copy()), traj
