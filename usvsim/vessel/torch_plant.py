"""The batched plant on a torch device: the same closed-loop step as the C kernel, generated.

:class:`TorchPlant` steps N boats with the torch code that :mod:`usvsim.vessel.torch_codegen`
generates from the CasADi plant (:func:`usvsim.vessel.plant.build_closed_loop_step`: autopilot and
speed control, then one RK4 step of the vessel with actuators and current): the integrator, the
order of operations and the constants are the C kernel's, so on ``torch-cpu`` in float64 the
trajectories equal :class:`usvsim.vessel.plant.Plant`'s to rounding (tested over 1,000 steps:
positions within 1e-6 m, headings within 1e-8 rad). It imports without CasADi: the default plant
(``default`` vessel, default PID, 0.1 s) comes from the committed
:mod:`usvsim.vessel.torch_default_kernel`; another vessel, autopilot or step is generated in
memory, which needs CasADi.

``device`` (:data:`DEVICES`) selects the backend: ``"cpu"`` is today's compiled C path
(:func:`make_plant` returns a :class:`usvsim.vessel.plant.Plant`), ``"torch-cpu"`` torch on the
CPU (for tests), ``"cuda"`` (or ``"cuda:K"``) a GPU; without one, a :class:`UserError` that
names the problem. ``dtype`` is ``"float64"`` (the default: the C kernel's numbers) or
``"float32"``.

Shapes (N boats, T steps), tensors on the plant's device and dtype:

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

import hashlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
from numpy.typing import ArrayLike

from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.vessel.vessels import VesselParams, get_vessel

if TYPE_CHECKING:
    from usvsim.vessel.plant import Plant

__all__ = [
    "DEVICES",
    "DTYPES",
    "TorchKernel",
    "TorchPlant",
    "TorchPlantState",
    "TorchWeatherKernel",
    "load_kernel",
    "load_weather_kernel",
    "make_plant",
    "torch_device",
    "vessel_fingerprint",
]

#: ``cpu``: the compiled C kernel; ``torch-cpu``: torch on the CPU; ``cuda``: torch on a GPU.
DEVICES = ("cpu", "torch-cpu", "cuda")
DTYPES = {"float64": torch.float64, "float32": torch.float32}

Columns = tuple[torch.Tensor, ...]


def torch_device(device: str) -> torch.device:
    """The torch device of ``device`` (``torch-cpu``, ``cuda`` or ``cuda:K``).

    Raises :class:`UserError` (one line) for ``cuda`` where torch sees no GPU, and for a name
    that is not a torch backend of :data:`DEVICES`.
    """
    if device == "torch-cpu":
        return torch.device("cpu")
    if device == "cuda" or device.startswith("cuda:"):
        if not torch.cuda.is_available():
            built = "built without CUDA" if torch.version.cuda is None else "no GPU visible"
            raise UserError(
                f"device {device!r} needs a CUDA GPU, but torch.cuda.is_available() is False "
                f"(torch {torch.__version__}, {built}); use device cpu or torch-cpu"
            )
        index = device.partition(":")[2]
        if index and not (index.isdigit() and int(index) < torch.cuda.device_count()):
            raise UserError(
                f"device {device!r}: no such GPU; torch sees {torch.cuda.device_count()} "
                f"(cuda:0 to cuda:{torch.cuda.device_count() - 1})"
            )
        return torch.device(device)
    raise UserError(f"device must be one of {', '.join(DEVICES)} (or cuda:K), got {device!r}")


@dataclass(frozen=True)
class TorchKernel:
    """The generated torch functions of one plant and the numbers they need."""

    step: Callable[..., Columns]  # closed_loop_step(s[13], w[4], g[25]) -> s_next[13]
    surge_drag: Callable[..., Columns]  # surge_drag(u[1]) -> drag (N) at surge speed u (m/s)
    gains: tuple[float, ...]  # the autopilot design's gains vector
    kind: str  # autopilot: "pid" or "rover"
    dt_s: float  # s, plant step
    cruise_speed_mps: float  # m/s, the design speed (default speed reference)
    nx: int  # plant state size
    ns: int  # closed-loop state size
    origin: str  # "committed" (torch_default_kernel) or "generated" (in memory, by CasADi)

    @classmethod
    def from_module(cls, module: ModuleType | dict[str, Any], origin: str) -> TorchKernel:
        """The kernel of a generated module (or the namespace its source was run in)."""
        ns = module if isinstance(module, dict) else vars(module)
        return cls(
            step=ns["closed_loop_step"],
            surge_drag=ns["surge_drag"],
            gains=tuple(ns["GAINS"]),
            kind=ns["AUTOPILOT"],
            dt_s=ns["DT_S"],
            cruise_speed_mps=ns["CRUISE_SPEED_MPS"],
            nx=ns["NX"],
            ns=ns["NS"],
            origin=origin,
        )


def load_kernel(
    vessel: VesselParams | str = "default", autopilot: Any = None, dt_s: float = 0.1
) -> TorchKernel:
    """The torch kernel of the plant: the committed one for the default plant (vessel parameters
    unchanged since it was generated, default autopilot, step 0.1 s), else generated in memory
    from the CasADi plant (``autopilot`` an :class:`usvsim.vessel.autopilot.AutopilotConfig`).

    Raises :class:`UserError` where the plant needs generating and CasADi is not installed.
    """
    from usvsim.vessel import torch_default_kernel as committed

    vessel = get_vessel(vessel) if isinstance(vessel, str) else vessel
    fingerprint = vessel_fingerprint(vessel)
    if autopilot is None and dt_s == committed.DT_S:
        if fingerprint == committed.VESSEL_FINGERPRINT:
            return TorchKernel.from_module(committed, "committed")
    try:
        from usvsim.vessel.torch_codegen import kernel_source
    except ModuleNotFoundError as err:
        raise UserError(
            f"the torch plant of vessel {vessel.name!r} with this autopilot and step "
            f"{dt_s:g} s is generated from the CasADi model, and {err.name} is not installed; "
            f"without it only the default plant ({committed.VESSEL}, the default "
            f"{committed.AUTOPILOT} autopilot, {committed.DT_S:g} s) runs"
        ) from None
    namespace: dict[str, Any] = {"__name__": f"usvsim_torch_kernel_{vessel.name}"}
    source = kernel_source(vessel, autopilot, dt_s)
    exec(compile(source, f"<torch kernel of {vessel.name}>", "exec"), namespace)
    return TorchKernel.from_module(namespace, "generated")


@dataclass(frozen=True)
class TorchWeatherKernel:
    """The generated torch weather step of one plant (:mod:`usvsim.vessel.weather_plant` with
    standard-normal innovations) and the sensors' wave offsets."""

    step: Callable[..., Columns]  # weather_step(s[21], w[37], g[25], e[3]) -> s_next[21]
    sensed_offsets: Callable[..., Columns]  # sensed_offsets(s[21], w[37]) -> [dn, de, dpsi, dr]
    nwi: int  # per-boat inputs
    nws: int  # weather states after the closed loop's
    origin: str  # "committed" (torch_default_weather_kernel) or "generated" (by CasADi)


