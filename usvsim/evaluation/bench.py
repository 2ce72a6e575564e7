"""``usvsim bench``: helmsmen on the validation and held-out sets, one table.

With no arguments: the classical baselines and the recommended models (``--helmsmen`` below;
``all``: each helmsman of :func:`usvsim.helm.registry.available_helmsmen`) run the 15
validation episodes and the 200 held-out episodes of the pole task (each set is ONE batch,
:func:`usvsim.evaluation.episodes.evaluate`), and the table gives per helmsman and set

==========================  ===================================================================
column                      meaning
==========================  ===================================================================
success [95 % CI]           strict successes / episodes, Wilson score interval
                            (:mod:`usvsim.evaluation.stats`)
min d_pole min / median     closest approach to the pole (m) over every episode: the worst
                            episode and the median episode (< 10 m fails, ≈ 2.5 m is a hit)
t_goal                      mean time to the goal (s), successful episodes
path                        mean path length (m), successful episodes
Σ|ΔΔψ|                      mean smoothness, Σ |Δψ_k − Δψ_{k−1}| (°), successful episodes
==========================  ===================================================================

``--scenario waypoints`` runs the waypoint courses of :mod:`usvsim.task.waypoints` instead (15
validation and ``--heldout`` held-out courses; t_goal is then the time to the last waypoint).
``--suite stress`` runs the stress suite instead (:mod:`usvsim.evaluation.stress`, its own table).
Why this module is long: the bench's options, rows, table formats and path plots belong together.

Results go to ``--out`` (default ``usvsim-results/bench/``), written as one unit
(:func:`usvsim.common.fileio.staged_dir`: a killed or failing bench leaves the previous results
as they were): ``bench[-waypoints].md``, ``bench[-waypoints].csv`` and one path plot per
helmsman and set, ``paths[-waypoints]-<helmsman>-<set>.png`` (older plots of the same scenario
are removed with the set they belonged to). ``--out`` is checked writable before anything runs.
``--json`` prints only JSON on stdout (NaN and ±inf as ``null``); the progress bar goes to
stderr.

``--helmsmen`` takes names of :mod:`usvsim.helm.registry` and checkpoint paths alike (a path is
labelled by its file stem); a name given twice runs once. With no ``--helmsmen`` the bench
compares the classical baselines with the models recommended in the model cards (``usvsim
models``; every helmsman while none is marked), ``--helmsmen all`` every shipped file. Without
``--helmsmen`` or with ``all``, a shipped model that cannot be read is skipped with a warning
(the other helmsmen still run); a named one that cannot be read is an error. On Ctrl-C or
SIGTERM the sets finished so far are written, marked "interrupted" (Markdown title,
``"interrupted": true`` in JSON).
"""

from __future__ import annotations

import csv
import io
import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, Protocol, get_args

import numpy as np

from usvsim.common.errors import UserError
from usvsim.common.options import bounds, check_bounds
from usvsim.evaluation.stats import Proportion, finite_mean, finite_median, proportion
from usvsim.task.observations import PERCEPTION

__all__ = [
    "SCENARIOS",
    "BenchArgs",
    "BenchResult",
    "BenchRow",
    "ScenarioKind",
    "format_table",
    "loadable_helmsmen",
    "plot_pole_paths",
    "plot_waypoint_paths",
    "run_bench",
    "summarize_set",
    "to_csv",
    "to_json",
    "to_markdown",
    "write_results",
]

ScenarioKind = Literal["pole", "waypoints"]
SCENARIOS: tuple[str, ...] = get_args(ScenarioKind)
SET_NAMES = ("validation", "held-out")


