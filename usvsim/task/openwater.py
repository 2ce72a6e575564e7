"""The ``open-water`` scenario family: many, large and moving obstacles, goals anywhere, currents,
degraded sensors. The study's pole task is one member (:func:`from_pole_episodes`).

Geometry (NED, angles clockwise from north), drawn per episode by :func:`draw_open_water`::

    primary obstacle  A = (0, 0)                       the study's pole (if ``primary_obstacle``)
    start             S = A + (d + R_A − 1 m)(cos β, sin β)   d ~ U[start range], β ~ U[0, 2π)
    reference line    u = (cos χ, sin χ), χ = β + π    the direction S → A
    goal              G = S + D (cos(χ + γ), sin(χ + γ)) + L n,   n = (−sin χ, cos χ)
                      D ~ U[goal range], γ ~ U[goal bearing range], L = ±U[goal lateral range]
                      (γ and D drawn again while G lies within clearance_m of A's edge)
    start heading     ψ0 = χ + δ,  δ ~ U[heading offset range]

Static obstacles are discs (centre, radius): a pole (1 m) up to an islet tens of metres across.
Extra obstacles lie in a corridor along S → G or, for ``near_primary_range_m``, at that centre
distance from A; a draw is repeated (same generator) while one lies within ``clearance_m`` of
S or G or closer than ``min_gap_m`` to another obstacle. Discs keep the hot path exact and
vectorised (distances, radar extents); shapely would add a dependency the per-step NumPy code
could not use.

Moving vessels are discs of radius ``vessel_radius_m`` on a constant or slowly turning course
(constant turn rate ω): p(t) = p0 + (V/ω)(sin(χ_v + ωt) − sin χ_v, cos χ_v − cos(χ_v + ωt)).
Each is placed so that, on the own boat's nominal run S → G at its cruise speed, the two would
meet at time t_c with miss distance m: head-on (χ_v ≈ χ_g + π), crossing (χ_v ≈ χ_g ± 90°,
from either side) or overtaking (χ_v ≈ χ_g, slower than the own boat). They do not react.

Success rule (the study's, generalised): reach the goal (within 10 m) without ever coming closer
than the safety distance to any obstacle, measured as for the study's pole: for an obstacle of
radius R, the distance ``|p − c| − R + R_pole`` (R_pole = 1 m, so a pole's is its centre
distance) must stay ≥ 10 m, i.e. 9 m of clear water from every disc's edge; the same for
moving vessels at their position at every 0.1 s plant step. A collision is the boat's centre
within R + half beam of a centre.

Every draw of an episode comes from its own generator ``default_rng([seed, k])``, in a fixed
order whatever the parameters, so an episode set is reproducible and a changed range moves only
what it names.

Weather (issue 38): with ``weather`` (:class:`usvsim.task.weather_draw.WeatherRanges`) episode k
gets ``disturbance.weather`` = :func:`usvsim.task.weather_draw.draw_weather` of ``(seed, k)`` and
its course χ (start → goal), drawn from the weather's own stream ``default_rng([seed, k,
WEATHER_STREAM])``: no other draw of the episode moves. ``weather=None`` (the default) leaves
the episodes as they were (calm: the batch keeps the calm plant).

Traffic (issue 41): with ``traffic`` (a :class:`TrafficDraw`, e.g.
:class:`usvsim.task.colreg_family.ColregTraffic`) episode k gets further vessels drawn by it
from their own stream ``default_rng([seed, k, TRAFFIC_STREAM])``, after every other draw of the
episode and relative to its start, goal and cruise speed: no other draw moves, and
``traffic=None`` (the default) leaves every episode bit for bit as it was.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa_float
from usvsim.task.disturbance import EpisodeDisturbance
from usvsim.task.scenario import EpisodeSpec, Scenario, episode_geometry
from usvsim.task.weather_draw import WeatherRanges, draw_weather

__all__ = [
    "ENCOUNTERS",
    "TRAFFIC_STREAM",
    "OpenWaterEpisode",
    "OpenWaterScenario",
    "RadarQuality",
    "TrafficDraw",
    "Vessel",
    "draw_open_water",
    "from_pole_episodes",
    "vessel_motion",
]

FloatArray = NDArray[np.float64]
ENCOUNTERS = ("head-on", "crossing", "overtaking")
_R_POLE = 1.0  # m, the study's pole radius: distances are pole-equivalent (module docstring)
Range = tuple[float, float]
TRAFFIC_STREAM = zlib.crc32(b"traffic")  # the traffic draw's stream (module docstring)


@dataclass(frozen=True)
class RadarQuality:
    """Per-episode radar degradation (all off: the study's clean image)."""

    clutter_probability: float = 0.0  # -, per pixel and frame, a false return
    speckle: float = 0.0  # -, a lit pixel's intensity times U[1 − speckle, 1]
    missed_probability: float = 0.0  # -, per obstacle and frame, its return is missing
    noise_amplitude: float = 0.0  # intensity units, uniform additive noise

    @property
    def clean(self) -> bool:
        return (
            not (self.clutter_probability or self.speckle or self.missed_probability)
            and not self.noise_amplitude
        )


@dataclass(frozen=True)
class Vessel:
    """A moving vessel: start position (m), course (rad), speed (m/s), turn rate (rad/s)."""

    x0_n: float
    y0_e: float
    course_rad: float
    speed_mps: float
    turn_rate_radps: float = 0.0
    radius_m: float = 5.0  # m, hull disc (a 10 m boat)
    encounter: str = "crossing"


@dataclass(frozen=True)
class OpenWaterEpisode:
    """One episode of the family. The start is the study's representation (an
    :class:`usvsim.task.scenario.EpisodeSpec` relative to ``anchor_ne``) so the batch starts the
    boat and its noise stream exactly as in the pole task."""

    anchor_ne: tuple[float, float]  # m, the point the start is given from (the primary obstacle)
    start: EpisodeSpec  # pole_index ignored: distance, bearing, heading offset, noise seed
    goal_ne: tuple[float, float]  # m
    obstacles: tuple[tuple[float, float, float], ...] = ()  # (x_N m, y_E m, radius m)
    vessels: tuple[Vessel, ...] = ()
    disturbance: EpisodeDisturbance | None = None  # None: calm, clean GNSS, study speed
    radar: RadarQuality = field(default_factory=RadarQuality)
    radar_seed: int = 0
    time_limit_s: float = 150.0  # s
    area_radius_m: float = 250.0  # m, around anchor_ne: "left the area" beyond it (truncation)

    @property
    def start_ne(self) -> FloatArray:
        b = self.start.start_bearing_rad
        return np.asarray(self.anchor_ne) + self.start.start_distance_m * np.array(
            [math.cos(b), math.sin(b)]
        )


class TrafficDraw(Protocol):
    """Draws further vessels for an episode (module docstring, "Traffic"): a frozen, hashable
    parameter object with this one method."""

    def vessels(self, episode: OpenWaterEpisode, rng: np.random.Generator) -> tuple[Vessel, ...]:
        """The vessels to add to ``episode`` (its start, goal and cruise speed), from ``rng``."""
        ...


@dataclass(frozen=True)
class OpenWaterScenario:
    """Parameters of the family; the defaults are the study's pole task (module docstring)."""

    start_distance_range_m: Range = (50.0, 100.0)  # m, d; study
    goal_distance_range_m: Range = (220.0, 220.0)  # m, D; study
    goal_bearing_range_rad: Range = (0.0, 0.0)  # rad, γ; study: on the line
    goal_lateral_range_m: Range = (0.0, 0.0)  # m, |L| (either side); study: on the line
    heading_offset_range_rad: Range = (0.0, 0.0)  # rad, δ; study: at the pole
    primary_obstacle: bool = True  # the study's pole at A
    primary_radius_range_m: Range = (1.0, 1.0)  # m; study pole 1 m (issue 3)
    n_extra_range: tuple[int, int] = (0, 0)  # further static obstacles, uniform integer
    extra_radius_range_m: Range = (1.0, 1.0)  # m, poles by default
    islet_probability: float = 0.0  # -, an extra obstacle is an islet
    islet_radius_range_m: Range = (8.0, 25.0)  # m, 16-50 m across
    near_primary_range_m: Range | None = None  # m, extra centres at this distance from A
    corridor_along_range: Range = (0.15, 0.85)  # -, extra centres along S → G (fraction)
    corridor_half_width_m: float = 40.0  # m, and across it
    clearance_m: float = 25.0  # m, no obstacle edge this close to S or G
    min_gap_m: float = 5.0  # m, between obstacle edges
    n_vessels_range: tuple[int, int] = (0, 0)
    encounters: tuple[str, ...] = ENCOUNTERS
    vessel_speed_range_mps: Range = (1.5, 4.0)  # m/s, head-on and crossing vessels
    overtaken_speed_fraction_range: Range = (0.3, 0.6)  # -, of the own speed
    vessel_turn_rate_range_radps: Range = (0.0, 0.0)  # rad/s, slowly changing courses
    vessel_radius_m: float = 5.0  # m
    meet_fraction_range: Range = (0.3, 0.7)  # -, t_c as a fraction of D / U
    miss_distance_range_m: Range = (-8.0, 8.0)  # m, signed miss distance at t_c
    current_speed_range_mps: Range = (0.0, 0.0)  # m/s
    # rad, relative to χ_g (0: following, π: head), mirrored to either side at random
    current_direction_range_rad: Range = (-math.pi, math.pi)
    speed_range_mps: Range = (3.0, 3.0)  # m/s, cruise speed reference; study 3
    gnss_noise_scale_range: Range = (1.0, 1.0)
    gnss_outlier_probability_range: Range = (0.0, 0.0)
    gnss_dropout_probability: float = 0.0  # -, an episode has one outage
    gnss_dropout_duration_range_s: Range = (10.0, 30.0)  # s
    radar_clutter_range: Range = (0.0, 0.0)  # -, per pixel
    radar_speckle_range: Range = (0.0, 0.0)
    radar_missed_range: Range = (0.0, 0.0)
    radar_noise_range: Range = (0.0, 0.0)  # intensity units
    time_factor: float = 2.0  # -, time limit = max(150 s, factor × |S G| / U)
    area_margin_m: float = 150.0  # m, area radius = |A − mid(S, G)| + |S G| / 2 + margin
    weather: WeatherRanges | None = None  # wind and waves per episode (module docstring); calm
    traffic: TrafficDraw | None = None  # further vessels from their own stream (docstring)

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if name.endswith(
                ("_range_m", "_range_rad", "_range_mps", "_range_s", "_range_radps")
            ) or (name.endswith("_range") and name != "n_extra_range"):
                if value is None:
                    continue
                lo, hi = value
                if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                    raise ValueError(f"OpenWaterScenario.{name} must be finite with lo <= hi")
        for name in ("n_extra_range", "n_vessels_range"):
            lo, hi = getattr(self, name)
            if not 0 <= lo <= hi:
                raise ValueError(f"OpenWaterScenario.{name} must satisfy 0 <= lo <= hi")
        if any(e not in ENCOUNTERS for e in self.encounters) or not self.encounters:
            raise ValueError(f"encounters must be a non-empty subset of {ENCOUNTERS}")
        if self.speed_range_mps[0] <= 0 or self.start_distance_range_m[0] <= 0:
            raise ValueError("speed_range_mps and start_distance_range_m must be > 0")


def _at(r: Range, u: float) -> float:
    """The point ``u`` ∈ [0, 1) of range ``r``: ``lo + (hi − lo) u``, the arithmetic of
    ``Generator.uniform(lo, hi)`` on the same draw ``Generator.random()`` (bit for bit)."""
    return r[0] + (r[1] - r[0]) * u


def _draws(rng: np.random.Generator, k: int) -> list[float]:
    """The next ``k`` uniform draws of ``rng`` in one call (the values of ``k`` calls)."""
    draws: list[float] = rng.random(k).tolist()
    return draws


def seeds63(rng: np.random.Generator, k: int) -> list[int]:
    """The next ``k`` values of ``rng.integers(2**63, size=k)``, 4× cheaper.

    NumPy draws a bounded 64-bit integer by Lemire's method: for the bound 2^63 (a power of
    two) every 64-bit draw x is accepted and mapped to ⌊x · 2^63 / 2^64⌋ = x >> 1, so the raw
    draws shifted right by one are those integers, bit for bit (tested)."""
    return [x >> 1 for x in rng.bit_generator.random_raw(k).tolist()]


def integer_in(rng: np.random.Generator, lo: int, hi: int) -> int:
    """``int(rng.integers(lo, hi + 1))``; NumPy draws nothing for an empty span (lo == hi),
    and neither does this."""
    return lo if lo == hi else int(rng.integers(lo, hi + 1))


def _hypot(x: float, y: float) -> float:
    """``np.hypot`` (C's ``hypot``) of two numbers; ``math.hypot`` rounds differently."""
    return float(np.hypot(x, y))


def _place_extras(
    rng: np.random.Generator, sc: OpenWaterScenario, s: tuple[float, float],
    g: tuple[float, float], obstacles: list[tuple[float, float, float]], n: int,
) -> None:  # fmt: skip
    """Append ``n`` extra obstacles (module docstring), rejection-sampled from ``rng``: per
    attempt four draws (islet, radius, then angle and distance from the primary, or position
    along and across the route)."""
    (sx, sy), (gx, gy) = s, g
    length = _hypot(gx - sx, gy - sy)
    scale = max(length, 1e-9)
    ux, uy = (gx - sx) / scale, (gy - sy) / scale  # unit vector S → G, normal (-uy, ux)
    half_width, gap_m = sc.corridor_half_width_m, sc.min_gap_m
    # rows: the start, the goal, then the obstacles so far (x, y, r): one np.hypot per attempt
    points = np.zeros((2 + len(obstacles) + n, 3))
    points[0, :2], points[1, :2] = s, g
    if obstacles:
        points[2 : 2 + len(obstacles)] = obstacles
    for _ in range(n):
        for _attempt in range(200):
            u_islet, u_radius, u_a, u_b = _draws(rng, 4)
            islet = u_islet < sc.islet_probability
            radius = _at(sc.islet_radius_range_m if islet else sc.extra_radius_range_m, u_radius)
            if sc.near_primary_range_m is not None and obstacles:
                ang = _at((0.0, 2.0 * math.pi), u_a)
                reach = _at(sc.near_primary_range_m, u_b)
                cx = obstacles[0][0] + reach * math.cos(ang)
                cy = obstacles[0][1] + reach * math.sin(ang)
            else:
                along = _at(sc.corridor_along_range, u_a) * length
                across = _at((-half_width, half_width), u_b)
                cx = sx + along * ux + across * -uy
                cy = sy + along * uy + across * ux
            # the start's, the goal's and every obstacle's distance in one call (np.hypot is
            # C's hypot element-wise: the numbers of a call per distance)
            m = 2 + len(obstacles)
            h = np.hypot(cx - points[:m, 0], cy - points[:m, 1])
            edge_s, edge_g = float(h[0]) - radius, float(h[1]) - radius
            if not min(edge_s, edge_g) >= sc.clearance_m:  # (a NaN edge fails, as before)
                continue
            # then (h - radius) - r in the order of the scalar expression, the same numbers
            if not obstacles or (h[2:] - radius - points[2:m, 2]).min() >= gap_m:
                points[m] = (cx, cy, radius)
                obstacles.append((cx, cy, radius))
                break


def _vessel(
    rng: np.random.Generator, sc: OpenWaterScenario, s: tuple[float, float], chi_g: float,
    own_mps: float, length_m: float,
) -> Vessel:  # fmt: skip
    """One vessel meeting the own boat's nominal run (module docstring)."""
    kind = sc.encounters[integer_in(rng, 0, len(sc.encounters) - 1)]
    u_side, u_jitter, u_speed, u_meet, u_miss, u_turn = _draws(rng, 6)
    side = 1.0 if u_side < 0.5 else -1.0
    jitter = _at((-math.radians(10.0), math.radians(10.0)), u_jitter)
    if kind == "head-on":
        course, speed = chi_g + math.pi + jitter, _at(sc.vessel_speed_range_mps, u_speed)
    elif kind == "crossing":
        course = chi_g + side * (math.pi / 2 + 3.0 * jitter)  # 60°-120° across
        speed = _at(sc.vessel_speed_range_mps, u_speed)
    else:
        course, speed = (
            chi_g + 0.5 * jitter,
            own_mps * _at(sc.overtaken_speed_fraction_range, u_speed),
        )
    t_c = _at(sc.meet_fraction_range, u_meet) * length_m / own_mps
    miss = _at(sc.miss_distance_range_m, u_miss)
    turn = _at(sc.vessel_turn_rate_range_radps, u_turn)
    ux, uy = math.cos(chi_g), math.sin(chi_g)
    run = own_mps * t_c
    meet_x, meet_y = s[0] + run * ux + miss * -uy, s[1] + run * uy + miss * ux
    back = speed * t_c
    x0, y0 = meet_x - back * math.cos(course), meet_y - back * math.sin(course)
    return Vessel(x0, y0, ssa_float(course), speed, turn, sc.vessel_radius_m, kind)


def _draw_one(rng: np.random.Generator, sc: OpenWaterScenario) -> OpenWaterEpisode:
    """One episode from ``rng`` (module docstring). Draws come in blocks of one
    ``Generator.random`` call where their number does not depend on earlier values; the
    order is that of one ``uniform`` call per quantity, so the episodes are those of a draw
    per call."""
    u_d, u_beta, u_delta = _draws(rng, 3)
    d = _at(sc.start_distance_range_m, u_d)
    beta = _at((0.0, 2.0 * math.pi), u_beta)
    delta = _at(sc.heading_offset_range_rad, u_delta)
    noise_seed, radar_seed, dist_seed = seeds63(rng, 3)
    u_goal_side, u_current_side, u_gamma, u_big_d, u_lateral, u_speed, u_primary = _draws(rng, 7)
    goal_side = -1.0 if u_goal_side < 0.5 else 1.0  # mirror images
    current_side = -1.0 if u_current_side < 0.5 else 1.0
    chi = beta + math.pi
    gamma = _at(sc.goal_bearing_range_rad, u_gamma)
    big_d = _at(sc.goal_distance_range_m, u_big_d)
    lateral = _at(sc.goal_lateral_range_m, u_lateral)
    speed = _at(sc.speed_range_mps, u_speed)
    primary_r = _at(sc.primary_radius_range_m, u_primary)
    d += primary_r - _R_POLE  # d is the pole-equivalent distance: from the edge, + 1 m
    s = (d * math.cos(beta), d * math.sin(beta))
    offset = goal_side * lateral
    normal = (-math.sin(chi), math.cos(chi))
    for _attempt in range(100):  # a goal must lie clear of the primary obstacle
        gx = s[0] + big_d * math.cos(chi + gamma) + offset * normal[0]
        gy = s[1] + big_d * math.sin(chi + gamma) + offset * normal[1]
        if _hypot(gx, gy) - primary_r >= sc.clearance_m or not sc.primary_obstacle:
            break
        u_gamma, u_big_d = _draws(rng, 2)
        gamma = _at(sc.goal_bearing_range_rad, u_gamma)
        big_d = _at(sc.goal_distance_range_m, u_big_d)
    g = (gx, gy)
    obstacles: list[tuple[float, float, float]] = [(0.0, 0.0, primary_r)]
    n_extra = integer_in(rng, *sc.n_extra_range)
    _place_extras(rng, sc, s, g, obstacles, n_extra)
    if not sc.primary_obstacle:
        obstacles = obstacles[1:]
    length = _hypot(gx - s[0], gy - s[1])
    chi_g = math.atan2(gy - s[1], gx - s[0])
    n_v = integer_in(rng, *sc.n_vessels_range)
    vessels = tuple(_vessel(rng, sc, s, chi_g, speed, length) for _ in range(n_v))
    (u_current, u_direction, u_scale, u_outlier, u_dropout, u_drop_start, u_drop_len,
     *u_radar) = _draws(rng, 11)  # fmt: skip
    current = _at(sc.current_speed_range_mps, u_current)
    turn = current_side * _at(sc.current_direction_range_rad, u_direction)
    current_dir = ssa_float(chi_g + turn)
    gnss_scale = _at(sc.gnss_noise_scale_range, u_scale)
    outlier = _at(sc.gnss_outlier_probability_range, u_outlier)
    time_limit = max(150.0, sc.time_factor * length / speed)
    time_limit = 2.0 * math.ceil(time_limit / 2.0 - 1e-9)
    dropout = u_dropout < sc.gnss_dropout_probability
    drop_start = _at((0.0, 0.5 * time_limit), u_drop_start)
    drop_len = _at(sc.gnss_dropout_duration_range_s, u_drop_len)
    radar = RadarQuality(
        _at(sc.radar_clutter_range, u_radar[0]), _at(sc.radar_speckle_range, u_radar[1]),
        _at(sc.radar_missed_range, u_radar[2]), _at(sc.radar_noise_range, u_radar[3]),
    )  # fmt: skip
    disturbance = EpisodeDisturbance(
        speed_mps=speed,
        current_speed_mps=current,
        current_direction_rad=current_dir,
        gnss_noise_scale=gnss_scale,
        gnss_outlier_probability=outlier,
        gnss_dropout_start_s=drop_start if dropout else math.inf,
        gnss_dropout_duration_s=drop_len if dropout else 0.0,
        seed=dist_seed,
    )
    area = _hypot(0.5 * (s[0] + gx), 0.5 * (s[1] + gy)) + 0.5 * length + sc.area_margin_m
    return OpenWaterEpisode(
        anchor_ne=(0.0, 0.0),
        start=EpisodeSpec(0, d, beta % (2.0 * math.pi), delta, noise_seed),
        goal_ne=g,
        obstacles=tuple(obstacles),
        vessels=vessels,
        disturbance=disturbance,
        radar=radar,
        radar_seed=radar_seed,
        time_limit_s=time_limit,
        area_radius_m=area,
    )


def episode_rng(*entropy: int) -> np.random.Generator:
    """``np.random.default_rng([*entropy])`` (e.g. ``[seed, k]``), the same generator about
    1.5× cheaper: ``SeedSequence`` is given, as one uint32 array, the words NumPy would make of
    the list (each int's 32-bit words, least significant first, at least one), which skips its
    coercion of Python ints; a family episode's draw makes one (tested equal)."""
    words: list[int] = []
    for value in map(int, entropy):
        if value < 0:
            raise ValueError(f"an episode seed must be >= 0, got {value}")
        words.append(value & 0xFFFFFFFF)
        while value := value >> 32:
            words.append(value & 0xFFFFFFFF)
    sequence = np.random.SeedSequence(np.array(words, dtype=np.uint32))
    return np.random.Generator(np.random.PCG64(sequence))


def draw_open_water(sc: OpenWaterScenario, seed: int, n: int) -> tuple[OpenWaterEpisode, ...]:
    """``n`` episodes of ``sc``; episode k from ``default_rng([seed, k])``, its traffic and
    weather (if ``sc.traffic``, ``sc.weather``) from their own streams (module docstring)."""
    episodes = tuple(_draw_one(episode_rng(seed, k), sc) for k in range(n))
    if sc.traffic is not None:
        draw = sc.traffic
        episodes = tuple(
            replace(e, vessels=e.vessels + draw.vessels(e, _traffic_rng(seed, k)))
            for k, e in enumerate(episodes)
        )
    if sc.weather is None:
        return episodes
    return tuple(_with_weather(e, sc.weather, seed, k) for k, e in enumerate(episodes))


def _traffic_rng(seed: int, k: int) -> np.random.Generator:
    """The traffic stream of episode k of the set of seed ``seed`` (module docstring)."""
    return episode_rng(seed, k, TRAFFIC_STREAM)


def _with_weather(
    episode: OpenWaterEpisode, ranges: WeatherRanges, seed: int, k: int
) -> OpenWaterEpisode:
    """``episode`` (k of the set of seed ``seed``) with its weather drawn relative to its course
    χ = atan2 of goal − start (rad)."""
    start = episode.start_ne
    course = math.atan2(episode.goal_ne[1] - start[1], episode.goal_ne[0] - start[0])
    weather = draw_weather(ranges, seed, k, course)
    if episode.disturbance is None:
        disturbance = EpisodeDisturbance(weather=weather)
    else:
        disturbance = replace(episode.disturbance, weather=weather)
    return replace(episode, disturbance=disturbance)


def from_pole_episodes(
    specs: Sequence[EpisodeSpec], scenario: Scenario | None = None
) -> tuple[OpenWaterEpisode, ...]:
    """The study's pole episodes as members of the family: same start, pole, goal, noise seed,
    time limit and area; no disturbance (the batch then runs exactly the study's numbers)."""
    scenario = scenario or Scenario()
    geo = episode_geometry(scenario, specs)
    return tuple(
        OpenWaterEpisode(
            anchor_ne=(float(geo.pole_ne[i, 0]), float(geo.pole_ne[i, 1])),
            start=spec,
            goal_ne=(float(geo.goal_ne[i, 0]), float(geo.goal_ne[i, 1])),
            obstacles=(
                (float(geo.pole_ne[i, 0]), float(geo.pole_ne[i, 1]), scenario.pole_radius_m),
            ),
            time_limit_s=scenario.time_limit_s,
            area_radius_m=scenario.area_radius_m,
        )
        for i, spec in enumerate(specs)
    )


def vessel_motion(
    p0: FloatArray, course: FloatArray, speed: FloatArray, turn: FloatArray, t_s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Positions and velocities of vessels at times ``t_s``.

    ``p0`` (..., 2) m, ``course``, ``speed``, ``turn`` (...) and ``t_s`` broadcastable to
    (...); returns position (..., 2) m and velocity (..., 2) m/s over ground (module docstring;
    the straight-line limit where |ω| t < 1e-9).
    """
    chi = course + turn * t_s
    sin_chi, cos_chi = np.sin(chi), np.cos(chi)  # each once (a hot path of the open-water step)
    sin0, cos0 = np.sin(course), np.cos(course)
    small = np.abs(turn * t_s) < 1e-9
    w = np.where(small, 1.0, turn)
    dx = np.where(small, speed * t_s * cos0, speed / w * (sin_chi - sin0))
    dy = np.where(small, speed * t_s * sin0, speed / w * (cos0 - cos_chi))
    pos = np.stack([p0[..., 0] + dx, p0[..., 1] + dy], axis=-1)
    vel = np.stack([speed * cos_chi, speed * sin_chi], axis=-1)
    return pos, vel