def load_weather_kernel(
    vessel: VesselParams | str = "default", autopilot: Any = None, dt_s: float = 0.1
) -> TorchWeatherKernel:
    """The torch weather step of the plant, as :func:`load_kernel`: the committed module for the
    default plant, else generated in memory (CasADi needed; else a one-line :class:`UserError`)."""
    from usvsim.vessel import torch_default_weather_kernel as committed

    vessel = get_vessel(vessel) if isinstance(vessel, str) else vessel
    ns: dict[str, Any] = vars(committed)
    origin = "committed"
    if not (
        autopilot is None
        and dt_s == committed.DT_S
        and vessel_fingerprint(vessel) == committed.VESSEL_FINGERPRINT
    ):
        try:
            from usvsim.vessel.torch_codegen import weather_kernel_source
        except ModuleNotFoundError as err:
            raise UserError(
                f"the torch weather plant of vessel {vessel.name!r} with this autopilot and step "
                f"{dt_s:g} s is generated from the CasADi model, and {err.name} is not "
                f"installed; without it only the default plant ({committed.VESSEL}, the default "
                f"{committed.AUTOPILOT} autopilot, {committed.DT_S:g} s) runs in weather"
            ) from None
        ns = {"__name__": f"usvsim_torch_weather_kernel_{vessel.name}"}
        source = weather_kernel_source(vessel, autopilot, dt_s)
        exec(compile(source, f"<torch weather kernel of {vessel.name}>", "exec"), ns)
        origin = "generated"
    return TorchWeatherKernel(
        ns["weather_step"], ns["sensed_offsets"], ns["NWI"], ns["NWS"], origin
    )


