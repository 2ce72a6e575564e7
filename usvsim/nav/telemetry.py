"""Navigation from telemetry: the simulator's Navigator fed by MAVLink instead of its sensors.

Used by the MAVLink bridge (:mod:`usvsim.mavlink.bridge`): the vehicle reports position and
velocity (GLOBAL_POSITION_INT), yaw and yaw rate (ATTITUDE); this estimator turns them into the
same navigation estimate the simulated boat's helmsman sees, with the same filter: a one-boat
:class:`usvsim.nav.filter.Navigator` driven through its measurement entry points
(:meth:`~usvsim.nav.filter.Navigator.start`, :meth:`~usvsim.nav.filter.Navigator.fuse`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.nav.filter import Navigator
from usvsim.nav.models import NavConfig

__all__ = ["TelemetryEstimator"]


class TelemetryEstimator:
    """The simulator's navigation filter of one boat, fed from telemetry ticks.

    Each tick predicts the filters over the whole plant steps since the last one
    (``round(Δt / dt_s)``, more than one after dropped packets, none for a tick that comes
    early) with the ATTITUDE yaw rate as the gyro, then fuses the GLOBAL_POSITION_INT position
    as the GNSS fix and the ATTITUDE yaw as the compass (innovation wrapped). The telemetry
    velocity only starts the filter: it is the autopilot's own estimate, not a Doppler reading
    independent of the position, so it is not fused at every tick (which
    ``NavConfig.gnss_velocity`` would do for the simulated receiver).

    Parameters
    ----------
    cfg : NavConfig, optional
        Filter configuration (default ``NavConfig()``, the simulator's).
    """

    def __init__(self, cfg: NavConfig | None = None) -> None:
        self.cfg = cfg or NavConfig()
        self.nav = Navigator(self.cfg, 1)
        self.last_ms: int | None = None  # vehicle time of the last fused tick (ms since boot)

    @property
    def ready(self) -> bool:
        """Whether a first tick has started the filter."""
        return self.last_ms is not None

    def update(
        self,
        time_ms: int,
        pos_ne: ArrayLike,
        vel_ne: ArrayLike,
        yaw_rad: float,
        gyro_radps: float,
    ) -> None:
        """One telemetry tick: predict to ``time_ms`` then correct with position and yaw.

        Parameters
        ----------
        time_ms : int
            Vehicle time of the tick (ms).
        pos_ne : array_like, shape (2,)
            Position [x_N, y_E] (m) relative to the mission origin.
        vel_ne : array_like, shape (2,)
            Velocity over ground [v_N, v_E] (m/s); used on the first tick only.
        yaw_rad : float
            Heading (rad).
        gyro_radps : float
            Yaw rate (rad/s).
        """
        pos = np.asarray(pos_ne, dtype=np.float64).reshape(1, 2)
        heading, gyro = np.array([yaw_rad], dtype=np.float64), np.array([gyro_radps], dtype=float)
        if self.last_ms is None:  # first fix: start like Navigator.reset
            vel = np.asarray(vel_ne, dtype=np.float64).reshape(1, 2)
            self.nav.start(pos, vel, heading, gyro)
        else:
            n = max(0, round((time_ms - self.last_ms) / 1000.0 / self.cfg.dt_s))
            self.nav.fuse(gyro, pos_ne=pos, heading_rad=heading, n_predict=n)
        self.last_ms = time_ms

    @property
    def pos_ne(self) -> NDArray[np.float64]:
        """Estimated position [x_N, y_E] (m), shape (2,)."""
        return self.nav.estimate.pos_ne[0].copy()

    @property
    def vel_ne(self) -> NDArray[np.float64]:
        """Estimated velocity over ground [v_N, v_E] (m/s), shape (2,)."""
        return self.nav.estimate.vel_ne[0].copy()

    @property
    def psi(self) -> float:
        """Estimated heading (rad) in [-π, π)."""
        return float(self.nav.estimate.psi[0])

    @property
    def yaw_rate(self) -> float:
        """Bias-corrected yaw rate ``g − b̂`` (rad/s)."""
        return float(self.nav.estimate.yaw_rate[0])
