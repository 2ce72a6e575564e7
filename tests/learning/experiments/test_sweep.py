"""``usvsim sweep``: the sweep definition (overrides of training fields, seeds, groups, trial
folders), the across-seed statistics (IQM, shipped-seed rule) and, marked slow, a real 2-trial
sweep on local Ray that is interrupted, resumed and checked against its trials' own logs."""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from learning.experiments.setups import get_setup
from learning.experiments.sweep import (
    Distribution,
    SweepSpec,
    apply_overrides,
    expand_setups,
    expected_trials,
    parse_seeds,
    remove_trial_temporaries,
    trial_dir_name,
)
from learning.experiments.sweep_report import (
    TrialRecord,
    choose_shipped,
)


def test_override_reaches_nested_training_fields() -> None:
    base = get_setup("rl-gaussian-radar")
    s = apply_overrides(
        base, {"max_kl": "0.005", "balanced_fusion": False, "validate_every": 7, "num_envs": 8}
    )
    assert s.algorithm_config.max_kl == 0.005
    assert s.algorithm_config.network.balanced_fusion is False
    assert s.validate_every == 7
    assert s.algorithm_config.num_envs == 8
    assert s.algorithm_config.gamma == base.algorithm_config.gamma  # the rest unchanged


def test_override_of_il_discriminator_field() -> None:
    from learning.experiments.il_setups import get_il_setup

    s = apply_overrides(get_il_setup("il-gaussian-positional"), {"gail.bc_epochs": 3})
    assert s.gail.bc_epochs == 3


def test_unknown_or_fixed_field_is_refused_with_the_allowed_ones() -> None:
    with pytest.raises(ValueError, match=r"unknown training field 'max_kll'.*max_kl"):
        apply_overrides(get_setup("rl-gaussian-positional"), {"max_kll": 0.01})
    with pytest.raises(ValueError, match="unknown training field 'seed'"):
        apply_overrides(get_setup("rl-gaussian-positional"), {"seed": 1})
    with pytest.raises(ValueError, match="integer"):
        apply_overrides(get_setup("rl-gaussian-positional"), {"num_envs": 2.5})


def test_seeds_groups_and_trial_count() -> None:
    assert parse_seeds("0-4") == (0, 1, 2, 3, 4)
    assert parse_seeds("3,7") == (3, 7)
    with pytest.raises(ValueError, match="range 0-4"):
        parse_seeds("a")
    assert expand_setups(["positional"]) == (
        "rl-gaussian-positional",
        "rl-categorical-positional",
        "il-gaussian-positional",
        "il-categorical-positional",
    )
    spec = SweepSpec(
        "t", expand_setups(["radar"]), (0, 1, 2), grid=(("max_kl", (0.01, 0.02)),), samples=1
    )
    assert expected_trials(spec) == 4 * 3 * 2
    # the study's groups stay the study's eight setups when open-water setups are added
    assert len(expand_setups(["rl", "il"])) == 8
    assert not any("-ow" in s for s in expand_setups(["rl", "radar", "positional"]))
    ow = expand_setups(["open-water"])
    assert all("-ow" in s for s in ow) and len(ow) == 13  # 4 RL, 4 IL, 3 fine-tuned, 2 continued
    colreg = expand_setups(["colreg"])
    assert all("-colreg" in s for s in colreg) and not set(colreg) & set(ow)
    assert {"rl-gaussian-radar-colreg", "il-gaussian-radar-colreg"} <= set(colreg)


def test_spec_round_trip_and_refusals() -> None:
    spec = SweepSpec(
        "hp",
        ("rl-gaussian-positional",),
        (0,),
        random=(("max_kl", Distribution.parse("loguniform:0.005:0.05")),),
        search="optuna",
        samples=8,
    )
    assert SweepSpec.from_json(spec.to_json()) == spec
    with pytest.raises(ValueError, match="optuna tunes one setup on one seed"):
        SweepSpec("hp", ("rl-gaussian-positional",), (0, 1), random=spec.random, search="optuna")
    with pytest.raises(ValueError, match="unknown setup 'rl-nope'"):
        SweepSpec("x", ("rl-nope",), (0,))
    with pytest.raises(ValueError, match="unknown sweep fields"):
        SweepSpec.from_json({"name": "x", "setups": ["rl-gaussian-positional"], "sedes": [0]})


