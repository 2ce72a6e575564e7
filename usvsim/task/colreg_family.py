"""COLREG encounter members of the open-water family, for training in traffic (issue 41).

:data:`COLREG_FAMILY` is a :class:`usvsim.task.openwater_env.ScenarioMixture` of two
:class:`usvsim.task.openwater.OpenWaterScenario` members whose vessels are drawn by
:class:`ColregTraffic` (the scenario's ``traffic`` field: its own random stream, after every
other draw of the episode):

* ``colreg-imazu``: 1-4 target vessels whose nominal tracks meet the own ship's nominal run at
  one common time t_c, as in Imazu's 22 problems (Imazu 1987; every target on a collision course
  at the same moment, :mod:`usvsim.evaluation.imazu`), target speeds 0.5-1 of the own ship's as
  there (5-10 m/s against 10 m/s);
* ``colreg-trafficgen``: 1-3 targets, each of one of DNV trafficgen's five encounter types
  (head-on HO, crossing give-way CR-GW, crossing stand-on CR-SO, overtaking give-way OT-GW,
  overtaking stand-on OT-SO; the titles of its baseline situations,
  :mod:`usvsim.evaluation.trafficgen_io`) and each meeting the own ship at its own time.

Every other range (own cruise speed, current, GNSS quality and outages, radar degradation) is
that of the open-water family's ``traffic`` member (:data:`OPEN_WATER_FAMILY`), so the
disturbances stay those of the family; the own ship starts heading within ±15° of its goal
(a goal 250-500 m away, no static obstacle), so that the encounter meets it under way;
:data:`COLREG_FAMILY_SUITE_GOALS` puts the goal 250-850 m away, so that the COLREG suite's goals
(Imazu 600 m, trafficgen 797 m) lie inside the training range. Use
:func:`colreg_training_family` for the training mixture (the open-water family with a share of
these members, :func:`usvsim.task.openwater_env.mix_families`).

Geometry of one target (NED, angles clockwise from north; χ_g the direction start → goal, U the
own cruise speed, n = (−sin χ_g, cos χ_g) the starboard normal)::

    meeting point   M = S + U t_c (cos χ_g, sin χ_g) + m n      m ~ U[miss range]
    target course   χ_t = χ_g + Δχ (by type, below)             speed V = ratio × U
    target start    P0 = M − V t_c (cos χ_t, sin χ_t)

==================  =====================================  =======================
type (own role)     Δχ (deg)                                V / U
==================  =====================================  =======================
head-on             180 ± 10                                head-on/crossing ratio
crossing-give-way   −(45 … 135): from the own starboard     head-on/crossing ratio
crossing-stand-on   +(45 … 135): from the own port side     head-on/crossing ratio
overtaking-give-way ±15 (the own ship overtakes)            0.25-0.75
overtaking-stand-on ±15 (the target overtakes)              1.3-1.8
==================  =====================================  =======================

The sectors follow COLREG rules 13-15 (head-on: reciprocal courses; overtaking: from more than
22.5° abaft the beam); their widths and the speed ratios are usvsim's choice. A target whose
start lies within ``start_clearance_m`` of the own start is drawn again (same stream).

Training never uses the COLREG suite's episodes: the suite's sets are Imazu's 22 fixed problems
and trafficgen's 55 fixed situations, perturbed by small jitters and drawn from the seeds
``crc32("<set>/<split>")`` (:mod:`usvsim.evaluation.colreg_suite`); these members draw their
own geometry (random types, angles, speeds, meeting times) from the family's per-boat seeds and
the traffic stream (tested: no test-split episode's targets are reproduced).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from usvsim.common.angles import ssa
from usvsim.task.openwater import OpenWaterEpisode, OpenWaterScenario, Vessel
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, ScenarioMixture, mix_families

__all__ = [
    "COLREG_FAMILY",
    "COLREG_KINDS",
    "ColregTraffic",
    "colreg_member",
    "colreg_training_family",
    "goal_overtaking_family",
]

Range = tuple[float, float]
DEG = math.pi / 180.0
COLREG_KINDS = (
    "head-on",
    "crossing-give-way",
    "crossing-stand-on",
    "overtaking-give-way",
    "overtaking-stand-on",
)


@dataclass(frozen=True)
class ColregTraffic:
    """How the target vessels of a COLREG member are drawn (module docstring); a
    :class:`usvsim.task.openwater.TrafficDraw`."""

    n_targets_range: tuple[int, int] = (1, 4)  # targets per episode, uniform integer
    kinds: tuple[str, ...] = COLREG_KINDS  # each target's type, uniform over these
    common_meeting: bool = True  # one t_c for every target (Imazu) or one each (trafficgen)
    meet_fraction_range: Range = (0.35, 0.6)  # -, t_c × U as a fraction of |S G|
    head_on_course_rad: Range = (-10 * DEG, 10 * DEG)  # rad, Δχ − π
    crossing_course_rad: Range = (45 * DEG, 135 * DEG)  # rad, |Δχ|
    overtaking_course_rad: Range = (-15 * DEG, 15 * DEG)  # rad, Δχ
    speed_ratio_range: Range = (0.5, 1.5)  # -, V / U head-on and crossing
    overtaken_ratio_range: Range = (0.25, 0.75)  # -, V / U, the own ship overtakes
    overtaking_ratio_range: Range = (1.3, 1.8)  # -, V / U, the target overtakes
    miss_distance_range_m: Range = (-10.0, 10.0)  # m, signed, starboard positive
    radius_m: float = 5.0  # m, hull disc of a 10 m vessel (usvsim.task.openwater)
    start_clearance_m: float = 40.0  # m, no target starts this close to the own start

    def __post_init__(self) -> None:
        lo, hi = self.n_targets_range
        if not 1 <= lo <= hi:
            raise ValueError(f"ColregTraffic.n_targets_range must be 1 <= lo <= hi, got {lo, hi}")
        if not self.kinds or any(k not in COLREG_KINDS for k in self.kinds):
            raise ValueError(f"ColregTraffic.kinds must be a non-empty subset of {COLREG_KINDS}")
        for name in ("meet_fraction_range", "speed_ratio_range", "overtaken_ratio_range",
                     "overtaking_ratio_range", "head_on_course_rad", "crossing_course_rad",
                     "overtaking_course_rad", "miss_distance_range_m"):  # fmt: skip
            a, b = getattr(self, name)
            if not (math.isfinite(a) and math.isfinite(b) and a <= b):
                raise ValueError(f"ColregTraffic.{name} must be finite with lo <= hi")
        if self.meet_fraction_range[0] <= 0 or self.speed_ratio_range[0] <= 0:
            raise ValueError("ColregTraffic: meeting fractions and speed ratios must be > 0")

    def vessels(self, episode: OpenWaterEpisode, rng: np.random.Generator) -> tuple[Vessel, ...]:
        """The targets of ``episode`` drawn from ``rng`` (module docstring)."""
        start = episode.start_ne
        sx, sy = float(start[0]), float(start[1])
        gx, gy = episode.goal_ne
        length = math.hypot(gx - sx, gy - sy)
        chi_g = math.atan2(gy - sy, gx - sx)
        dist = episode.disturbance
        own = dist.speed_mps if dist is not None and dist.speed_mps else 3.0  # m/s; study 3
        n = int(rng.integers(self.n_targets_range[0], self.n_targets_range[1] + 1))
        t_common = _at(self.meet_fraction_range, rng.random()) * length / own
        out = []
        for _ in range(n):
            kind = self.kinds[int(rng.integers(len(self.kinds)))]
            for _attempt in range(20):
                t_c = t_common if self.common_meeting else (
                    _at(self.meet_fraction_range, rng.random()) * length / own
                )  # fmt: skip
                v = self._target(rng, kind, (sx, sy), chi_g, own, t_c)
                if math.hypot(v.x0_n - sx, v.y0_e - sy) >= self.start_clearance_m:
                    break
            out.append(v)
        return tuple(out)

    def _target(self, rng: np.random.Generator, kind: str, s: tuple[float, float],
                chi_g: float, own: float, t_c: float) -> Vessel:  # fmt: skip
        """One target of type ``kind`` meeting the own ship at ``t_c`` (module docstring)."""
        u_course, u_speed, u_miss = rng.random(3).tolist()
        if kind == "head-on":
            dchi, ratio = math.pi + _at(self.head_on_course_rad, u_course), self.speed_ratio_range
        elif kind.startswith("crossing"):
            side = -1.0 if kind == "crossing-give-way" else 1.0  # heading to port: from starboard
            dchi, ratio = side * _at(self.crossing_course_rad, u_course), self.speed_ratio_range
        else:
            dchi = _at(self.overtaking_course_rad, u_course)
            ratio = (self.overtaken_ratio_range if kind == "overtaking-give-way"
                     else self.overtaking_ratio_range)  # fmt: skip
        course = chi_g + dchi
        speed = _at(ratio, u_speed) * own
        miss = _at(self.miss_distance_range_m, u_miss)
        run = own * t_c
        mx = s[0] + run * math.cos(chi_g) - miss * math.sin(chi_g)
        my = s[1] + run * math.sin(chi_g) + miss * math.cos(chi_g)
        back = speed * t_c
        x0, y0 = mx - back * math.cos(course), my - back * math.sin(course)
        return Vessel(x0, y0, float(ssa(course)), speed, 0.0, self.radius_m, kind)


def _at(r: Range, u: float) -> float:
    """The point ``u`` ∈ [0, 1) of range ``r``."""
    return r[0] + (r[1] - r[0]) * u


def _traffic_member() -> OpenWaterScenario:
    """The open-water family's ``traffic`` member (its disturbance ranges)."""
    return OPEN_WATER_FAMILY.members[OPEN_WATER_FAMILY.names.index("traffic")]


