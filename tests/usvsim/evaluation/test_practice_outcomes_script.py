"""benchmarks/practice_outcomes.py: helmsmen on a practice member's episodes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

_SCRIPT = Path(__file__).resolve().parents[3] / "benchmarks" / "practice_outcomes.py"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(_SCRIPT), *args], capture_output=True, text=True,
                          check=False, timeout=300)  # fmt: skip


def test_every_episode_has_one_outcome_and_the_classical_helmsman_reaches_open_goals() -> None:
    """Goal approaches without obstacles: ``los`` (steer at the goal) reaches more goals than
    the sanity helmsman ``straight`` (never turns); the counts add up to the episodes."""
    done = _run("--member", "goal-approach", "--helmsmen", "los,straight", "--episodes", "4")
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["member"] == "goal-approach" and out["seed"] == 12345
    los, straight = out["outcomes"]["los"], out["outcomes"]["straight"]
    assert sum(los.values()) == 4 and sum(straight.values()) == 4
    assert los.get("success", 0) > straight.get("success", 0)


def test_an_unknown_helmsman_is_a_one_line_error_with_exit_2() -> None:
    done = _run("--member", "goal-islet", "--helmsmen", "no-such-helmsman", "--episodes", "1")
    assert done.returncode == 2 and "no-such-helmsman" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