def test_trial_folders_are_distinct_per_draw() -> None:
    a = trial_dir_name("rl-gaussian-positional", 1, {"max_kl": 0.0123456789}, "random")
    b = trial_dir_name("rl-gaussian-positional", 1, {"max_kl": 0.0123456788}, "random")
    assert a != b and a.startswith("rl-gaussian-positional-seed1-h")
    grid = trial_dir_name("rl-gaussian-positional", 0, {"max_kl": 0.01}, "grid")
    assert grid == "rl-gaussian-positional-seed0-max_kl=0.01"


def _record(seed: int, best: int, auc: float, status: str = "finished") -> TrialRecord:
    metrics = {"val_best_successes": best, "val_auc": auc}
    return TrialRecord("s", seed, {}, Path("."), status, "", metrics, 0.5, [])


def test_shipped_seed_is_the_validation_median() -> None:
    trials = [_record(0, 15, 0.5), _record(1, 14, 0.9), _record(2, 15, 0.7), _record(3, 15, 0.2)]
    trials.append(_record(4, 0, 0.0, status="crashed"))
    # by (best, auc): seed1 (14), seed3, seed0, seed2 -> lower median of 4 = seed3
    shipped = choose_shipped(trials, "median-validation")
    assert shipped is not None and shipped.seed == 3
    fixed = choose_shipped(trials, "seed:2")
    assert fixed is not None and fixed.seed == 2
    assert choose_shipped(trials, "seed:4") is None  # crashed: never shipped


# --- a real sweep -----------------------------------------------------------------------------

# Tiny budget: 20 iterations (a validation every 4, so latest.pt after 4 and 4 more after the
# interrupt), 10 held-out episodes. Measured on 2 loaded cores (see the README's test timings):
# each session pays ~3 s of imports, ~5 s of Ray start, ~8 s until Tune's trial actors have
# imported torch, ~2 s of Ray shutdown; training is ~8 s per trial.
ITERATIONS, HELDOUT = 20, 10
SWEEP = [
    "--setups", "rl-categorical-positional", "--seeds", "0,1", "--iterations", str(ITERATIONS),
    "--validate-every", "4", "--n-envs", "4", "--heldout", str(HELDOUT), "--max-concurrent", "2",
    "--no-shipped",
]  # fmt: skip


def _sweep(out: Path, ray_tmp: Path, *extra: str) -> subprocess.Popen[str]:
    main = "import sys; from usvsim.cli.main import main; sys.exit(main())"
    cmd = [sys.executable, "-c", main, "sweep", *SWEEP, "--out", str(out), *extra]
    env = {**os.environ, "MPLBACKEND": "Agg", "RAY_TMPDIR": str(ray_tmp)}
    env.pop("RAY_ADDRESS", None)  # always a local Ray of its own
    return subprocess.Popen(  # its own process group: Ctrl-C below reaches all of it
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        start_new_session=True,
    )


@pytest.fixture
def start_sweep() -> Iterator[Callable[..., subprocess.Popen[str]]]:
    """Start the test sweep in ``out``; what is still running at the end is killed (its group).

    Ray's files go to a short folder of the test's own (socket paths are limited to 107 bytes),
    which records a cluster that is long gone, as a ``ray start`` that was not stopped leaves
    it: a local sweep must start a Ray of its own all the same.
    """
    procs: list[subprocess.Popen[str]] = []
    ray_tmp = Path(tempfile.mkdtemp(prefix="ray-", dir="/tmp"))
    (ray_tmp / "ray_current_cluster").write_text("127.0.0.1:1")

    def start(out: Path, *extra: str) -> subprocess.Popen[str]:
        procs.append(_sweep(out, ray_tmp, *extra))
        return procs[-1]

    yield start
    for proc in procs:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)
    shutil.rmtree(ray_tmp, ignore_errors=True)


