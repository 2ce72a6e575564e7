"""GENERATED from the CasADi navigation filter (:mod:`usvsim.nav.torch_nav_codegen`).

Do not edit.

Configuration: the default NavConfig (fingerprint 3fe1429a5f11f37c). :func:`nav_step` is
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

NAV_CONFIG_FINGERPRINT = "3fe1429a5f11f37c"
DT_S = 0.1  # s, plant step
GPS_PERIOD_STEPS = 2  # plant steps between GNSS fixes
COMPASS_PERIOD_STEPS = 1  # plant steps between compass readings
GNSS_VELOCITY = True  # a Doppler velocity with each GNSS fix
GPS_SIGMA_M = 1.5  # m, GNSS position noise per axis
COMPASS_SIGMA_RAD = 0.017453292519943295  # rad, compass noise
GYRO_SIGMA_RADPS = 0.0017453292519943296  # rad/s, gyro noise per sample
GYRO_BIAS_SIGMA_RADPS = 0.0008726646259971648  # rad/s, the turn-on gyro bias drawn per episode
INIT_VEL_SIGMA_MPS = 0.1  # m/s, the first fix's velocity noise per axis
# a started filter's variances: position m², velocity (m/s)², heading rad², gyro bias (rad/s)²
START_VARIANCES = (2.25, 0.010000000000000002, 0.00030461741978670857, 7.615435494667715e-07)
NAV_STATE_FIELDS = (
    "p_n",
    "p_e",
    "w_n",
    "w_e",
    "L_pp",
    "L_pw_re",
    "L_pw_im",
    "L_ww",
    "psi",
    "b",
    "P_psi",
    "P_pb",
    "P_b",
    "gyro_bias",
    "yaw_rate",
)


def nav_step(n: Sequence[Any], x: Sequence[Any], e: Sequence[Any]) -> tuple[torch.Tensor, ...]:
    """Sensors and Kalman filter of one plant step, N boats: n[15] (NAV_STATE_FIELDS),
    x[8] (the plant state after the step), e[8] (standard normals gyro, gps_n, gps_e,
    vel_n, vel_e, compass, then the GNSS and compass firing flags) -> n_next[15]."""
    _ref = n[0]
    _dtype = _ref.dtype

    def _full(value: float) -> torch.Tensor:
        return torch.full_like(_ref, value)

    v1 = e[6]
    v1 = 0.5 < v1
    v2 = n[0]
    v5 = x[5]
    v6 = n[13]
    v5 = v5 + v6
    v8 = e[0]
    v7 = 0.0017453292519943296 * v8
    v5 = v5 + v7
    v7 = n[9]
    v8 = v5 - v7
    v4 = 0.05 * v8
    v9 = v4 != 0.0
    v10 = torch.sin(v4)
    v11 = v10 / v4
    v11 = torch.where(v9, v11, 0.0)
    v9 = ~v9
    v9 = torch.where(v9, _full(1.0), 0.0)
    v11 = v11 + v9
    v11 = 0.1 * v11
    v4 = torch.cos(v4)
    v9 = v11 * v4
    v13 = n[2]
    v14 = v9 * v13
    v11 = v11 * v10
    v15 = n[3]
    v16 = v11 * v15
    v14 = v14 - v16
    v2 = v2 + v14
    v14 = n[4]
    v16 = n[5]
    v17 = n[7]
    v18 = v9 * v17
    v18 = v16 + v18
    v16 = v16 + v18
    v16 = v9 * v16
    v19 = n[6]
    v20 = v11 * v17
    v20 = v19 + v20
    v19 = v19 + v20
    v19 = v11 * v19
    v16 = v16 + v19
    v14 = v14 + v16
    v14 = v14 + 6.250000000000001e-06
    v19 = v14 + 2.25
    v21 = v14 / v19
    v22 = x[0]
    v24 = e[1]
    v24 = 1.5 * v24
    v22 = v22 + v24
    v22 = v22 - v2
    v24 = v21 * v22
    v24 = v2 + v24
    v24 = torch.where(v1, v24, 0.0)
    v25 = ~v1
    v2 = torch.where(v25, v2, 0.0)
    v24 = v24 + v2
    v2 = v4 * v4
    v26 = v10 * v10
    v2 = v2 - v26
    v26 = v18 * v2
    v4 = v4 * v10
    v4 = 2.0 * v4
    v10 = v20 * v4
    v26 = v26 + v10
    v26 = v26 + 0.00012500000000000003
    v10 = 1.0 - v21
    v27 = v26 * v10
    v27 = torch.where(v1, v27, 0.0)
    v28 = torch.where(v25, v26, 0.0)
    v27 = v27 + v28
    v17 = v17 + 0.0025000000000000005
    v28 = v26 / v19
    v26 = v28 * v26
    v20 = v20 * v2
    v18 = v18 * v4
    v20 = v20 - v18
    v19 = v20 / v19
    v18 = v19 * v20
    v26 = v26 + v18
    v26 = v17 - v26
    v26 = torch.where(v1, v26, 0.0)
    v17 = torch.where(v25, v17, 0.0)
    v26 = v26 + v17
    v18 = v26 + 0.010000000000000002
    v29 = v27 / v18
    v30 = x[3]
    v31 = x[2]
    v32 = torch.cos(v31)
    v33 = v30 * v32
    v34 = x[4]
    v35 = torch.sin(v31)
    v36 = v34 * v35
    v33 = v33 - v36
    v36 = e[3]
    v36 = 0.1 * v36
    v33 = v33 + v36
    v36 = v2 * v13
    v37 = v4 * v15
    v36 = v36 - v37
    v37 = v28 * v22
    v38 = x[1]
    v39 = e[2]
    v23 = 1.5 * v39
    v38 = v38 + v23
    v23 = n[1]
    v9 = v9 * v15
    v11 = v11 * v13
    v9 = v9 + v11
    v23 = v23 + v9
    v38 = v38 - v23
    v9 = v19 * v38
    v37 = v37 + v9
    v37 = v36 + v37
    v37 = torch.where(v1, v37, 0.0)
    v36 = torch.where(v25, v36, 0.0)
    v37 = v37 + v36
    v33 = v33 - v37
    v36 = v29 * v33
    v10 = v20 * v10
    v10 = torch.where(v1, v10, 0.0)
    v20 = torch.where(v25, v20, 0.0)
    v10 = v10 + v20
    v20 = v10 / v18
    v30 = v30 * v35
    v34 = v34 * v32
    v30 = v30 + v34
    v34 = e[4]
    v34 = 0.1 * v34
    v30 = v30 + v34
    v2 = v2 * v15
    v4 = v4 * v13
    v2 = v2 + v4
    v28 = v28 * v38
    v19 = v19 * v22
    v28 = v28 - v19
    v28 = v2 + v28
    v28 = torch.where(v1, v28, 0.0)
    v2 = torch.where(v25, v2, 0.0)
    v28 = v28 + v2
    v30 = v30 - v28
    v2 = v20 * v30
    v36 = v36 - v2
    v36 = v24 + v36
    v36 = torch.where(v1, v36, 0.0)
    v24 = torch.where(v25, v24, 0.0)
    v36 = v36 + v24
    o0 = v36
    v38 = v21 * v38
    v38 = v23 + v38
    v38 = torch.where(v1, v38, 0.0)
    v23 = torch.where(v25, v23, 0.0)
    v38 = v38 + v23
    v23 = v29 * v30
    v36 = v20 * v33
    v23 = v23 + v36
    v23 = v38 + v23
    v23 = torch.where(v1, v23, 0.0)
    v38 = torch.where(v25, v38, 0.0)
    v23 = v23 + v38
    o1 = v23
    v18 = v26 / v18
    v33 = v18 * v33
    v33 = v37 + v33
    v33 = torch.where(v1, v33, 0.0)
    v37 = torch.where(v25, v37, 0.0)
    v33 = v33 + v37
    o2 = v33
    v30 = v18 * v30
    v30 = v28 + v30
    v30 = torch.where(v1, v30, 0.0)
    v28 = torch.where(v25, v28, 0.0)
    v30 = v30 + v28
    o3 = v30
    v16 = 2.25 * v21
    v16 = torch.where(v1, v16, 0.0)
    v14 = torch.where(v25, v14, 0.0)
    v16 = v16 + v14
    v29 = v29 * v27
    v20 = v20 * v10
    v29 = v29 + v20
    v29 = v16 - v29
    v29 = torch.where(v1, v29, 0.0)
    v16 = torch.where(v25, v16, 0.0)
    v29 = v29 + v16
    o4 = v29
    v29 = 1.0 - v18
    v16 = v27 * v29
    v16 = torch.where(v1, v16, 0.0)
    v27 = torch.where(v25, v27, 0.0)
    v16 = v16 + v27
    o5 = v16
    v29 = v10 * v29
    v29 = torch.where(v1, v29, 0.0)
    v10 = torch.where(v25, v10, 0.0)
    v29 = v29 + v10
    o6 = v29
    v17 = 0.010000000000000002 * v18
    v1 = torch.where(v1, v17, 0.0)
    v25 = torch.where(v25, v26, 0.0)
    v1 = v1 + v25
    o7 = v1
    v1 = e[7]
    v0 = 0.5 < v1
    v1 = n[8]
    v8 = 0.1 * v8
    v1 = v1 + v8
    v8 = n[10]
    v25 = n[11]
    v26 = n[12]
    v17 = 0.1 * v26
    v17 = v25 - v17
    v25 = v25 + v17
    v3 = 0.1 * v25
    v8 = v8 - v3
    v8 = v8 + 3.0461741978670866e-08
    v25 = v8 + 0.00030461741978670857
    v18 = v8 / v25
    v10 = e[5]
    v29 = 0.017453292519943295 * v10
    v31 = v31 + v29
    v31 = v31 - v1
    v31 = v31 + 3.141592653589793
    v31 = torch.fmod(v31, 6.283185307179586)
    v31 = v31 + 6.283185307179586
    v31 = torch.fmod(v31, 6.283185307179586)
    v31 = v31 - 3.141592653589793
    v16 = v18 * v31
    v16 = v1 + v16
    v16 = torch.where(v0, v16, 0.0)
    v27 = ~v0
    v1 = torch.where(v27, v1, 0.0)
    v16 = v16 + v1
    v16 = v16 + 3.141592653589793
    v16 = torch.fmod(v16, 6.283185307179586)
    v16 = v16 + 6.283185307179586
    v16 = torch.fmod(v16, 6.283185307179586)
    v16 = v16 - 3.141592653589793
    o8 = v16
    v25 = v17 / v25
    v31 = v25 * v31
    v31 = v7 + v31
    v31 = torch.where(v0, v31, 0.0)
    v7 = torch.where(v27, v7, 0.0)
    v31 = v31 + v7
    o9 = v31
    v3 = 0.00030461741978670857 * v18
    v3 = torch.where(v0, v3, 0.0)
    v8 = torch.where(v27, v8, 0.0)
    v3 = v3 + v8
    o10 = v3
    v12 = 1.0 - v18
    v12 = v17 * v12
    v12 = torch.where(v0, v12, 0.0)
    v18 = torch.where(v27, v17, 0.0)
    v12 = v12 + v18
    o11 = v12
    v26 = v26 + 3.046174197867086e-11
    v25 = v25 * v17
    v25 = v26 - v25
    v0 = torch.where(v0, v25, 0.0)
    v27 = torch.where(v27, v26, 0.0)
    v0 = v0 + v27
    o12 = v0
    o13 = v6
    v5 = v5 - v31
    o14 = v5
    return (o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, o12, o13, o14)