@dataclass(frozen=True)
class BenchArgs:
    """Compare helmsmen on the validation and held-out episodes: the classical baselines and
    the recommended models (--helmsmen all: every shipped one), or those named."""

    scenario: ScenarioKind = "pole"  # pole (the study's task) | waypoints (courses with poles)
    helmsmen: str = ""  # names or checkpoint paths; empty: baselines + recommended models; all
    heldout: int = field(default=200, metadata=bounds(ge=1, le=100_000))  # held-out episodes
    out: str = "usvsim-results/bench"  # results folder: Markdown, CSV and path plots
    json: bool = False  # print JSON only (stdout)
    plots: bool = True  # write the path plots (--no-plots: skip them)
    likeness: bool = True  # the expert-likeness columns (validation, pole scenario)
    # stress: usvsim.evaluation.stress (named sets); colreg: usvsim.evaluation.colreg_suite
    suite: Literal["study", "stress", "colreg"] = "study"  # study | stress sets | colreg sets
    sets: str = ""  # --suite stress | colreg: comma-separated sets; empty: all
    stress_episodes: int = field(default=100, metadata=bounds(ge=1, le=10_000))  # per stress set
    split: Literal["validation", "test"] = "test"  # --suite stress: test reports; validation picks
    # --suite colreg: perturbed episodes per set (22 Imazu problems + trafficgen-1ts)
    colreg_episodes: int = field(default=5, metadata=bounds(ge=1, le=1000))  # per colreg set
    reactive_targets: bool = False  # --suite colreg: targets steered by vo (default: hold course)
    trafficgen: str = ""  # --suite colreg: trafficgen situation file or folder (trafficgen-user)
    sweep: str = ""  # a usvsim sweep folder: its across-seed held-out IQM beside shipped models
    # a learned policy's float sums, so its figures to the last episode, depend on torch's
    # thread count: pinned, so that a command gives the same figures on any machine
    threads: int = field(default=2, metadata=bounds(ge=1, le=1024))  # torch CPU threads

    def check(self) -> None:
        """Rules beyond the ranges (:func:`usvsim.cli.args.check_options` calls it)."""
        if self.scenario not in SCENARIOS:
            raise UserError(f"--scenario must be one of {SCENARIOS}, not {self.scenario!r}")
        if self.sets and self.suite not in ("stress", "colreg"):
            raise UserError("--sets needs --suite stress or colreg (the study's has no named sets)")
        if (self.reactive_targets or self.trafficgen) and self.suite != "colreg":
            raise UserError("--reactive-targets and --trafficgen need --suite colreg")
        if self.split != "test" and self.suite not in ("stress", "colreg"):
            raise UserError("--split needs --suite stress or colreg (the study's shows both)")
        if self.sweep:  # a folder that is not a sweep: one line before anything runs
            from usvsim.evaluation.bench_sweep import load_sweep

            if self.suite != "study" or self.scenario != "pole":
                raise UserError("--sweep goes with the pole scenario's study suite (its held-out)")
            load_sweep(self.sweep)

    def selection(self) -> tuple[list[str], bool]:
        """The names ``--helmsmen`` selects and whether the user named them: none → the
        baselines and the recommended models (:func:`usvsim.evaluation.model_cards.
        default_helmsmen`); ``all`` → every available helmsman (unreadable files skipped)."""
        names = self.names()
        if not names:
            from usvsim.evaluation.model_cards import default_helmsmen

            return default_helmsmen(), False
        return names, names != ["all"]

    def names(self) -> list[str]:
        """The ``--helmsmen`` list, blanks dropped (duplicates kept: the registry drops them)."""
        return [n.strip() for n in self.helmsmen.split(",") if n.strip()]


class _Record(Protocol):
    """What the summary reads of an episode record (EpisodeRecord or WaypointRecord)."""

    @property
    def success(self) -> bool: ...
    @property
    def collision(self) -> bool: ...
    @property
    def min_pole_distance_m(self) -> float: ...
    @property
    def time_to_goal_s(self) -> float: ...
    @property
    def path_length_m(self) -> float: ...
    @property
    def smoothness_rad(self) -> float: ...


