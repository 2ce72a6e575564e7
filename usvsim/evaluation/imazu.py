"""Imazu's 22 encounter problems, scaled to usvsim's boat, as open-water episodes.

Imazu (1987) drew 22 standard encounters of one own ship with one to three target ships in
head-on, crossing and overtaking combinations, every target on a collision course; they are the
usual test set of collision-avoidance methods (e.g. Sawada, Sato & Majima 2021, J. Mar. Sci.
Technol. 26, who report a DRL policy passing all 22). The geometry below is that of NTNU's
colav-simulator scenario files ``scenarios/imazu_cases/imazuNN.yaml`` (Tengesdal et al.; read on
its public repository): the own ship starts heading north at 10 m/s, every target's start
position relative to the own ship (north, east m), speed (m/s) and course (deg, from north). The
courses agree with the Imazu table of TUD_RL's ``MMG_Imazu`` (Waltz & Paulig, after Sawada et
al. 2021) to within 30° except problems 8 and 12, where TUD_RL repeats problem 5's pair; we
follow colav-simulator there (problem 8: head-on and crossing from port).

Scaling to the boat (stated rule)
---------------------------------
Speeds keep their ratios to the own ship's: ``U_target = U_ship,target / 10 m/s × U_boat``, with
U_boat the vessel's cruise speed (:data:`usvsim.vessel.vessels.DEFAULT_VESSEL`, 3.0 m/s).
Positions scale by ``λ = meeting_distance_m / 7060 m``: in colav-simulator the own ship meets
the crossing targets after 7060 m (706 s at 10 m/s). Our default 300 m (100 s at 3 m/s, 29 boat
lengths; usvsim's choice so that a set runs in seconds) gives λ = 0.0425, and times then scale
by λ U_ship / U_boat = 0.142, so every target still arrives at its meeting point together with
the own ship: the collision courses are kept exactly.

Episodes
--------
Problem p, episode k: ``default_rng([crc32("imazu-pp/<split>"), k])`` draws, in order, the
noise, radar and disturbance seeds, a rotation of the whole scene (uniform over the circle: the
rules do not depend on the compass), and per target a course change (±3°), a speed factor
(0.95-1.05) and a start shift (±10 m north and east): the "small perturbations". The own ship
starts at ``anchor + D (cos β, sin β)`` heading at the anchor (D = meeting_distance_m), the goal
lies 2 D ahead of the start (colav-simulator: the own ship's waypoint far beyond the meeting),
time limit 2 × 2 D / U_boat, area radius 3 D around the anchor (the meeting point).
``validation`` and ``test`` draw from different seeds: choose on the first, report on the
second.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from typing import Literal

import numpy as np

from usvsim.common.splits import check_test_draw
from usvsim.task.disturbance import EpisodeDisturbance
from usvsim.task.openwater import OpenWaterEpisode, Vessel
from usvsim.task.scenario import EpisodeSpec
from usvsim.vessel.vessels import DEFAULT_VESSEL

__all__ = [
    "IMAZU_PROBLEMS",
    "SHIP_MEETING_DISTANCE_M",
    "SHIP_SPEED_MPS",
    "ImazuConfig",
    "ImazuTarget",
    "imazu_episodes",
    "perturbed_episode",
]

Split = Literal["validation", "test"]
SHIP_SPEED_MPS = 10.0  # m/s, the own ship's speed in colav-simulator's Imazu files
SHIP_MEETING_DISTANCE_M = 7060.0  # m, own start to the crossing targets' meeting point, there


@dataclass(frozen=True)
class ImazuTarget:
    """A target ship at ship scale, relative to the own ship's start (own heading north)."""

    north_m: float  # m, colav-simulator Imazu file
    east_m: float  # m
    speed_mps: float  # m/s (the own ship: 10 m/s)
    course_deg: float  # deg, clockwise from north


def _t(north: float, east: float, speed: float, course: float) -> ImazuTarget:
    return ImazuTarget(north, east, speed, course)


