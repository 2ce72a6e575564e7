"""Reactive targets for the torch open-water env (issue 41's ``-colreg-reactive`` on the device).

:class:`DeviceReactiveTargets` is the ``on_decision`` hook of
:class:`usvsim.task.torch_openwater.TorchOpenWaterEnv`: the target vessels of every boat are
steered by :class:`usvsim.evaluation.colreg_rollout.ReactiveTargets` (``vo`` with the give-way
rule, the same code and numbers as the CPU env's
:class:`~usvsim.evaluation.colreg_rollout.TrainingReactiveTargets`) on the host. The hook reads
the own ships' true states and the vessels' motion to the host once a decision, as NumPy arrays,
and writes the vessels' new courses back; this is the one host round trip of a decision that
the torch env makes when targets react (``vo``, 120 candidate courses against every disc, stays
CPU code; the other parts of a step stay on the device).

The host view of the env (:class:`_HostView`) has the attributes of
:class:`usvsim.task.openwater_batch.OpenWaterBatch` that ``ReactiveTargets`` reads, with the
vessel and static slots cut to the widest episode started so far, as the CPU batch grows them,
so that ``vo``'s per-target memory is kept and cleared exactly as on the CPU env (tested: the
same trajectories and rewards with the episodes' noise replayed).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets

__all__ = ["DeviceReactiveTargets"]

FloatArray = NDArray[np.float64]


@dataclass
class _Inner:
    """The inner batch's true state, as ``OpenWaterBatch.inner.state.x`` (N, 13)."""

    x: FloatArray

    @property
    def state(self) -> _Inner:
        return self


@dataclass
class _Base:
    max_heading_change_rad: float


@dataclass
class _HostView:
    """The env's scene on the host, named as ``OpenWaterBatch``'s (module docstring)."""

    v_p0: FloatArray  # (N, M, 2) m
    v_course: FloatArray  # (N, M) rad
    v_speed: FloatArray  # (N, M) m/s
    v_turn: FloatArray  # (N, M) rad/s
    v_radius: FloatArray  # (N, M) m
    vessel_ok: NDArray[np.bool_]  # (N, M)
    centres: FloatArray  # (N, K, 2) m
    radii: FloatArray  # (N, K) m
    static_ok: NDArray[np.bool_]  # (N, K)
    inner: _Inner
    base: _Base


class DeviceReactiveTargets:
    """The torch open-water env's ``on_decision`` hook (module docstring); ``target_helmsman``:
    what steers the targets (default ``vo`` from the registry)."""

    def __init__(self, target_helmsman: Any = None) -> None:
        self.targets = TrainingReactiveTargets(target_helmsman)
        self.m_seen = 0  # vessel slots of the widest episode started so far
        self.k_seen = 0  # static slots, the same
        self._host: _HostView | None = None

    def _view(self, env: Any) -> _HostView:
        """The host view, updated in place from ``env`` (one object for the hook's life:
        ``ReactiveTargets`` keeps the batch it was built with and reads it again)."""
        d, m, k = env.discs, self.m_seen, self.k_seen

        def host(t: torch.Tensor) -> np.ndarray:
            a = t.detach().cpu().numpy()
            return a if a.dtype == np.bool_ else a.astype(np.float64)

        fields: dict[str, Any] = dict(
            v_p0=host(d.vessel_p0_ne[:, :m]),
            v_course=host(d.vessel_course_rad[:, :m]),
            v_speed=host(d.vessel_speed_mps[:, :m]),
            v_turn=host(d.vessel_turn_radps[:, :m]),
            v_radius=host(d.vessel_radius_m[:, :m]),
            vessel_ok=host(d.vessel_ok[:, :m]),
            centres=host(d.centres_ne[:, :k]),
            radii=host(d.radii_m[:, :k]),
            static_ok=host(d.static_ok[:, :k]),
            inner=_Inner(host(env.state)),
            base=_Base(env.scenario.max_heading_change_rad),
        )
        if self._host is None:
            self._host = _HostView(**fields)
        else:
            for name, value in fields.items():
                setattr(self._host, name, value)
        return self._host

    def reset(self, env: Any, boats: torch.Tensor) -> None:
        """``boats`` (N,) bool of ``env`` started new episodes (their discs already set)."""
        rows = boats.detach().cpu().numpy()
        idx = np.flatnonzero(rows)
        if idx.size == 0:
            return
        d = env.discs
        vessels = int(d.vessel_ok[boats].sum(1).max())
        statics = int(d.static_ok[boats].sum(1).max())
        self.m_seen, self.k_seen = max(self.m_seen, vessels), max(self.k_seen, statics)
        self.targets.reset(self._view(env), idx)  # type: ignore[arg-type]

    def steer(self, env: Any, time_s: torch.Tensor) -> bool:
        """Steer every target at its boat's episode time ``time_s`` (N,) s and write the
        vessels' new motion into ``env.discs``; False (nothing changed) without targets."""
        view = self._view(env)
        if not self.targets.steer(view, time_s.detach().cpu().numpy()):  # type: ignore[arg-type]
            return False
        d, m = env.discs, self.m_seen

        def device(a: np.ndarray, like: torch.Tensor) -> torch.Tensor:
            new = like.clone()
            new[:, :m] = torch.as_tensor(a, dtype=like.dtype, device=like.device)
            return new

        env.discs = replace(
            d,
            vessel_p0_ne=device(view.v_p0, d.vessel_p0_ne),
            vessel_course_rad=device(view.v_course, d.vessel_course_rad),
            vessel_turn_radps=device(view.v_turn, d.vessel_turn_radps),
        )
        return True