@dataclass(frozen=True)
class BenchRow:
    """One line of the table: a helmsman on one episode set."""

    helmsman: str
    episode_set: str
    success: Proportion
    collisions: int
    min_pole_distance_min_m: float  # worst episode
    min_pole_distance_median_m: float  # median episode
    time_to_goal_mean_s: float  # successful episodes; NaN if none
    path_length_mean_m: float  # successful episodes; NaN if none
    smoothness_mean_deg: float  # successful episodes; NaN if none
    wall_s: float  # evaluation time of the set (s)
    # expert-likeness (usvsim.evaluation.likeness) on the pole scenario's validation set, else NaN:
    expert_path_distance_m: float = math.nan  # mean distance to the nearest expert path, m
    expert_side_agreement: float = math.nan  # fraction of expert samples passing the same side
    expert_action_distance_deg: float = math.nan  # Wasserstein distance of 2 s heading changes
    perceives: str = ""  # what the helmsman sees of the obstacles (observations.PERCEPTION)

    def flat(self) -> dict[str, Any]:
        """Flat dict for CSV and JSON (the proportion spread into columns)."""
        d = asdict(self)
        p = d.pop("success")
        return {
            "helmsman": self.helmsman,
            "episode_set": self.episode_set,
            "episodes": p["n"],
            "successes": p["successes"],
            "success_rate": p["rate"],
            "success_ci95_low": p["lower"],
            "success_ci95_high": p["upper"],
            **{k: v for k, v in d.items() if k not in ("helmsman", "episode_set")},
        }


def summarize_set(
    helmsman: str, episode_set: str, records: Sequence[_Record], wall_s: float
) -> BenchRow:
    """The table row of ``records`` (see the module docstring for the columns)."""
    ok = [r for r in records if r.success]
    d = [r.min_pole_distance_m for r in records]
    return BenchRow(
        helmsman=helmsman,
        episode_set=episode_set,
        success=proportion(len(ok), len(records)),
        collisions=sum(bool(r.collision) for r in records),
        min_pole_distance_min_m=float(min(d)),
        min_pole_distance_median_m=finite_median(d),
        time_to_goal_mean_s=finite_mean(r.time_to_goal_s for r in ok),
        path_length_mean_m=finite_mean(r.path_length_m for r in ok),
        smoothness_mean_deg=finite_mean(math.degrees(r.smoothness_rad) for r in ok),
        wall_s=wall_s,
    )


@dataclass(frozen=True)
class BenchResult:
    """Rows of the table and the records behind them, keyed by (helmsman, set)."""

    scenario: ScenarioKind
    rows: tuple[BenchRow, ...]
    records: dict[tuple[str, str], list[Any]]
    wall_s: float
    interrupted: bool = False  # Ctrl-C / SIGTERM: the rows are the sets finished before it
    skipped: tuple[str, ...] = ()  # "name: why" of shipped models that could not be loaded


def _episode_sets(scenario: ScenarioKind, heldout: int) -> dict[str, Sequence[Any]]:
    if scenario == "pole":
        from usvsim.evaluation.episodes import heldout_episodes, validation_episodes

        return {"validation": validation_episodes(), "held-out": heldout_episodes(n=heldout)}
    from usvsim.task.waypoints import heldout_courses, validation_courses

    return {"validation": validation_courses(), "held-out": heldout_courses(n=heldout)}


