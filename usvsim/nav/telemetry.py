"""Navigation from telemetry: the simulator's Kalman filters fed by MAVLink instead of sensors.

Used by the MAVLink bridge (:mod:`usvsim.mavlink.bridge`): the vehicle reports position
(GLOBAL_POSITION_INT), yaw and yaw rate (ATTITUDE); this estimator turns them into the same
navigation estimate the simulated boat's helmsman sees.
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import KalmanFilter

from usvsim.common.angles import ssa
from usvsim.nav.models import NavConfig, heading_filter_model, position_filter_model
from usvsim.nav.models import position_transition as turn_transition

__all__ = ["TelemetryEstimator"]


class TelemetryEstimator:
    """The simulator's two Kalman filters fed from telemetry instead of raw sensors.

    Position filter (:func:`usvsim.nav.filter.position_filter_model`, coordinated turn with the
    gyro rate): measurement = GLOBAL_POSITION_INT position in NED. Heading filter
    (:func:`usvsim.nav.filter.heading_filter_model`): input = ATTITUDE yaw rate (gyro),
    measurement = ATTITUDE yaw (compass), innovation wrapped with ``ssa``. Both are filterpy
    ``KalmanFilter`` objects with the navigation module's matrices; a tick that comes late
    (dropped packets) is predicted in whole plant steps (``round(dt / dt_s)``).
    The Navigator itself cannot be reused: it draws its own sensor noise from the true state.
    """

    def __init__(self, cfg: NavConfig | None = None) -> None:
        self.cfg = cfg or NavConfig()
        pm, hm = position_filter_model(self.cfg), heading_filter_model(self.cfg)
        self.pos = KalmanFilter(dim_x=4, dim_z=2)
        self.pos.Q, self.pos.H, self.pos.R = pm.Q.copy(), pm.H.copy(), pm.R.copy()
        self.head = KalmanFilter(dim_x=2, dim_z=1, dim_u=1)
        self.head.F, self.head.B = hm.F.copy(), hm.B.copy()
        self.head.Q, self.head.H, self.head.R = hm.Q.copy(), hm.H.copy(), hm.R.copy()
        self.last_ms: int | None = None
        self.yaw_rate = 0.0

    @property
    def ready(self) -> bool:
        return self.last_ms is not None

    def update(
        self,
        time_ms: int,
        pos_ne: np.ndarray,
        vel_ne: np.ndarray,
        yaw_rad: float,
        gyro_radps: float,
    ) -> None:
        """One telemetry tick: predict to ``time_ms`` then correct with position and yaw."""
        s = self.cfg.sensors
        if self.last_ms is None:  # first fix: initialise like Navigator.reset
            self.pos.x = np.array([pos_ne[0], pos_ne[1], vel_ne[0], vel_ne[1]])
            self.pos.P = np.diag([s.gps_sigma_m**2] * 2 + [self.cfg.init_vel_sigma_mps**2] * 2)
            self.head.x = np.array([yaw_rad, 0.0])
            self.head.P = np.diag([s.compass_sigma_rad**2, s.gyro_bias_sigma_radps**2])
            self.last_ms, self.yaw_rate = time_ms, gyro_radps
            return
        n = max(0, round((time_ms - self.last_ms) / 1000.0 / self.cfg.dt_s))
        for _ in range(n):
            omega = gyro_radps - float(self.head.x[1])
            self.head.predict(u=np.array([gyro_radps]))
            self.pos.predict(F=turn_transition(np.array(omega), self.cfg.dt_s))
        self.pos.update(np.asarray(pos_ne, dtype=float))
        psi_prior = float(self.head.x[0])
        self.head.update(np.array([psi_prior + float(ssa(yaw_rad - psi_prior))]))
        self.head.x[0] = float(ssa(self.head.x[0]))
        self.last_ms = time_ms
        self.yaw_rate = gyro_radps - float(self.head.x[1])

    @property
    def pos_ne(self) -> np.ndarray:
        return np.array(self.pos.x[0:2], dtype=float)

    @property
    def psi(self) -> float:
        return float(self.head.x[0])
