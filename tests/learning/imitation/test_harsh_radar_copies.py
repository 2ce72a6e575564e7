"""Radar IL on the family with demonstrations also seen through the harshest radar
(``ILSetup.harsh_radar_copies``, ``usvsim train --harsh-radar-copies``): the copies, the expert
pairs they add, the training mixture that matches them, and the setup and CLI rules."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from learning.cli.train import TrainArgs, run
from learning.experiments.il_setups import MAX_HARSH_RADAR_COPIES, get_il_setup
from learning.experiments.train_il import expert_pairs
from learning.imitation.demonstrations import DEMOS_DIR, load_recordings, save_recordings
from learning.imitation.family_demos import record_family_demonstrations
from learning.imitation.preprocess import harsh_radar_runs, with_radar
from usvsim.evaluation.stress import STRESS_SETS
from usvsim.task.openwater import RadarQuality
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, draw_family, harsh_radar_family


@pytest.fixture(scope="module")
def recordings():  # type: ignore[no-untyped-def]
    return record_family_demonstrations(6, seed=11)


def _strongest() -> RadarQuality:
    """The family's harshest radar: each degradation at the most any member draws; speckle,
    missed returns and noise as the stress suite's ``radar-noise`` set has them."""
    top = [
        max(getattr(m, name)[1] for m in OPEN_WATER_FAMILY.members)
        for name in ("radar_clutter_range", "radar_speckle_range", "radar_missed_range",
                     "radar_noise_range")
    ]  # fmt: skip
    (radar_noise,) = [s.scenario for s in STRESS_SETS if s.name == "radar-noise"]
    assert radar_noise is not None
    assert top[1:] == [radar_noise.radar_speckle_range[1], radar_noise.radar_missed_range[1],
                       radar_noise.radar_noise_range[1]]  # fmt: skip
    return RadarQuality(*top)


def test_a_copy_changes_only_the_radar_and_each_copy_draws_its_own_noise(recordings) -> None:  # type: ignore[no-untyped-def]
    q = _strongest()
    a, b = with_radar(recordings[0], q, 1), with_radar(recordings[0], q, 2)
    other = with_radar(recordings[1], q, 1)
    for c in (a, b):
        scene = c.scene
        assert scene is not None and scene.radar == q
        np.testing.assert_array_equal(c.gps_latlon_deg, recordings[0].gps_latlon_deg)
        np.testing.assert_array_equal(c.compass_rad, recordings[0].compass_rad)
        assert {k: v for k, v in c.meta.items() if k != "scene"} == {
            k: v for k, v in recordings[0].meta.items() if k != "scene"
        }
    seeds = {r.scene.radar_seed for r in (a, b, other)}  # type: ignore[union-attr]
    assert len(seeds) == 3 and recordings[0].scene.radar_seed not in seeds
    assert recordings[0].meta["scene"].get("radar") != a.meta["scene"]["radar"]  # not mutated
    assert with_radar(recordings[0], q, 1).meta == a.meta  # reproducible


def test_copies_of_a_one_pole_run_or_copy_zero_are_refused(recordings) -> None:  # type: ignore[no-untyped-def]
    pole_run = load_recordings(DEMOS_DIR).recordings[0]
    with pytest.raises(ValueError, match="not a scene run"):
        with_radar(pole_run, _strongest(), 1)
    with pytest.raises(ValueError, match="copy must be >= 1"):
        with_radar(recordings[0], _strongest(), 0)


