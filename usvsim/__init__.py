"""usvsim: learning and testing steering policies for unmanned surface vehicles.

Modules (the architecture, bottom up): :mod:`usvsim.vessel.vessels` (parameters),
:mod:`usvsim.vessel.model` (CasADi 3-DOF model), :mod:`usvsim.vessel.autopilot` (heading
autopilot, speed control), :mod:`usvsim.vessel.plant` (batched closed-loop plant),
:mod:`usvsim.nav.sensors` and :mod:`usvsim.nav.filter` (GPS/compass/gyro and the Kalman filter),
then the task and environments (:mod:`usvsim.task`), the helmsmen (:mod:`usvsim.helm`),
evaluation (:mod:`usvsim.evaluation`), the MAVLink link (:mod:`usvsim.mavlink`) and the
command-line interface (:mod:`usvsim.cli`).
"""

from __future__ import annotations

from importlib.util import find_spec

__version__ = "0.1.0"

ENV_ID = "usvsim/PoleAvoidance-v0"
OPEN_WATER_ENV_ID = "usvsim/OpenWater-v0"

# gymnasium is a dependency, but the torch plant also runs where only torch and NumPy are
# installed (benchmarks/gpu_check.sh on a bare GPU machine): there, nothing is registered
if find_spec("gymnasium") is not None:
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        # string entry points: the environment modules are imported only on gymnasium.make(_vec);
        # make_vec(ENV_ID, num_envs=N) returns the native batch (one plant call for N boats)
        gymnasium.register(
            id=ENV_ID,
            entry_point="usvsim.task.env:PoleAvoidanceEnv",
            vector_entry_point="usvsim.task.vector_env:PoleAvoidanceVectorEnv",
        )
    if OPEN_WATER_ENV_ID not in gymnasium.registry:
        # the open-water family (usvsim.task.openwater_env): a vector env only,
        # gymnasium.make_vec(OPEN_WATER_ENV_ID, num_envs=N, observation="scene", ...)
        gymnasium.register(
            id=OPEN_WATER_ENV_ID,
            entry_point=None,
            vector_entry_point="usvsim.task.openwater_env:OpenWaterVectorEnv",
        )
