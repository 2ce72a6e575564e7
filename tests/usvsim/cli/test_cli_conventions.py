"""Conventions every ``usvsim`` command shares: ``--json`` prints JSON on stdout (a file is a
separate ``--...-out PATH`` option), ``--version``, model names where a checkpoint is taken,
``train --help`` listing every setup."""

from __future__ import annotations

import dataclasses
import json
import re
import typing
from pathlib import Path

import pytest

from learning.experiments.il_setups import IL_SETUPS
from learning.experiments.setups import SETUPS
from usvsim.cli import main
from usvsim.cli.main import COMMANDS, command_spec
from usvsim.helm.registry import MODELS_DIR

ROOT = Path(__file__).resolve().parents[3]
MODEL = "positional-gaussian-trpo-study"  # a shipped model (usvsim/models/MODEL.pt)
SETUP = "rl-gaussian-positional"  # its setup and former name


def test_version_prints_the_package_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    pyproject = (ROOT / "pyproject.toml").read_text()
    version = re.search(r'^version = "([^"]+)"', pyproject, flags=re.MULTILINE).group(1)
    assert capsys.readouterr().out.strip() == f"usvsim {version}"


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_json_is_a_stdout_switch_in_every_command(command: str) -> None:
    """Where a command has ``--json`` it is a switch (JSON on stdout), never a path."""
    cls = command_spec(command)[0]
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if f.name == "json":
            assert hints[f.name] is bool and f.default is False
        elif "json" in f.name:  # a file: --json-out PATH
            assert f.name.endswith("_out") and hints[f.name] is str


def test_train_help_lists_every_setup(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["train", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    listed = re.findall(r"^[* ] ((?:rl|il)-[a-z0-9-]+) ", out, flags=re.MULTILINE)
    assert listed == [*SETUPS, *IL_SETUPS]
    assert len(listed) == len(SETUPS) + len(IL_SETUPS) >= 25
    from usvsim.evaluation.model_cards import load_cards

    shipped = {card.setup for card in load_cards().values()}
    marked = set(re.findall(r"^\* ((?:rl|il)-[a-z0-9-]+) ", out, flags=re.MULTILINE))
    assert marked == shipped & set(listed)


def test_evaluate_takes_a_model_name_and_prints_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["evaluate", MODEL, "--heldout", "0", "--json"]) == 0
    captured = capsys.readouterr()
    payload = json.loads(captured.out)  # stdout holds the JSON and nothing else
    assert payload["checkpoint"] == str(MODELS_DIR / f"{MODEL}.pt")
    assert payload["setup"] == SETUP
    assert [(r["set"], r["episodes"]) for r in payload["rows"]] == [("validation", 15)]
    assert payload["rows"][0]["successes"] == 15  # the shipped model passes its validation
    assert main(["evaluate", SETUP, "--heldout", "0", "--json"]) == 0  # its former name
    again = capsys.readouterr()
    assert json.loads(again.out)["checkpoint"] == payload["checkpoint"] and not again.err


def test_evaluate_deprecated_json_path_still_writes_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "e.json"
    assert main(["evaluate", MODEL, "--heldout", "0", "--json", str(out)]) == 0
    captured = capsys.readouterr()
    assert "--json PATH is deprecated, use --json-out PATH" in captured.err
    assert "validation" in captured.out and not captured.out.lstrip().startswith("{")
    assert json.loads(out.read_text())["rows"][0]["episodes"] == 15


def test_evaluate_unknown_model_is_one_line_naming_the_shipped_ones(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["evaluate", "no-such-model"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "unknown model 'no-such-model'" in err and MODEL in err and ".pt file" in err


def test_no_json_takes_no_path(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", MODEL, "--no-json", "x.json"])
    assert exc.value.code == 2
    assert "--no-json takes no value" in capsys.readouterr().err