def loadable_helmsmen(
    factories: dict[str, Any], explicit: bool, warn: Any
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """The factories whose helmsman can be built; the others skipped ("name: why") unless the
    user named them (then the first failure is raised)."""
    kept, skipped = {}, []
    for name, factory in factories.items():
        try:
            factory()
        except ValueError as err:
            if explicit:
                raise UserError(f"--helmsmen {name}: {err}") from None
            skipped.append(f"{name}: {err}")
            warn(f"usvsim bench: skipping {name}: {err}")
            continue
        kept[name] = factory
    return kept, tuple(skipped)


def _stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run_bench(args: BenchArgs, progress: bool = True) -> BenchResult:
    """Evaluate the selected helmsmen on both sets of ``args.scenario``; no files, no printing
    (but a warning on stderr per skipped model). Ctrl-C (``KeyboardInterrupt``) ends it early
    with the rows finished so far and ``interrupted`` set.

    Raises
    ------
    UserError
        For a bad option, an unknown helmsman or a named one that cannot be loaded.
    """
    from tqdm import tqdm

    from usvsim.evaluation.episodes import evaluate
    from usvsim.evaluation.waypoints import evaluate_waypoints
    from usvsim.helm.registry import helmsman_kinds, select_helmsmen

    check_bounds(args)
    args.check()
    names, explicit = args.selection()
    factories, skipped = loadable_helmsmen(select_helmsmen(names), explicit, _stderr)
    if not factories:
        raise UserError("no helmsman to compare: " + "; ".join(skipped))
    sets = _episode_sets(args.scenario, args.heldout)
    start = time.perf_counter()
    reference = _expert_reference(args, sets["validation"])
    rows, records = [], {}
    jobs = [(name, set_name) for name in factories for set_name in sets]
    bar = tqdm(jobs, desc="bench", unit="set", file=sys.stderr, disable=not progress)
    interrupted = False
    try:
        for name, set_name in bar:
            bar.set_postfix_str(f"{name} / {set_name}")
            helmsman = factories[name]()
            obs_kind, act_kind = helmsman_kinds(helmsman)
            t0 = time.perf_counter()
            evaluator = evaluate if args.scenario == "pole" else evaluate_waypoints
            recs = evaluator(helmsman, sets[set_name], observation=obs_kind, action=act_kind)
            row = summarize_set(name, set_name, recs, time.perf_counter() - t0)
            row = replace(row, perceives=PERCEPTION[obs_kind])
            if reference is not None and set_name == "validation":
                row = _with_likeness(row, recs, reference)
            rows.append(row)
            records[(name, set_name)] = recs
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    return BenchResult(
        args.scenario,
        tuple(rows),
        records,
        time.perf_counter() - start,
        interrupted=interrupted,
        skipped=skipped,
    )


def _expert_reference(args: BenchArgs, specs: Sequence[Any]) -> Any:
    """The expert model's paths on the validation starts, or None where it does not apply."""
    if not args.likeness or args.scenario != "pole":
        return None
    from usvsim.evaluation.likeness import expert_reference

    return expert_reference(specs)


def _with_likeness(row: BenchRow, records: Sequence[Any], reference: Any) -> BenchRow:
    from usvsim.evaluation.likeness import likeness

    score = likeness(records, reference)
    return replace(
        row,
        expert_path_distance_m=score.path_distance_m,
        expert_side_agreement=score.side_agreement,
        expert_action_distance_deg=score.action_distance_deg,
    )


def _num(x: float, fmt: str) -> str:
    return "–" if not math.isfinite(x) else format(x, fmt)


_HEADER = (
    "helmsman",
    "perceives",
    "set",
    "n",
    "success [95 % CI]",
    "min d_pole min / median (m)",
    "t_goal (s)",
    "path (m)",
    "Σ|ΔΔψ| (°)",
    "to expert (m)",
    "same side",
)


def _cells(row: BenchRow) -> tuple[str, ...]:
    return (
        row.helmsman,
        row.perceives,
        row.episode_set,
        str(row.success.n),
        row.success.format_percent(),
        f"{row.min_pole_distance_min_m:.1f} / {row.min_pole_distance_median_m:.1f}",
        _num(row.time_to_goal_mean_s, ".1f"),
        _num(row.path_length_mean_m, ".1f"),
        _num(row.smoothness_mean_deg, ".0f"),
        _num(row.expert_path_distance_m, ".1f"),
        _num(row.expert_side_agreement, ".2f"),
    )


def format_table(rows: Sequence[BenchRow]) -> str:
    """Fixed-width table for the terminal."""
    cells = [_HEADER, *(_cells(r) for r in rows)]
    widths = [max(len(c[i]) for c in cells) for i in range(len(_HEADER))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)) for line in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


