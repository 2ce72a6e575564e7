"""GENERATED from the CasADi plant by :mod:`usvsim.vessel.torch_codegen`: do not edit.

Plant: vessel 'usv105' (fingerprint 85a89271dcab6870), autopilot 'pid' (the default design), step
0.1 s. :func:`closed_loop_step` is :func:`usvsim.vessel.plant.build_closed_loop_step`
(autopilot update, one RK4 step with actuators and current, heading wrapped) and
:func:`surge_drag` is :func:`usvsim.vessel.model.surge_trim`, one torch statement per CasADi
instruction (:mod:`usvsim.vessel.torch_codegen`); ``GAINS`` is the design's
:meth:`usvsim.vessel.autopilot.AutopilotDesign.gains_vector`. Needs torch only.

Why this module is long: it is generated, one statement per instruction of the CasADi plant.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

VESSEL = "usv105"
VESSEL_FINGERPRINT = "85a89271dcab6870"
AUTOPILOT = "pid"
DT_S = 0.1  # s, plant step
CRUISE_SPEED_MPS = 3.0  # m/s, the design's speed (default speed reference)
NX = 8  # plant state size
NS = 13  # closed-loop state size: plant state, then the controller's
GAINS = (
    218378.6167292672,
    225151.87501621875,
    43675.72334585345,
    54594.6541823168,
    0.0,
    3.5,
    1.0,
    0.2617993877991494,
    1.0471975511965976,
    0.3490658503988659,
    1.0,
    0.25,
    8194.545484072858,
    41676.32787609039,
    2.0,
    2.0943951023931953,
    0.2,
    0.2,
    0.2,
    1.0,
    2.0943951023931953,
    2.0,
    0.75,
    2.0,
    4.0,
)


def closed_loop_step(
    s: Sequence[Any], w: Sequence[Any], g: Sequence[Any]
) -> tuple[torch.Tensor, ...]:
    """One plant step of N boats: s[13] (x, c), w[4] (psi_ref rad, U_ref m/s, V_c m/s,
    beta_c rad), g[25] (GAINS) -> s_next[13]; each entry (N,) or a shared number."""
    _ref = s[0]
    _dtype = _ref.dtype

    def _full(value: float) -> torch.Tensor:
        return torch.full_like(_ref, value)

    v0 = s[0]
    v2 = s[2]
    v3 = torch.cos(v2)
    v4 = s[3]
    v5 = v3 * v4
    v6 = torch.sin(v2)
    v7 = s[4]
    v8 = v6 * v7
    v5 = v5 - v8
    v9 = s[5]
    v10 = 0.05 * v9
    v10 = v2 + v10
    v11 = torch.cos(v10)
    v14 = s[6]
    v15 = 0.0 < v14
    v17 = w[2]
    v18 = w[3]
    v19 = torch.cos(v18)
    v19 = v17 * v19
    v20 = v3 * v19
    v18 = torch.sin(v18)
    v17 = v17 * v18
    v18 = v6 * v17
    v20 = v20 + v18
    v18 = v4 - v20
    v22 = v18 / 20.0
    v22 = 1.0 - v22
    v22 = torch.where(v22 >= 0.0, v22, 0.0)
    v22 = torch.where(v22 <= 1.0, v22, 1.0)
    v22 = v14 * v22
    v22 = torch.where(v15, v22, 0.0)
    v15 = ~v15
    v15 = torch.where(v15, v14, 0.0)
    v22 = v22 + v15
    v15 = s[7]
    v23 = torch.cos(v15)
    v23 = v22 * v23
    v25 = v3 * v17
    v26 = v6 * v19
    v25 = v25 - v26
    v26 = v7 - v25
    v27 = -7449.586803702598 * v26
    v27 = v27 * v9
    v29 = -4090.558427545018 * v26
    v31 = -5247.633533593847 * v9
    v29 = v29 + v31
    v31 = v29 * v9
    v27 = v27 + v31
    v23 = v23 - v27
    v31 = -84.30323981460388 * v18
    v33 = torch.abs(v18)
    v33 = -205.0374429676652 * v33
    v33 = v33 * v18
    v31 = v31 + v33
    v23 = v23 + v31
    v23 = 0.00012203239361397496 * v23
    v25 = v9 * v25
    v23 = v23 + v25
    v25 = 0.05 * v23
    v25 = v4 + v25
    v31 = v11 * v25
    v10 = torch.sin(v10)
    v34 = v18 * v18
    v35 = v26 * v26
    v34 = v34 + v35
    v34 = torch.sqrt(v34)
    v34 = v34 / 3.0
    v37 = -2800.06618922723 * v26
    v39 = 6465.526331760081 * v9
    v37 = v37 + v39
    v37 = v34 * v37
    v40 = torch.abs(v26)
    v41 = -1325.0 * v40
    v41 = v41 * v26
    v37 = v37 + v41
    v42 = torch.abs(v9)
    v43 = -6057.0 * v42
    v43 = v43 * v26
    v37 = v37 + v43
    v43 = torch.sin(v15)
    v22 = v22 * v43
    v44 = 7449.586803702598 * v18
    v45 = v44 * v9
    v47 = 744.9586803702599 * v18
    v47 = v47 * v9
    v45 = v45 + v47
    v45 = v22 + v45
    v37 = v37 - v45
    v45 = 9.004513151905337e-05 * v37
    v22 = 4.5 * v22
    v49 = 7449.586803702598 * v26
    v49 = v49 * v18
    v44 = v44 * v26
    v49 = v49 - v44
    v50 = -744.9586803702599 * v18
    v50 = v50 * v26
    v29 = v29 * v18
    v50 = v50 - v29
    v49 = v49 + v50
    v22 = v22 - v49
    v26 = 437.14158044970463 * v26
    v29 = -34439.120539074014 * v9
    v26 = v26 + v29
    v34 = v34 * v26
    v40 = -19813.0 * v40
    v40 = v40 * v9
    v34 = v34 + v40
    v42 = -46976.0 * v42
    v42 = v42 * v9
    v34 = v34 + v42
    v22 = v22 + v34
    v34 = -6.89118437747792e-06 * v22
    v45 = v45 + v34
    v20 = v9 * v20
    v45 = v45 - v20
    v20 = 0.05 * v45
    v20 = v7 + v20
    v34 = v10 * v20
    v31 = v31 - v34
    v31 = 2.0 * v31
    v5 = v5 + v31
    v37 = -8.125078877499304e-06 * v37
    v22 = 1.6511238607243835e-05 * v22
    v37 = v37 + v22
    v22 = 0.05 * v37
    v22 = v9 + v22
    v42 = 0.05 * v22
    v42 = v2 + v42
    v29 = torch.cos(v42)
    v18 = w[1]
    v51 = -84.30323981460388 * v18
    v52 = torch.abs(v18)
    v52 = -205.0374429676652 * v52
    v52 = v52 * v18
    v51 = v51 + v52
    v52 = g[12]
    v53 = g[10]
    v54 = v4 - v18
    v53 = v53 * v54
    v55 = g[11]
    v56 = s[12]
    v55 = v55 * v56
    v53 = v53 + v55
    v53 = v52 * v53
    v53 = v51 + v53
    v53 = -v53
    v57 = 0.6 * v51
    v57 = -v57
    v55 = torch.where(v57 < 1200.0, v57, 1200.0)
    v53 = torch.fmax(v53, v55)
    v55 = g[3]
    v57 = s[10]
    v55 = v55 * v57
    v58 = g[4]
    v59 = s[9]
    v58 = v58 * v59
    v55 = v55 + v58
    v58 = g[0]
    v60 = s[8]
    v61 = v2 - v60
    v61 = v61 + 3.141592653589793
    v61 = torch.fmod(v61, 6.283185307179586)
    v61 = v61 + 6.283185307179586
    v61 = torch.fmod(v61, 6.283185307179586)
    v61 = v61 - 3.141592653589793
    v58 = v58 * v61
    v55 = v55 - v58
    v58 = g[1]
    v64 = v9 - v59
    v58 = v58 * v64
    v55 = v55 - v58
    v58 = g[2]
    v64 = s[11]
    v58 = v58 * v64
    v55 = v55 - v58
    v58 = g[13]
    v65 = -v58
    v65 = torch.fmax(v55, v65)
    v65 = torch.fmin(v65, v58)
    v66 = v65 / 4.5
    v67 = torch.atan2(v66, v53)
    v67 = torch.where(v67 >= -0.47123889803846897, v67, -0.47123889803846897)
    v67 = torch.where(v67 <= 0.47123889803846897, v67, 0.47123889803846897)
    v70 = torch.cos(v67)
    v53 = v53 / v70
    v66 = torch.abs(v66)
    v66 = v66 / 0.45399049973954675
    v65 = v65 * v9
    v65 = v65 < 0.0
    v70 = g[24]
    v71 = g[21]
    v52 = v52 * v71
    v71 = g[22]
    v18 = v18 + v71
    v18 = v18 - v4
    v52 = v52 * v18
    v52 = v52 - v51
    v70 = v70 * v52
    v70 = torch.where(v65, v70, 0.0)
    v65 = ~v65
    v65 = torch.where(v65, v52, 0.0)
    v70 = v70 + v65
    v66 = torch.fmin(v66, v70)
    v53 = torch.fmax(v53, v66)
    v70 = v4 / 20.0
    v70 = 1.0 - v70
    v70 = torch.where(v70 >= 0.0, v70, 0.0)
    v70 = torch.where(v70 <= 1.0, v70, 1.0)
    v70 = torch.where(v70 >= 0.05, v70, 0.05)
    v65 = 24000.0 * v70
    v53 = torch.fmin(v53, v65)
    v70 = v53 / v70
    v70 = torch.where(v70 >= -9600.0, v70, -9600.0)
    v70 = torch.where(v70 <= 24000.0, v70, 24000.0)
    v66 = v70 - v14
    v66 = v66 / 0.3
    v52 = 0.05 * v66
    v52 = v14 + v52
    v51 = 0.0 < v52
    v18 = v11 * v19
    v71 = v10 * v17
    v18 = v18 + v71
    v71 = v25 - v18
    v72 = v71 / 20.0
    v72 = 1.0 - v72
    v72 = torch.where(v72 >= 0.0, v72, 0.0)
    v72 = torch.where(v72 <= 1.0, v72, 1.0)
    v72 = v52 * v72
    v72 = torch.where(v51, v72, 0.0)
    v51 = ~v51
    v51 = torch.where(v51, v52, 0.0)
    v72 = v72 + v51
    v68 = torch.where(v67 >= -0.47123889803846897, v67, -0.47123889803846897)
    v68 = torch.where(v68 <= 0.47123889803846897, v68, 0.47123889803846897)
    v69 = v68 - v15
    v69 = v69 / 0.15
    v69 = torch.where(v69 >= -1.0471975511965976, v69, -1.0471975511965976)
    v69 = torch.where(v69 <= 1.0471975511965976, v69, 1.0471975511965976)
    v75 = 0.05 * v69
    v75 = v15 + v75
    v76 = torch.cos(v75)
    v76 = v72 * v76
    v77 = v11 * v17
    v78 = v10 * v19
    v77 = v77 - v78
    v78 = v20 - v77
    v79 = -7449.586803702598 * v78
    v79 = v79 * v22
    v80 = -4090.558427545018 * v78
    v81 = -5247.633533593847 * v22
    v80 = v80 + v81
    v81 = v80 * v22
    v79 = v79 + v81
    v76 = v76 - v79
    v79 = -84.30323981460388 * v71
    v81 = torch.abs(v71)
    v81 = -205.0374429676652 * v81
    v81 = v81 * v71
    v79 = v79 + v81
    v76 = v76 + v79
    v76 = 0.00012203239361397496 * v76
    v77 = v22 * v77
    v76 = v76 + v77
    v77 = 0.05 * v76
    v77 = v4 + v77
    v79 = v29 * v77
    v42 = torch.sin(v42)
    v81 = v71 * v71
    v82 = v78 * v78
    v81 = v81 + v82
    v81 = torch.sqrt(v81)
    v81 = v81 / 3.0
    v82 = -2800.06618922723 * v78
    v83 = 6465.526331760081 * v22
    v82 = v82 + v83
    v82 = v81 * v82
    v83 = torch.abs(v78)
    v84 = -1325.0 * v83
    v84 = v84 * v78
    v82 = v82 + v84
    v84 = torch.abs(v22)
    v85 = -6057.0 * v84
    v85 = v85 * v78
    v82 = v82 + v85
    v85 = torch.sin(v75)
    v72 = v72 * v85
    v85 = 7449.586803702598 * v71
    v86 = v85 * v22
    v87 = 744.9586803702599 * v71
    v87 = v87 * v22
    v86 = v86 + v87
    v86 = v72 + v86
    v82 = v82 - v86
    v86 = 9.004513151905337e-05 * v82
    v72 = 4.5 * v72
    v87 = 7449.586803702598 * v78
    v87 = v87 * v71
    v85 = v85 * v78
    v87 = v87 - v85
    v85 = -744.9586803702599 * v71
    v85 = v85 * v78
    v80 = v80 * v71
    v85 = v85 - v80
    v87 = v87 + v85
    v72 = v72 - v87
    v78 = 437.14158044970463 * v78
    v87 = -34439.120539074014 * v22
    v78 = v78 + v87
    v81 = v81 * v78
    v83 = -19813.0 * v83
    v83 = v83 * v22
    v81 = v81 + v83
    v84 = -46976.0 * v84
    v84 = v84 * v22
    v81 = v81 + v84
    v72 = v72 + v81
    v81 = -6.89118437747792e-06 * v72
    v86 = v86 + v81
    v18 = v22 * v18
    v86 = v86 - v18
    v18 = 0.05 * v86
    v18 = v7 + v18
    v81 = v42 * v18
    v79 = v79 - v81
    v79 = 2.0 * v79
    v5 = v5 + v79
    v82 = -8.125078877499304e-06 * v82
    v72 = 1.6511238607243835e-05 * v72
    v82 = v82 + v72
    v72 = 0.05 * v82
    v72 = v9 + v72
    v81 = 0.1 * v72
    v81 = v2 + v81
    v84 = torch.cos(v81)
    v52 = v70 - v52
    v52 = v52 / 0.3
    v83 = 0.05 * v52
    v83 = v14 + v83
    v78 = 0.0 < v83
    v87 = v29 * v19
    v85 = v42 * v17
    v87 = v87 + v85
    v85 = v77 - v87
    v80 = v85 / 20.0
    v80 = 1.0 - v80
    v80 = torch.where(v80 >= 0.0, v80, 0.0)
    v80 = torch.where(v80 <= 1.0, v80, 1.0)
    v80 = v83 * v80
    v80 = torch.where(v78, v80, 0.0)
    v78 = ~v78
    v78 = torch.where(v78, v83, 0.0)
    v80 = v80 + v78
    v75 = v68 - v75
    v75 = v75 / 0.15
    v75 = torch.where(v75 >= -1.0471975511965976, v75, -1.0471975511965976)
    v75 = torch.where(v75 <= 1.0471975511965976, v75, 1.0471975511965976)
    v8 = 0.05 * v75
    v8 = v15 + v8
    v78 = torch.cos(v8)
    v78 = v80 * v78
    v71 = v29 * v17
    v88 = v42 * v19
    v71 = v71 - v88
    v88 = v18 - v71
    v89 = -7449.586803702598 * v88
    v89 = v89 * v72
    v90 = -4090.558427545018 * v88
    v91 = -5247.633533593847 * v72
    v90 = v90 + v91
    v91 = v90 * v72
    v89 = v89 + v91
    v78 = v78 - v89
    v89 = -84.30323981460388 * v85
    v91 = torch.abs(v85)
    v91 = -205.0374429676652 * v91
    v91 = v91 * v85
    v89 = v89 + v91
    v78 = v78 + v89
    v78 = 0.00012203239361397496 * v78
    v71 = v72 * v71
    v78 = v78 + v71
    v71 = 0.1 * v78
    v71 = v4 + v71
    v89 = v84 * v71
    v81 = torch.sin(v81)
    v91 = v85 * v85
    v92 = v88 * v88
    v91 = v91 + v92
    v91 = torch.sqrt(v91)
    v91 = v91 / 3.0
    v92 = -2800.06618922723 * v88
    v93 = 6465.526331760081 * v72
    v92 = v92 + v93
    v92 = v91 * v92
    v93 = torch.abs(v88)
    v94 = -1325.0 * v93
    v94 = v94 * v88
    v92 = v92 + v94
    v94 = torch.abs(v72)
    v95 = -6057.0 * v94
    v95 = v95 * v88
    v92 = v92 + v95
    v95 = torch.sin(v8)
    v80 = v80 * v95
    v95 = 7449.586803702598 * v85
    v96 = v95 * v72
    v97 = 744.9586803702599 * v85
    v97 = v97 * v72
    v96 = v96 + v97
    v96 = v80 + v96
    v92 = v92 - v96
    v96 = 9.004513151905337e-05 * v92
    v80 = 4.5 * v80
    v97 = 7449.586803702598 * v88
    v97 = v97 * v85
    v95 = v95 * v88
    v97 = v97 - v95
    v95 = -744.9586803702599 * v85
    v95 = v95 * v88
    v90 = v90 * v85
    v95 = v95 - v90
    v97 = v97 + v95
    v80 = v80 - v97
    v88 = 437.14158044970463 * v88
    v97 = -34439.120539074014 * v72
    v88 = v88 + v97
    v91 = v91 * v88
    v93 = -19813.0 * v93
    v93 = v93 * v72
    v91 = v91 + v93
    v94 = -46976.0 * v94
    v94 = v94 * v72
    v91 = v91 + v94
    v80 = v80 + v91
    v91 = -6.89118437747792e-06 * v80
    v96 = v96 + v91
    v87 = v72 * v87
    v96 = v96 - v87
    v87 = 0.1 * v96
    v87 = v7 + v87
    v91 = v81 * v87
    v89 = v89 - v91
    v5 = v5 + v89
    v5 = 0.016666666666666666 * v5
    v0 = v0 + v5
    o0 = v0
    v0 = s[1]
    v6 = v6 * v4
    v3 = v3 * v7
    v6 = v6 + v3
    v10 = v10 * v25
    v11 = v11 * v20
    v10 = v10 + v11
    v10 = 2.0 * v10
    v6 = v6 + v10
    v42 = v42 * v77
    v29 = v29 * v18
    v42 = v42 + v29
    v42 = 2.0 * v42
    v6 = v6 + v42
    v42 = v81 * v71
    v29 = v84 * v87
    v42 = v42 + v29
    v6 = v6 + v42
    v6 = 0.016666666666666666 * v6
    v0 = v0 + v6
    o1 = v0
    v22 = 2.0 * v22
    v22 = v9 + v22
    v72 = 2.0 * v72
    v22 = v22 + v72
    v92 = -8.125078877499304e-06 * v92
    v80 = 1.6511238607243835e-05 * v80
    v92 = v92 + v80
    v80 = 0.1 * v92
    v80 = v9 + v80
    v22 = v22 + v80
    v22 = 0.016666666666666666 * v22
    v2 = v2 + v22
    v2 = v2 + 3.141592653589793
    v2 = torch.fmod(v2, 6.283185307179586)
    v2 = v2 + 6.283185307179586
    v2 = torch.fmod(v2, 6.283185307179586)
    v2 = v2 - 3.141592653589793
    o2 = v2
    v76 = 2.0 * v76
    v23 = v23 + v76
    v78 = 2.0 * v78
    v23 = v23 + v78
    v83 = v70 - v83
    v83 = v83 / 0.3
    v78 = 0.1 * v83
    v78 = v14 + v78
    v76 = 0.0 < v78
    v2 = v84 * v19
    v22 = v81 * v17
    v2 = v2 + v22
    v71 = v71 - v2
    v21 = v71 / 20.0
    v21 = 1.0 - v21
    v21 = torch.where(v21 >= 0.0, v21, 0.0)
    v21 = torch.where(v21 <= 1.0, v21, 1.0)
    v21 = v78 * v21
    v21 = torch.where(v76, v21, 0.0)
    v76 = ~v76
    v76 = torch.where(v76, v78, 0.0)
    v21 = v21 + v76
    v8 = v68 - v8
    v8 = v8 / 0.15
    v8 = torch.where(v8 >= -1.0471975511965976, v8, -1.0471975511965976)
    v8 = torch.where(v8 <= 1.0471975511965976, v8, 1.0471975511965976)
    v76 = 0.1 * v8
    v76 = v15 + v76
    v13 = torch.cos(v76)
    v13 = v21 * v13
    v84 = v84 * v17
    v81 = v81 * v19
    v84 = v84 - v81
    v87 = v87 - v84
    v24 = -7449.586803702598 * v87
    v24 = v24 * v80
    v28 = -4090.558427545018 * v87
    v30 = -5247.633533593847 * v80
    v28 = v28 + v30
    v30 = v28 * v80
    v24 = v24 + v30
    v13 = v13 - v24
    v27 = -84.30323981460388 * v71
    v24 = torch.abs(v71)
    v32 = -205.0374429676652 * v24
    v32 = v32 * v71
    v27 = v27 + v32
    v13 = v13 + v27
    v12 = 0.00012203239361397496 * v13
    v84 = v80 * v84
    v12 = v12 + v84
    v23 = v23 + v12
    v23 = 0.016666666666666666 * v23
    v4 = v4 + v23
    o3 = v4
    v86 = 2.0 * v86
    v45 = v45 + v86
    v96 = 2.0 * v96
    v45 = v45 + v96
    v96 = v71 * v71
    v86 = v87 * v87
    v96 = v96 + v86
    v96 = torch.sqrt(v96)
    v96 = v96 / 3.0
    v36 = -2800.06618922723 * v87
    v38 = 6465.526331760081 * v80
    v36 = v36 + v38
    v36 = v96 * v36
    v38 = torch.abs(v87)
    v39 = -1325.0 * v38
    v39 = v39 * v87
    v36 = v36 + v39
    v39 = torch.abs(v80)
    v41 = -6057.0 * v39
    v41 = v41 * v87
    v36 = v36 + v41
    v41 = torch.sin(v76)
    v21 = v21 * v41
    v41 = 7449.586803702598 * v71
    v35 = v41 * v80
    v46 = 744.9586803702599 * v71
    v46 = v46 * v80
    v35 = v35 + v46
    v35 = v21 + v35
    v36 = v36 - v35
    v33 = 9.004513151905337e-05 * v36
    v21 = 4.5 * v21
    v43 = 7449.586803702598 * v87
    v43 = v43 * v71
    v41 = v41 * v87
    v43 = v43 - v41
    v44 = -744.9586803702599 * v71
    v44 = v44 * v87
    v28 = v28 * v71
    v44 = v44 - v28
    v43 = v43 + v44
    v21 = v21 - v43
    v49 = 437.14158044970463 * v87
    v50 = -34439.120539074014 * v80
    v49 = v49 + v50
    v96 = v96 * v49
    v26 = -19813.0 * v38
    v26 = v26 * v80
    v96 = v96 + v26
    v40 = -46976.0 * v39
    v40 = v40 * v80
    v96 = v96 + v40
    v21 = v21 + v96
    v47 = -6.89118437747792e-06 * v21
    v33 = v33 + v47
    v80 = v80 * v2
    v33 = v33 - v80
    v45 = v45 + v33
    v45 = 0.016666666666666666 * v45
    v7 = v7 + v45
    o4 = v7
    v82 = 2.0 * v82
    v37 = v37 + v82
    v92 = 2.0 * v92
    v37 = v37 + v92
    v31 = -8.125078877499304e-06 * v36
    v34 = 1.6511238607243835e-05 * v21
    v31 = v31 + v34
    v37 = v37 + v31
    v37 = 0.016666666666666666 * v37
    v9 = v9 + v37
    o5 = v9
    v52 = 2.0 * v52
    v66 = v66 + v52
    v83 = 2.0 * v83
    v66 = v66 + v83
    v70 = v70 - v78
    v70 = v70 / 0.3
    v66 = v66 + v70
    v66 = 0.016666666666666666 * v66
    v14 = v14 + v66
    o6 = v14
    v75 = 2.0 * v75
    v69 = v69 + v75
    v8 = 2.0 * v8
    v69 = v69 + v8
    v68 = v68 - v76
    v68 = v68 / 0.15
    v68 = torch.where(v68 >= -1.0471975511965976, v68, -1.0471975511965976)
    v68 = torch.where(v68 <= 1.0471975511965976, v68, 1.0471975511965976)
    v69 = v69 + v68
    v1 = 0.016666666666666666 * v69
    v15 = v15 + v1
    o7 = v15
    v15 = 0.1 * v59
    v15 = v60 + v15
    v15 = v15 + 3.141592653589793
    v15 = torch.fmod(v15, 6.283185307179586)
    v15 = v15 + 6.283185307179586
    v15 = torch.fmod(v15, 6.283185307179586)
    v15 = v15 - 3.141592653589793
    o8 = v15
    v15 = 0.1 * v57
    v15 = v59 + v15
    v1 = g[7]
    v69 = -v1
    v15 = torch.fmax(v15, v69)
    v15 = torch.fmin(v15, v1)
    o9 = v15
    v15 = g[5]
    v1 = v15 * v15
    v69 = v15 * v1
    v68 = w[0]
    v68 = v68 - v60
    v68 = v68 + 3.141592653589793
    v68 = torch.fmod(v68, 6.283185307179586)
    v68 = v68 + 6.283185307179586
    v68 = torch.fmod(v68, 6.283185307179586)
    v68 = v68 - 3.141592653589793
    v69 = v69 * v68
    v68 = g[6]
    v68 = 2.0 * v68
    v68 = v68 + 1.0
    v15 = v68 * v15
    v15 = v15 * v57
    v69 = v69 - v15
    v68 = v68 * v1
    v68 = v68 * v59
    v69 = v69 - v68
    v69 = 0.1 * v69
    v57 = v57 + v69
    v69 = g[8]
    v68 = -v69
    v57 = torch.fmax(v57, v68)
    v57 = torch.fmin(v57, v69)
    o10 = v57
    v48 = 4.5 * v53
    v67 = torch.sin(v67)
    v48 = v48 * v67
    v48 = v48 - v55
    v48 = torch.abs(v48)
    v55 = 0.01 * v58
    v48 = v48 < v55
    v61 = 0.1 * v61
    v61 = v64 + v61
    v61 = torch.where(v48, v61, 0.0)
    v48 = ~v48
    v48 = torch.where(v48, v64, 0.0)
    v61 = v61 + v48
    v48 = g[9]
    v64 = -v48
    v61 = torch.fmax(v61, v64)
    v61 = torch.fmin(v61, v48)
    o11 = v61
    v79 = 0.1 * v54
    v56 = v56 + v79
    v79 = g[23]
    v54 = -v79
    v56 = torch.fmax(v56, v54)
    v56 = torch.fmin(v56, v79)
    o12 = v56
    return (o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, o12)


def surge_drag(u: Sequence[Any]) -> tuple[torch.Tensor, ...]:
    """Surge drag (N) at surge speed u[0] (m/s, (N,)): the trim thrust."""
    _ref = u[0]
    _dtype = _ref.dtype

    def _full(value: float) -> torch.Tensor:
        return torch.full_like(_ref, value)

    v1 = u[0]
    v0 = -84.30323981460388 * v1
    v3 = torch.abs(v1)
    v2 = -205.0374429676652 * v3
    v2 = v2 * v1
    v0 = v0 + v2
    v1 = v1 / 20.0
    v1 = 1.0 - v1
    v1 = torch.where(v1 >= 0.0, v1, 0.0)
    v1 = torch.where(v1 <= 1.0, v1, 1.0)
    v1 = torch.where(v1 >= 0.05, v1, 0.05)
    v0 = v0 / v1
    v0 = -v0
    o0 = v0
    return (o0,)