def vessel_fingerprint(vessel: VesselParams) -> str:
    """A short hash of every parameter of ``vessel`` (its repr): a committed kernel generated for
    it is used only while the registry's vessel has the same parameters."""
    return hashlib.sha256(repr(vessel).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class TorchPlantState:
    """State of N boats on the plant's device: plant ``x`` (N, 8) and autopilot ``c`` (N, 5)."""

    x: torch.Tensor
    c: torch.Tensor

    @property
    def eta(self) -> torch.Tensor:
        """[x_N, y_E, ψ] (N, 3) in m, m, rad."""
        return self.x[:, 0:3]

    @property
    def nu(self) -> torch.Tensor:
        """[u, v, r] (N, 3) in m/s, m/s, rad/s."""
        return self.x[:, 3:6]

    @property
    def n_boats(self) -> int:
        return int(self.x.shape[0])


class TorchPlant:
    """N boats of one vessel type with their autopilots, stepped together by torch.

    Parameters
    ----------
    vessel : VesselParams or str
        A vessel or the name of a preset (:func:`usvsim.vessel.vessels.get_vessel`).
    autopilot : AutopilotConfig, optional
        Design choices; default the default PID (a non-default one needs CasADi).
    dt_s : float
        Plant step (s), default 0.1.
    current : (speed m/s, direction rad)
        Irrotational ocean current in NED, direction it flows towards; default none.
    device : "torch-cpu" | "cuda" | "cuda:K"
        Where the tensors live (:func:`torch_device`).
    dtype : "float64" | "float32"
        Number type of the state and the arithmetic.
    compile : bool
        Wrap the step in ``torch.compile`` (one fused kernel per step on a GPU; the first call
        compiles, which takes seconds to minutes).
    """

    def __init__(
        self,
        vessel: VesselParams | str = "default",
        autopilot: Any = None,
        dt_s: float = 0.1,
        current: tuple[float, float] = (0.0, 0.0),
        device: str = "torch-cpu",
        dtype: str = "float64",
        compile: bool = False,
    ) -> None:
        if dtype not in DTYPES:
            raise UserError(f"dtype must be one of {', '.join(DTYPES)}, got {dtype!r}")
        if not (math.isfinite(dt_s) and 0 < dt_s <= 1.0):
            raise ValueError(f"dt_s must be in (0, 1] s, got {dt_s}")
        if len(current) != 2 or not np.all(np.isfinite(current)) or current[0] < 0:
            raise ValueError(f"current must be (speed >= 0 m/s, direction rad), got {current}")
        self.device = torch_device(device)
        self.dtype = DTYPES[dtype]
        self.vessel = get_vessel(vessel) if isinstance(vessel, str) else vessel
        self.kernel = load_kernel(self.vessel, autopilot, float(dt_s))
        self.dt_s = float(dt_s)
        self.current = (float(current[0]), float(current[1]))
        self.kind = self.kernel.kind
        # numbers shared by all boats: 0-d tensors (broadcast), built once
        self._gains = self._shared(self.kernel.gains)
        self._current = self._shared(self.current)
        self.step_function: Callable[..., Columns] = self.kernel.step
        if compile:
            self.step_function = torch.compile(self.kernel.step, dynamic=True)

    def _shared(self, values: Sequence[float]) -> Columns:
        return tuple(torch.tensor(list(values), dtype=self.dtype, device=self.device).unbind(0))

    def _tensor(self, name: str, value: ArrayLike | torch.Tensor, n: int) -> torch.Tensor:
        """``value`` (a number or (n,)) as an (n,) tensor on the device; numbers from the host
        are checked finite (a tensor already on a GPU is not: that would wait for the GPU)."""
        if isinstance(value, torch.Tensor):
            t = value.to(device=self.device, dtype=self.dtype)
        else:
            arr = np.asarray(value, dtype=float)
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name} contains NaN or inf")
            t = torch.as_tensor(arr, dtype=self.dtype, device=self.device)
        if t.ndim == 0:
            t = t.expand(n)
        if t.shape != (n,):
            raise ValueError(f"{name} must be a scalar or have shape ({n},), got {tuple(t.shape)}")
        return t

    @property
    def backend(self) -> str:
        """``torch-cpu`` or the CUDA device's name (``cuda:0``)."""
        return "torch-cpu" if self.device.type == "cpu" else str(self.device)

    @property
    def cruise_speed_mps(self) -> float:
        """The design speed (m/s): the default speed reference."""
        return self.kernel.cruise_speed_mps

    def trim_actuator(self, speed_mps: ArrayLike | torch.Tensor) -> torch.Tensor:
        """Actuator values (N, 2) that hold surge speed ``speed_mps`` (N,) on a straight course:
        the surge drag as thrust, clipped to the actuator's limits, nozzle (or side force) 0."""
        n = speed_mps.numel() if isinstance(speed_mps, torch.Tensor) else np.size(speed_mps)
        speed = self._tensor("speed_mps", speed_mps, int(n))
        (drag,) = self.kernel.surge_drag((speed,))
        act = self.vessel.actuation
        a1 = drag.clamp(act.a1_min, act.a1_max)
        return torch.stack([a1, torch.zeros_like(a1)], dim=1)

    def initial_state(
        self, eta: ArrayLike | torch.Tensor, speed_mps: ArrayLike | torch.Tensor | None = None
    ) -> TorchPlantState:
        """Boats at poses ``eta`` (N, 3) [m, m, rad] moving straight ahead at ``speed_mps``."""
        eta_arr = np.asarray(eta.cpu() if isinstance(eta, torch.Tensor) else eta, dtype=float)
        if eta_arr.ndim != 2 or eta_arr.shape[1] != 3:
            raise ValueError(f"eta must have shape (N, 3), got {eta_arr.shape}")
        if not np.all(np.isfinite(eta_arr)):
            raise ValueError("eta contains NaN or inf")
        n = eta_arr.shape[0]
        speed = self._tensor(
            "speed_mps", self.cruise_speed_mps if speed_mps is None else speed_mps, n
        )
        x = torch.zeros((n, self.kernel.nx), dtype=self.dtype, device=self.device)
        x[:, 0:2] = torch.as_tensor(eta_arr[:, 0:2], dtype=self.dtype, device=self.device)
        psi = torch.as_tensor(ssa(eta_arr[:, 2]), dtype=self.dtype, device=self.device)
        x[:, 2] = psi
        x[:, 3] = speed
        x[:, 6:8] = self.trim_actuator(speed)
        # the controller state of usvsim.vessel.autopilot.initial_controller_state (tested equal)
        c = torch.zeros((n, self.kernel.ns - self.kernel.nx), dtype=self.dtype, device=self.device)
        if self.kind == "pid":
            c[:, 0] = psi
            c[:, 1] = x[:, 5]
        return TorchPlantState(x=x, c=c)

    def advance(
        self, s: Columns, w: Columns, n_steps: int, trajectory: torch.Tensor | None = None
    ) -> Columns:
        """``n_steps`` plant steps of state columns ``s`` (13 tensors (N,)) under the per-boat
        inputs ``w``: (ψ_ref rad, U_ref m/s), the plant's current for all boats, or (ψ_ref, U_ref,
        V_c m/s, β_c rad), a current per boat (each an (N,) tensor or a 0-d one shared by all);
        ``trajectory[:, k]`` (N, n_steps, 13), if given, receives the state after step k. No
        checks: the fast path for batches (environments, benchmarks)."""
        inputs = (*w, *self._current) if len(w) == 2 else tuple(w)
        for k in range(n_steps):
            s = self.step_function(s, inputs, self._gains)
            if trajectory is not None:
                trajectory[:, k, :] = torch.stack(s, dim=1)
        return s

    def step(
        self,
        state: TorchPlantState,
        psi_ref_rad: ArrayLike | torch.Tensor,
        speed_ref_mps: ArrayLike | torch.Tensor | None = None,
        n_steps: int = 1,
        trajectory: bool = True,
    ) -> tuple[TorchPlantState, torch.Tensor | None]:
        """Advance all boats ``n_steps`` plant steps with references held constant.

        Returns the new state and the trajectory (N, n_steps, 13) of [x, c] after each step
        (None with ``trajectory=False``), as :meth:`usvsim.vessel.plant.Plant.step` does.
        """
        n, nx, ns = state.n_boats, self.kernel.nx, self.kernel.ns
        if tuple(state.x.shape) != (n, nx) or tuple(state.c.shape) != (n, ns - nx):
            raise ValueError(
                f"state tensors must be (N, {nx}) and (N, {ns - nx}), got "
                f"{tuple(state.x.shape)} and {tuple(state.c.shape)}"
            )
        if not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
            raise ValueError(f"n_steps must be a positive integer, got {n_steps!r}")
        psi_ref = self._tensor("psi_ref_rad", psi_ref_rad, n)
        speed = self._tensor(
            "speed_ref_mps", self.cruise_speed_mps if speed_ref_mps is None else speed_ref_mps, n
        )
        s0 = torch.cat([state.x, state.c], dim=1).to(device=self.device, dtype=self.dtype)
        columns = tuple(col.contiguous() for col in s0.unbind(1))
        traj = None
        if trajectory:
            traj = torch.empty((n, int(n_steps), ns), dtype=self.dtype, device=self.device)
        last = torch.stack(self.advance(columns, (psi_ref, speed), int(n_steps), traj), dim=1)
        return TorchPlantState(x=last[:, :nx], c=last[:, nx:]), traj


def make_plant(
    device: str = "cpu",
    vessel: VesselParams | str = "default",
    autopilot: Any = None,
    dt_s: float = 0.1,
    current: tuple[float, float] = (0.0, 0.0),
    dtype: str = "float64",
) -> Plant | TorchPlant:
    """The plant on ``device`` (:data:`DEVICES`): ``cpu`` the compiled C
    :class:`usvsim.vessel.plant.Plant` (float64 only), else a :class:`TorchPlant`."""
    if device == "cpu":
        if dtype != "float64":
            raise UserError(f"device cpu (the C kernel) runs float64 only, got dtype {dtype!r}")
        from usvsim.vessel.plant import Plant

        return Plant(vessel, autopilot=autopilot, dt_s=dt_s, current=current)
    return TorchPlant(vessel, autopilot, dt_s, current, device=device, dtype=dtype)