# colav-simulator scenarios/imazu_cases/imazu01..22.yaml, csog_state of ships 1.. minus ship 0's
HEAD_ON = _t(14120.0, 0.0, 10.0, 180.0)
IMAZU_PROBLEMS: tuple[tuple[ImazuTarget, ...], ...] = (
    (_t(13060.0, 0.0, 10.0, 180.0),),  # 1 head-on
    (_t(7060.0, 7000.0, 10.0, 270.0),),  # 2 crossing from starboard (give way)
    (_t(2060.0, 0.0, 5.0, 0.0),),  # 3 overtaking
    (_t(2560.0, -5500.0, 10.0, 40.0),),  # 4 crossing from port (stand on)
    (_t(7060.0, 7000.0, 10.0, 270.0), HEAD_ON),  # 5
    (_t(2560.0, 5000.0, 10.0, 320.0), _t(860.0, 2700.0, 10.0, 342.0)),  # 6
    (_t(2560.0, 5000.0, 9.0, 320.0), _t(2060.0, 0.0, 5.0, 0.0)),  # 7
    (_t(7060.0, -7000.0, 10.0, 90.0), HEAD_ON),  # 8
    (_t(7060.0, 7000.0, 10.0, 270.0), _t(810.0, 2950.0, 10.0, 345.0)),  # 9
    (_t(7060.0, 7000.0, 10.0, 270.0), _t(710.0, -2750.0, 10.0, 45.0)),  # 10
    (_t(7060.0, -7000.0, 10.0, 90.0), _t(810.0, 2950.0, 10.0, 345.0)),  # 11
    (_t(2560.0, 5000.0, 9.0, 320.0), _t(710.0, -2750.0, 10.0, 45.0), HEAD_ON),  # 12
    (_t(2560.0, -5500.0, 10.0, 40.0), _t(710.0, -2750.0, 10.0, 45.0), HEAD_ON),  # 13
    (_t(2200.0, 5000.0, 10.0, 320.0), _t(500.0, 2700.0, 10.0, 342.0),
     _t(5700.0, 6400.0, 10.0, 270.0)),  # 14
    (_t(2200.0, 5000.0, 10.0, 320.0), _t(1700.0, 0.0, 5.0, 0.0),
     _t(5700.0, 6400.0, 10.0, 270.0)),  # 15
    (_t(7060.0, -7000.0, 10.0, 90.0), _t(710.0, -2750.0, 10.0, 45.0),
     _t(7060.0, 7000.0, 10.0, 270.0)),  # 16
    (_t(2200.0, 5000.0, 10.0, 320.0), _t(1700.0, 0.0, 5.0, 0.0),
     _t(350.0, -2750.0, 10.0, 45.0)),  # 17
    (_t(2200.0, 5000.0, 10.0, 320.0), _t(500.0, 2700.0, 10.0, 342.0),
     _t(10200.0, 4500.0, 10.0, 225.0)),  # 18
    (_t(350.0, -2450.0, 10.0, 45.0), _t(500.0, 2700.0, 10.0, 342.0),
     _t(10200.0, 4500.0, 10.0, 225.0)),  # 19
    (_t(500.0, 2700.0, 10.0, 342.0), _t(1700.0, 0.0, 5.0, 0.0),
     _t(5700.0, 6400.0, 10.0, 270.0)),  # 20
    (_t(350.0, -2450.0, 10.0, 45.0), _t(500.0, 2700.0, 10.0, 342.0),
     _t(5700.0, 6400.0, 10.0, 270.0)),  # 21
    (_t(2200.0, 5000.0, 10.0, 320.0), _t(1700.0, 0.0, 5.0, 0.0),
     _t(5700.0, 6400.0, 10.0, 270.0)),  # 22 (as 15 in colav-simulator and TUD_RL alike)
)  # fmt: skip


@dataclass(frozen=True)
class ImazuConfig:
    """Scaling and perturbations of the Imazu episodes (module docstring)."""

    meeting_distance_m: float = 300.0  # m, D: own start to the meeting point (usvsim's choice)
    own_speed_mps: float = DEFAULT_VESSEL.cruise_speed_mps  # m/s, U_boat (vessel registry)
    target_radius_m: float = 5.0  # m, hull disc of a 10 m target (usvsim.task.openwater)
    course_jitter_rad: float = math.radians(3.0)  # rad, ± uniform per target
    speed_jitter: float = 0.05  # -, speed factor 1 ± this, uniform per target
    position_jitter_m: float = 10.0  # m, ± uniform north and east per target
    goal_factor: float = 2.0  # -, goal 2 D ahead of the start
    time_factor: float = 2.0  # -, time limit = factor × |start goal| / U_boat
    area_factor: float = 3.0  # -, area radius = factor × D around the meeting point
    rotate: bool = True  # turn each episode's whole scene by a uniform angle

    @property
    def length_scale(self) -> float:
        """λ: boat metres per ship metre (module docstring)."""
        return self.meeting_distance_m / SHIP_MEETING_DISTANCE_M

    @property
    def speed_scale(self) -> float:
        """Boat m/s per ship m/s."""
        return self.own_speed_mps / SHIP_SPEED_MPS


def _seed(problem: int, split: Split) -> int:
    return zlib.crc32(f"imazu-{problem:02d}/{split}".encode())


