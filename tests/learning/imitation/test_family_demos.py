"""usvsim-demo/2: family runs with their scene, the loader's checks, the quality filter and
the expert pairs built from them."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from learning.imitation.demo_scene import DemoScene
from learning.imitation.demonstrations import (
    DemoFormatError,
    load_recording,
    quality_check,
    recording_to_text,
    save_recordings,
)
from learning.imitation.family_demos import FAMILY_DEMOS_DIR, record_family_demonstrations
from learning.imitation.preprocess import check_observations, expert_data
from usvsim.task.observations import SCENE_FEATURES
from usvsim.task.openwater import vessel_motion
from usvsim.task.openwater_batch import SceneDiscs, observe_scene
from usvsim.task.scene_radar import RadarDegradation, RadarStreams


@pytest.fixture(scope="module")
def recordings():  # type: ignore[no-untyped-def]
    return record_family_demonstrations(8, seed=4)


def test_files_round_trip_with_their_scene(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    paths = save_recordings(recordings, tmp_path)
    assert paths[0].read_text().startswith("# usvsim-demo/2 ")
    back = load_recording(paths[3])
    assert back.meta == recordings[3].meta
    a, b = back.scene, recordings[3].scene
    assert a is not None and b is not None
    assert np.array_equal(a.obstacles, b.obstacles) and np.array_equal(a.vessels, b.vessels)


def _edit(text: str, change) -> str:  # type: ignore[no-untyped-def]
    first, rest = text.split("\n", 1)
    magic, payload = first[2:].split(" ", 1)
    meta = json.loads(payload)
    magic = change(meta) or magic
    return f"# {magic} {json.dumps(meta)}\n{rest}"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m: m.pop("scene") and None, "needs the metadata scene"),
        (lambda m: "usvsim-demo/1", "has none"),
        (
            lambda m: m["scene"].update(obstacles=[[0, 0]]),
            r"scene\.obstacles must be a list of \[3",
        ),
        (lambda m: m["scene"].update(obstacles=[[0, 0, -1]]), r"obstacles\[0\] radius"),
        (lambda m: m["scene"].update(goal_ne=[9e3, 0]), r"goal_ne\[0\] lies more than"),
        (
            lambda m: m["scene"].update(vessels=[[0, 0, 0, 40, 0, 5]]),
            r"vessels\[0\] speed 40 m/s is over 15",
        ),
        (lambda m: m["scene"].pop("goal_ne") and None, "scene lacks goal_ne"),
        (lambda m: m["scene"]["radar"].pop("seed") and None, r"scene\.radar must be an object"),
        (
            lambda m: m["scene"]["radar"].update(speckle=1.5),
            r"radar\.speckle must be a number in \[0, 1\]",
        ),
        (lambda m: m["scene"]["radar"].update(seed=-1), r"radar\.seed must be an integer"),
    ],
)
def test_a_bad_scene_is_refused_naming_the_entry(
    recordings, tmp_path: Path, change, message
) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "demo_000.csv"
    path.write_text(_edit(recording_to_text(recordings[0]), change))
    with pytest.raises(DemoFormatError, match=message):
        load_recording(path)


def test_scene_distance_follows_the_vessels() -> None:
    scene = DemoScene(
        goal_ne=np.array([200.0, 0.0]),
        episode_start_s=10.0,
        obstacles=np.array([[50.0, 0.0, 3.0]]),
        vessels=np.array([[0.0, 100.0, math.pi, 2.0, 0.0, 5.0]]),
    )
    t = np.array([10.0, 30.0])
    pos = np.array([[0.0, 0.0], [0.0, 60.0]])
    # t = 10 s: the pole-equivalent distance to the islet, 50 − 3 + 1; t = 30 s: the vessel,
    # 40 m south of where it started, is 40 m from (0, 60)... and the islet 78.1 − 2
    vessel_then, _ = vessel_motion(np.array([0.0, 100.0]), np.array(math.pi), np.array(2.0),
                                   np.array(0.0), np.array(20.0))  # fmt: skip
    expected_1 = min(np.hypot(*(vessel_then - pos[1])) - 5 + 1, np.hypot(50, 60) - 3 + 1)
    d = scene.distance_m(t, pos)
    assert d[0] == pytest.approx(48.0)
    assert d[1] == pytest.approx(expected_1)


def test_quality_filter_judges_against_every_obstacle(recordings) -> None:  # type: ignore[no-untyped-def]
    rec = recordings[0]
    assert rec.scene is not None
    # move an islet onto the path's midpoint: the run now passes through it
    mid = rec.gps_ne[len(rec.gps_ne) // 2]
    meta = dict(rec.meta, scene=dict(rec.meta["scene"], obstacles=[[*mid.tolist(), 2.0]]))
    bad = type(rec)(**{**rec.__dict__, "meta": meta})
    assert any("from an obstacle" in why for why in quality_check(bad))
    far = dict(rec.meta, scene=dict(rec.meta["scene"], goal_ne=[-400.0, 0.0]))
    assert any(
        "from the goal" in why for why in quality_check(type(rec)(**{**rec.__dict__, "meta": far}))
    )


def test_expert_pairs_see_the_scene_where_it_was(recordings) -> None:  # type: ignore[no-untyped-def]
    kept = [r for r in recordings if not quality_check(r)]
    assert kept
    data = expert_data(kept, "scene", "gaussian")
    check_observations(data, "scene")
    obs = data.obs
    assert isinstance(obs, np.ndarray)
    # the goal is the scene's, not the last fix; its range falls to ~10 m at the end
    track = data.tracks[0]
    assert np.array_equal(track.goal_ne, kept[0].scene.goal_ne)  # type: ignore[union-attr]
    # speed over ground from the GPS fit: within 1 m/s of the run's nominal speed on average
    speed = np.hypot(obs[:, 2], obs[:, 3])
    nominal = np.repeat(
        [r.meta["speed_mps"] for r in kept], [t.heading_change_rad.size for t in data.tracks]
    )
    assert abs(float(np.median(speed - nominal))) < 1.0
    # the first slot is the nearest obstacle by edge distance, at the decision's GPS position
    slots = obs[:, 4:].reshape(len(obs), -1, SCENE_FEATURES)
    first = slots[:, 0]
    for k in np.flatnonzero(first[:, 5] > 0)[:5]:
        ep = int(data.episode[k])
        j = k - int(np.flatnonzero(data.episode == ep)[0])
        tr = data.tracks[ep]
        scene = kept[ep].scene
        assert scene is not None
        centres, _ = scene.discs(tr.t_s[j : j + 1])
        edge = np.hypot(*(centres[0] - tr.pos_ne[j]).T) - scene.radii_m()
        assert first[k, 0] - first[k, 2] == pytest.approx(edge.min(), abs=1e-3)


def test_expert_radar_images_are_drawn_as_the_simulator_draws_the_episode(recordings) -> None:  # type: ignore[no-untyped-def]
    runs = copy.deepcopy(recordings[:3])
    for r in runs:  # the runs' own quality (often clean) replaced by a strong one
        r.meta["scene"]["radar"].update(noise_amplitude=30.0, speckle=0.4,
                                        clutter_probability=0.002)  # fmt: skip
    data = expert_data(runs, "radar", "gaussian")
    for r in runs:
        del r.meta["scene"]["radar"]
    clean = expert_data(runs, "radar", "gaussian")
    assert isinstance(data.obs, np.ndarray) and isinstance(clean.obs, np.ndarray)
    dark = clean.obs == 0
    assert data.obs[dark].mean() == pytest.approx(14.5 + 0.26, abs=0.5)  # 30 U truncated + clutter
    # decision 1 of run 0 is the simulator's second radar frame of an episode with that radar
    # seed (reset, then one step), at the recorded pose and scene
    scene, track = recordings[0].scene, data.tracks[0]
    streams = RadarStreams(1)
    streams.seed([0], [scene.radar_seed])
    streams.frame_keys(np.arange(1))
    centres, velocity = scene.discs(track.t_s[1:2])
    discs = SceneDiscs(centres, scene.radii_m()[None], velocity, np.ones((1, scene.n_discs), bool))
    q = RadarDegradation(
        *(np.array([x]) for x in (0.002, 0.4, scene.radar.missed_probability, 30.0))
    )
    image = observe_scene(
        "radar", track.pos_ne[1:2], track.psi_rad[1:2], np.zeros((1, 2)), track.goal_ne[None],
        discs, None, q, streams.frame_keys(np.arange(1)),
    )  # fmt: skip
    np.testing.assert_array_equal(image[0], data.obs[1])
    assert not np.array_equal(data.obs[0], data.obs[1])


def test_mixing_one_pole_and_scene_runs_is_refused(recordings) -> None:  # type: ignore[no-untyped-def]
    from learning.imitation.demonstrations import record_demonstrations

    with pytest.raises(ValueError, match="mix"):
        expert_data([*record_demonstrations(1, seed=2), recordings[0]], "positional", "gaussian")
    with pytest.raises(ValueError, match="scene demonstrations"):
        expert_data(record_demonstrations(1, seed=2), "scene", "gaussian")


def test_the_shipped_family_demonstrations_load() -> None:
    paths = sorted(FAMILY_DEMOS_DIR.glob("demo_*.csv.gz"))
    assert len(paths) == 960
    kept = [p for p in paths[:20] if not quality_check(load_recording(p))]
    assert len(kept) >= 12  # 785 of the 960 pass


def test_gzipped_files_load_as_the_text_does(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from learning.imitation.demonstrations import load_recordings

    for sub in ("plain", "packed", "again"):
        (tmp_path / sub).mkdir()
    plain = save_recordings(recordings[:2], tmp_path / "plain")
    packed = save_recordings(recordings[:2], tmp_path / "packed", compress=True)
    assert packed[0].name == "demo_000.csv.gz"
    assert (
        packed[0].read_bytes()
        == save_recordings(recordings[:1], tmp_path / "again", compress=True)[0].read_bytes()
    )
    a, b = load_recording(plain[1]), load_recording(packed[1])
    assert a.meta == b.meta and np.array_equal(a.gps_latlon_deg, b.gps_latlon_deg)
    assert len(load_recordings(tmp_path / "packed").recordings) == 2
    (tmp_path / "packed" / "demo_009.csv.gz").write_bytes(b"not gzip")
    report = load_recordings(tmp_path / "packed")
    assert "not a gzip file" in report.errors[str(tmp_path / "packed" / "demo_009.csv.gz")]