# the goal distances of the COLREG suite's episodes (usvsim.evaluation.colreg_suite): Imazu's
# problems 600 m ahead (usvsim.evaluation.imazu), trafficgen's baseline situations 797 m (the
# own ship's 8 min run at ship scale, usvsim.evaluation.trafficgen_io); measured on the suite
GOAL_DISTANCE_RANGE_M: Range = (250.0, 500.0)  # m, the members' default (COLREG_FAMILY)
SUITE_GOAL_DISTANCE_RANGE_M: Range = (250.0, 850.0)  # m, covers both of the suite's goals


def colreg_member(
    traffic: ColregTraffic, goal_distance_range_m: Range = GOAL_DISTANCE_RANGE_M
) -> OpenWaterScenario:
    """A COLREG member with ``traffic`` (module docstring): the family's ``traffic`` member's
    disturbances, no static obstacle, no route vessel, the goal ``goal_distance_range_m``
    (default 250-500 m) ahead of a start heading within ±15° of it."""
    return replace(
        _traffic_member(),
        primary_obstacle=False,
        n_vessels_range=(0, 0),
        goal_distance_range_m=goal_distance_range_m,
        goal_bearing_range_rad=(0.0, 0.0),
        goal_lateral_range_m=(0.0, 0.0),
        heading_offset_range_rad=(-15 * DEG, 15 * DEG),
        traffic=traffic,
    )


