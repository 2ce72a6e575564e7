"""Observations of the pole-avoidance task as tensors: the twins of :mod:`usvsim.task.observations`
and :func:`usvsim.task.radar.render_radar` for the torch environment.

Each function does the NumPy original's operations in the same order on tensors of N boats (on
any device), tested equal to it in ``tests/usvsim/task/test_torch_env.py``. The goal vector's
standardisation constants are those of :data:`usvsim.task.observations.GOAL_STANDARDIZATION`
(repeated here, tested equal, because that module needs gymnasium, which a GPU machine may lack).

==============  =====================================  ==============================
kind            observation                            tensor
==============  =====================================  ==============================
``positional``  ``[r_pole, φ_pole, r_goal, φ_goal]``   (N, 4) float32 (or float64)
``radar``       the polar radar image                  (N, 1, 50, 119) uint8
``radar+goal``  ``{"radar": image, "goal": ĝ}``        dict; ĝ (N, 2) float32
==============  =====================================  ==============================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from usvsim.nav.torch_nav import torch_ssa
from usvsim.task.radar import RadarConfig

__all__ = [
    "GOAL_MEAN",
    "GOAL_STD",
    "TORCH_OBSERVATIONS",
    "RadarGrid",
    "TorchObservation",
    "radar_image",
    "relative_polar_torch",
    "select_rows",
    "standardized_goal",
]

#: The observation kinds the torch environment builds.
TORCH_OBSERVATIONS = ("positional", "radar", "radar+goal")
#: :data:`usvsim.task.observations.GOAL_STANDARDIZATION`: r_goal over U[0, 220] m, φ over U[-π, π)
GOAL_MEAN = (110.0, 0.0)
GOAL_STD = (220.0 / math.sqrt(12.0), math.pi / math.sqrt(3.0))

TorchObservation = torch.Tensor | dict[str, torch.Tensor]


def relative_polar_torch(
    pos_ne: torch.Tensor, psi_rad: torch.Tensor, targets_ne: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`usvsim.task.observations.relative_polar`: range (m) and bearing relative to the
    heading (rad, [-π, π)) from ``pos_ne`` (N, 2), ``psi_rad`` (N,) to ``targets_ne`` (N, K, 2),
    each (N, K)."""
    d = targets_ne - pos_ne[:, None, :]
    r = torch.hypot(d[..., 0], d[..., 1])
    return r, torch_ssa(torch.atan2(d[..., 1], d[..., 0]) - psi_rad[:, None])


@dataclass(frozen=True)
class RadarGrid:
    """The radar image's pixel edges as tensors on the device, built once (not per step)."""

    range_hi: torch.Tensor  # (rows,) m, upper row edges
    range_lo: torch.Tensor  # (rows,) m, lower row edges
    bearing_lo: torch.Tensor  # (cols,) rad, left column edges
    bearing_hi: torch.Tensor  # (cols,) rad, right column edges, the last one just past +fov

    @classmethod
    def build(cls, cfg: RadarConfig, dtype: torch.dtype, device: torch.device) -> RadarGrid:
        """The edges of :class:`usvsim.task.radar.RadarConfig` as :func:`render_radar` uses them."""
        r_edges, b_edges = cfg.range_edges_m, cfg.bearing_edges_rad
        b_hi = b_edges[1:].copy()
        b_hi[-1] = np.nextafter(b_hi[-1], np.inf)  # the last column includes +half_fov

        def put(a: np.ndarray) -> torch.Tensor:
            return torch.as_tensor(a, dtype=dtype, device=device)

        return cls(put(r_edges[1:]), put(r_edges[:-1]), put(b_edges[:-1]), put(b_hi))


def radar_image(
    range_m: torch.Tensor, bearing_rad: torch.Tensor, radius_m: float, grid: RadarGrid
) -> torch.Tensor:
    """:func:`usvsim.task.radar.render_radar` of one obstacle per boat: (N, 1, rows, cols) uint8,
    255 where the obstacle's polar box touches the pixel. ``range_m``, ``bearing_rad`` (N,).

    The box's wrap past ±π is always evaluated (the NumPy original evaluates it only where a
    box is wide enough to wrap: elsewhere the shifted tests are all false, so the images are the
    same). Clutter and intensity noise are not drawn here (the caller refuses them)."""
    phi = torch_ssa(bearing_rad)
    lo_r, hi_r = (range_m - radius_m)[:, None], (range_m + radius_m)[:, None]
    rows = (grid.range_hi > lo_r) & (grid.range_lo <= hi_r)  # (N, rows)
    half = torch.asin(torch.clamp(radius_m / torch.clamp(range_m, min=1e-12), max=1.0))
    lo_b, hi_b = (phi - half)[:, None], (phi + half)[:, None]
    cols = (grid.bearing_hi > lo_b) & (grid.bearing_lo <= hi_b)  # (N, cols)
    for shift in (-2.0 * math.pi, 2.0 * math.pi):
        cols |= (grid.bearing_hi > lo_b + shift) & (grid.bearing_lo <= hi_b + shift)
    lit = rows[:, :, None] & cols[:, None, :]
    return (lit.to(torch.uint8) * 255)[:, None]


def standardized_goal(range_m: torch.Tensor, bearing_rad: torch.Tensor) -> torch.Tensor:
    """The ``goal`` entry of ``radar+goal`` (N, 2) float32: ``(x − mean) / std`` per column."""
    r = (range_m - GOAL_MEAN[0]) / GOAL_STD[0]
    b = (bearing_rad - GOAL_MEAN[1]) / GOAL_STD[1]
    return torch.stack([r, b], dim=-1).to(torch.float32)


def select_rows(
    mask: torch.Tensor, new: TorchObservation, old: TorchObservation
) -> TorchObservation:
    """Rows of ``new`` where ``mask`` (N,) bool, else of ``old`` (tensors or dicts of tensors)."""
    if isinstance(new, dict):
        assert isinstance(old, dict)
        return {k: select_rows(mask, new[k], old[k]) for k in new}  # type: ignore[misc]
    assert isinstance(old, torch.Tensor)
    return torch.where(mask.view(-1, *([1] * (new.ndim - 1))), new, old)
