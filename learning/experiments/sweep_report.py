"""Across-seed statistics of a sweep (:mod:`learning.experiments.sweep`), after Agarwal et al.
(2021), "Deep reinforcement learning at the edge of the statistical precipice", with their
library ``rliable``.

Per arm (a setup with one set of hyperparameter overrides; its trials differ only by seed):

* the interquartile mean (IQM: the mean of the middle 50 % of runs, ``scipy.stats.trim_mean``
  with 25 % cut at each end, Agarwal et al. §4.3) of the held-out success rate of each seed's
  ``best.pt``, with a 95 % stratified-bootstrap percentile interval (rliable, 10 000 resamples);
* performance profiles: the fraction of runs with held-out success above τ (Agarwal et al.
  §4.2, ``performance_profile.png``), with 95 % bootstrap intervals (2 000 resamples, seeded);
* the probability of improvement P(X > Y) between every two arms (the Mann–Whitney statistic,
  Agarwal et al. §4.4) with its bootstrap interval;
* sample-efficiency curves: validation success vs env steps and vs wall-clock, the mean over
  seeds and its 95 % bootstrap interval at each point (``efficiency_env_steps.png``,
  ``efficiency_wall_clock.png``). A run's curve holds each validation's value until the next
  one, 0 before its first and its last value after it ended (an early stop after
  ``stop_after`` 15/15 validations);
* the median iterations (and wall-clock) to the first 15/15 over the seeds that reached it;
* the shipped seed, chosen by the rule of ``sweep.json`` on validation only
  (:func:`choose_shipped`), beside the study's Table 4.1 and the model usvsim ships.

Held-out results come from each run's ``heldout.json``; every other number from its
``log.csv`` and ``summary.json``. A crashed trial is listed, not left out silently.

Why this module is long: each statistic above is a short function, and the report that puts
them in one table and its figures reads them together; the report is one idea.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.experiments.il_setups import IL_SETUPS
from learning.experiments.run_log import VALIDATION_EPISODES
from learning.experiments.setups import SETUPS
from learning.experiments.sweep import OBJECTIVE, SweepSpec, trial_metrics, validation_curve
from usvsim.common.fileio import atomic_savefig, atomic_write_text, json_safe
from usvsim.common.splits import selection_mode
from usvsim.evaluation.seed_stats import bootstrap_intervals, iqm

__all__ = [
    "TrialRecord",
    "best_by_validation",
    "bootstrap_intervals",
    "choose_shipped",
    "iqm",
    "load_trials",
    "probability_of_improvement",
    "score_distribution",
    "write_report",
]

# resamples of the stratified bootstrap: rliable's default is 50 000, but arch's bootstrap costs
# ~1 ms per resample on a loaded 2-core machine (measured: a 4-setup report took 3.6 min); the
# IQM and P(X > Y) intervals use usvsim.evaluation.seed_stats.BOOTSTRAP_REPS (10 000), seeded
CURVE_REPS = 2_000  # per point of the sample-efficiency curves
CURVE_POINTS = 60
PROFILE_REPS = 2_000  # performance-profile intervals (rliable's default)


@dataclass(frozen=True)
class TrialRecord:
    """One trial as the report sees it: status, validation metrics, held-out result."""

    setup: str
    seed: int
    overrides: dict[str, Any]
    dir: Path
    status: str  # finished, crashed, not run
    error: str
    metrics: dict[str, Any]  # sweep.trial_metrics (validation only); {} unless finished
    heldout_success: float  # NaN unless finished
    curve: list[dict[str, float]]

    @property
    def arm(self) -> str:
        extra = ",".join(f"{k}={v}" for k, v in sorted(self.overrides.items()))
        return self.setup + (f" [{extra}]" if extra else "")


def load_trials(root: Path) -> list[TrialRecord]:
    """Every trial of the sweep in ``root`` (from ``trials.json`` and the run folders), in the
    order of ``sweep.json``'s setups, then overrides, then seed: ``trials.json`` is in Tune's
    order, which a continued sweep shuffles, and the report's per-seed columns follow this one."""
    out = []
    listed = json.loads((root / "trials.json").read_text())
    spec_path = root / "sweep.json"
    setups = list(json.loads(spec_path.read_text())["setups"]) if spec_path.is_file() else []
    for t in listed:
        if t["setup"] not in setups:
            setups.append(t["setup"])
    listed.sort(
        key=lambda t: (
            setups.index(t["setup"]),
            json.dumps(t["overrides"], sort_keys=True),
            int(t["seed"]),
        )
    )
    for t in listed:
        run = root / "runs" / t["dir"]
        finished = t["status"] == "finished"
        heldout = json.loads((run / "heldout.json").read_text()) if finished else {}
        out.append(
            TrialRecord(
                t["setup"],
                int(t["seed"]),
                dict(t["overrides"]),
                run,
                t["status"],
                t["error"],
                trial_metrics(run) if finished else {},
                float(heldout["success_rate"]) if finished else math.nan,
                validation_curve(run / "log.csv") if finished else [],
            )
        )
    return out


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> float:
    """P(X > Y) + ½ P(X = Y) over all pairs of runs, the Mann–Whitney U statistic over
    ``n_x n_y`` (Agarwal et al. 2021 §4.4); rliable's ``probability_of_improvement`` for one task
    without scipy's per-call overhead (the bootstrap calls it once per resample)."""
    a, b = np.asarray(x, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
    diff = a[:, None] - b[None, :]
    return float((np.sum(diff > 0) + 0.5 * np.sum(diff == 0)) / diff.size)


def score_distribution(scores: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """The performance profile: the fraction of runs with a score above each τ (Agarwal et al.
    2021 §4.2); rliable's ``score_distributions`` in one array operation instead of one call
    per τ (the bootstrap calls it once per resample)."""
    x = np.asarray(scores, dtype=float).reshape(-1, 1)
    return np.mean(x > np.asarray(taus, dtype=float)[None, :], axis=0)


@selection_mode("choose_shipped")
def choose_shipped(trials: Sequence[TrialRecord], rule: str) -> TrialRecord | None:
    """The trial that ships under ``rule``, using validation only.

    ``median-validation``: sort the finished seeds by (best validation successes, validation
    AUC, seed) and take the lower median; ``seed:K``: seed K (None if it did not finish).
    """
    done = [t for t in trials if t.status == "finished"]
    if not done:
        return None
    if rule.startswith("seed:"):
        seed = int(rule.split(":", 1)[1])
        return next((t for t in done if t.seed == seed), None)
    ranked = sorted(
        done, key=lambda t: (t.metrics["val_best_successes"], t.metrics[OBJECTIVE], t.seed)
    )
    return ranked[(len(ranked) - 1) // 2]


def _study(setup: str) -> dict[str, Any]:
    """The study's Table 4.1 row: best validation success and iterations to it."""
    if setup in IL_SETUPS:
        s = IL_SETUPS[setup]
        return {"success": s.study_success, "iterations": s.study_iterations}
    if setup in SETUPS:
        return {"success": 1.0, "iterations": SETUPS[setup].study_iterations}
    return {"success": math.nan, "iterations": 0}


def _shipped_model(setup: str, n: int) -> float:
    """Held-out success of the model usvsim ships for ``setup`` (NaN if none)."""
    from usvsim.evaluation.episodes import evaluate, heldout_episodes
    from usvsim.helm.registry import helmsman_kinds, make_helmsman, model_path

    if not model_path(setup).is_file():  # found by the setup's name (a former name)
        return math.nan
    helmsman = make_helmsman(setup)
    observation, action = helmsman_kinds(helmsman)
    records = evaluate(helmsman, heldout_episodes(n=n), observation=observation, action=action)
    return float(np.mean([r.success for r in records]))


def _arm_rows(
    trials: Sequence[TrialRecord], spec: SweepSpec, compare_shipped: bool
) -> list[dict[str, Any]]:
    arms: dict[str, list[TrialRecord]] = {}
    for t in trials:
        arms.setdefault(t.arm, []).append(t)
    scores = {
        a: np.array([[t.heldout_success] for t in ts if t.status == "finished"])
        for a, ts in arms.items()
    }
    scores = {a: s for a, s in scores.items() if len(s)}
    points, cis = (
        bootstrap_intervals(scores, lambda x: np.array([iqm(x[:, 0])])) if scores else ({}, {})
    )
    rows = []
    shipped_models: dict[str, float] = {}  # held-out success of usvsim's model, per setup
    for arm, ts in arms.items():
        done = [t for t in ts if t.status == "finished"]
        firsts = [t for t in done if t.metrics["first_full_iteration"] >= 0]
        walls = [_first_full_wall(t) for t in firsts]
        shipped = choose_shipped(ts, spec.ship_rule)
        if ts[0].setup not in shipped_models:
            shipped_models[ts[0].setup] = (
                _shipped_model(ts[0].setup, spec.heldout) if compare_shipped else math.nan
            )
        rows.append(
            {
                "arm": arm,
                "setup": ts[0].setup,
                "overrides": ts[0].overrides,
                "seeds": [t.seed for t in done],
                "crashed_seeds": [t.seed for t in ts if t.status == "crashed"],
                "not_run_seeds": [t.seed for t in ts if t.status == "not run"],
                "heldout_success": [t.heldout_success for t in done],
                "heldout_iqm": float(points[arm][0]) if arm in points else math.nan,
                "heldout_iqm_ci95": [float(c) for c in cis[arm][:, 0]] if arm in cis else [],
                "heldout_mean": float(np.mean(scores[arm])) if arm in scores else math.nan,
                "val_best_successes": [t.metrics["val_best_successes"] for t in done],
                "reached_15_of_15": len(firsts),
                "median_iterations_to_15_of_15": _median(
                    [t.metrics["first_full_iteration"] for t in firsts]
                ),
                "median_wall_s_to_15_of_15": _median(walls),
                "train_wall_s": [t.metrics["train_wall_s"] for t in done],
                "shipped_seed": None if shipped is None else shipped.seed,
                "shipped_heldout_success": math.nan if shipped is None else shipped.heldout_success,
                "study": _study(ts[0].setup),
                "usvsim_model_heldout_success": shipped_models[ts[0].setup],
            }
        )
    return rows


@selection_mode("best_by_validation")
def best_by_validation(trials: Sequence[TrialRecord]) -> dict[str, Any] | None:
    """The search's answer: the finished trial with the best validation score (then best
    validation, then fewer iterations); held-out plays no part."""
    done = [t for t in trials if t.status == "finished"]
    if not done:
        return None
    best = max(
        done,
        key=lambda t: (
            t.metrics[OBJECTIVE],
            t.metrics["val_best_successes"],
            -t.metrics["iterations"],
        ),
    )
    return {"dir": best.dir.name, "overrides": best.overrides, "metrics": best.metrics}


def _first_full_wall(t: TrialRecord) -> float:
    summary = json.loads((t.dir / "summary.json").read_text())
    return float(summary["first_15_of_15"]["wall_time_s"])


def _median(values: Sequence[float]) -> float:
    return float(np.median(values)) if len(values) else math.nan


def _improvement(trials: Sequence[TrialRecord]) -> list[dict[str, Any]]:
    """P(X > Y) on held-out success for every two arms, with its 95 % bootstrap interval."""
    arms: dict[str, list[float]] = {}
    for t in trials:
        if t.status == "finished":
            arms.setdefault(t.arm, []).append(t.heldout_success)
    pairs = {
        f"{x} > {y}": (np.array(arms[x])[:, None], np.array(arms[y])[:, None])
        for x, y in itertools.combinations(arms, 2)
    }
    if not pairs:
        return []
    points, cis = bootstrap_intervals(pairs, probability_of_improvement)
    return [
        {"pair": p, "probability": float(points[p]), "ci95": [float(c) for c in cis[p].ravel()]}
        for p in pairs
    ]


def _curves(trials: Sequence[TrialRecord], x_key: str) -> dict[str, dict[str, list[float]]]:
    """Per arm: validation success rate vs ``x_key`` on a common grid, mean and 95 % CI."""
    arms: dict[str, list[TrialRecord]] = {}
    for t in trials:
        if t.status == "finished" and t.curve:
            arms.setdefault(t.arm, []).append(t)
    out: dict[str, dict[str, list[float]]] = {}
    for arm, ts in arms.items():
        x_max = max(t.curve[-1][x_key] for t in ts)
        grid = np.linspace(0.0, x_max, CURVE_POINTS)
        runs = np.array([_step_curve(t.curve, x_key, grid) for t in ts])
        points, cis = bootstrap_intervals({arm: runs}, lambda s: np.mean(s, axis=0), CURVE_REPS)
        out[arm] = {
            "x": grid.tolist(),
            "mean": points[arm].tolist(),
            "low": cis[arm][0].tolist(),
            "high": cis[arm][1].tolist(),
        }
    return out


def _step_curve(curve: list[dict[str, float]], x_key: str, grid: np.ndarray) -> np.ndarray:
    xs = np.array([c[x_key] for c in curve])
    ys = np.array([c["successes"] / VALIDATION_EPISODES for c in curve])
    idx = np.searchsorted(xs, grid, side="right") - 1
    return np.where(idx >= 0, ys[np.clip(idx, 0, None)], 0.0)


def _plots(root: Path, rows: list[dict[str, Any]], trials: Sequence[TrialRecord]) -> list[str]:
    from usvsim.common.mpl import use_file_backend_if_headless

    use_file_backend_if_headless()
    import matplotlib.pyplot as plt
    from rliable import plot_utils

    files = []
    scores = {r["arm"]: np.array(r["heldout_success"])[:, None] for r in rows if r["seeds"]}
    if scores:
        taus = np.linspace(0.0, 1.0, 101)
        profiles, profile_cis = bootstrap_intervals(
            scores, lambda x: score_distribution(x, taus), PROFILE_REPS
        )
        fig, ax = plt.subplots(figsize=(7, 4))
        plot_utils.plot_performance_profiles(
            profiles,
            taus,
            performance_profile_cis=profile_cis,
            ax=ax,
            xlabel=r"held-out success rate $\tau$",
            ylabel=r"fraction of seeds with success $> \tau$",
        )
        ax.legend(list(scores), fontsize=7)
        fig.tight_layout()
        atomic_savefig(fig, root / "performance_profile.png", dpi=100)
        plt.close(fig)
        files.append("performance_profile.png")
    for key, label, name in (
        ("env_steps", "environment steps (decisions)", "efficiency_env_steps.png"),
        ("wall_time_s", "wall-clock of the run, s", "efficiency_wall_clock.png"),
    ):
        curves = _curves(trials, key)
        if not curves:
            continue
        fig, ax = plt.subplots(figsize=(7, 4))
        for arm, c in curves.items():
            (line,) = ax.plot(c["x"], c["mean"], label=arm)
            ax.fill_between(c["x"], c["low"], c["high"], color=line.get_color(), alpha=0.2)
        ax.set_xlabel(label)
        ax.set_ylabel("validation success (mean, 95 % CI over seeds)")
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        atomic_savefig(fig, root / name, dpi=100)
        plt.close(fig)
        files.append(name)
    return files


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def _num(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{x:.0f}"


def _markdown(report: dict[str, Any]) -> str:
    spec = report["spec"]
    lines = [
        f"# Sweep {spec['name']}",
        "",
        f"{len(report['trials'])} trials: setups {', '.join(spec['setups'])}; seeds "
        f"{spec['seeds']}; search {spec['search']}; wall-clock {report['wall_s']:.0f} s in "
        f"{report['sessions']} session(s). Held-out: {spec['heldout']} episodes per `best.pt`, "
        f"used for this report only. Shipped-seed rule (fixed in `sweep.json` before the sweep, "
        f"validation only): `{spec['ship_rule']}`.",
        "",
        "| arm | seeds | held-out IQM [95 % CI] | mean | per seed | reached 15/15 | "
        "median it. to 15/15 | median s to 15/15 | shipped seed: held-out | study: success / it. "
        "| usvsim model: held-out |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in report["arms"]:
        ci = r["heldout_iqm_ci95"]
        ci_text = f"[{_pct(ci[0])}, {_pct(ci[1])}]" if ci else ""
        crashed = f" ({len(r['crashed_seeds'])} crashed)" if r["crashed_seeds"] else ""
        lines.append(
            f"| {r['arm']} | {len(r['seeds'])}{crashed} | {_pct(r['heldout_iqm'])} {ci_text} | "
            f"{_pct(r['heldout_mean'])} | {', '.join(_pct(x) for x in r['heldout_success'])} | "
            f"{r['reached_15_of_15']}/{len(r['seeds'])} | "
            f"{_num(r['median_iterations_to_15_of_15'])} | "
            f"{_num(r['median_wall_s_to_15_of_15'])} | "
            f"{r['shipped_seed']}: {_pct(r['shipped_heldout_success'])} | "
            f"{_pct(r['study']['success'])} / {r['study']['iterations']} | "
            f"{_pct(r['usvsim_model_heldout_success'])} |"
        )
    best = report["best_by_validation"]
    searched = spec["search"] != "grid" or spec["grid"]
    if best is not None and searched:
        lines += [
            "",
            f"Best trial by validation score (the search's objective): `{best['dir']}` "
            f"(overrides {json.dumps(best['overrides'])}, validation score "
            f"{best['metrics'][OBJECTIVE]:.3f}).",
        ]
    if report["improvement"]:
        lines += ["", "| probability of improvement (held-out) | P | 95 % CI |", "|---|---|---|"]
        for p in report["improvement"]:
            lines.append(
                f"| {p['pair']} | {p['probability']:.2f} | "
                f"[{p['ci95'][0]:.2f}, {p['ci95'][1]:.2f}] |"
            )
    lines += [
        "",
        "| trial | status | iterations | first 15/15 | best validation | validation AUC | "
        "held-out | train s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for t in report["trials"]:
        m = t["metrics"]
        if t["status"] != "finished":
            lines.append(f"| {t['dir']} | {t['status']}: {t['error']} | | | | | | |")
            continue
        first = m["first_full_iteration"]
        lines.append(
            f"| {t['dir']} | finished | {m['iterations']} | {'never' if first < 0 else first} | "
            f"{m['val_best_successes']}/15 | {m[OBJECTIVE]:.3f} | {_pct(t['heldout_success'])} | "
            f"{m['train_wall_s']:.0f} |"
        )
    lines += [""] + [f"![{f}]({f})" for f in report["plots"]]
    return "\n".join(lines) + "\n"


def write_report(root: Path, compare_shipped: bool = True) -> dict[str, Any]:
    """Write ``report.json``, ``report.md`` and the PNGs of the sweep in ``root``; the report.

    ``compare_shipped`` also evaluates the model usvsim ships for each setup on the same
    held-out episodes (``usvsim_model_heldout_success``).
    """
    spec = SweepSpec.from_json(json.loads((root / "sweep.json").read_text()))
    trials = load_trials(root)
    sessions = json.loads((root / "sessions.json").read_text())
    rows = _arm_rows(trials, spec, compare_shipped)
    report = {
        "spec": spec.to_json(),
        "wall_s": float(sum(s["wall_s"] for s in sessions)),
        "sessions": len(sessions),
        "arms": rows,
        "improvement": _improvement(trials),
        "best_by_validation": best_by_validation(trials),
        "efficiency": {k: _curves(trials, k) for k in ("env_steps", "wall_time_s")},
        "trials": [
            {
                "dir": t.dir.name,
                "setup": t.setup,
                "seed": t.seed,
                "overrides": t.overrides,
                "status": t.status,
                "error": t.error,
                "metrics": t.metrics,
                "heldout_success": t.heldout_success,
            }
            for t in trials
        ],
        "plots": _plots(root, rows, trials),
    }
    atomic_write_text(root / "report.json", json.dumps(json_safe(report), indent=2) + "\n")
    atomic_write_text(root / "report.md", _markdown(report))
    return report
