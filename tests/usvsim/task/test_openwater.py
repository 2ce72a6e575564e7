"""The open-water family: draws, the study as a member, the scene batch, radar, k-nearest."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from baselines.avoid import AvoidHelmsman
from usvsim.evaluation.episodes import evaluate, heldout_episodes
from usvsim.evaluation.openwater import evaluate_open_water
from usvsim.helm.protocol import StraightAheadHelmsman
from usvsim.task.batch import PoleAvoidanceBatch
from usvsim.task.observations import SCENE_FEATURES, scene_observation
from usvsim.task.openwater import (
    OpenWaterEpisode,
    OpenWaterScenario,
    RadarQuality,
    Vessel,
    draw_open_water,
    episode_rng,
    from_pole_episodes,
    integer_in,
    seeds63,
    vessel_motion,
)
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.radar import RadarConfig
from usvsim.task.scenario import EpisodeSpec
from usvsim.task.scene_radar import RadarDegradation, render_scene

BUSY = OpenWaterScenario(
    n_extra_range=(2, 5),
    islet_probability=0.5,
    n_vessels_range=(1, 2),
    current_speed_range_mps=(0.2, 0.6),
    radar_clutter_range=(0.001, 0.003),
    radar_missed_range=(0.1, 0.2),
    gnss_noise_scale_range=(1.0, 3.0),
    gnss_dropout_probability=0.5,
)


def test_the_study_is_a_member_of_the_family():
    specs = heldout_episodes(n=24)
    study = evaluate(AvoidHelmsman(), specs)
    member = evaluate_open_water(AvoidHelmsman(), from_pole_episodes(specs))
    assert [r.success for r in study] == [r.success for r in member]
    assert [r.min_pole_distance_m for r in study] == [r.min_pole_distance_m for r in member]
    assert [r.path_length_m for r in study] == [r.path_length_m for r in member]


def test_study_member_sees_the_pole_tasks_radar_image():
    specs = list(heldout_episodes(n=16))
    pole = PoleAvoidanceBatch(16, observation="radar+goal")
    water = OpenWaterBatch(16, observation="radar+goal")
    a, b = pole.reset(None, specs), water.reset(None, list(from_pole_episodes(specs)))
    for _ in range(12):  # into the pole's near field (the boats run straight at it)
        np.testing.assert_array_equal(a["radar"], b["radar"])
        np.testing.assert_array_equal(a["goal"], b["goal"])
        act = np.zeros((16, 1), dtype=np.float32)
        a, b = pole.step(act).observation, water.step(act).observation
    assert (a["radar"][:, 0, :3] > 0).any()  # some pole within 12 m


def test_default_parameters_draw_the_studys_geometry():
    for e in draw_open_water(OpenWaterScenario(), 3, 50):
        s, g = e.start_ne, np.asarray(e.goal_ne)
        assert len(e.obstacles) == 1 and e.obstacles[0] == (0.0, 0.0, 1.0)
        assert 50.0 <= e.start.start_distance_m <= 100.0
        assert np.hypot(*(g - s)) == pytest.approx(220.0)
        # goal beyond the pole on the start → pole line
        d = g - s
        assert abs(d[0] * -s[1] - d[1] * -s[0]) < 1e-6 and np.dot(g - s, -s) > 0


def test_same_seed_same_episodes():
    assert draw_open_water(BUSY, 5, 20) == draw_open_water(BUSY, 5, 20)
    assert draw_open_water(BUSY, 5, 20) != draw_open_water(BUSY, 6, 20)
    # episode k does not depend on how many are drawn
    assert draw_open_water(BUSY, 5, 20)[7] == draw_open_water(BUSY, 5, 8)[7]


def test_goal_keeps_clear_of_the_primary_obstacle():
    sc = replace(BUSY, goal_bearing_range_rad=(-math.pi, math.pi), goal_distance_range_m=(60, 300))
    for e in draw_open_water(sc, 9, 200):
        x, y, r = e.obstacles[0]
        assert math.hypot(e.goal_ne[0] - x, e.goal_ne[1] - y) - r >= sc.clearance_m


def test_extra_obstacles_keep_clear_of_start_goal_and_each_other():
    for e in draw_open_water(BUSY, 1, 60):
        obs = np.array(e.obstacles)
        assert 3 <= len(obs) <= 6
        for p in (e.start_ne, np.asarray(e.goal_ne)):
            assert np.all(np.hypot(*(obs[:, :2] - p).T) - obs[:, 2] >= BUSY.clearance_m - 1e-9)
        gaps = np.hypot(*(obs[:, None, :2] - obs[None, :, :2]).T).T - obs[:, None, 2] - obs[:, 2]
        np.fill_diagonal(gaps, np.inf)
        assert gaps.min() >= BUSY.min_gap_m - 1e-9


def test_vessels_meet_the_nominal_run():
    sc = replace(BUSY, miss_distance_range_m=(-3.0, 3.0))
    for e in draw_open_water(sc, 2, 30):
        s, g = e.start_ne, np.asarray(e.goal_ne)
        u = (g - s) / np.hypot(*(g - s))
        speed = e.disturbance.speed_mps
        for v in e.vessels:
            t = np.linspace(0.0, 2 * np.hypot(*(g - s)) / speed, 2001)
            pos, _ = vessel_motion(np.array([v.x0_n, v.y0_e]), v.course_rad, v.speed_mps, 0.0, t)
            own = s + speed * t[:, None] * u
            assert np.hypot(*(pos - own).T).min() <= 3.0 + 0.5


def test_vessel_motion_integrates_a_constant_turn():
    t = np.linspace(0.0, 60.0, 6001)
    pos, vel = vessel_motion(np.zeros(2), 0.3, 2.0, 0.02, t)
    chi = 0.3 + 0.02 * t
    dt = t[1] - t[0]
    x = np.concatenate([[0.0], np.cumsum(0.5 * dt * 2.0 * (np.cos(chi[1:]) + np.cos(chi[:-1])))])
    y = np.concatenate([[0.0], np.cumsum(0.5 * dt * 2.0 * (np.sin(chi[1:]) + np.sin(chi[:-1])))])
    np.testing.assert_allclose(pos, np.stack([x, y], -1), atol=1e-4)
    np.testing.assert_allclose(vel[-1], 2.0 * np.array([math.cos(chi[-1]), math.sin(chi[-1])]))


def test_scene_radar_draws_a_disc_at_its_true_extent():
    cfg = RadarConfig()
    rho, phi, radius = 40.0, math.radians(15.0), 18.0
    img = render_scene(
        np.array([[rho]]), np.array([[phi]]), np.array([[radius]]), np.ones((1, 1), bool)
    )
    lit = img[0, 0] > 0
    # sample the disc densely: each sample's pixel must be lit ...
    rng = np.random.default_rng(0)
    a, rr = rng.uniform(0, 2 * math.pi, 200_000), radius * np.sqrt(rng.uniform(0, 1, 200_000))
    c = rho * np.array([math.cos(phi), math.sin(phi)])
    pts = c + np.stack([rr * np.cos(a), rr * np.sin(a)], -1)
    row = (np.hypot(*pts.T) // (cfg.max_range_m / cfg.n_rows)).astype(int)
    col = (
        (np.arctan2(pts[:, 1], pts[:, 0]) + cfg.half_fov_rad) // (2 * cfg.half_fov_rad / cfg.n_cols)
    ).astype(int)
    seen = np.zeros_like(lit)
    seen[row, col] = True
    assert lit[seen].all()
    # ... and (up to cells the samples graze) every lit pixel holds a sample: not a bounding box
    assert (lit & ~seen).sum() <= 0.05 * lit.sum()
    box_rows = np.arange(cfg.n_rows)[
        (np.arange(1, 51) * 4 > rho - radius) & (np.arange(50) * 4 <= rho + radius)
    ]
    assert lit.sum() < 0.9 * len(box_rows) * lit.any(axis=0).sum()


def test_radar_missed_returns_and_clutter_are_per_boat_streams():
    ep = draw_open_water(
        replace(BUSY, radar_clutter_range=(0.01, 0.01), radar_missed_range=(0.5, 0.5)), 4, 3
    )
    alone = OpenWaterBatch(1, observation="radar").reset(None, [ep[2]])
    mixed = OpenWaterBatch(3, observation="radar").reset(None, list(ep))
    np.testing.assert_array_equal(alone[0], mixed[2])
    assert 0.004 < np.mean(alone > 0) < 0.05  # ~1 % clutter plus the drawn discs


def test_scene_observation_sorts_by_edge_distance_and_masks():
    pos, psi, vel = np.zeros((1, 2)), np.array([math.pi / 2]), np.array([[0.0, 3.0]])  # east, 3 m/s
    centres = np.array([[[0.0, 60.0], [0.0, 50.0], [40.0, 0.0], [0.0, -30.0]]])
    radii = np.array([[25.0, 1.0, 1.0, 1.0]])
    obst_vel = np.array([[[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]])
    valid = np.array([[True, True, True, False]])
    obs = scene_observation(
        pos, psi, vel, np.array([[0.0, 200.0]]), centres, radii, obst_vel, valid, k=4
    )
    assert obs[0, 2] == pytest.approx(3.0) and obs[0, 3] == pytest.approx(0.0, abs=1e-12)
    slots = obs[0, 4:].reshape(4, SCENE_FEATURES)
    assert slots[:, 2].tolist() == [25.0, 1.0, 1.0, 0.0]  # the islet's edge (35 m) is nearest
    assert slots[0, 1] == pytest.approx(0.0, abs=1e-6)  # dead ahead
    assert slots[0, 3] == pytest.approx(-3.0)  # a static obstacle closes at the own speed
    assert slots[1, 1] == pytest.approx(-math.pi / 2, abs=1e-6)  # the north one (39 m) is to port
    assert slots[1, 3:5] == pytest.approx([-3.0, -1.0])  # moving north = to port, in body frame
    assert slots[3].tolist() == [0.0] * 6


def test_pole_task_scene_kind_puts_the_pole_in_the_first_slot():
    batch = PoleAvoidanceBatch(1, observation="scene")
    obs = batch.reset(None, [EpisodeSpec(0, 80.0, 0.0)])
    slots = obs[0, 4:].reshape(-1, SCENE_FEATURES)
    assert slots[0, 0] == pytest.approx(80.0, abs=3.0) and slots[0, 5] == 1.0
    assert slots[0, 3] == pytest.approx(-3.0, abs=0.3)
    assert not slots[1:].any()
    assert batch.single_observation_space.contains(obs[0])


def test_positional_reports_the_nearest_disc_as_a_pole():
    e = OpenWaterEpisode(
        anchor_ne=(0.0, 0.0),
        start=EpisodeSpec(0, 100.0, 0.0),
        goal_ne=(-120.0, 0.0),
        obstacles=((0.0, 0.0, 1.0), (60.0, 0.0, 20.0)),  # islet edge 20 m ahead
    )
    obs = OpenWaterBatch(1).reset(None, [e])
    assert obs[0, 0] == pytest.approx(40.0 - 20.0 + 1.0, abs=3.0)


def test_head_on_vessel_hits_a_boat_that_holds_its_course():
    v = Vessel(-100.0, 0.0, 0.0, 3.0, radius_m=5.0, encounter="head-on")  # north, at us
    e = OpenWaterEpisode(
        anchor_ne=(0.0, 0.0), start=EpisodeSpec(0, 100.0, 0.0), goal_ne=(-300.0, 0.0), vessels=(v,)
    )
    rec = evaluate_open_water(StraightAheadHelmsman(), [e])[0]
    assert rec.collision and rec.duration_s < 40.0  # they meet after 200 m / 6 m/s ≈ 33 s


def test_degradation_needs_a_noise_source():
    q = RadarDegradation(*(np.full(1, x) for x in (0.1, 0.0, 0.0, 0.0)))
    with pytest.raises(ValueError, match="noise source"):
        render_scene(
            np.ones((1, 1)), np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1), bool), None, q
        )
    assert RadarQuality().clean and not RadarQuality(speckle=0.1).clean


def test_seeds63_are_numpys_bounded_integers() -> None:
    """The episode seeds: raw draws shifted right by one are ``integers(2**63)``, bit for bit,
    and leave the generator where NumPy's call leaves it."""
    for seed in range(500):
        a, b = np.random.default_rng([seed, 9]), np.random.default_rng([seed, 9])
        assert seeds63(a, 3) == b.integers(2**63, size=3).tolist()
        assert seeds63(a, 1)[0] == int(b.integers(2**63))
        assert a.random() == b.random()


def test_episode_rng_is_numpys_default_rng() -> None:
    """The episode generators: the raw stream of ``default_rng([seed, k])`` (and of a third
    entry), for seeds of one, two and three 32-bit words and zero."""
    rng = np.random.default_rng(3)
    seeds = [0, 1, 2**32 - 1, 2**32, 2**63 - 1, 2**64 + 5, *rng.integers(0, 2**63, 300).tolist()]
    for seed in seeds:
        for entropy in ((seed, 0), (seed, 7), (seed, 2**32 + 1), (seed, 3, 0x7A11)):
            ours = episode_rng(*entropy).bit_generator.random_raw(4)
            assert (
                ours.tolist()
                == np.random.default_rng(list(entropy)).bit_generator.random_raw(4).tolist()
            )
    with pytest.raises(ValueError, match="must be >= 0"):
        episode_rng(-1, 0)


def test_integer_in_is_numpys_integers() -> None:
    for seed in range(200):
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        for lo, hi in ((0, 0), (2, 2), (0, 1), (1, 6), (0, 12)):
            assert integer_in(a, lo, hi) == int(b.integers(lo, hi + 1))
        assert a.random() == b.random()  # an empty span draws nothing in either
