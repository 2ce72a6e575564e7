"""Plant and navigation filter fused into one compiled step: the environments' hot path.

Per boat and plant step, one CasADi Function runs the autopilot, the RK4 vessel step, then the
sensors and the Kalman filter on the new true state (:func:`usvsim.nav.compiled.build_nav_step`,
the same formulas as :class:`usvsim.nav.filter.Navigator`, which stays the reference and is
tested equal to filterpy). The sensor noise is drawn beforehand in NumPy, in the navigator's draw
order, so the fused path reproduces ``Plant.step`` followed by ``Navigator.run`` to rounding
(tested to 1e-9), at a fraction of the cost: no Python work per plant step.

State per boat (28): plant ``x`` (8), autopilot ``c`` (5), filter ``n`` (15,
:data:`usvsim.nav.compiled.NAV_STATE_FIELDS`), read by name through :data:`PACKED`.
:meth:`NavigatedPlant.run` steps this packed state directly (what the batch keeps between
decisions); :meth:`NavigatedPlant.step` takes and updates a
:class:`usvsim.vessel.plant.PlantState` and a :class:`usvsim.nav.filter.Navigator` instead.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ParamSpec, TypeVar

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.nav.compiled import (
    NAV_NS,
    NAV_STATE_FIELDS,
    build_nav_step,
    export_nav_state,
    import_nav_state,
    nav_draws_per_step,
    nav_noise_block,
)
from usvsim.nav.filter import Navigator
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import period_steps
from usvsim.vessel.codegen import BatchStepper, GatheredSteps
from usvsim.vessel.model import NX
from usvsim.vessel.plant import NS, Plant, PlantState
from usvsim.vessel.weather_plant import NWI, NWS, WeatherPlant, sensed_offsets_expr

__all__ = ["PACKED", "NavigatedPlant", "PackedLayout"]

FloatArray = NDArray[np.float64]
P = ParamSpec("P")
R = TypeVar("R")


def _arguments_of(source: Callable[P, object]) -> Callable[[Callable[..., R]], Callable[P, R]]:
    """Give a method that passes ``*args, **kwargs`` on to ``source`` the parameters of
    ``source`` for type checkers and ``help()``: they are written once, on ``source``."""

    def use(method: Callable[..., R]) -> Callable[P, R]:
        returns = inspect.signature(method).return_annotation
        method.__signature__ = inspect.signature(source).replace(  # type: ignore[attr-defined]
            return_annotation=returns
        )
        return method

    return use


@dataclass(frozen=True)
class PackedLayout:
    """Named column slices of the packed per-boat state ``[x, c, n]`` (N, ``size``).

    Attributes
    ----------
    plant : slice
        ``x``, the vessel's state (:data:`usvsim.vessel.model.NX` entries).
    controller : slice
        ``c``, the autopilot's state.
    closed_loop : slice
        ``[x, c]``, one :class:`usvsim.vessel.plant.PlantState` row
        (:data:`usvsim.vessel.plant.NS` entries).
    nav : slice
        ``n``, the filter state (:data:`usvsim.nav.compiled.NAV_STATE_FIELDS`).
    nav_pos : slice
        Estimated position ``[x_N, y_E]`` (m).
    nav_vel : slice
        Estimated velocity over ground ``[v_N, v_E]`` (m/s).
    nav_psi : int
        Estimated heading ψ (rad).
    size : int
        Entries per boat.
    weather : slice
        The weather states of :mod:`usvsim.vessel.weather_plant` (empty without weather),
        between the controller and the filter.
    """

    plant: slice
    controller: slice
    closed_loop: slice
    nav: slice
    nav_pos: slice
    nav_vel: slice
    nav_psi: int
    size: int
    weather: slice = field(default_factory=lambda: slice(NS, NS))

    @classmethod
    def build(cls, n_weather: int = 0) -> PackedLayout:
        """The layout of :class:`NavigatedPlant`: ``x`` (NX), ``c`` (NS − NX), the weather
        states (``n_weather``, 0 without weather), ``n`` (NAV_NS)."""
        base = NS + n_weather

        def nav(name: str) -> int:
            return base + NAV_STATE_FIELDS.index(name)

        return cls(
            plant=slice(0, NX),
            controller=slice(NX, NS),
            closed_loop=slice(0, NS),
            nav=slice(base, base + NAV_NS),
            nav_pos=slice(nav("p_n"), nav("p_e") + 1),
            nav_vel=slice(nav("w_n"), nav("w_e") + 1),
            nav_psi=nav("psi"),
            size=base + NAV_NS,
            weather=slice(NS, base),
        )


#: The packed state's layout, computed once.
PACKED = PackedLayout.build()


class NavigatedPlant:
    """``plant`` + ``navigator`` stepped together in compiled code.

    Parameters
    ----------
    plant : Plant
        The batched plant (its closed-loop step function is reused).
    nav_config : NavConfig
        The navigator's configuration (its ``dt_s`` must equal the plant's).
    weather : WeatherPlant, optional
        Step the boats in wind and waves instead (:mod:`usvsim.vessel.weather_plant`, built on
        the same ``plant``, with ``innovations="normal"``): the packed state gains the weather
        states (:attr:`layout`), :meth:`run` takes the per-boat weather inputs and three more
        standard normals per boat and step, and the filter's GNSS position, compass and gyro see
        the first-order wave motion (:func:`usvsim.vessel.weather_plant.sensed_offsets_expr`;
        the GNSS velocity does not).
    """

    def __init__(
        self, plant: Plant, nav_config: NavConfig, weather: WeatherPlant | None = None
    ) -> None:
        if abs(plant.dt_s - nav_config.dt_s) > 1e-12:
            raise ValueError(f"NavConfig.dt_s {nav_config.dt_s} != plant dt_s {plant.dt_s}")
        if weather is not None and weather.plant is not plant:
            raise ValueError("NavigatedPlant: the weather plant must be built on this plant")
        self.plant = plant
        self.nav_config = nav_config
        self.weather = weather
        self.layout = PACKED if weather is None else PackedLayout.build(NWS)
        nav_fn = build_nav_step(nav_config)
        lay = self.layout
        s = ca.SX.sym("s", lay.size)
        g = ca.SX.sym("g", plant.gains.size)
        if weather is None:
            w, e = ca.SX.sym("w", 4), ca.SX.sym("e", 8)
            s_plant = plant.step_function(s[PACKED.closed_loop], w, g)
            n_next = nav_fn(s[PACKED.nav], s_plant[PACKED.plant], e)
        else:
            w, e = ca.SX.sym("w", NWI), ca.SX.sym("e", 8 + 3)
            s_plant = weather.step_function(s[0 : lay.weather.stop], w, g, e[8:11])
            d = sensed_offsets_expr(s_plant, w)
            x = s_plant[lay.plant]
            sensed = ca.vertcat(x[0] + d[0], x[1] + d[1], x[2] + d[2], x[3], x[4], x[5] + d[3])
            n_next = nav_fn(s[lay.nav], ca.vertcat(sensed, x[6:8]), e[0:8])
        # noise layouts repeat with the sensor schedule: cache them per phase of the cycle
        self._cycle = int(
            np.lcm(
                period_steps(nav_config.sensors.gps_rate_hz, nav_config.dt_s),
                period_steps(nav_config.sensors.compass_rate_hz, nav_config.dt_s),
            )
        )
        self._layouts: dict[tuple[int, int], tuple[NDArray[np.int64], FloatArray, int]] = {}
        self.step_function = ca.Function(
            "usv_nav_step", [s, w, g, e], [ca.vertcat(s_plant, n_next)]
        )
        # with weather the environments read only [x, c] per step and the last packed state
        # (run_recorded: its driver copies NS states per step in a loop of constant length);
        # blocks of 16 boats, which help the weather plant alone, were slower here (N = 256)
        self._stepper = BatchStepper(
            self.step_function,
            backend="casadi" if plant.backend == "casadi" else "auto",
            record=None if weather is None else NS,
        )

    @property
    def backend(self) -> str:
        return self._stepper.backend

    def _layout(
        self, first_step_index: int, n_steps: int
    ) -> tuple[NDArray[np.int64], FloatArray, int]:
        """Cached layout of :func:`nav_noise_block` as :class:`GatheredSteps` index and factor
        (T, 8), and the number of normals per boat.

        Entry (j, k < 6) of the block is ``normals[:, index[j, k]] * factor[j, k]`` (factor 0
        where the sensor is silent, 1 where it fires); columns 6 and 7 are the constant firing
        flags (index -1, factor the flag).
        """
        key = (first_step_index % self._cycle, n_steps)
        layout = self._layouts.get(key)
        if layout is None:
            m = sum(
                nav_draws_per_step(self.nav_config, first_step_index + j)[2] for j in range(n_steps)
            )
            probe = np.arange(1.0, m + 1.0)[None, :]  # column c holds c + 1
            block = nav_noise_block(self.nav_config, first_step_index, n_steps, probe)[0]
            index = np.full((n_steps, 8), -1, dtype=np.int64)
            index[:, :6] = np.maximum(block[:, :6].astype(np.int64) - 1, 0)
            factor = np.concatenate([block[:, :6] > 0, block[:, 6:]], axis=1).astype(float)
            layout = self._layouts[key] = (index, factor, m)
        return layout

    def draws_needed(self, first_step_index: int, n_steps: int) -> int:
        """Standard normals each boat consumes over plant steps first..first + n_steps - 1."""
        return self._layout(first_step_index, n_steps)[2]

    def noise_steps(
        self, first_step_index: int, n_steps: int, normals: FloatArray
    ) -> GatheredSteps:
        """The per-step sensor noise and flags (N, n_steps, 8) of :func:`nav_noise_block` from
        ``normals`` (N, :meth:`draws_needed`), as a pool and the cached layout."""
        index, factor, m = self._layout(first_step_index, n_steps)
        if normals.ndim != 2 or normals.shape[1] != m:
            raise ValueError(
                f"expected {m} normals per boat for these steps, got array of shape {normals.shape}"
            )
        return GatheredSteps(normals, index, factor)

    def _inputs(
        self,
        s0: FloatArray,
        psi_ref_rad: FloatArray,
        speed_ref_mps: float | FloatArray,
        n_steps: int,
        first_step_index: int,
        normals: FloatArray,
        current: FloatArray | None = None,
        gnss_available: NDArray[np.bool_] | None = None,
        weather_inputs: FloatArray | None = None,
        weather_normals: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray, int, GatheredSteps]:
        """:meth:`run`'s arguments (documented there) checked, as the stepper's (s0, w, gains,
        n_steps, noise)."""
        psi_ref = np.asarray(psi_ref_rad, dtype=float)
        if not (np.all(np.isfinite(psi_ref)) and np.all(np.isfinite(speed_ref_mps))):
            raise ValueError("psi_ref_rad / speed_ref_mps contain NaN or inf")
        w = np.empty((psi_ref.shape[0], 4 if self.weather is None else NWI))
        w[:, 0], w[:, 1] = psi_ref, speed_ref_mps
        w[:, 2], w[:, 3] = self.plant.current
        if current is not None:
            w[:, 2:4] = current
        noise = self.noise_steps(first_step_index, n_steps, normals)
        if gnss_available is not None:
            noise = _with_gnss_mask(noise, np.asarray(gnss_available, dtype=bool))
        if self.weather is not None:
            if weather_inputs is None or weather_normals is None:
                raise ValueError(
                    "a weather NavigatedPlant needs weather_inputs and weather_normals"
                )
            w[:, 4:] = weather_inputs
            noise = _with_weather_normals(noise, np.asarray(weather_normals, dtype=float))
        elif weather_inputs is not None or weather_normals is not None:
            raise ValueError("weather_inputs / weather_normals given to a calm NavigatedPlant")
        return s0, w, self.plant.gains, n_steps, noise

    @_arguments_of(_inputs)
    def run(self, *args: Any, **kwargs: Any) -> FloatArray:
        """Advance packed states ``s0`` (N, 28) = [x, c, n] ``n_steps`` plant steps.

        Arguments ``(s0, psi_ref_rad, speed_ref_mps, n_steps, first_step_index, normals,
        current=None, gnss_available=None, weather_inputs=None, weather_normals=None)``.
        With weather (:attr:`weather`): ``s0`` is (N, :attr:`layout`.size) = [x, c, m, n],
        ``weather_inputs`` (N, 33) each boat's per-episode weather
        (:attr:`usvsim.vessel.weather_plant.WeatherPlantState.inputs`) and ``weather_normals``
        (N, 3 n_steps) its next standard normals (gust, wave motion ×2 per step).

        ``psi_ref_rad`` (N,) rad and ``speed_ref_mps`` (m/s, all boats or (N,)) are held over
        the steps; ``normals`` (N, :meth:`draws_needed`) are each boat's next standard normals,
        in :meth:`Navigator.step` order. ``current`` (N, 2): [speed m/s, direction rad] per boat
        (default: the plant's, for all); ``gnss_available`` (N, n_steps) bool: False silences a
        boat's GNSS fix at that step (a dropout; default: every scheduled fix arrives). Returns
        the packed states after each step, (N, T, 28).
        """
        return self._stepper.run(*self._inputs(*args, **kwargs))

    @_arguments_of(_inputs)
    def run_recorded(self, *args: Any, **kwargs: Any) -> tuple[FloatArray, FloatArray]:
        """As :meth:`run` (the same arguments, the same numbers), writing only ``[x, c]`` per
        step: the closed-loop trajectory (N, T, 13) and the last packed state
        (N, :attr:`layout`.size)."""
        return self._stepper.run_recorded(*self._inputs(*args, **kwargs), NS)

    def step(
        self,
        state: PlantState,
        navigator: Navigator,
        psi_ref_rad: FloatArray,
        speed_ref_mps: FloatArray | float,
        n_steps: int,
        first_step_index: int,
        normals: FloatArray,
    ) -> tuple[PlantState, FloatArray, Any]:
        """Advance plant and filter ``n_steps`` steps; the navigator is updated in place.

        ``normals`` (N, :meth:`draws_needed`) are each boat's next standard normals, in the
        order :meth:`Navigator.step` would draw them. Returns the new plant state, the plant
        trajectory (N, n_steps, 13) and the filter states (N, n_steps, 15) after each step.
        """
        if self.weather is not None:
            raise ValueError("NavigatedPlant.step is the calm path; with weather use run()")
        n = state.n_boats
        psi_ref = np.broadcast_to(np.asarray(psi_ref_rad, dtype=float), (n,))
        speed = np.broadcast_to(np.asarray(speed_ref_mps, dtype=float), (n,))
        if not (np.all(np.isfinite(psi_ref)) and np.all(np.isfinite(speed))):
            raise ValueError("psi_ref_rad / speed_ref_mps contain NaN or inf")
        w = np.empty((n, 4))
        w[:, 0], w[:, 1] = psi_ref, speed
        w[:, 2], w[:, 3] = self.plant.current
        s0 = np.concatenate([state.x, state.c, export_nav_state(navigator)], axis=1)
        noise = self.noise_steps(first_step_index, n_steps, normals)
        traj = self._stepper.run(s0, w, self.plant.gains, n_steps, noise)
        last = traj[:, -1]
        import_nav_state(navigator, last[:, PACKED.nav])
        new_state = PlantState(x=last[:, PACKED.plant].copy(), c=last[:, PACKED.controller].copy())
        return new_state, traj[:, :, PACKED.closed_loop], traj[:, :, PACKED.nav]


def _with_weather_normals(noise: GatheredSteps, normals: FloatArray) -> GatheredSteps:
    """``noise`` (T, 8 columns) with three more per step read from ``normals`` (N, 3 T),
    appended to the pool: the weather step's innovations."""
    n, m = noise.pool.shape
    n_steps = noise.index.shape[0]
    if normals.shape != (n, 3 * n_steps):
        raise ValueError(f"weather_normals must have shape {(n, 3 * n_steps)}, got {normals.shape}")
    pool = np.concatenate([noise.pool, normals], axis=1)
    extra = m + np.arange(3 * n_steps, dtype=np.int64).reshape(n_steps, 3)
    index = np.concatenate([noise.index, extra], axis=1)
    factor = np.concatenate([noise.factor, np.ones((n_steps, 3))], axis=1)
    return GatheredSteps(pool, index, factor)


def _with_gnss_mask(noise: GatheredSteps, available: NDArray[np.bool_]) -> GatheredSteps:
    """``noise`` with each boat's GNSS firing flag (column 6) times ``available`` (N, T).

    The flag becomes a pool entry (appended columns holding 0 or 1) instead of a constant, so the
    compiled step reads it per boat.
    """
    n, m = noise.pool.shape
    n_steps = noise.index.shape[0]
    if available.shape != (n, n_steps):
        raise ValueError(f"gnss_available must have shape {(n, n_steps)}, got {available.shape}")
    pool = np.concatenate([noise.pool, available.astype(np.float64)], axis=1)
    index, factor = noise.index.copy(), noise.factor.copy()
    index[:, 6] = m + np.arange(n_steps)
    return GatheredSteps(pool, index, factor)
