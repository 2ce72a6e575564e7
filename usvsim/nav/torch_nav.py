"""The navigation filter on a torch device: sensors and Kalman filter of N boats, generated.

The filter step is :mod:`usvsim.nav.torch_nav_kernel`, generated from the CasADi twin of
:class:`usvsim.nav.filter.Navigator` (:func:`usvsim.nav.compiled.build_nav_step`) by
:mod:`usvsim.nav.torch_nav_codegen`, so the formulas stay defined once. This module adds what the
batched torch environment needs around it, each tested equal to its NumPy original:

- :func:`noise_layout`: which standard normal feeds which sensor at each plant step of a
  decision (:func:`usvsim.nav.compiled.nav_noise_block`'s order: gyro, then GNSS position and
  velocity where a fix arrives, then the compass where it reads);
- :func:`started_nav_state`: a started filter from the first fix
  (:func:`usvsim.nav.compiled.started_nav_rows` / :func:`usvsim.nav.start.first_fix`, the same
  seven draws per boat in the same order: GNSS (2), compass, velocity (2), gyro bias, gyro).

It imports without CasADi, SciPy or filterpy (the default configuration's kernel is committed);
another :class:`usvsim.nav.models.NavConfig` is generated in memory, which needs CasADi.

Shapes (N boats, T plant steps per decision, M normals per boat and decision):

==============  ==========  ===============================================================
name            shape       content
==============  ==========  ===============================================================
nav state       (15, N)     :data:`usvsim.nav.compiled.NAV_STATE_FIELDS`, one row per field
normals         (N, M)      standard normals, each boat's next M in draw order
fix normals     (N, 7)      the first fix's standard normals
==============  ==========  ===============================================================
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import torch

from usvsim.common.errors import UserError

__all__ = [
    "FIX_DRAWS",
    "NoiseLayout",
    "TorchNavKernel",
    "load_nav_kernel",
    "nav_config_fingerprint",
    "noise_layout",
    "started_nav_state",
    "torch_ssa",
]

#: Standard normals of a first fix per boat: GNSS (2), compass, velocity (2), gyro bias, gyro.
FIX_DRAWS = 7


def torch_ssa(angle_rad: torch.Tensor) -> torch.Tensor:
    """:func:`usvsim.common.angles.ssa` on tensors: ``remainder(a + π, 2π) − π`` (torch's
    ``remainder`` is NumPy's ``mod`` bit for bit), in [-π, π)."""
    return torch.remainder(angle_rad + math.pi, 2.0 * math.pi) - math.pi


def nav_config_fingerprint(cfg: object) -> str:
    """A short hash of every number of a :class:`usvsim.nav.models.NavConfig` (its repr): the
    committed kernel is used only for a configuration with the same numbers."""
    return hashlib.sha256(repr(cfg).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class TorchNavKernel:
    """The generated filter step and the configuration's numbers it comes with."""

    step: Callable[..., tuple[torch.Tensor, ...]]  # nav_step(n[15], x[8], e[8]) -> n_next[15]
    dt_s: float  # s, plant step
    gps_period_steps: int
    compass_period_steps: int
    gnss_velocity: bool
    gps_sigma_m: float
    compass_sigma_rad: float
    gyro_sigma_radps: float
    gyro_bias_sigma_radps: float
    init_vel_sigma_mps: float
    start_variances: tuple[float, float, float, float]  # m², (m/s)², rad², (rad/s)²
    origin: str  # "committed" (torch_nav_kernel) or "generated" (in memory, by CasADi)

    @classmethod
    def from_module(cls, module: ModuleType | dict[str, Any], origin: str) -> TorchNavKernel:
        ns = module if isinstance(module, dict) else vars(module)
        return cls(
            step=ns["nav_step"],
            dt_s=ns["DT_S"],
            gps_period_steps=ns["GPS_PERIOD_STEPS"],
            compass_period_steps=ns["COMPASS_PERIOD_STEPS"],
            gnss_velocity=ns["GNSS_VELOCITY"],
            gps_sigma_m=ns["GPS_SIGMA_M"],
            compass_sigma_rad=ns["COMPASS_SIGMA_RAD"],
            gyro_sigma_radps=ns["GYRO_SIGMA_RADPS"],
            gyro_bias_sigma_radps=ns["GYRO_BIAS_SIGMA_RADPS"],
            init_vel_sigma_mps=ns["INIT_VEL_SIGMA_MPS"],
            start_variances=tuple(ns["START_VARIANCES"]),
            origin=origin,
        )

    @property
    def cycle_steps(self) -> int:
        """Plant steps after which the sensor schedule repeats."""
        return math.lcm(self.gps_period_steps, self.compass_period_steps)


def load_nav_kernel(cfg: object | None = None) -> TorchNavKernel:
    """The torch filter of ``cfg`` (a :class:`usvsim.nav.models.NavConfig`; None: the default):
    the committed kernel where the numbers are the default's, else generated in memory.

    Raises :class:`UserError` where it needs generating and CasADi is not installed.
    """
    from usvsim.nav import torch_nav_kernel as committed

    if cfg is None or nav_config_fingerprint(cfg) == committed.NAV_CONFIG_FINGERPRINT:
        return TorchNavKernel.from_module(committed, "committed")
    try:
        from usvsim.nav.torch_nav_codegen import nav_kernel_source
    except ModuleNotFoundError as err:
        raise UserError(
            f"the torch navigation filter of a non-default NavConfig is generated from the "
            f"CasADi filter, and {err.name} is not installed; without it only the default "
            f"NavConfig runs"
        ) from None
    namespace: dict[str, Any] = {"__name__": "usvsim_torch_nav_kernel"}
    exec(compile(nav_kernel_source(cfg), "<torch nav kernel>", "exec"), namespace)  # type: ignore[arg-type]
    return TorchNavKernel.from_module(namespace, "generated")


@dataclass(frozen=True)
class NoiseLayout:
    """Where each plant step of a decision takes its sensor noise from.

    ``index[j, k]`` is the column of the decision's normals (N, ``draws``) that feeds entry k of
    step j's noise vector (gyro, gps_n, gps_e, vel_n, vel_e, compass), -1 where that sensor is
    silent (the entry is 0); ``gps[j]`` / ``compass[j]`` say whether the sensor fires.
    """

    index: tuple[tuple[int, ...], ...]  # (T, 6)
    gps: tuple[bool, ...]  # (T,)
    compass: tuple[bool, ...]  # (T,)
    draws: int  # M: normals per boat and decision

    def step_inputs(self, normals: torch.Tensor) -> list[tuple[torch.Tensor | float, ...]]:
        """The filter's ``e`` (8 entries) of each step from ``normals`` (N, M): columns of
        ``normals``, a 0-d zero where a sensor is silent, 0-d firing flags."""
        zero = normals.new_zeros(())
        one = normals.new_ones(())
        out = []
        for j, cols in enumerate(self.index):
            e: list[torch.Tensor | float] = [normals[:, c] if c >= 0 else zero for c in cols]
            e += [one if self.gps[j] else zero, one if self.compass[j] else zero]
            out.append(tuple(e))
        return out


def noise_layout(kernel: TorchNavKernel, first_step_index: int, n_steps: int) -> NoiseLayout:
    """The layout of plant steps ``first_step_index`` … ``+ n_steps − 1`` (sensors fire at steps
    0, p, 2p, … of the clock, :func:`usvsim.nav.sensors.sensor_fires`)."""
    index, gps_on, compass_on = [], [], []
    col = 0
    for j in range(n_steps):  # a loop over the steps of a decision, never over boats
        k = first_step_index + j
        gps = k % kernel.gps_period_steps == 0
        compass = k % kernel.compass_period_steps == 0
        row = [col, -1, -1, -1, -1, -1]
        col += 1
        if gps:
            row[1:3] = [col, col + 1]
            col += 2
            if kernel.gnss_velocity:
                row[3:5] = [col, col + 1]
                col += 2
        if compass:
            row[5] = col
            col += 1
        index.append(tuple(row))
        gps_on.append(gps)
        compass_on.append(compass)
    return NoiseLayout(tuple(index), tuple(gps_on), tuple(compass_on), col)


def started_nav_state(
    kernel: TorchNavKernel, x: torch.Tensor, fix_normals: torch.Tensor
) -> torch.Tensor:
    """Started filters (15, N) of boats at true plant states ``x`` (8, N) from the first fix's
    standard normals ``fix_normals`` (N, 7) (:data:`FIX_DRAWS`, in :func:`usvsim.nav.start.
    first_fix`'s order), as :func:`usvsim.nav.compiled.started_nav_rows`: position a GNSS fix,
    velocity ``R(ψ)[u, v]`` plus noise, heading a compass reading, a new true gyro bias and
    the first gyro reading; cross terms and the bias estimate 0."""
    z = fix_normals.T
    psi, u, v, r = x[2], x[3], x[4], x[5]
    cos, sin = torch.cos(psi), torch.sin(psi)
    out = x.new_zeros((15, x.shape[1]))
    out[0] = x[0] + (0.0 + kernel.gps_sigma_m * z[0])
    out[1] = x[1] + (0.0 + kernel.gps_sigma_m * z[1])
    out[8] = torch_ssa(psi + (0.0 + kernel.compass_sigma_rad * z[2]))
    # (u + i v) e^{iψ} as NumPy's complex product, then the Doppler noise
    out[2] = (u * cos - v * sin) + (0.0 + kernel.init_vel_sigma_mps * z[3])
    out[3] = (u * sin + v * cos) + (0.0 + kernel.init_vel_sigma_mps * z[4])
    var_p, var_v, var_c, var_b = kernel.start_variances
    out[4], out[7], out[10], out[12] = var_p, var_v, var_c, var_b
    bias = 0.0 + kernel.gyro_bias_sigma_radps * z[5]
    out[13] = bias
    out[14] = r + bias + (0.0 + kernel.gyro_sigma_radps * z[6])
    return out