def to_markdown(result: BenchResult) -> str:
    """The table as Markdown, with the scenario and what the columns mean."""
    title = f"# usvsim bench — scenario `{result.scenario}`"
    lines = [
        title + (" (interrupted: the sets finished before Ctrl-C)" if result.interrupted else ""),
        "",
        "| " + " | ".join(_HEADER) + " |",
        "|" + "---|" * len(_HEADER),
        *("| " + " | ".join(_cells(r)) + " |" for r in result.rows),
        "",
        "success: strict (goal reached, never closer than 10 m to a pole), Wilson 95 % interval; "
        "min d_pole over all episodes; t_goal, path and Σ|ΔΔψ| are means over successful "
        "episodes. to expert / same side: expert-likeness on the validation starts "
        "(mean distance to the nearest of 8 expert paths; fraction of expert runs passing the "
        "pole on the same side). "
        f"Evaluation wall time {result.wall_s:.1f} s.",
        "",
    ]
    return "\n".join(lines)


def to_csv(rows: Sequence[BenchRow]) -> str:
    """The rows as CSV (one column per :meth:`BenchRow.flat` key)."""
    buffer = io.StringIO()
    flat = [r.flat() for r in rows]
    writer = csv.DictWriter(buffer, fieldnames=list(flat[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
    return buffer.getvalue()


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def to_json(result: BenchResult, files: Sequence[str] = ()) -> str:
    """Machine-readable result: scenario, sets, rows (NaN → null), wall time, files written."""
    sizes: dict[str, int] = {}
    for r in result.rows:
        sizes[r.episode_set] = r.success.n
    payload = {
        "scenario": result.scenario,
        "episode_sets": sizes,
        "rows": [{k: _json_safe(v) for k, v in r.flat().items()} for r in result.rows],
        "wall_s": result.wall_s,
        "files": list(files),
        "interrupted": result.interrupted,
        "skipped": list(result.skipped),
    }
    return json.dumps(payload, indent=2, allow_nan=False)


def write_results(result: BenchResult, out: Path, plots: bool = True) -> list[Path]:
    """Write the Markdown table, the CSV and (optionally) the path plots as one unit
    (:func:`usvsim.common.fileio.staged_dir`; module docstring). Nothing is written when there
    are no rows (an interrupt before the first set)."""
    from usvsim.common.fileio import remove_stale_temporaries, staged_dir

    if not result.rows:
        return []
    stem = "bench" if result.scenario == "pole" else f"bench-{result.scenario}"
    prefix = "paths" if result.scenario == "pole" else f"paths-{result.scenario}"
    remove_stale_temporaries(out)
    # the older set's plots go too (also with plots=False): they belong to the older table
    with staged_dir(out, stem, replaces=(f"{prefix}-*.png",)) as staging:
        (staging / f"{stem}.csv").write_text(to_csv(result.rows))
        names = _write_plots(result, staging) if plots else []
        (staging / f"{stem}.md").write_text(to_markdown(result))
    return [out / f"{stem}.md", out / f"{stem}.csv", *(out / p.name for p in names)]


def _write_plots(result: BenchResult, out: Path) -> list[Path]:
    from usvsim.common.mpl import use_file_backend_if_headless

    use_file_backend_if_headless()
    import matplotlib.pyplot as plt

    from usvsim.common.fileio import atomic_savefig

    prefix = "paths" if result.scenario == "pole" else f"paths-{result.scenario}"
    plot = plot_pole_paths if result.scenario == "pole" else plot_waypoint_paths
    written = []
    for (name, set_name), recs in result.records.items():
        fig = plot(recs, f"{name} — {set_name}")
        path = out / f"{prefix}-{name}-{set_name}.png"
        atomic_savefig(fig, path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def plot_pole_paths(records: Sequence[Any], title: str) -> Any:
    """All paths of a pole-task set in one frame: pole at the origin, start → goal along +x.

    Each true path is rotated and shifted so the pole sits at (0, 0) and the start on the
    negative x axis (the study's geometry puts start, pole and goal on one line); successes
    green, failures red and drawn on top (a few failures stay visible among many successes),
    each episode's goal ★, and the pole's 10 m safety circle; a legend names each mark.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    n_ok = sum(bool(r.success) for r in records)
    labels = {True: f"success ({n_ok})", False: f"failure ({len(records) - n_ok})"}
    goals = []
    for r in records:
        axis = r.goal_ne - r.pole_ne
        u = axis / np.hypot(*axis)
        rel = r.trajectory[:, :2] - r.pole_ne
        along, across = rel @ u, rel @ np.array([-u[1], u[0]])
        ok = bool(r.success)
        colour, lw, alpha, z = ("tab:green", 0.7, 0.5, 2) if ok else ("tab:red", 1.0, 0.8, 3)
        ax.plot(
            along, across, color=colour, lw=lw, alpha=alpha, zorder=z, label=labels.pop(ok, None)
        )
        goals.append(np.hypot(*axis))
    ax.plot(goals, np.zeros(len(goals)), "*", color="tab:orange", ms=7, zorder=4, label="goal")
    ax.plot(0.0, 0.0, "x", color="k", ms=8, mew=2, zorder=5, label="pole")
    t = np.linspace(0.0, 2.0 * math.pi, 100)
    circle = (10.0 * np.cos(t), 10.0 * np.sin(t))
    ax.plot(*circle, "--", color="tab:red", lw=1.0, zorder=4, label="10 m safety circle")
    ax.legend(fontsize=8, loc="best")
    ax.set(
        xlabel="along start → goal, from the pole (m)",
        ylabel="across (m, starboard of the line > 0)",
        title=f"{title}: {n_ok}/{len(records)} successes",
    )
    ax.set_aspect("equal", adjustable="datalim")
    fig.tight_layout()
    return fig


def plot_waypoint_paths(records: Sequence[Any], title: str, n_courses: int = 6) -> Any:
    """The first ``n_courses`` waypoint courses: waypoints ★, poles ✕ with 10 m circles, path;
    one legend for all panels."""
    import matplotlib.pyplot as plt

    shown = list(records)[:n_courses]
    fig, axes = plt.subplots(2, math.ceil(len(shown) / 2), figsize=(12, 7.5), squeeze=False)
    t = np.linspace(0.0, 2.0 * math.pi, 60)
    for ax, r in zip(axes.flat, shown, strict=False):
        w, p = r.course.waypoints_ne, r.course.poles_ne
        ax.plot(w[:, 1], w[:, 0], "*--", color="0.5", lw=0.8, ms=9, label="waypoints")
        for pole in p:
            ax.plot(pole[1], pole[0], "x", color="k", ms=5, mew=1.5, label="pole")
            circle = (pole[1] + 10 * np.sin(t), pole[0] + 10 * np.cos(t))
            ax.plot(*circle, "--", color="tab:red", lw=1, label="10 m safety circle")
        colour = "tab:green" if r.success else "tab:red"
        label = "path, success" if r.success else "path, failure"
        ax.plot(r.trajectory[:, 1], r.trajectory[:, 0], color=colour, lw=1.3, zorder=3, label=label)
        ax.set_title(f"{r.outcome}, min d_pole {r.min_pole_distance_m:.1f} m", fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(shown) :]:
        ax.set_visible(False)
    legend: dict[str, Any] = {}  # one entry per label over all panels, in drawing order
    for ax in axes.flat:
        legend.update(zip(*reversed(ax.get_legend_handles_labels()), strict=True))
    fig.legend(legend.values(), legend.keys(), loc="lower center", ncol=5, fontsize=8)
    fig.suptitle(f"{title} (north up, east right, m)")
    fig.tight_layout(rect=(0.0, 0.05, 1.0, 1.0))
    return fig
