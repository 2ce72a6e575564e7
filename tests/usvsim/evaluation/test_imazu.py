"""Imazu's problems as open-water episodes: every target on a collision course, seeded draws."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.evaluation.imazu import IMAZU_PROBLEMS, ImazuConfig, imazu_episodes
from usvsim.task.openwater import vessel_motion

EXACT = ImazuConfig(rotate=False, course_jitter_rad=0.0, speed_jitter=0.0, position_jitter_m=0.0)


def _cpa(episode, cfg: ImazuConfig) -> tuple[np.ndarray, np.ndarray]:
    """Closest approach (m) and its time (s) of each target to the own ship held on course."""
    t = np.arange(0.0, episode.time_limit_s, 0.5)
    start, goal = episode.start_ne, np.asarray(episode.goal_ne)
    u = (goal - start) / np.hypot(*(goal - start))
    own = start + cfg.own_speed_mps * t[:, None] * u
    v = episode.vessels
    p0 = np.array([[x.x0_n, x.y0_e] for x in v])[:, None]
    course = np.array([x.course_rad for x in v])[:, None]
    speed = np.array([x.speed_mps for x in v])[:, None]
    pos, _ = vessel_motion(p0, course, speed, np.zeros((len(v), 1)), t[None])
    d = np.hypot(*np.moveaxis(pos - own[None], -1, 0))
    return d.min(axis=1), t[d.argmin(axis=1)]


def test_twenty_two_problems_with_one_to_three_targets() -> None:
    counts = [len(p) for p in IMAZU_PROBLEMS]
    assert len(counts) == 22
    assert counts[:4] == [1] * 4 and counts[4:11] == [2] * 7 and counts[11:] == [3] * 11


@pytest.mark.parametrize("problem", range(1, 23))
def test_every_target_is_on_a_collision_course(problem: int) -> None:
    """Unperturbed, every target comes within 35 m of the own ship held on its course (measured:
    0-31 m; colav-simulator's own misses, scaled), 40-170 s after the start (measured 44-165 s;
    the crossing targets meet it at 300 m, 100 s at 3 m/s)."""
    (episode,) = imazu_episodes(problem, 1, config=EXACT)
    cpa, when = _cpa(episode, EXACT)
    assert np.all(cpa < 35.0), cpa
    assert np.all((when > 40.0) & (when < 170.0)), when


def test_scaling_keeps_the_speed_ratios_and_the_own_ship_speed() -> None:
    (episode,) = imazu_episodes(3, 1, config=EXACT)  # overtaking: the target at half speed
    assert episode.disturbance.speed_mps == pytest.approx(3.0)
    assert episode.vessels[0].speed_mps == pytest.approx(1.5)
    assert math.dist(episode.start_ne, episode.goal_ne) == pytest.approx(600.0)
    assert EXACT.length_scale == pytest.approx(300.0 / 7060.0)


def test_same_seed_same_episodes_and_splits_differ() -> None:
    a, b = imazu_episodes(5, 3), imazu_episodes(5, 3)
    assert a == b
    v = imazu_episodes(5, 3, split="validation")
    assert all(x.start.noise_seed != y.start.noise_seed for x, y in zip(a, v, strict=True))


def test_perturbations_are_small_and_the_scene_turns_as_a_whole() -> None:
    """Relative to the own ship (course turned to north), a perturbed target starts within the
    jitter of the exact one, whatever the rotation of the scene."""
    cfg = ImazuConfig()
    (exact,) = imazu_episodes(14, 1, config=EXACT)
    for ep in imazu_episodes(14, 10, config=cfg):
        chi = ep.start.start_bearing_rad + math.pi
        c, s = math.cos(chi), math.sin(chi)
        for v, w in zip(ep.vessels, exact.vessels, strict=True):
            dn, de = v.x0_n - ep.start_ne[0], v.y0_e - ep.start_ne[1]
            rel = (c * dn + s * de, -s * dn + c * de)
            assert math.dist(rel, (w.x0_n, w.y0_e)) <= math.sqrt(2) * cfg.position_jitter_m + 1e-9
            assert abs(math.remainder(v.course_rad - chi - w.course_rad, 2 * math.pi)) <= (
                cfg.course_jitter_rad + 1e-12
            )


def test_bad_problem_is_refused() -> None:
    with pytest.raises(ValueError, match="1-22"):
        imazu_episodes(23, 1)
