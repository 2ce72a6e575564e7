"""Torch code of the navigation filter, generated from its CasADi twin (the filter stays defined
once).

:func:`nav_kernel_source` writes a module with :func:`usvsim.nav.compiled.build_nav_step` (sensors
and the Kalman filter of one plant step: gyro, GNSS position and Doppler velocity, compass;
the same formulas, in the same order, as :class:`usvsim.nav.filter.Navigator`) as batched torch
code, one statement per CasADi instruction (:func:`usvsim.vessel.torch_codegen.
torch_function_source`), and the numbers of the :class:`usvsim.nav.models.NavConfig` that the
batched torch environment needs besides the step (sensor periods and noise, start variances).
The module needs torch only, so the GPU path imports without CasADi, SciPy or filterpy.

The default configuration's module is committed as :mod:`usvsim.nav.torch_nav_kernel`;
``python -m usvsim.nav.torch_nav_codegen`` rewrites it, and a test checks that it equals what
this module writes today. Another configuration is generated in memory
(:func:`usvsim.nav.torch_nav.load_nav_kernel`), which needs CasADi.
"""

from __future__ import annotations

from pathlib import Path

from usvsim.nav.compiled import NAV_STATE_FIELDS, build_nav_step
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import period_steps
from usvsim.nav.start import start_variances
from usvsim.nav.torch_nav import nav_config_fingerprint
from usvsim.vessel.torch_codegen import torch_function_source

__all__ = [
    "DEFAULT_NAV_KERNEL_PATH",
    "default_nav_kernel_source",
    "nav_kernel_source",
]

#: Where the default configuration's generated module lives (committed).
DEFAULT_NAV_KERNEL_PATH = Path(__file__).with_name("torch_nav_kernel.py")

_HEADER = '''"""GENERATED from the CasADi navigation filter (:mod:`usvsim.nav.torch_nav_codegen`).

Do not edit.

Configuration: {config_name} (fingerprint {fingerprint}). :func:`nav_step` is
:func:`usvsim.nav.compiled.build_nav_step` (gyro, GNSS position and velocity, compass, and the
Kalman filter of one plant step), one torch statement per CasADi instruction; the constants are
the configuration's numbers that the batched torch environment needs besides the step. Needs
torch only.

Why this module is long: it is generated, one statement per instruction of the CasADi filter.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

NAV_CONFIG_FINGERPRINT = "{fingerprint}"
DT_S = {dt_s!r}  # s, plant step
GPS_PERIOD_STEPS = {gps_period}  # plant steps between GNSS fixes
COMPASS_PERIOD_STEPS = {compass_period}  # plant steps between compass readings
GNSS_VELOCITY = {gnss_velocity}  # a Doppler velocity with each GNSS fix
GPS_SIGMA_M = {gps_sigma!r}  # m, GNSS position noise per axis
COMPASS_SIGMA_RAD = {compass_sigma!r}  # rad, compass noise
GYRO_SIGMA_RADPS = {gyro_sigma!r}  # rad/s, gyro noise per sample
GYRO_BIAS_SIGMA_RADPS = {bias_sigma!r}  # rad/s, the turn-on gyro bias drawn per episode
INIT_VEL_SIGMA_MPS = {init_vel_sigma!r}  # m/s, the first fix's velocity noise per axis
# a started filter's variances: position m², velocity (m/s)², heading rad², gyro bias (rad/s)²
START_VARIANCES = {start_variances!r}
NAV_STATE_FIELDS = (
{fields}
)

'''


def nav_kernel_source(cfg: NavConfig) -> str:
    """The torch module (Python source) of the filter of ``cfg`` (module docstring)."""
    s = cfg.sensors
    header = _HEADER.format(
        config_name="the default NavConfig" if cfg == NavConfig() else repr(cfg),
        fingerprint=nav_config_fingerprint(cfg),
        dt_s=float(cfg.dt_s),
        gps_period=period_steps(s.gps_rate_hz, cfg.dt_s),
        compass_period=period_steps(s.compass_rate_hz, cfg.dt_s),
        gnss_velocity=bool(cfg.gnss_velocity),
        gps_sigma=float(s.gps_sigma_m),
        compass_sigma=float(s.compass_sigma_rad),
        gyro_sigma=float(s.gyro_sigma_radps),
        bias_sigma=float(s.gyro_bias_sigma_radps),
        init_vel_sigma=float(cfg.init_vel_sigma_mps),
        start_variances=tuple(float(v) for v in start_variances(cfg)),
        fields="\n".join(f'    "{name}",' for name in NAV_STATE_FIELDS),
    )
    doc = (
        "Sensors and Kalman filter of one plant step, N boats: n[15] (NAV_STATE_FIELDS),\n"
        "    x[8] (the plant state after the step), e[8] (standard normals gyro, gps_n, gps_e,\n"
        "    vel_n, vel_e, compass, then the GNSS and compass firing flags) -> n_next[15]."
    )
    return header + "\n" + torch_function_source(build_nav_step(cfg), "nav_step", doc)


def default_nav_kernel_source() -> str:
    """The committed module's text: the default :class:`NavConfig`."""
    return nav_kernel_source(NavConfig())


def main() -> None:
    """Rewrite :data:`DEFAULT_NAV_KERNEL_PATH` from the CasADi filter."""
    DEFAULT_NAV_KERNEL_PATH.write_text(default_nav_kernel_source())
    print(f"wrote {DEFAULT_NAV_KERNEL_PATH}")


if __name__ == "__main__":
    main()
