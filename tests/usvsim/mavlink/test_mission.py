"""Mission files (usvsim.mavlink.mission): parsing, NED conversion and precise errors."""

import json
from pathlib import Path

import numpy as np
import pytest

from usvsim.mavlink.mission import Mission, MissionError, load_mission, parse_mission
from usvsim.nav.geo import GeoOrigin

GOOD = {
    "origin": {"lat": 63.43, "lon": 10.39},
    "poles": [{"lat": 63.43, "lon": 10.39}, {"lat": 63.4309, "lon": 10.3918}],
    "goal": {"lat": 63.4315, "lon": 10.3920},
    "goal_radius_m": 8.0,
}


def test_json_mission_parses_to_ned() -> None:
    m = parse_mission(GOOD)
    assert m.poles_ne.shape == (2, 2)
    np.testing.assert_allclose(m.poles_ne[0], [0.0, 0.0], atol=1e-9)
    assert m.goal_radius_m == 8.0 and m.pole_radius_m == 1.0
    # 0.0015° of latitude ≈ 167.3 m at 63.4° N
    assert m.goal_ne[0] == pytest.approx(167.3, abs=0.2)


def test_origin_defaults_to_first_pole() -> None:
    data = {k: v for k, v in GOOD.items() if k != "origin"}
    assert parse_mission(data).origin == GeoOrigin(63.43, 10.39)


def test_round_trip_through_file(tmp_path: Path) -> None:
    m = Mission.from_ned(GeoOrigin(10.0, 20.0), np.array([[30.0, -40.0]]), np.array([200.0, 5.0]))
    path = tmp_path / "m.json"
    path.write_text(json.dumps(m.to_dict()))
    back = load_mission(path)
    np.testing.assert_allclose(back.poles_ne, [[30.0, -40.0]], atol=1e-6)
    np.testing.assert_allclose(back.goal_ne, [200.0, 5.0], atol=1e-6)


def test_yaml_mission(tmp_path: Path) -> None:
    pytest.importorskip("yaml")
    path = tmp_path / "m.yaml"
    path.write_text("poles:\n  - {lat: 1.0, lon: 2.0}\ngoal: {lat: 1.001, lon: 2.0}\n")
    assert load_mission(path).goal_ne[0] == pytest.approx(110.57, abs=0.01)


@pytest.mark.parametrize(
    ("patch", "message"),
    [
        ({"poles": []}, "mission: poles: must be a non-empty list"),
        ({"poles": [{"lat": 91.0, "lon": 0.0}]}, r"mission: poles\[0\].lat: must lie in"),
        ({"goal": {"lat": 63.0}}, "mission: goal: missing 'lon'"),
        ({"goal": {"lat": "x", "lon": 1.0}}, "mission: goal.lat: must be a number"),
        ({"goal": {"lat": 1.0, "lon": 1.0, "alt": 3}}, r"goal: unknown key\(s\) \['alt'\]"),
        ({"speed": 3}, r"mission: unknown key\(s\) \['speed'\]"),
        ({"goal_radius_m": -1}, "mission: goal_radius_m: must lie in"),
        ({"goal": {"lat": 64.0, "lon": 10.39}}, "within 20 km"),
    ],
)
def test_precise_errors(patch: dict, message: str) -> None:
    with pytest.raises(MissionError, match=message):
        parse_mission({**GOOD, **patch})


def test_json_syntax_error_names_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text('{"poles": [\n  {"lat": 1, "lon": 2},\n]}')
    with pytest.raises(MissionError, match=r"bad.json: invalid JSON at line 3 column 1"):
        load_mission(path)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissionError, match="cannot read mission file"):
        load_mission(tmp_path / "nope.json")
