"""Encounter geometry of COLREG rules 13-15, shared by the scorer and the training reward.

The scorer (:func:`usvsim.evaluation.colreg.evaluate_colreg`, on recorded tracks) and the
per-decision reward (:mod:`usvsim.task.colreg_reward`, on the batch's true state) classify an
encounter the same way; the functions live here, in the task layer, so that the task need not
import the evaluation (the architecture's one-way imports).

Frame and signs: NED, positions (north, east) m, courses clockwise from north (rad). The
*relative bearing* β of a target is its direction from the own ship minus the own course
(positive to starboard); its *aspect* α is the own ship's direction from the target minus the
target's course. CPA and TCPA are those of straight-line motion at the present velocities.

Classification (COLREG rules 13-15; sectors of :class:`usvsim.task.colreg_params.ColregParams`,
after Woerner et al. 2019, "Quantifying protocol evaluation for autonomous collision avoidance",
Autonomous Robots 43):

========================  ==============================================================
OVERTAKING_GIVE_WAY        |α| > 112.5° (own ship abaft the target's beam), own faster (13)
OVERTAKEN_STAND_ON         |β| > 112.5° (target abaft our beam), target faster (13, 17)
HEAD_ON                    |β| < 13° and |α| < 13°: reciprocal courses, each dead ahead (14)
CROSSING_GIVE_WAY          otherwise with −10° ≤ β: target on the starboard side (15, 16)
CROSSING_STAND_ON          otherwise, β < −10°: target on the port side (15, 17)
========================  ==============================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.colreg_params import ColregParams

__all__ = [
    "GIVE_WAY",
    "STAND_ON",
    "EncounterKinematics",
    "EncounterType",
    "classify_encounter",
    "encounter_kinematics",
]

FloatArray = NDArray[np.float64]


class EncounterType(IntEnum):
    """The own ship's role in an encounter, decided when it begins (module docstring)."""

    NONE = 0  # no risk of collision within the entry range
    HEAD_ON = 1  # rule 14
    CROSSING_GIVE_WAY = 2  # rules 15, 16
    CROSSING_STAND_ON = 3  # rules 15, 17
    OVERTAKING_GIVE_WAY = 4  # rule 13: the own ship overtakes
    OVERTAKEN_STAND_ON = 5  # rules 13, 17: the own ship is overtaken


GIVE_WAY = (
    EncounterType.HEAD_ON,
    EncounterType.CROSSING_GIVE_WAY,
    EncounterType.OVERTAKING_GIVE_WAY,
)
STAND_ON = (EncounterType.CROSSING_STAND_ON, EncounterType.OVERTAKEN_STAND_ON)


@dataclass(frozen=True)
class EncounterKinematics:
    """Own-ship/target geometry, every array of the broadcast shape of the inputs."""

    range_m: FloatArray  # m, centre to centre
    bearing_rad: FloatArray  # rad, β: target's direction minus own course, + starboard
    aspect_rad: FloatArray  # rad, α: own ship's direction from the target minus its course
    cpa_m: FloatArray  # m, predicted closest range (straight lines, present velocities)
    tcpa_s: FloatArray  # s, time to it (< 0: already passed; 0 without relative motion)
    x_t_m: FloatArray  # m, own ship ahead of the target's bow (target body frame)
    y_t_m: FloatArray  # m, own ship to the target's starboard (target body frame)


def encounter_kinematics(
    own_ne: FloatArray, own_course_rad: FloatArray, own_speed_mps: FloatArray,
    target_ne: FloatArray, target_course_rad: FloatArray, target_speed_mps: FloatArray,
) -> EncounterKinematics:  # fmt: skip
    """Range, bearing, aspect, CPA, TCPA and the own ship in the target's frame.

    Positions (..., 2) m, courses (...) rad, speeds (...) m/s, broadcast together (e.g. own
    (N, 1), targets (N, K)); returns arrays of the broadcast shape (module docstring).
    """
    d = np.asarray(target_ne, float) - np.asarray(own_ne, float)
    chi_o = np.asarray(own_course_rad, float)
    chi_t = np.asarray(target_course_rad, float)
    u_o = np.asarray(own_speed_mps, float)
    u_t = np.asarray(target_speed_mps, float)
    dv_n = u_t * np.cos(chi_t) - u_o * np.cos(chi_o)  # target velocity relative to own ship
    dv_e = u_t * np.sin(chi_t) - u_o * np.sin(chi_o)
    rng = np.hypot(d[..., 0], d[..., 1])
    dv2 = dv_n**2 + dv_e**2
    moving = dv2 > 1e-12
    tcpa = np.where(
        moving, -(d[..., 0] * dv_n + d[..., 1] * dv_e) / np.where(moving, dv2, 1.0), 0.0
    )
    cpa = np.hypot(d[..., 0] + dv_n * tcpa, d[..., 1] + dv_e * tcpa)
    los = np.arctan2(d[..., 1], d[..., 0])  # line of sight own -> target
    # own ship in the target's body frame (x forward, y starboard): which side of its track
    x_t = -(d[..., 0] * np.cos(chi_t) + d[..., 1] * np.sin(chi_t))
    y_t = -(-d[..., 0] * np.sin(chi_t) + d[..., 1] * np.cos(chi_t))
    return EncounterKinematics(
        range_m=rng,
        bearing_rad=ssa(los - chi_o),
        aspect_rad=ssa(los + np.pi - chi_t),
        cpa_m=cpa,
        tcpa_s=tcpa,
        x_t_m=x_t,
        y_t_m=y_t,
    )


def classify_encounter(
    bearing_rad: FloatArray, aspect_rad: FloatArray, own_speed_mps: FloatArray,
    target_speed_mps: FloatArray, params: ColregParams,
) -> NDArray[np.intp]:  # fmt: skip
    """:class:`EncounterType` of each geometry (module docstring table), as integers."""
    p = params
    bearing, aspect = bearing_rad, aspect_rad
    u_o, u_t = own_speed_mps, target_speed_mps
    out = np.where(bearing >= -p.crossing_port_rad, EncounterType.CROSSING_GIVE_WAY,
                   EncounterType.CROSSING_STAND_ON)  # fmt: skip
    out = np.where((np.abs(bearing) < p.head_on_rad) & (np.abs(aspect) < p.head_on_rad),
                   EncounterType.HEAD_ON, out)  # fmt: skip
    out = np.where((np.abs(bearing) > p.overtaking_rad) & (u_t > u_o),
                   EncounterType.OVERTAKEN_STAND_ON, out)  # fmt: skip
    out = np.where((np.abs(aspect) > p.overtaking_rad) & (u_o > u_t),
                   EncounterType.OVERTAKING_GIVE_WAY, out)  # fmt: skip
    return np.asarray(out).astype(np.intp)