def _log(run: Path) -> list[dict[str, str]]:
    with (run / "log.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_sweep_interrupted_resumed_and_report_matches_the_logs(
    tmp_path: Path, start_sweep: Callable[..., subprocess.Popen[str]]
) -> None:
    pytest.importorskip("ray.tune")  # the sweep extra
    pytest.importorskip("rliable")
    out = tmp_path / "sweep"
    t0 = time.monotonic()
    first = start_sweep(out, "--max-concurrent", "1")  # one trial at a time, then two
    latest = [out / "runs" / f"rl-categorical-positional-seed{s}" / "latest.pt" for s in (0, 1)]
    deadline = time.monotonic() + 120
    while not any(p.exists() for p in latest) and first.poll() is None:
        assert time.monotonic() < deadline, "no trial wrote latest.pt within 120 s"
        time.sleep(0.2)
    assert first.poll() is None, first.communicate()[0]  # still running at its first latest.pt
    t_signal = time.monotonic()
    # Ctrl-C as a terminal sends it: to the foreground process group, i.e. the driver and the
    # local Ray processes it started (Ray's workers run in groups of their own)
    os.killpg(first.pid, signal.SIGINT)
    text, _ = first.communicate(timeout=120)
    assert first.returncode == 130, text
    assert time.monotonic() - t_signal < 60, "Ctrl-C did not stop the sweep within a minute"
    assert "run the same command to continue" in text
    trials = json.loads((out / "trials.json").read_text())
    assert [t["status"] for t in trials] == ["not run", "not run"]

    second = start_sweep(out)
    text, _ = second.communicate(timeout=180)
    wall = time.monotonic() - t0
    assert second.returncode == 0, text
    assert "continuing the sweep" in text
    # the second session's cap (2), not the first one's that Tune restored: both trials at once
    assert re.search(r"\[sweep\] start \S+ \(.*, 1 running\)", text), text
    assert wall < 180, f"interrupted + resumed sweep took {wall:.0f} s (43 s at load 2)"

    report = json.loads((out / "report.json").read_text())
    assert [t["status"] for t in report["trials"]] == ["finished", "finished"]
    assert report["sessions"] == 2
    resumed = 0
    firsts, best_auc = [], []
    for t in report["trials"]:
        run = out / "runs" / t["dir"]
        rows = _log(run)
        # one row per iteration: the resumed run continued, nothing twice or lost
        assert [int(r["iteration"]) for r in rows] == list(range(1, ITERATIONS + 1))
        val = [(int(r["iteration"]), int(r["val_successes"])) for r in rows if r["val_successes"]]
        m = t["metrics"]
        assert m["iterations"] == ITERATIONS
        assert m["env_steps"] == int(rows[-1]["env_steps"])
        assert m["val_best_successes"] == max(v for _, v in val)
        assert m["val_auc"] == pytest.approx(np.mean([v for _, v in val]) / 15)
        first_full = next((i for i, v in val if v == 15), -1)
        assert m["first_full_iteration"] == first_full
        if first_full >= 0:
            firsts.append(first_full)
        best_auc.append((m["val_best_successes"], m["val_auc"], t["seed"]))
        resumed += "--resume" in json.loads((run / "summary.json").read_text())["command"]
        # the held-out figure is best.pt's own, re-evaluated here
        from usvsim.evaluation.episodes import evaluate, heldout_episodes
        from usvsim.helm.registry import helmsman_kinds, make_helmsman

        helmsman = make_helmsman(str(run / "best.pt"))
        obs, act = helmsman_kinds(helmsman)
        records = evaluate(helmsman, heldout_episodes(n=HELDOUT), observation=obs, action=act)
        assert t["heldout_success"] == pytest.approx(np.mean([r.success for r in records]))
    assert resumed >= 1  # the interrupted trial continued from its latest.pt

    (arm,) = report["arms"]
    heldout = [t["heldout_success"] for t in report["trials"]]
    assert arm["heldout_success"] == pytest.approx(heldout)
    assert arm["heldout_iqm"] == pytest.approx(np.mean(heldout))  # IQM of 2 runs: their mean
    low, high = arm["heldout_iqm_ci95"]
    assert min(heldout) <= low <= arm["heldout_iqm"] <= high <= max(heldout)
    assert arm["reached_15_of_15"] == len(firsts)
    if firsts:
        assert arm["median_iterations_to_15_of_15"] == pytest.approx(np.median(firsts))
    assert arm["shipped_seed"] == sorted(best_auc)[0][2]  # lower median of two by validation
    for png in ("performance_profile.png", "efficiency_env_steps.png", "efficiency_wall_clock.png"):
        assert (out / png).stat().st_size > 5000
    assert "rl-categorical-positional" in (out / "report.md").read_text()


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_sigterm_stops_the_sweep_as_ctrl_c_does(
    tmp_path: Path, start_sweep: Callable[..., subprocess.Popen[str]]
) -> None:
    pytest.importorskip("ray.tune")  # the sweep extra
    out = tmp_path / "sweep"
    proc = start_sweep(out)
    latest = [out / "runs" / f"rl-categorical-positional-seed{s}" / "latest.pt" for s in (0, 1)]
    deadline = time.monotonic() + 120
    while not any(p.exists() for p in latest) and proc.poll() is None:
        assert time.monotonic() < deadline, "no trial wrote latest.pt within 120 s"
        time.sleep(0.2)
    assert proc.poll() is None, proc.communicate()[0]
    proc.terminate()  # SIGTERM to the driver only, as `kill PID` or a batch system sends it
    text, _ = proc.communicate(timeout=90)
    assert proc.returncode == 130, text
    assert "Stop signal received" in text  # Tune's graceful stop, not a KeyboardInterrupt
    assert "run the same command to continue" in text
    trials = json.loads((out / "trials.json").read_text())
    assert [t["status"] for t in trials] == ["not run", "not run"]
    assert len(json.loads((out / "sessions.json").read_text())) == 1
    json.loads((out / "report.json").read_text())  # whole
    assert not [p for p in out.rglob("*") if p.name.startswith(".") and p.suffix == ".tmp"]


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_crashed_trial_is_reported_not_dropped(tmp_path: Path) -> None:
    pytest.importorskip("ray.tune")  # the sweep extra
    out = tmp_path / "crash"
    main = "import sys; from usvsim.cli.main import main; sys.exit(main())"
    args = ["sweep", "--setups", "rl-categorical-positional", "--seeds", "0", "--grid"]
    args += ["gamma=1.5", "--iterations", "5", "--heldout", "5", "--no-shipped", "--out", str(out)]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    done = subprocess.run(
        [sys.executable, "-c", main, *args], capture_output=True, text=True, env=env, timeout=170
    )
    assert done.returncode == 1, done.stdout + done.stderr
    (trial,) = json.loads((out / "trials.json").read_text())
    assert trial["status"] == "crashed"
    assert "gamma must lie in [0, 1)" in trial["error"]
    report = json.loads((out / "report.json").read_text())
    assert report["arms"][0]["crashed_seeds"] == [0]
    assert report["arms"][0]["heldout_iqm"] is None
    assert "crashed" in (out / "report.md").read_text()
    assert "CRASHED rl-categorical-positional-seed0-gamma=1.5" in done.stdout


