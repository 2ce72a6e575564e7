"""Parameters of the COLREG evaluation (:mod:`usvsim.evaluation.colreg`) and of the COLREG reward
(:mod:`usvsim.task.colreg_reward`), scaled to usvsim's boat. In the task layer so that both the
scorer and the training reward read the same values (:mod:`usvsim.task.colreg_geometry`).

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
from dataclasses import dataclass, field, fields, replace
from typing import Any

from usvsim.vessel.vessels import DEFAULT_VESSEL

__all__ = ["RANGE_SCALE", "SHIP_SPEED_MPS", "ColregParams", "parameter_markdown", "parameter_table"]

SHIP_SPEED_MPS = 10.0  # m/s, own ship of colav-simulator's Imazu files (imazu.SHIP_SPEED_MPS)
RANGE_SCALE = DEFAULT_VESSEL.cruise_speed_mps / SHIP_SPEED_MPS  # 0.3: ranges as equal times
_DEG = math.pi / 180.0
_W = "Woerner et al. 2019 (colav-simulator evaluator defaults)"
_U = "usvsim's choice"


def _f(value: float, unit: str, meaning: str, source: str) -> Any:
    """A parameter field: its default with unit, meaning and source as metadata (the docs'
    table, :func:`parameter_markdown`)."""
    return field(default=value, metadata={"unit": unit, "meaning": meaning, "source": source})


@dataclass(frozen=True)
class ColregParams:
    """Every range, angle and weight of the COLREG evaluation (boat scale by default).

    Ranges in m at boat scale (ship value × :data:`RANGE_SCALE`, module docstring); angles in rad;
    weights and penalties dimensionless (a rule score is 1 minus its penalties).
    """

    # --- entry criteria (when an encounter begins) ---
    entry_range_m: float = _f(
        2500.0 * RANGE_SCALE, "m", "entry (risk-assessment) range; stage-1 range 2500 m", _W
    )
    risk_cpa_m: float = _f(
        190.0 * RANGE_SCALE,
        "m",
        "risk of collision: predicted CPA below the preferred passing distance",
        _W,
    )
    risk_tcpa_s: float = _f(
        300.0,
        "s",
        "risk of collision: predicted CPA at most this far ahead (750 m closed at 2.5 m/s)",
        _U,
    )
    # --- classification sectors (COLREG rules 13-15) ---
    head_on_rad: float = _f(
        13.0 * _DEG, "rad", "head-on: relative bearing and aspect both within ±", _W
    )
    crossing_port_rad: float = _f(
        10.0 * _DEG,
        "rad",
        "a crossing target this far on the port bow still makes us give way (−10°)",
        _W,
    )
    overtaking_rad: float = _f(
        112.5 * _DEG, "rad", "overtaking sector: more than 22.5° abaft the beam", "COLREG rule 13"
    )
    # --- manoeuvre thresholds (rules 8, 14, 16, 17) ---
    starboard_min_rad: float = _f(
        10.0 * _DEG, "rad", "the first alteration this large decides the manoeuvre's side", _W
    )
    apparent_course_rad: float = _f(
        30.0 * _DEG, "rad", "readily apparent course change (rule 8)", _W
    )
    detectable_course_rad: float = _f(2.0 * _DEG, "rad", "detectable course change", _W)
    apparent_speed_ratio: float = _f(
        0.5, "-", "readily apparent speed reduction (to half; rule 8(b))", _U
    )
    detectable_speed_ratio: float = _f(0.1, "-", "detectable speed reduction", _U)
    stand_on_course_rad: float = _f(
        10.0 * _DEG,
        "rad",
        "a stand-on course change (the starboard-manoeuvre threshold; smaller is track keeping)",
        _U,
    )
    stand_on_speed_ratio: float = _f(0.2, "-", "a stand-on speed change, relative", _U)
    stand_on_free_range_m: float = _f(
        1100.0 * RANGE_SCALE,
        "m",
        "inside it the stand-on vessel may act (rule 17(a)(ii)); stage-2 range 1100 m",
        _W,
    )
    ahead_range_m: float = _f(
        1100.0 * RANGE_SCALE,
        "m",
        "crossing its course line this close ahead of its bow is crossing ahead (stage 2)",
        _U,
    )
    # --- safety (CPA) ---
    preferred_cpa_m: float = _f(190.0 * RANGE_SCALE, "m", "preferred passing distance", _W)
    min_cpa_m: float = _f(100.0 * RANGE_SCALE, "m", "minimum acceptable CPA (below it: fail)", _W)
    near_miss_m: float = _f(50.0 * RANGE_SCALE, "m", "near miss", _W)
    collision_m: float = _f(30.0 * RANGE_SCALE, "m", "collision", _W)
    weight_min_cpa: float = _f(
        0.2, "-", "safety weight: CPA below the preferred distance (ramp to the minimum)", _W
    )
    weight_near_miss: float = _f(0.3, "-", "safety weight: near miss", _W)
    weight_collision: float = _f(0.5, "-", "safety weight: collision", _W)
    # --- rule penalties ---
    penalty_head_on_starboard_pass: float = _f(
        0.6, "-", "head-on passed starboard to starboard (rule 14)", _W
    )
    penalty_head_on_not_starboard: float = _f(
        0.4, "-", "head-on manoeuvre not to starboard (rule 14)", _W
    )
    penalty_crossing_ahead: float = _f(0.5, "-", "give-way vessel crosses ahead (rule 15)", _W)
    penalty_overtaking_ahead: float = _f(0.3, "-", "overtaking vessel crosses ahead (rule 13)", _W)
    penalty_not_apparent: float = _f(
        0.5, "-", "give-way manoeuvre not readily apparent (rules 8, 16), × its deficiency", _W
    )
    penalty_stand_on_course: float = _f(
        0.5, "-", "stand-on vessel changes course without need (rule 17)", _W
    )
    penalty_stand_on_speed: float = _f(
        0.25, "-", "stand-on vessel changes speed without need (rule 17)", _W
    )
    # --- pass/fail ---
    pass_apparent_fraction: float = _f(
        0.5,
        "-",
        "a give-way manoeuvre passes up to this deficiency (16° course, 30 % speed)",
        _U,
    )

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


def parameter_table(params: ColregParams | None = None) -> list[dict[str, Any]]:
    """One row per field: name, unit (degrees for angles), value at boat scale, ship value
    (ranges: value / RANGE_SCALE; None where not scaled), meaning, source."""
    p = params or ColregParams()
    rows = []
    for f in fields(p):
        v = float(getattr(p, f.name))
        unit, ship = f.metadata["unit"], None
        if unit == "rad":
            unit, v = "deg", math.degrees(v)
        elif unit == "m":
            ship = v / RANGE_SCALE
        rows.append({"name": f.name, "unit": unit, "value": v, "ship_value": ship,
                     "meaning": f.metadata["meaning"], "source": f.metadata["source"]})  # fmt: skip
    return rows


def parameter_markdown(params: ColregParams | None = None) -> str:
    """The parameter table in Markdown (``python -m usvsim.task.colreg_params``)."""
    lines = [
        "| parameter | unit | boat value | ship value | meaning | source |",
        "|---|---|---|---|---|---|",
    ]
    for r in parameter_table(params):
        ship = "" if r["ship_value"] is None else f"{r['ship_value']:g}"
        lines.append(
            f"| `{r['name']}` | {r['unit']} | {r['value']:g} | {ship} | {r['meaning']} "
            f"| {r['source']} |"
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(parameter_markdown(), end="")