def imazu_episodes(
    problem: int, n: int, split: Split = "test", config: ImazuConfig | None = None
) -> tuple[OpenWaterEpisode, ...]:
    """``n`` perturbed episodes of Imazu problem ``problem`` (1-22; module docstring).

    Raises
    ------
    ValueError
        For a problem outside 1-22, ``n < 1`` or an unknown split.
    """
    if not 1 <= problem <= len(IMAZU_PROBLEMS):
        raise ValueError(f"Imazu problem must be 1-{len(IMAZU_PROBLEMS)}, got {problem}")
    if n < 1 or split not in ("validation", "test"):
        raise ValueError(f"need n >= 1 and split validation|test, got {n}, {split!r}")
    if split == "test":  # test splits report, validation splits choose (usvsim.common.splits)
        check_test_draw(f"imazu-{problem:02d}")
    cfg = config or ImazuConfig()
    targets = IMAZU_PROBLEMS[problem - 1]
    seed = _seed(problem, split)
    return tuple(_episode(np.random.default_rng([seed, k]), targets, cfg) for k in range(n))


def _episode(
    rng: np.random.Generator, targets: tuple[ImazuTarget, ...], cfg: ImazuConfig
) -> OpenWaterEpisode:
    return perturbed_episode(
        rng,
        targets,
        cfg,
        cfg.length_scale,
        cfg.speed_scale,
        cfg.goal_factor * cfg.meeting_distance_m,
    )


def perturbed_episode(
    rng: np.random.Generator,
    targets: tuple[ImazuTarget, ...],
    cfg: ImazuConfig,
    length_scale: float,
    speed_scale: float,
    goal_distance_m: float,
) -> OpenWaterEpisode:
    """One episode of a ship-scale encounter (``targets`` relative to the own ship's start, own
    heading north), scaled by ``length_scale`` (boat m per ship m) and ``speed_scale``, drawn
    from ``rng`` as the module docstring says; the goal ``goal_distance_m`` (boat m) ahead.
    The jitters of ``cfg`` apply; a zero-jitter config with no rotation gives the encounter
    exactly (used by :mod:`usvsim.evaluation.trafficgen_io`)."""
    noise_seed, radar_seed, dist_seed = (int(x) for x in rng.integers(2**63, size=3))
    rot = float(rng.uniform(0.0, 2.0 * math.pi)) if cfg.rotate else 0.0
    c, s = math.cos(rot), math.sin(rot)
    vessels = []
    for tgt in targets:
        dc = rng.uniform(-cfg.course_jitter_rad, cfg.course_jitter_rad)
        fs = rng.uniform(1.0 - cfg.speed_jitter, 1.0 + cfg.speed_jitter)
        shift = rng.uniform(-cfg.position_jitter_m, cfg.position_jitter_m, size=2)
        n_m, e_m = tgt.north_m * length_scale, tgt.east_m * length_scale
        p0 = np.array([c * n_m - s * e_m, s * n_m + c * e_m]) + shift
        course = math.remainder(math.radians(tgt.course_deg) + rot + dc, 2.0 * math.pi)
        vessels.append(
            Vessel(float(p0[0]), float(p0[1]), course, tgt.speed_mps * speed_scale * fs,
                   0.0, cfg.target_radius_m, _encounter_kind(tgt))
        )  # fmt: skip
    # the anchor (area centre, the start's reference) lies half way to the goal
    half = 0.5 * goal_distance_m
    anchor = half * np.array([c, s])
    goal = 2.0 * anchor
    limit = 2.0 * math.ceil(cfg.time_factor * goal_distance_m / cfg.own_speed_mps / 2.0 - 1e-9)
    return OpenWaterEpisode(
        anchor_ne=(float(anchor[0]), float(anchor[1])),
        start=EpisodeSpec(0, half, (rot + math.pi) % (2.0 * math.pi), 0.0, noise_seed),
        goal_ne=(float(goal[0]), float(goal[1])),
        obstacles=(),
        vessels=tuple(vessels),
        disturbance=EpisodeDisturbance(speed_mps=cfg.own_speed_mps, seed=dist_seed),
        radar_seed=radar_seed,
        time_limit_s=max(150.0, limit),
        area_radius_m=cfg.area_factor * half,
    )


def _encounter_kind(tgt: ImazuTarget) -> str:
    """The open-water family's label of a target (head-on, crossing or overtaking), by course."""
    rel = abs(math.remainder(math.radians(tgt.course_deg), 2.0 * math.pi))
    if rel > math.radians(157.5):
        return "head-on"
    return "overtaking" if rel < math.radians(22.5) else "crossing"