def colreg_family(goal_distance_range_m: Range = GOAL_DISTANCE_RANGE_M) -> ScenarioMixture:
    """The two COLREG members (module docstring), half the episodes each, with their goals
    ``goal_distance_range_m`` ahead (m)."""
    return ScenarioMixture(
        members=(
            colreg_member(
                ColregTraffic(n_targets_range=(1, 4), speed_ratio_range=(0.5, 1.0)),
                goal_distance_range_m,
            ),
            colreg_member(
                ColregTraffic(n_targets_range=(1, 3), common_meeting=False), goal_distance_range_m
            ),
        ),
        weights=(0.5, 0.5),
        names=("imazu", "trafficgen"),
    )


COLREG_FAMILY = colreg_family()
# the members with goals as far as the suite's (SUITE_GOAL_DISTANCE_RANGE_M)
COLREG_FAMILY_SUITE_GOALS = colreg_family(SUITE_GOAL_DISTANCE_RANGE_M)


# goal overtaking: one slow vessel on the route that the own boat overtakes about where the goal
# is (the meeting point 80-110 % of the route, ±10 m across it), goals 120-300 m ahead. The
# situation of most goal orbits on the stress suite's moving-vessels set (docs/notes/
# 2026-12-traffic.md: an overtaken vessel that passes within 15 m of the goal); usvsim's
# practice member for them, not tuned.
GOAL_OVERTAKING = ColregTraffic(
    n_targets_range=(1, 1), kinds=("overtaking-give-way",), meet_fraction_range=(0.8, 1.1),
)  # fmt: skip


def goal_overtaking_family() -> ScenarioMixture:
    """One member, ``goal-overtaking``: :data:`GOAL_OVERTAKING`'s vessel, the goal 120-300 m
    ahead, the family's traffic disturbances (:func:`colreg_member`); mixed into a training
    family by :func:`usvsim.task.openwater_env.mix_families` (``RLSetup.goal_traffic_share``)."""
    return ScenarioMixture(
        members=(colreg_member(GOAL_OVERTAKING, (120.0, 300.0)),),
        weights=(1.0,),
        names=("goal-overtaking",),
    )


def colreg_training_family(
    share: float = 0.5, base: ScenarioMixture = OPEN_WATER_FAMILY
) -> ScenarioMixture:
    """``base`` (default the open-water family) with :data:`COLREG_FAMILY` drawn in a share
    ``share`` of the episodes; its members named ``colreg-imazu`` and ``colreg-trafficgen``."""
    return mix_families(base, COLREG_FAMILY, share, prefix="colreg-")
