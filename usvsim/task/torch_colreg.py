"""The per-decision COLREG reward terms (:mod:`usvsim.task.colreg_reward`) as tensor code, for
the torch open-water env (issue 41 on the device).

:class:`TorchColregReward` is :class:`usvsim.task.colreg_reward.ColregReward` on any torch
device: the same encounters (entry, role and course fixed when one begins, open until the
vessel is passed), the same six terms and weights, batched over boats and vessel slots
(tensors (N, K), no host read and no Python loop over boats or vessels), its encounter memory
as tensors that a restart clears with a mask. The geometry is
:func:`usvsim.task.colreg_geometry.encounter_kinematics` and ``classify_encounter`` in torch
(:func:`encounter_kinematics_torch`, :func:`classify_encounter_torch`). Equal to the NumPy
terms in float64 (tests: the env's rewards on the COLREG family against ``OpenWaterVectorEnv``
with ``colreg_reward``).

Shapes: own position (N, 2) m, course over ground and speed (N,) rad and m/s; vessels'
positions and velocities (N, K, 2) m and m/s, valid (N, K) bool.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from usvsim.nav.torch_nav import torch_ssa
from usvsim.task.colreg_geometry import GIVE_WAY, STAND_ON, EncounterType
from usvsim.task.colreg_params import ColregParams
from usvsim.task.colreg_reward import COLREG_TERMS, ColregRewardWeights
from usvsim.task.torch_scene import TorchDiscs, vessel_motion_torch

__all__ = [
    "TorchColregReward",
    "TorchEncounterKinematics",
    "classify_encounter_torch",
    "encounter_kinematics_torch",
    "own_motion_torch",
]

_NONE = int(EncounterType.NONE)


@dataclass(frozen=True)
class TorchEncounterKinematics:
    """:class:`usvsim.task.colreg_geometry.EncounterKinematics` as tensors (same fields)."""

    range_m: torch.Tensor
    bearing_rad: torch.Tensor
    aspect_rad: torch.Tensor
    cpa_m: torch.Tensor
    tcpa_s: torch.Tensor
    x_t_m: torch.Tensor
    y_t_m: torch.Tensor


def encounter_kinematics_torch(
    own_ne: torch.Tensor, own_course_rad: torch.Tensor, own_speed_mps: torch.Tensor,
    target_ne: torch.Tensor, target_course_rad: torch.Tensor, target_speed_mps: torch.Tensor,
) -> TorchEncounterKinematics:  # fmt: skip
    """:func:`usvsim.task.colreg_geometry.encounter_kinematics` on tensors (positions (..., 2)
    m, courses (...) rad, speeds (...) m/s, broadcast together)."""
    d = target_ne - own_ne
    dn, de = d[..., 0], d[..., 1]
    dv_n = target_speed_mps * torch.cos(target_course_rad) - own_speed_mps * torch.cos(
        own_course_rad
    )
    dv_e = target_speed_mps * torch.sin(target_course_rad) - own_speed_mps * torch.sin(
        own_course_rad
    )
    dv2 = dv_n**2 + dv_e**2
    moving = dv2 > 1e-12
    tcpa = torch.where(moving, -(dn * dv_n + de * dv_e) / torch.where(moving, dv2, 1.0), 0.0)
    cpa = torch.hypot(dn + dv_n * tcpa, de + dv_e * tcpa)
    los = torch.atan2(de, dn)
    cos_t, sin_t = torch.cos(target_course_rad), torch.sin(target_course_rad)
    return TorchEncounterKinematics(
        range_m=torch.hypot(dn, de),
        bearing_rad=torch_ssa(los - own_course_rad),
        aspect_rad=torch_ssa(los + math.pi - target_course_rad),
        cpa_m=cpa,
        tcpa_s=tcpa,
        x_t_m=-(dn * cos_t + de * sin_t),
        y_t_m=-(-dn * sin_t + de * cos_t),
    )


def classify_encounter_torch(
    bearing_rad: torch.Tensor, aspect_rad: torch.Tensor, own_speed_mps: torch.Tensor,
    target_speed_mps: torch.Tensor, params: ColregParams,
) -> torch.Tensor:  # fmt: skip
    """:func:`usvsim.task.colreg_geometry.classify_encounter` on tensors: the
    :class:`EncounterType` of each geometry as int64."""
    p, et = params, EncounterType
    out = torch.where(bearing_rad >= -p.crossing_port_rad, int(et.CROSSING_GIVE_WAY),
                      int(et.CROSSING_STAND_ON))  # fmt: skip
    head_on = (bearing_rad.abs() < p.head_on_rad) & (aspect_rad.abs() < p.head_on_rad)
    out = torch.where(head_on, int(et.HEAD_ON), out)
    overtaken = (bearing_rad.abs() > p.overtaking_rad) & (target_speed_mps > own_speed_mps)
    out = torch.where(overtaken, int(et.OVERTAKEN_STAND_ON), out)
    overtaking = (aspect_rad.abs() > p.overtaking_rad) & (own_speed_mps > target_speed_mps)
    return torch.where(overtaking, int(et.OVERTAKING_GIVE_WAY), out).to(torch.int64)


def own_motion_torch(
    north_m: torch.Tensor, east_m: torch.Tensor, end_step: torch.Tensor, dt_s: float,
    window: int = 10,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:  # fmt: skip
    """:func:`usvsim.task.colreg_reward.own_motion` from a period's true positions ``north_m``,
    ``east_m`` (N, T) m, one per plant step of ``dt_s``, and each boat's last step's index
    ``end_step`` (N,) (0-based, the judge's): position (N, 2) m, course (N,) rad and speed (N,)
    m/s over ground over the ``window`` steps before, and that step's time in the period (N,)
    s."""
    hi = torch.clamp(end_step, min=1)  # own_motion's max(count − 1, 1), with count = index + 1
    lo = torch.clamp(hi - window, min=0)
    at = torch.stack([hi, lo], 1)
    n, e = north_m.gather(1, at), east_m.gather(1, at)
    dn, de = n[:, 0] - n[:, 1], e[:, 0] - e[:, 1]
    span = (hi - lo).to(north_m.dtype) * dt_s
    pos = torch.stack([n[:, 0], e[:, 0]], 1)
    return pos, torch.atan2(de, dn), torch.hypot(dn, de) / span, (hi + 1).to(north_m.dtype) * dt_s


def _role_table(roles: tuple[EncounterType, ...], device: torch.device) -> torch.Tensor:
    """``table[role]`` True for ``roles`` (bool, one entry per :class:`EncounterType`)."""
    table = torch.zeros(len(EncounterType), dtype=torch.bool, device=device)
    table[[int(r) for r in roles]] = True
    return table


class TorchColregReward:
    """The COLREG terms of ``n_boats`` boats with ``n_slots`` vessel slots each, on ``device``
    in ``dtype`` (module docstring; :class:`usvsim.task.colreg_reward.ColregReward`)."""

    def __init__(
        self, weights: ColregRewardWeights, n_boats: int, n_slots: int, device: torch.device,
        dtype: torch.dtype,
    ) -> None:  # fmt: skip
        self.weights = weights
        shape = (n_boats, n_slots)
        self.role = torch.zeros(shape, dtype=torch.int64, device=device)  # EncounterType
        self.chi0 = torch.zeros(shape, dtype=dtype, device=device)  # rad, own course at start
        self.prev_y = torch.zeros(shape, dtype=dtype, device=device)  # m, own side of its track
        self.prev_dev = torch.zeros(shape, dtype=dtype, device=device)  # rad, δ before
        self.age_s = torch.zeros(shape, dtype=dtype, device=device)  # s, since it began
        self.max_dev = torch.zeros(shape, dtype=dtype, device=device)  # rad, largest δ so far
        self._give_way = _role_table(GIVE_WAY, device)
        self._stand_on = _role_table(STAND_ON, device)
        self._ahead = _role_table(
            (EncounterType.CROSSING_GIVE_WAY, EncounterType.OVERTAKING_GIVE_WAY), device
        )
        self._alter = _role_table((EncounterType.HEAD_ON, EncounterType.CROSSING_GIVE_WAY), device)

    def reset(self, boats: torch.Tensor) -> None:
        """Forget the encounters of ``boats`` (N,) bool (they start new episodes)."""
        self.role = torch.where(boats[:, None], _NONE, self.role)
        self.age_s = torch.where(boats[:, None], 0.0, self.age_s)

    def __call__(
        self, own_ne: torch.Tensor, own_course_rad: torch.Tensor, own_speed_mps: torch.Tensor,
        vessel_ne: torch.Tensor, vessel_velocity_ne: torch.Tensor, vessel_ok: torch.Tensor,
        dt_s: float,
    ) -> dict[str, torch.Tensor]:  # fmt: skip
        """The terms of one decision, each (N,) by name (:data:`COLREG_TERMS`), and their sum
        under ``"total"``; ``dt_s`` the time since the previous call (s, the decision
        period)."""
        w, p = self.weights, self.weights.params
        vn, ve = vessel_velocity_ne[..., 0], vessel_velocity_ne[..., 1]
        v_course, v_speed = torch.atan2(ve, vn), torch.hypot(vn, ve)
        chi, u = own_course_rad[:, None], own_speed_mps[:, None]
        kin = encounter_kinematics_torch(own_ne[:, None], chi, u, vessel_ne, v_course, v_speed)
        risk = (kin.cpa_m < p.risk_cpa_m) & (kin.tcpa_s > 0.0) & (kin.tcpa_s <= p.risk_tcpa_s)
        entry = vessel_ok & (kin.range_m < p.entry_range_m) & (risk | (kin.range_m < p.risk_cpa_m))
        new = (self.role == _NONE) & entry
        cls = classify_encounter_torch(kin.bearing_rad, kin.aspect_rad, u, v_speed, p)
        role = torch.where(new, cls, self.role)
        chi0 = torch.where(new, chi, self.chi0)
        prev_y = torch.where(new, kin.y_t_m, self.prev_y)
        prev_dev = torch.where(new, 0.0, self.prev_dev)
        age = torch.where(new, 0.0, self.age_s + dt_s)
        engaged = vessel_ok & (role != _NONE)
        open_ = engaged & (kin.tcpa_s > 0.0)
        zero = torch.zeros_like(kin.range_m)
        dev = torch.where(engaged, torch_ssa(chi - chi0), zero)
        head_on = open_ & (role == int(EncounterType.HEAD_ON))

        # rule 14: the target's predicted position at the CPA, in the own body frame
        cos_c, sin_c = torch.cos(chi), torch.sin(chi)
        rel_n, rel_e = vn - u * cos_c, ve - u * sin_c
        d_n = vessel_ne[..., 0] - own_ne[:, None, 0] + rel_n * kin.tcpa_s
        d_e = vessel_ne[..., 1] - own_ne[:, None, 1] + rel_e * kin.tcpa_s
        y_cpa = -sin_c * d_n + cos_c * d_e
        side = torch.where(head_on, torch.clamp(y_cpa / p.preferred_cpa_m, 0.0, 1.0), zero)
        max_dev = torch.where(new, zero, torch.maximum(self.max_dev, torch.where(open_, dev, zero)))
        first = head_on & (max_dev < p.starboard_min_rad)
        port = torch.where(first, torch.clamp(-dev / p.starboard_min_rad, 0.0, 1.0), zero)
        # rules 13, 15: crossed the target's course line ahead of its bow
        flip = torch.sign(kin.y_t_m) != torch.sign(prev_y)
        ahead = (engaged & self._ahead[role] & flip & (kin.x_t_m > 0.0)
                 & (kin.x_t_m < p.ahead_range_m))  # fmt: skip
        # rules 8, 16: growth of the starboard alteration up to a readily apparent one
        a = p.apparent_course_rad
        alter = open_ & self._alter[role]
        grown = (torch.clamp(dev, 0.0, a) - torch.clamp(prev_dev, 0.0, a)) / a
        gain = torch.where(alter, grown, zero)
        # rule 17: stand-on course change before the give-way vessel had time to act
        busy = torch.any(open_ & self._give_way[role], dim=1, keepdim=True)
        early = (kin.range_m > p.stand_on_free_range_m) | (age < w.stand_on_grace_s)
        stand = open_ & self._stand_on[role] & early & ~busy
        span = p.stand_on_course_rad - p.detectable_course_rad
        so = torch.where(
            stand, torch.clamp((dev.abs() - p.detectable_course_rad) / span, 0.0, 1.0), zero
        )
        # safety: predicted passing distance below the preferred one (Woerner's ramp)
        at_risk = (vessel_ok & (kin.tcpa_s > 0.0) & (kin.tcpa_s <= p.risk_tcpa_s)
                   & (kin.range_m < p.entry_range_m))  # fmt: skip
        short = (p.preferred_cpa_m - kin.cpa_m) / (p.preferred_cpa_m - p.min_cpa_m)
        cpa = torch.where(at_risk, torch.clamp(short, 0.0, 1.0), zero)

        self.role, self.chi0, self.prev_y = role, chi0, kin.y_t_m
        self.prev_dev = torch.where(engaged, torch.where(open_, dev, prev_dev), zero)
        self.age_s, self.max_dev = age, max_dev
        terms = {
            "head_on_side": -w.head_on_side * side.sum(1),
            "head_on_port": -w.head_on_port * port.sum(1),
            "crossing_ahead": -w.crossing_ahead * ahead.to(zero.dtype).sum(1),
            "starboard": w.starboard * gain.sum(1),
            "stand_on": -w.stand_on * so.sum(1),
            "cpa": -w.cpa * cpa.sum(1),
        }
        total = terms[COLREG_TERMS[0]]
        for t in COLREG_TERMS[1:]:
            total = total + terms[t]
        terms["total"] = total
        return terms

    def of_period(
        self, north_m: torch.Tensor, east_m: torch.Tensor, end_step: torch.Tensor,
        discs: TorchDiscs, period_start_s: torch.Tensor, dt_s: float, decision_period_s: float,
    ) -> dict[str, torch.Tensor]:  # fmt: skip
        """The terms of a decision just taken, from its true positions ``north_m``, ``east_m``
        (N, T) m (one per plant step of ``dt_s``), each boat's last step ``end_step`` (N,)
        (0-based) and the period's start ``period_start_s`` (N,) s (episode time): the own ship
        at that step (:func:`own_motion_torch`), the vessels of ``discs`` where they are then
        (``ColregReward.from_batch``)."""
        pos, course, speed, t_s = own_motion_torch(north_m, east_m, end_step, dt_s)
        v_pos, v_vel = vessel_motion_torch(
            discs.vessel_p0_ne, discs.vessel_course_rad, discs.vessel_speed_mps,
            discs.vessel_turn_radps, (period_start_s + t_s)[:, None],
        )  # fmt: skip
        return self(pos, course, speed, v_pos, v_vel, discs.vessel_ok, decision_period_s)
