"""Kill at random points: ``usvsim train``, ``usvsim bench`` and the demonstration recorder are
SIGKILLed after a random delay (seeded), repeatedly, and the invariant is checked each time: the
previous results or checkpoint are intact and loadable, nothing half-written is visible, and the
only temporaries a kill can leave (hidden ``.*.tmp`` files, ``.staging-*`` folders) are removed
by the next run. Also Ctrl-C (SIGINT) and SIGTERM: exit 130, summary marked "interrupted".

Slow (each kill starts a fresh interpreter): ``python -m pytest -m slow tests/usvsim/cli``.
"""

from __future__ import annotations

import csv
import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from learning.experiments.checkpoint import load_agent, load_checkpoint
from learning.imitation.demonstrations import load_recordings

pytestmark = pytest.mark.slow
KILLS = int(os.environ.get("USVSIM_KILLS", "3"))  # kills per test
ENV = {**os.environ, "MPLBACKEND": "Agg", "PYTHONUNBUFFERED": "1"}
TRAIN = [sys.executable, "-m", "usvsim.cli", "train", "rl-gaussian-positional", "--quiet"]
TRAIN += ["--n-envs", "2", "--validate-every", "1", "--threads", "1"]


def _run(argv: list[str], timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(argv, env=ENV, capture_output=True, text=True, timeout=timeout)


def _kill_after(argv: list[str], delay_s: float) -> int:
    proc = subprocess.Popen(argv, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        proc.wait(timeout=delay_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    return proc.returncode


def _temporaries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def _only_ours(names: list[str]) -> bool:
    return all(n.endswith(".tmp") or n.startswith(".staging-") for n in names)


def test_train_killed_at_random_points_keeps_a_loadable_checkpoint(tmp_path: Path) -> None:
    rng = random.Random(14)
    out = tmp_path / "run"
    assert _run([*TRAIN, "--iterations", "2", "--out", str(out)]).returncode == 0
    iterations = 2
    for _ in range(KILLS):
        iterations += 40
        delay = rng.uniform(2.0, 9.0)
        rc = _kill_after(
            [*TRAIN, "--iterations", str(iterations), "--out", str(out), "--resume"], delay
        )
        assert rc in (-signal.SIGKILL, 0)
        for name in ("latest.pt", "best.pt"):
            ckpt = load_checkpoint(out / name)
            load_agent(ckpt, out / name)
        # best.pt (the last one loaded) may come from the first validation, at iteration 1
        assert not ckpt.slim and int(ckpt.agent["iteration"]) >= 1
        with (out / "log.csv").open() as handle:
            rows = list(csv.DictReader(handle))
        assert rows and all(r["iteration"] for r in rows)
        json.loads((out / "summary.json").read_text())
        assert _only_ours(_temporaries(out)), _temporaries(out)
    done = _run([*TRAIN, "--iterations", str(iterations + 1), "--out", str(out), "--resume"])
    assert done.returncode == 0, done.stderr
    assert _temporaries(out) == []


def _bench(out: Path, helmsmen: str, heldout: int = 400) -> list[str]:
    return [
        sys.executable,
        "-m",
        "usvsim.cli",
        "bench",
        "--helmsmen",
        helmsmen,
        "--heldout",
        str(heldout),
        "--no-likeness",
        "--out",
        str(out),
    ]


def _result_set(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if not p.name.startswith(".")}


def _consistent(files: dict[str, bytes]) -> bool:
    """bench.md, bench.csv and exactly the plots of the helmsmen in the CSV."""
    rows = list(csv.DictReader(files["bench.csv"].decode().splitlines()))
    plots = {f"paths-{r['helmsman']}-{r['episode_set']}.png" for r in rows}
    return set(files) == {"bench.md", "bench.csv", *plots} and all(
        files[p][:8] == b"\x89PNG\r\n\x1a\n" for p in plots
    )


def test_bench_killed_at_random_points_keeps_one_whole_result_set(tmp_path: Path) -> None:
    rng = random.Random(41)
    out = tmp_path / "bench"
    assert _run(_bench(out, "los")).returncode == 0
    previous = _result_set(out)
    assert _consistent(previous)
    for k in range(KILLS):
        helmsmen = ["los,los-avoid", "straight,los", "los-avoid"][k % 3]
        _kill_after(_bench(out, helmsmen), rng.uniform(1.0, 8.0))
        now = _result_set(out)
        assert now == previous or _consistent(now), sorted(now)
        assert _only_ours(_temporaries(out)), _temporaries(out)
        previous = now
    assert _run(_bench(out, "los")).returncode == 0
    assert _temporaries(out) == [] and _consistent(_result_set(out))


def test_the_recorder_killed_at_random_points_keeps_a_whole_set(tmp_path: Path) -> None:
    rng = random.Random(46)
    out = tmp_path / "demos"
    record = [sys.executable, "-m", "learning.imitation.demonstrations", str(out)]
    assert _run(record).returncode == 0
    before = _result_set(out)
    for _ in range(KILLS):
        _kill_after(record, rng.uniform(1.0, 9.0))
        report = load_recordings(out)
        assert len(report.recordings) == 46 and report.errors == {}
        assert _result_set(out) == before  # same seed: the new set equals the old one
        assert _only_ours(_temporaries(out)), _temporaries(out)
    assert _run(record).returncode == 0
    assert _temporaries(out) == []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_train_interrupted_exits_130_with_an_interrupted_summary(tmp_path: Path, sig) -> None:
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [*TRAIN, "--iterations", "500", "--stop-after", "0", "--out", str(out)],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not (out / "latest.pt").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(1.0)
    proc.send_signal(sig)  # once: one swallowed in a CasADi call is raised again (issue 19)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("usvsim train: interrupted at iteration")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop_reason"] == "interrupted" and summary["interrupted"] is True
    ckpt = load_checkpoint(out / "latest.pt")
    assert int(ckpt.agent["iteration"]) == summary["checkpoint_iteration"]
    assert _temporaries(out) == []


def _interrupt_bench(out: Path) -> tuple[int, str, str]:
    """Run a bench and send SIGINT once its first set is done and the second has started (the
    progress bar says so on stderr), whatever the machine's speed; (exit status, stdout, stderr).
    """
    argv = [*_bench(out, "los,los-avoid,straight", heldout=3000), "--json"]
    proc = subprocess.Popen(
        argv, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stderr is not None and proc.stdout is not None
    err_seen: list[str] = []
    reader = threading.Thread(target=lambda: err_seen.extend(iter(lambda: proc.stderr.read(1), "")))
    reader.start()
    deadline = time.monotonic() + 120
    while "los / held-out" not in "".join(err_seen) and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    stdout = proc.stdout.read()
    proc.wait(timeout=60)
    reader.join(timeout=10)
    return proc.returncode, stdout, "".join(err_seen)


def test_bench_interrupted_exits_130_and_keeps_the_finished_sets(tmp_path: Path) -> None:
    # A SIGINT that lands inside a CasADi call used to be consumed there (the bench then ran to
    # completion, exit 0, in 3 tries of 4); it is raised again at the next batch step now
    # (usvsim.common.interrupt), so every try must end early.
    for attempt in range(3):
        out = tmp_path / f"bench{attempt}"
        code, stdout, err = _interrupt_bench(out)
        assert code == 130, err
        assert _temporaries(out) == []
        payload = json.loads(stdout)
        assert payload["interrupted"] is True and 0 < len(payload["rows"]) < 6
        assert "(interrupted" in (out / "bench.md").read_text().splitlines()[0]
