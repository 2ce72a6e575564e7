"""One error path for every command: a user error is one line on stderr and exit status 2.

Each case of issue 14's list that needs no training: the option ranges of every options
dataclass, unwritable outputs (checked before any work), bad URLs, ports, key files, missions,
and helmsman kinds that contradict a checkpoint.
"""

from __future__ import annotations

import json
import shutil
import socket
from pathlib import Path

import pytest

from usvsim.cli import main
from usvsim.helm.registry import MODELS_DIR

MODEL = MODELS_DIR / "positional-gaussian-trpo-study.pt"  # a shipped checkpoint (positional)


def _mission(path: Path, goal_lat: float) -> str:
    data = {"poles": [{"lat": 63.4305, "lon": 10.3951}], "goal": {"lat": goal_lat, "lon": 10.3951}}
    path.write_text(json.dumps(data))
    return str(path)


@pytest.fixture
def mission(tmp_path: Path) -> str:
    return _mission(tmp_path / "mission.json", 63.4315)


def _one_line_error(capsys: pytest.CaptureFixture[str], *words: str) -> str:
    err = capsys.readouterr().err.strip()
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["train", "rl-gaussian-positional", "--seed", "-1"], ["--seed", ">= 0", "got -1"]),
        (["train", "rl-gaussian-positional", "--threads", "-3"], ["--threads", ">= 1"]),
        (["train", "rl-gaussian-positional", "--time-budget-s", "nan"], ["finite", "nan"]),
        (["train", "rl-gaussian-positional", "--n-envs", "-4"], ["--n-envs", "(or 0)"]),
        (["train", "bogus"], ["unknown setup 'bogus'", "rl-gaussian-positional", "IL setups"]),
        (["train", "rl-gaussian-positional", "--demos", "x"], ["--demos is for the il-*"]),
        (["train", "il-gaussian-positional", "--demos", "/no/such"], ["--demos", "no such"]),
        (["evaluate", str(MODEL), "--heldout", "-1"], ["--heldout", ">= 0"]),
        (["bench", "--heldout", "0"], ["--heldout", ">= 1"]),
        (["bench", "--helmsmen", "nobody"], ["unknown helmsman 'nobody'", "checkpoint file"]),
        (["sitl", "--lat", "95"], ["--lat", "<= 90", "got 95"]),
        (["sitl", "--speedup", "0"], ["--speedup", "> 0"]),
        (["sitl", "--listen", "tcpin:127.0.0.1:99999"], ["port 99999", "0..65535"]),
        (["sitl-physics", "--port", "70000"], ["--port", "<= 65535"]),
        (["sitl-physics", "--steering-channel", "0"], ["--steering-channel", ">= 1"]),
        (["sitl-physics", "--steering-channel", "99"], ["--steering-channel", "<= 16"]),
        (["sitl-physics", "--throttle-channel", "1"], ["must differ"]),
        (["bridge"], ["--mission FILE is required"]),
        (["perf", "--seconds", "inf"], ["--seconds", "finite"]),
    ],
)
def test_a_bad_option_is_one_line_and_status_2(
    argv: list[str], words: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    _one_line_error(capsys, f"usvsim {argv[0]}:", *words)


def test_an_unconvertible_value_is_one_line_and_status_2(capsys: pytest.CaptureFixture[str]):
    with pytest.raises(SystemExit) as stop:
        main(["train", "rl-gaussian-positional", "--seed", "abc"])
    assert stop.value.code == 2
    _one_line_error(capsys, "--seed", "invalid int value: 'abc'")


def test_debug_shows_the_traceback_of_a_user_error() -> None:
    from usvsim.common.errors import UserError

    with pytest.raises(UserError, match="--lat"):
        main(["--debug", "sitl", "--lat", "95"])


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--decision-period-s", "0"], ["--decision-period-s", ">= 0.1"]),
        (["--max-heading-change-deg", "1000"], ["--max-heading-change-deg", "<= 180"]),
        (["--connect", "bogus://x"], ["bad MAVLink URL 'bogus://x'", "tcp, tcpin"]),
        (["--connect", "tcp:127.0.0.1"], ["bad MAVLink URL"]),
        (["--signing-key", "/no/such/key"], ["signing key /no/such/key", "cannot read"]),
        (["--helmsman", str(MODEL), "--observation", "radar"], ["contradicts", "positional"]),
        (["--helmsman", str(MODEL), "--action", "categorical"], ["contradicts", "gaussian"]),
        (["--helmsman", "nobody"], ["unknown helmsman 'nobody'"]),
    ],
)
def test_bridge_refuses_bad_input_before_connecting(
    extra: list[str], words: list[str], mission: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bridge", "--mission", mission, "--tlog", "", "--log-csv", "", *extra]) == 2
    _one_line_error(capsys, "usvsim bridge:", *words)


def test_bridge_goal_on_the_pole_is_refused(tmp_path: Path, capsys) -> None:
    on_pole = _mission(tmp_path / "m.json", 63.43052)  # 2.2 m north of the pole
    assert main(["bridge", "--mission", on_pole]) == 2
    _one_line_error(capsys, "goal: lies 2.2 m from poles[0]", "10 m safety circle")


def test_bridge_connection_refused_and_heartbeat_timeout(mission: str, tmp_path: Path, capsys):
    with socket.socket() as probe:  # a TCP port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    logs = ["--tlog", "", "--log-csv", str(tmp_path / "d.csv")]
    assert main(["bridge", "--mission", mission, "--connect", f"tcp:127.0.0.1:{port}", *logs]) == 2
    _one_line_error(capsys, f"cannot open MAVLink link tcp:127.0.0.1:{port}", "refused")
    args = ["--connect", f"udpout:127.0.0.1:{port}", "--heartbeat-timeout-s", "0.3", *logs]
    assert main(["bridge", "--mission", mission, *args]) == 2
    _one_line_error(capsys, "no vehicle HEARTBEAT", "within 0.3 s")


def test_sitl_physics_on_a_busy_port(capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as busy:
        busy.bind(("127.0.0.1", 0))
        port = busy.getsockname()[1]
        assert main(["sitl-physics", "--port", str(port), "--duration-s", "0.1"]) == 2
    _one_line_error(capsys, f"127.0.0.1:{port}", "Address already in use", "--port")


def test_outputs_are_checked_before_the_work(tmp_path: Path, capsys) -> None:
    a_file = tmp_path / "file"
    a_file.write_text("x")
    assert main(["bench", "--helmsmen", "los", "--out", str(a_file)]) == 2
    _one_line_error(capsys, f"--out {a_file}: is a file, not a folder")
    assert main(["bench", "--helmsmen", "los", "--out", str(a_file / "sub")]) == 2
    _one_line_error(capsys, "--out", "cannot create the folder")
    assert main(["train", "rl-gaussian-positional", "--out", str(a_file)]) == 2
    _one_line_error(capsys, "usvsim train: --out", "is a file")
    assert main(["evaluate", str(MODEL), "--json-out", str(tmp_path)]) == 2
    _one_line_error(capsys, f"--json-out {tmp_path}: is a folder, not a file")
    assert main(["evaluate", str(MODEL), "--json-out", str(a_file / "x.json")]) == 2
    _one_line_error(capsys, "--json-out", "is a file, not a folder")


def test_resume_refuses_a_conflicting_seed_or_n_envs(tmp_path: Path, capsys) -> None:
    from usvsim.helm.registry import checkpoint_facts

    shutil.copy(MODEL, tmp_path / "latest.pt")  # the setup's 32 boats
    stored = checkpoint_facts(str(MODEL))["seed"]
    other = stored + 9
    base = ["train", "rl-gaussian-positional", "--out", str(tmp_path), "--resume"]
    assert main([*base, "--seed", str(other)]) == 2
    _one_line_error(
        capsys, f"--seed {other} contradicts", f"(--seed {stored})", "--resume continues"
    )
    assert main([*base, "--n-envs", "4"]) == 2
    _one_line_error(capsys, "--n-envs 4 contradicts", "(--n-envs 32)")


def test_evaluate_json_has_null_not_nan(tmp_path: Path, monkeypatch, capsys) -> None:
    from learning.cli import evaluate

    def no_success(name: str, records: list) -> dict:
        return {**real(name, records), "min_pole_distance_successful_m": float("nan")}

    real = evaluate.evaluation_row
    monkeypatch.setattr(evaluate, "evaluation_row", no_success)
    out = tmp_path / "e.json"
    assert main(["evaluate", str(MODEL), "--heldout", "0", "--json-out", str(out)]) == 0
    text = out.read_text()
    assert "NaN" not in text
    assert json.loads(text)["rows"][0]["min_pole_distance_successful_m"] is None
