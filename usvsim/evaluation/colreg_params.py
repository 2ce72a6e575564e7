"""Parameters of the COLREG evaluation (:mod:`usvsim.evaluation.colreg`), scaled to usvsim's boat.

Sources
-------
The ship-scale values are those of the evaluator of NTNU's colav-simulator (Woerner 2016 /
Woerner et al. 2019, "Quantifying protocol evaluation for autonomous collision avoidance",
Autonomous Robots 43; Minne 2017, NTNU MSc thesis), as collected in the project's reference note
``colreg-facts.md``: stage ranges 2500 / 1100 / 200 m, preferred passing distance 190 m, minimum
acceptable CPA 100 m, near miss 50 m, collision 30 m, a course change of 30° readily apparent and
2° detectable, head-on sector 13°, crossing threshold −10°, overtaking sector 112.5°-247.5°
(COLREG rule 13: 22.5° abaft the beam), a starboard manoeuvre ≥ 10°, safety weights 0.2 / 0.3 /
0.5 and the rule penalties listed with each field below.

Scaling rule (stated)
---------------------
Every range is kept as the same *time at the own ship's speed*: ``r_boat = r_ship × U_boat /
U_ship`` with U_ship = 10 m/s (the own ship of colav-simulator's Imazu scenario files, where these
defaults are used; :data:`usvsim.evaluation.imazu.SHIP_SPEED_MPS`) and U_boat = 3.0 m/s (the
cruise speed of :data:`usvsim.vessel.vessels.DEFAULT_VESSEL`), so the factor is
:data:`RANGE_SCALE` = 0.3. A give-way vessel at the entry range then has the same 250 s to act as
the ship had at 2500 m. The scaled distances fit the task's own: collision 9 m lies between
usvsim's collision (centres within 5 m + half a beam, 6.7 m, :mod:`usvsim.task.openwater`) and its
success margin (centres 14 m apart), and the near miss, 15 m, is that margin. Angles,
weights and ratios are scale-free and kept as published. The values that the sources do not give
(TCPA horizon, stand-on tolerances, the speed-change thresholds) are usvsim's choices and say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from usvsim.vessel.vessels import DEFAULT_VESSEL

__all__ = ["RANGE_SCALE", "SHIP_SPEED_MPS", "ColregParams", "parameter_table"]

SHIP_SPEED_MPS = 10.0  # m/s, own ship of colav-simulator's Imazu files (imazu.SHIP_SPEED_MPS)
RANGE_SCALE = DEFAULT_VESSEL.cruise_speed_mps / SHIP_SPEED_MPS  # 0.3: ranges as equal times
_DEG = math.pi / 180.0


@dataclass(frozen=True)
class ColregParams:
    """Every range, angle and weight of the COLREG evaluation (boat scale by default).

    Ranges in m at boat scale (ship value × :data:`RANGE_SCALE`, module docstring); angles in rad;
    weights and penalties dimensionless (a rule score is 1 minus its penalties).
    """

    # --- entry criteria (when an encounter begins) ---
    entry_range_m: float = 2500.0 * RANGE_SCALE  # m, 750; Woerner stage-1 range 2500 m
    risk_cpa_m: float = 190.0 * RANGE_SCALE  # m, 57; a risk of collision: predicted CPA below the
    # preferred passing distance (Woerner 2019 entry criterion, r_pref)
    risk_tcpa_s: float = 300.0  # s, predicted CPA at most this far ahead (usvsim's choice: the
    # 750 m entry range closed at 2.5 m/s, slow overtaking included)
    # --- classification sectors (COLREG rules 13-15) ---
    head_on_rad: float = 13.0 * _DEG  # rad, |bearing| and |aspect| within: head-on (Woerner 2019)
    crossing_port_rad: float = 10.0 * _DEG  # rad, a crossing target up to this far on the port
    # bow still makes the own ship give way (Woerner 2019, crossing threshold −10°)
    overtaking_rad: float = 112.5 * _DEG  # rad, 22.5° abaft the beam (COLREG rule 13)
    # --- manoeuvre thresholds (rules 8, 14, 16, 17) ---
    starboard_min_rad: float = 10.0 * _DEG  # rad, first alteration this large decides its side
    # (Woerner 2019, starboard manoeuvre ≥ 10°)
    apparent_course_rad: float = 30.0 * _DEG  # rad, readily apparent course change (Woerner 2019)
    detectable_course_rad: float = 2.0 * _DEG  # rad, detectable course change (Woerner 2019)
    apparent_speed_ratio: float = 0.5  # -, readily apparent speed reduction: to half (usvsim's
    # choice; rule 8(b) "large enough to be readily apparent")
    detectable_speed_ratio: float = 0.1  # -, a 10 % reduction is detectable (usvsim's choice)
    stand_on_course_rad: float = 10.0 * _DEG  # rad, a stand-on course change (usvsim's choice:
    # the starboard-manoeuvre threshold; smaller is track keeping)
    stand_on_speed_ratio: float = 0.2  # -, a stand-on speed change |ΔU|/U (usvsim's choice)
    stand_on_free_range_m: float = 1100.0 * RANGE_SCALE  # m, 330; inside it the stand-on may act
    # (rule 17(a)(ii)); Woerner stage-2 range 1100 m
    ahead_range_m: float = 1100.0 * RANGE_SCALE  # m, 330; crossing the target's track this close
    # ahead of its bow is "crossing ahead" (usvsim's choice: the stage-2 range)
    # --- safety (CPA) ---
    preferred_cpa_m: float = 190.0 * RANGE_SCALE  # m, 57; preferred passing distance (Woerner)
    min_cpa_m: float = 100.0 * RANGE_SCALE  # m, 30; minimum acceptable CPA (Woerner)
    near_miss_m: float = 50.0 * RANGE_SCALE  # m, 15; near miss (Woerner)
    collision_m: float = 30.0 * RANGE_SCALE  # m, 9; collision (Woerner)
    weight_min_cpa: float = 0.2  # -, safety weight of CPA below preferred (Woerner 2019)
    weight_near_miss: float = 0.3  # -, safety weight of a near miss (Woerner 2019)
    weight_collision: float = 0.5  # -, safety weight of a collision (Woerner 2019)
    # --- rule penalties (Woerner 2019, colav-simulator evaluator defaults) ---
    penalty_head_on_starboard_pass: float = 0.6  # -, head-on passed starboard to starboard
    penalty_head_on_not_starboard: float = 0.4  # -, head-on manoeuvre not to starboard
    penalty_crossing_ahead: float = 0.5  # -, give-way vessel crosses ahead (rule 15)
    penalty_overtaking_ahead: float = 0.3  # -, overtaking vessel crosses ahead (rule 13)
    penalty_not_apparent: float = 0.5  # -, give-way manoeuvre not readily apparent (rules 8, 16)
    penalty_stand_on_course: float = 0.5  # -, stand-on vessel changes course (rule 17)
    penalty_stand_on_speed: float = 0.25  # -, stand-on vessel changes speed (rule 17)
    # --- pass/fail ---
    pass_apparent_fraction: float = 0.5  # -, a give-way manoeuvre passes when its "not apparent"
    # deficiency is at most this (a 16° course change or a 30 % slow-down; usvsim's choice)

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0.0):
                raise ValueError(f"ColregParams.{f.name} must be a finite number ≥ 0, got {v!r}")
        if not self.collision_m < self.near_miss_m < self.min_cpa_m < self.preferred_cpa_m:
            raise ValueError(
                "ColregParams: need collision_m < near_miss_m < min_cpa_m < preferred_cpa_m"
            )
        if not self.detectable_course_rad < self.apparent_course_rad:
            raise ValueError("ColregParams: need detectable_course_rad < apparent_course_rad")
        if not self.detectable_speed_ratio < self.apparent_speed_ratio:
            raise ValueError("ColregParams: need detectable_speed_ratio < apparent_speed_ratio")

    def scaled(self, factor: float) -> ColregParams:
        """The same parameters with every range (``*_m``) multiplied by ``factor`` (another
        vessel: e.g. ``1 / RANGE_SCALE`` gives the ship values back)."""
        if not (math.isfinite(factor) and factor > 0.0):
            raise ValueError(f"factor must be a positive finite number, got {factor}")
        return replace(
            self,
            **{
                f.name: getattr(self, f.name) * factor
                for f in fields(self)
                if f.name.endswith("_m")
            },
        )


def parameter_table(params: ColregParams | None = None) -> list[tuple[str, float, float | None]]:
    """(name, value in SI / degrees for angles, ship value or None) per field: the docs' table."""
    p = params or ColregParams()
    rows: list[tuple[str, float, float | None]] = []
    for f in fields(p):
        v = float(getattr(p, f.name))
        if f.name.endswith("_rad"):
            rows.append((f.name, math.degrees(v), None))
        elif f.name.endswith("_m"):
            rows.append((f.name, v, v / RANGE_SCALE))
        else:
            rows.append((f.name, v, None))
    return rows