def test_harsh_copies_add_the_same_actions_and_scene_behind_a_noisier_image(
    recordings,  # type: ignore[no-untyped-def]
    tmp_path: Path,
) -> None:
    save_recordings(recordings, tmp_path)
    base = get_il_setup("il-gaussian-radar-ow").replace(harsh_radar_copies=0)
    plain, n_plain, _ = expert_pairs(base, (tmp_path,), lambda _: None)
    said: list[str] = []
    data, n_runs, _ = expert_pairs(base.replace(harsh_radar_copies=2), (tmp_path,), said.append)
    assert n_runs == n_plain  # the recorded runs, not the copies
    m = len(plain)
    assert len(data) == 3 * m and "each also 2× at the harshest radar level" in said[0]
    assert isinstance(data.obs, dict) and isinstance(plain.obs, dict)
    assert data.disc_obs is not None and plain.disc_obs is not None
    for k in range(3):  # the recorded runs first, then copy 1, then copy 2
        part = slice(k * m, (k + 1) * m)
        np.testing.assert_array_equal(data.actions[part], plain.actions)
        np.testing.assert_array_equal(data.disc_obs[part], plain.disc_obs)  # D's scene: the same
        np.testing.assert_array_equal(data.obs["goal"][part], plain.obs["goal"])
    np.testing.assert_array_equal(data.obs["radar"][:m], plain.obs["radar"])
    one, two = data.obs["radar"][m : 2 * m], data.obs["radar"][2 * m :]
    assert not np.array_equal(one, two)  # each copy its own noise
    assert one.mean() > plain.obs["radar"].mean() + 5.0  # harsher than the family's draws
    copies = harsh_radar_runs(recordings, 2)  # copy by copy, at the family's harshest level
    assert [c.meta for c in copies] == [
        with_radar(r, _strongest(), c).meta for c in (1, 2) for r in recordings
    ]


def test_the_training_mixture_draws_the_harsh_share_at_the_strongest_level() -> None:
    setup = get_il_setup("il-categorical-radar-ow").replace(harsh_radar_copies=3)
    assert setup.harsh_radar_share == pytest.approx(0.75)
    family = setup.training_family
    harsh = [n.startswith("harsh-") for n in family.names]
    assert family.probabilities[harsh].sum() == pytest.approx(0.75)
    episodes = draw_family(family, 7, 400)
    q = _strongest()
    at_top = np.array([e.radar == q for e in episodes])
    assert 0.68 < at_top.mean() < 0.82  # 0.75 ± 3.5 σ of 400 draws
    plain = get_il_setup("il-gaussian-radar-ow").replace(harsh_radar_copies=0)
    assert plain.training_family == OPEN_WATER_FAMILY
    top = (q.noise_amplitude,) * 2
    assert all(m.radar_noise_range == top for m in harsh_radar_family().members)


def test_harsh_copies_need_a_radar_setup_on_the_family_and_a_bounded_count() -> None:
    with pytest.raises(ValueError, match="for radar setups on the open-water family"):
        get_il_setup("il-gaussian-scene-ow").replace(harsh_radar_copies=1)
    with pytest.raises(ValueError, match="for radar setups on the open-water family"):
        get_il_setup("il-gaussian-radar").replace(harsh_radar_copies=1)
    with pytest.raises(ValueError, match=f"in \\[0, {MAX_HARSH_RADAR_COPIES}\\]"):
        get_il_setup("il-gaussian-radar-ow").replace(harsh_radar_copies=-1)


def _args(out: Path, **kw: object) -> TrainArgs:
    base: dict[str, object] = dict(
        setup="il-gaussian-radar-ow", iterations=1, n_envs=2, out=str(out), quiet=True, threads=1
    )
    base.update(kw)
    return TrainArgs(**base)  # type: ignore[arg-type]


def test_harsh_radar_copies_option_is_for_new_radar_runs_on_the_family(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="for the il-\\*-radar-ow setups"):
        run(_args(tmp_path / "a", setup="il-gaussian-scene-ow", harsh_radar_copies=1))
    with pytest.raises(SystemExit, match="for the il-\\*-radar-ow setups"):
        run(_args(tmp_path / "b", setup="rl-gaussian-radar-ow", harsh_radar_copies=1))
    with pytest.raises(SystemExit, match="--resume keeps the run's own"):
        run(_args(tmp_path / "c", harsh_radar_copies=1, resume=True))
    with pytest.raises(SystemExit, match=f"<= {MAX_HARSH_RADAR_COPIES}"):
        run(_args(tmp_path / "d", harsh_radar_copies=MAX_HARSH_RADAR_COPIES + 1))
    assert not any(tmp_path.rglob("*.pt"))


def test_the_radar_setups_clone_about_as_long_as_without_copies() -> None:
    """``bc_epochs`` counts passes over the data with its copies: the shipped radar setups scale
    it by 1/(K+1), so cloning takes about the 50 epochs' steps of the recorded runs alone."""
    for name in ("il-gaussian-radar-ow", "il-categorical-radar-ow"):
        setup = get_il_setup(name)
        assert setup.harsh_radar_copies > 0
        passes = setup.gail.bc_epochs * (setup.harsh_radar_copies + 1)
        assert 45 <= passes <= 55, (name, passes)
