"""The IL setups on COLREG encounters (issue 41): the SB-MPC expert's demonstrations, the
encounters they were recorded in, the -ow recipes."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import pytest

from learning.experiments.colreg_demos import COLREG_DEMOS_DIR
from learning.experiments.il_setups import COLREG_EPISODE_SHARE, IL_SETUPS, ILSetup
from learning.experiments.setups import setup_from_params, setup_params
from learning.experiments.train_il import expert_pairs
from learning.imitation.family_demos import FAMILY_DEMOS_DIR
from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.openwater_env import OPEN_WATER_FAMILY

RADAR, SCENE = IL_SETUPS["il-gaussian-radar-colreg"], IL_SETUPS["il-gaussian-scene-colreg"]


def test_they_learn_from_the_sbmpc_demonstrations_in_the_colreg_encounters() -> None:
    for s in (RADAR, SCENE):
        assert s.demos_dirs == (COLREG_DEMOS_DIR,) and s.task == "open-water"
    assert RADAR.observation == "radar+goal" and SCENE.observation == "scene"
    assert SCENE.training_family == COLREG_FAMILY
    # the radar setup: the encounters, 3/4 of them at the harshest radar (as -ow's recipe)
    fam = RADAR.training_family
    assert fam.members[:2] == COLREG_FAMILY.members and len(fam.members) == 4
    assert fam.probabilities[2:].sum() == pytest.approx(0.75)
    assert {m.radar_noise_range for m in fam.members[2:]} == {(40.0, 40.0)}
    ow = IL_SETUPS["il-gaussian-radar-ow"]
    assert (RADAR.algorithm_config, RADAR.gail) == (ow.algorithm_config, ow.gail)
    assert ow.demos_dirs == (FAMILY_DEMOS_DIR,) and ow.training_family.members[0] in (
        OPEN_WATER_FAMILY.members
    )


def test_the_scene_setup_loads_the_shipped_demonstrations() -> None:
    data, n_runs, skipped = expert_pairs(SCENE, SCENE.demos_dirs, lambda _: None)
    assert (n_runs, skipped) == (201, 0)  # 201 of the 250 pass the quality filter
    assert len(data) > 10_000 and data.obs.shape[1] == 4 + 6 * 8  # type: ignore[union-attr]


def test_the_radar_setup_loads_them_with_its_harsh_copies(tmp_path: Path) -> None:
    for p in sorted(COLREG_DEMOS_DIR.glob("demo_*.csv.gz"))[:4]:
        shutil.copy(p, tmp_path / p.name)
    data, n_runs, _ = expert_pairs(RADAR, (tmp_path,), lambda _: None)
    assert n_runs >= 3
    assert data.disc_obs is not None  # its discriminator sees the true scene
    assert len(data) == 4 * len(expert_pairs(SCENE, (tmp_path,), lambda _: None)[0])


def test_demos_and_family_are_checked_and_stored_in_a_checkpoint() -> None:
    with pytest.raises(ValueError, match=r"ILSetup\.demos must be one of"):
        dataclasses.replace(SCENE, demos="nowhere")
    with pytest.raises(ValueError, match=r"ILSetup\.family must be one of"):
        dataclasses.replace(SCENE, family="harbour")
    params = setup_params(RADAR)
    assert (params["demos"], params["family"]) == ("colreg", "colreg")
    assert setup_from_params(IL_SETUPS["il-gaussian-radar-ow"], params) == RADAR
    # checkpoints written before these fields read as the open-water family's demonstrations
    old = {k: v for k, v in setup_params(IL_SETUPS["il-gaussian-radar-ow"]).items()
           if k not in ("demos", "family")}  # fmt: skip
    back: ILSetup = setup_from_params(IL_SETUPS["il-gaussian-radar-ow"], old)
    assert back.demos_dirs == (FAMILY_DEMOS_DIR,) and back.training_family.members[0] in (
        OPEN_WATER_FAMILY.members
    )


BOTH = IL_SETUPS["il-gaussian-radar-ow-colreg"]


def test_the_mixed_setup_draws_colreg_encounters_in_the_share_of_their_runs() -> None:
    assert BOTH.demos_dirs == (FAMILY_DEMOS_DIR, COLREG_DEMOS_DIR)
    ow = IL_SETUPS["il-gaussian-radar-ow"]
    assert (BOTH.algorithm_config, BOTH.gail, BOTH.harsh_radar_copies) == (
        ow.algorithm_config,
        ow.gail,
        ow.harsh_radar_copies,
    )
    fam = BOTH.training_family
    colreg = [i for i, n in enumerate(fam.names) if "colreg-" in n]
    harsh = [i for i, n in enumerate(fam.names) if n.startswith("harsh-")]
    # the COLREG members hold their share in the calm and the harsh-radar halves alike
    assert fam.probabilities[colreg].sum() == pytest.approx(COLREG_EPISODE_SHARE)
    assert fam.probabilities[harsh].sum() == pytest.approx(0.75)
    assert {fam.members[i] for i in colreg if i not in harsh} == set(COLREG_FAMILY.members)
    assert 0.15 < COLREG_EPISODE_SHARE < 0.25


def test_the_mixed_setup_learns_from_the_runs_of_both_folders(tmp_path: Path) -> None:
    folders = (tmp_path / "ow", tmp_path / "cr")
    for src, dst in zip((FAMILY_DEMOS_DIR, COLREG_DEMOS_DIR), folders, strict=True):
        dst.mkdir()
        for p in sorted(src.glob("demo_*.csv*"))[:3]:
            shutil.copy(p, dst / p.name)
    each = [expert_pairs(SCENE, (d,), lambda _: None) for d in folders]
    both, n_runs, skipped = expert_pairs(SCENE, folders, lambda _: None)
    assert n_runs == each[0][1] + each[1][1] and skipped == 0
    assert len(both) == len(each[0][0]) + len(each[1][0])


def test_the_colreg_share_is_that_of_the_kept_demonstrations() -> None:
    from learning.imitation.demonstrations import load_recordings, quality_check

    kept = [
        sum(not quality_check(r) for r in load_recordings(d).recordings) for d in BOTH.demos_dirs
    ]
    assert COLREG_EPISODE_SHARE == pytest.approx(kept[1] / sum(kept))