def test_temporaries_of_stopped_trials_are_removed_and_whole_files_kept(tmp_path: Path) -> None:
    run = tmp_path / "runs" / "rl-gaussian-positional-seed0"
    (run / ".staging-bench").mkdir(parents=True)
    (run / ".curve.png.gu5q52he.tmp").write_bytes(b"half a PNG")
    (run / "latest.pt").write_bytes(b"whole")
    removed = remove_trial_temporaries(tmp_path)
    assert sorted(p.name for p in removed) == [".curve.png.gu5q52he.tmp", ".staging-bench"]
    assert [p.name for p in run.iterdir()] == ["latest.pt"]
    assert remove_trial_temporaries(tmp_path / "no-such-sweep") == []


def test_a_budget_without_validation_is_refused() -> None:
    with pytest.raises(ValueError, match="2 iterations < validation every 5: no validation"):
        SweepSpec("x", ("rl-categorical-positional",), (0,), iterations=2)


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_optuna_search_sees_validation_only(tmp_path: Path) -> None:
    pytest.importorskip("ray.tune")  # the sweep extra
    pytest.importorskip("optuna")
    out = tmp_path / "hp"
    main = "import sys; from usvsim.cli.main import main; sys.exit(main())"
    args = ["sweep", "--setups", "rl-categorical-positional", "--seeds", "0", "--search"]
    args += ["optuna", "--samples", "2", "--random", "max_kl=loguniform:0.005:0.05"]
    args += ["--iterations", "5", "--n-envs", "4", "--heldout", "5", "--no-shipped"]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    done = subprocess.run(
        [sys.executable, "-c", main, *args, "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=170,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    trials = json.loads((out / "trials.json").read_text())
    draws = [t["overrides"]["max_kl"] for t in trials]
    assert len(set(draws)) == 2 and all(0.005 <= d <= 0.05 for d in draws)
    from learning.experiments.checkpoint import load_checkpoint

    for t in trials:  # the run trained with the drawn value
        ckpt = load_checkpoint(out / "runs" / t["dir"] / "latest.pt")
        assert ckpt.setup_params["algorithm_config"]["max_kl"] == t["overrides"]["max_kl"]
    # what Tune (and Optuna) saw: validation metrics, no held-out number anywhere
    results = list((out / "tune").rglob("result.json"))
    assert len(results) == 2
    for path in results:
        for line in path.read_text().splitlines():
            assert not any("heldout" in key for key in json.loads(line))
    report = json.loads((out / "report.json").read_text())
    best = report["best_by_validation"]
    scores = {t["dir"]: t["metrics"]["val_auc"] for t in report["trials"]}
    assert scores[best["dir"]] == max(scores.values())


def test_config_file_and_flags_define_the_same_sweep(tmp_path: Path) -> None:
    from learning.cli.sweep import SweepArgs, spec_of

    flags = SweepArgs(setups="positional", seeds="0-2", grid="max_kl=0.01,0.02", name="s")
    config = tmp_path / "s.json"
    config.write_text(
        json.dumps({"setups": ["positional"], "seeds": [0, 1, 2], "grid": {"max_kl": [0.01, 0.02]}})
    )
    assert spec_of(SweepArgs(config=str(config))) == spec_of(flags)
    with pytest.raises(SystemExit, match="--config defines the sweep; drop --seeds"):
        spec_of(SweepArgs(config=str(config), seeds="0-1"))


def test_config_file_values_are_range_checked_as_the_flags(tmp_path: Path) -> None:
    import dataclasses

    from learning.cli.sweep import SweepArgs, spec_of
    from usvsim.common.options import BOUNDS_KEY

    config = tmp_path / "s.json"
    for bad, message in (
        ({"iterations": -1}, "--iterations must be >= 0, got -1"),
        ({"heldout": 0}, "--heldout must be >= 1 and <= 100000, got 0"),
        ({"samples": "2"}, "sweep field samples must be a number"),
    ):
        config.write_text(json.dumps({"setups": ["rl-categorical-positional"], **bad}))
        with pytest.raises(SystemExit, match=f"^usvsim sweep: {message}"):
            spec_of(SweepArgs(config=str(config)))
    flags = {f.name: f.metadata.get(BOUNDS_KEY) for f in dataclasses.fields(SweepArgs)}
    for f in dataclasses.fields(SweepSpec):  # one range per option, whichever way it is given
        if BOUNDS_KEY in f.metadata:
            assert flags[f.name] == f.metadata[BOUNDS_KEY], f.name


def test_a_continued_sweep_takes_this_sessions_concurrency_cap() -> None:
    """Tune restores the first session's search algorithm; its cap must be the new one's."""
    pytest.importorskip("ray.tune")
    pytest.importorskip("optuna")
    import pickle

    from ray.tune.search.optuna import OptunaSearch

    from learning.experiments.sweep_search import (
        SessionLimitedGenerator,
        SessionLimiter,
        set_session_limit,
    )

    try:
        set_session_limit(1)
        first = SessionLimitedGenerator(random_state=0)
        limiter = SessionLimiter(OptunaSearch(metric="m", mode="max"), max_concurrent=1)
        assert (first.max_concurrent, limiter.max_concurrent) == (1, 1)
        stored, state = pickle.dumps(first), first.get_state()
        set_session_limit(3)  # the continuing session's --max-concurrent
        restored = pickle.loads(stored)
        restored.set_state(state)
        assert restored.max_concurrent == 3
        assert pickle.loads(pickle.dumps(limiter)).max_concurrent == 3
        set_session_limit(0)
        assert restored.max_concurrent == 0 and limiter.max_concurrent > 10**6  # no cap
        with pytest.raises(ValueError, match="max_concurrent must be >= 0"):
            set_session_limit(-1)
    finally:
        set_session_limit(0)


def test_trials_are_reported_in_setup_then_seed_order(tmp_path: Path) -> None:
    """trials.json is in Tune's order (a continued sweep shuffles it); the report is not."""
    from learning.experiments.sweep_report import load_trials

    setups = ["rl-gaussian-radar", "il-gaussian-radar"]
    (tmp_path / "sweep.json").write_text(json.dumps({"setups": setups}))
    shuffled = [("il-gaussian-radar", 2), ("rl-gaussian-radar", 1), ("il-gaussian-radar", 0)]
    shuffled += [("rl-gaussian-radar", 0), ("il-gaussian-radar", 1)]
    rows = [
        {"setup": s, "seed": k, "overrides": {}, "dir": f"{s}-seed{k}", "status": "not run",
         "error": ""}
        for s, k in shuffled
    ]  # fmt: skip
    (tmp_path / "trials.json").write_text(json.dumps(rows))
    order = [(t.setup, t.seed) for t in load_trials(tmp_path)]
    assert order == [
        ("rl-gaussian-radar", 0), ("rl-gaussian-radar", 1),
        ("il-gaussian-radar", 0), ("il-gaussian-radar", 1), ("il-gaussian-radar", 2),
    ]  # fmt: skip
