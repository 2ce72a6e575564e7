"""trafficgen situation files: read, scaled to the boat, written back; bad files refused."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from usvsim.common.errors import UserError
from usvsim.evaluation.colreg_suite import TRAFFICGEN_DIR
from usvsim.evaluation.imazu import ImazuConfig
from usvsim.evaluation.trafficgen_io import (
    KNOT_MPS,
    read_situation,
    situation_episodes,
    write_situation,
)

FILES = [TRAFFICGEN_DIR / f"baseline_situation_{i:02d}.json" for i in range(1, 6)]  # 1 target
EXACT = ImazuConfig(rotate=False, course_jitter_rad=0.0, speed_jitter=0.0, position_jitter_m=0.0)


def test_the_five_one_target_baseline_situations() -> None:
    sits = [read_situation(f) for f in FILES]
    assert [s.title for s in sits] == ["HO", "CR-GW", "CR-SO", "OT-GW", "OT-SO"]
    for s in sits:
        assert len(s.targets) == 1 and s.own.length_m == 122.0
        assert s.own.speed_mps == pytest.approx(10.0 * KNOT_MPS)
        assert s.own.north_m == 0.0 and s.own.east_m == 0.0 and s.own.course_rad == 0.0
    head_on = sits[0].targets[0]
    assert abs(math.degrees(head_on.course_rad)) == pytest.approx(176.4, abs=0.5)
    scale = sits[0].scale()
    assert scale.length == pytest.approx(10.5 / 122.0)
    assert scale.speed == pytest.approx(3.0 / (10.0 * KNOT_MPS))


def test_round_trip_gives_the_same_own_ship_and_target_states(tmp_path: Path) -> None:
    """File → boat-scale episode → file (same scale and origin) → the same states: positions
    to 1 mm, courses to 1e-9 rad, speeds exactly (the written file keeps full precision)."""
    for f in FILES:
        sit = read_situation(f)
        episode = situation_episodes(sit, np.random.default_rng(0), EXACT)
        out = write_situation(episode, tmp_path / f.name, sit.scale(), origin_deg=sit.origin_deg)
        back = read_situation(out)
        for a, b in [(sit.own, back.own), *zip(sit.targets, back.targets, strict=True)]:
            assert math.hypot(a.north_m - b.north_m, a.east_m - b.east_m) < 1e-3
            assert math.remainder(a.course_rad - b.course_rad, 2 * math.pi) == pytest.approx(
                0.0, abs=1e-9
            )
            assert a.speed_mps == pytest.approx(b.speed_mps, rel=1e-12)
        # and the episode read back from the written file is the same episode
        again = situation_episodes(back, np.random.default_rng(0), EXACT)
        for v, w in zip(episode.vessels, again.vessels, strict=True):
            assert math.hypot(v.x0_n - w.x0_n, v.y0_e - w.y0_e) < 1e-3
            assert v.speed_mps == pytest.approx(w.speed_mps) and v.course_rad == pytest.approx(
                w.course_rad
            )
        assert again.goal_ne == pytest.approx(episode.goal_ne, abs=1e-3)


def _broken(tmp_path: Path, edit) -> Path:
    data = json.loads(FILES[1].read_text())
    edit(data)
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(data))
    return path


OWN_WP, TGT_WP = ("ownShip", "waypoints"), ("targetShips", 0, "waypoints")
CASES = [  # (where, key, new value or None to delete it, the field the message must name)
    ((*OWN_WP, 0, "position"), "lat", None, "ownShip.waypoints[0].position.lat"),
    ((*TGT_WP, 0, "leg"), "sog", 500.0, "targetShips[0].waypoints[0].leg.sog"),
    (("targetShips", 0, "initial"), "heading", "north", "targetShips[0].initial.heading"),
    ((*OWN_WP, 1, "position"), "lon", 200.0, "ownShip.waypoints[1].position.lon"),
    (("ownShip",), "waypoints", [], "ownShip.waypoints"),
]


@pytest.mark.parametrize(("where", "key", "value", "field"), CASES)
def test_a_bad_file_is_one_line_naming_the_field(
    tmp_path: Path, where: tuple, key: str, value: object, field: str
) -> None:
    def edit(data: dict) -> None:
        node = data
        for step in where:
            node = node[step]
        if value is None:
            node.pop(key)
        else:
            node[key] = value

    with pytest.raises(UserError) as info:
        read_situation(_broken(tmp_path, edit))
    message = str(info.value)
    assert field in message and "\n" not in message


def test_not_json_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "x.json"
    path.write_text("{ownShip: ")
    with pytest.raises(UserError, match="not JSON"):
        read_situation(path)


def test_cli_bad_trafficgen_file_exits_2_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from usvsim.cli import main

    bad = _broken(tmp_path, lambda d: d["ownShip"]["waypoints"][0]["leg"].update(sog=-3.0))
    out = tmp_path / "results"
    argv = ["bench", "--suite", "colreg", "--trafficgen", str(bad), "--helmsmen", "vo",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "ownShip.waypoints[0].leg.sog" in lines[0], lines
    assert not out.exists() or not any(out.iterdir())
