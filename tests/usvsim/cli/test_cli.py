"""The command line: help, errors, perf JSON, demo plots."""

from __future__ import annotations

import json

import pytest

from usvsim.cli import main
from usvsim.cli.main import COMMANDS


def test_help_lists_every_command(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    for name in COMMANDS:
        assert name in out


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_documented_options(name, capsys):
    with pytest.raises(SystemExit) as exc:
        main([name, "--help"])
    assert exc.value.code == 0
    assert "usage: usvsim " + name in capsys.readouterr().out


def test_unknown_vessel_is_a_clear_error(capsys):
    assert main(["demo", "--vessel", "titanic"]) == 2
    err = capsys.readouterr().err
    assert "unknown vessel 'titanic'" in err and len(err.strip().splitlines()) == 1


def test_unknown_option_is_rejected(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["perf", "--bogus"])
    assert exc.value.code == 2
    assert "unrecognized arguments: --bogus" in capsys.readouterr().err


def test_perf_json_reports_the_plant_figures(capsys):
    assert main(["perf", "--json", "--seconds", "0.2", "--no-env"]) == 0
    result = json.loads(capsys.readouterr().out)
    plant = result["plant"]
    assert set(plant["boat_substeps_per_s"]) == {"N=1", "N=1024"}
    assert plant["boat_substeps_per_s"]["N=1024"] > 0
    assert plant["batched_N1024_over_loop"] > 1.0


def test_demo_writes_the_plant_plots(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "phase margin" in out and "closed-loop poles" in out
    for name in ("turning_circle.png", "heading_steps.png", "bode.png", "kalman_vs_gps.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
