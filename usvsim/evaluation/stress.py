"""``usvsim bench --suite stress``: every helmsman on named episode sets, each isolating one
perturbation of the study's task, plus one with everything at once. The weather sets
(``wind-beam``, ``gusts``, ``sea-state-3``, ``sea-state-4``; issue 38) step the boats in wind and
waves (:mod:`usvsim.task.weather_draw`); ``everything`` the ``moderate`` one (0-8 m/s, H_s 0-1 m;
calm before 2026-12-06).

Each set is a member of the open-water family (:class:`usvsim.task.openwater.OpenWaterScenario`,
drawn by :func:`usvsim.task.openwater.draw_open_water` from the set's own seed, the CRC-32 of its
name, so adding a set moves no other) or, for ``study`` and ``waypoints``, the existing held-out
episodes. Same seed and size → identical episodes → identical rows (tested).

Two splits of every set (issue 37: validation splits choose, test splits report):

* ``test`` (the default, the reported figures): the episodes above — seed CRC-32 of the set's
  name, the study's 200 held-out episodes, the held-out waypoint courses. Drawing it inside
  :func:`usvsim.common.splits.selection_mode` raises.
* ``validation`` (what a choice between models or settings is made on): the same set drawn
  from another seed stream, CRC-32 of ``"validation/<name>"`` (for ``study`` the study's
  scenario by :func:`usvsim.task.scenario.draw_episodes`, for ``waypoints``
  :func:`usvsim.task.waypoints.draw_course`, each from a ``default_rng`` of that seed); no
  episode equals a test episode (tested on every set).

The table (set × helmsman): success with its Wilson 95 % interval, collisions, the closest
approach to any obstacle (pole-equivalent distance, :mod:`usvsim.task.openwater`: < 10 m fails),
worst and median episode; on the sets with traffic (``moving-vessels``, ``everything``) also
COLREG compliance with its Wilson interval, the mean score and the encounters scored
(:mod:`usvsim.evaluation.stress_colreg`, the COLREG suite's scorer). ``stress.md``,
``stress.csv``, ``stress-heatmap.png`` (success, sets × helmsmen) and, with ``--json``, the same
on stdout; the run time is in the Markdown and JSON.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal, get_args

import numpy as np

from usvsim.common.splits import check_test_draw
from usvsim.task.observations import PERCEPTION
from usvsim.task.openwater import OpenWaterScenario, draw_open_water, from_pole_episodes
from usvsim.task.weather_draw import WEATHER_SETS

__all__ = ["SPLITS", "STRESS_SETS", "Split", "StressSet", "stress_episodes", "stress_set_names"]

DEG = math.pi / 180.0
_CALM = OpenWaterScenario()  # the study's geometry and setting
Split = Literal["validation", "test"]  # validation chooses, test reports (module docstring)
SPLITS: tuple[str, ...] = get_args(Split)


@dataclass(frozen=True)
class StressSet:
    """A named episode set: ``scenario`` (open-water) or ``kind`` study / waypoints."""

    name: str
    description: str
    scenario: OpenWaterScenario | None = None
    kind: str = "open-water"  # open-water | study | waypoints

    @property
    def seed(self) -> int:
        """The set's test seed: CRC-32 of its name (stable when sets are added or reordered)."""
        return zlib.crc32(self.name.encode())

    def split_seed(self, split: Split) -> int:
        """The seed of ``split``: :attr:`seed` for ``test``, CRC-32 of ``"validation/<name>"``
        for ``validation`` (module docstring)."""
        if split == "test":
            return self.seed
        if split == "validation":
            return zlib.crc32(f"validation/{self.name}".encode())
        raise ValueError(f"unknown split {split!r}; choose from {', '.join(SPLITS)}")


def _s(**changes: Any) -> OpenWaterScenario:
    return replace(_CALM, **changes)


_EVERYTHING = _s(
    start_distance_range_m=(40.0, 150.0),
    goal_distance_range_m=(150.0, 320.0),
    goal_bearing_range_rad=(-60 * DEG, 60 * DEG),
    heading_offset_range_rad=(-180 * DEG, 180 * DEG),
    primary_radius_range_m=(1.0, 15.0),
    n_extra_range=(1, 4),
    extra_radius_range_m=(1.0, 3.0),
    islet_probability=0.3,
    n_vessels_range=(0, 2),
    vessel_turn_rate_range_radps=(-0.3 * DEG, 0.3 * DEG),
    current_speed_range_mps=(0.0, 0.6),
    speed_range_mps=(2.0, 4.0),
    gnss_noise_scale_range=(1.0, 3.0),
    gnss_outlier_probability_range=(0.0, 0.03),
    gnss_dropout_probability=0.3,
    radar_clutter_range=(0.0, 0.001),
    radar_speckle_range=(0.0, 0.5),
    radar_missed_range=(0.0, 0.1),
    weather=WEATHER_SETS["moderate"],
)

STRESS_SETS: tuple[StressSet, ...] = (
    StressSet(
        "study", "the study's held-out episodes (one pole on the line, calm, clean)", None, "study"
    ),
    StressSet(
        "start-short", "start 30-50 m from the pole", _s(start_distance_range_m=(30.0, 50.0))
    ),
    StressSet(
        "start-long",
        "start 150-200 m from the pole, goal 320 m away",
        _s(start_distance_range_m=(150.0, 200.0), goal_distance_range_m=(320.0, 320.0)),
    ),
    StressSet(
        "heading-offset",
        "start heading anywhere (uniform ±180° off the pole)",
        _s(heading_offset_range_rad=(-180 * DEG, 180 * DEG)),
    ),
    StressSet(
        "goal-off-line",
        "goal 20-60 m off the start → pole line",
        _s(goal_lateral_range_m=(20.0, 60.0)),
    ),
    StressSet(
        "goal-anywhere",
        "goal at any bearing, 100-300 m from the start",
        _s(goal_bearing_range_rad=(-180 * DEG, 180 * DEG), goal_distance_range_m=(100.0, 300.0)),
    ),
    StressSet(
        "current-following",
        "current 0.3-0.8 m/s along the course",
        _s(current_speed_range_mps=(0.3, 0.8), current_direction_range_rad=(-20 * DEG, 20 * DEG)),
    ),
    StressSet(
        "current-crossing",
        "current 0.3-0.8 m/s across the course",
        _s(current_speed_range_mps=(0.3, 0.8), current_direction_range_rad=(70 * DEG, 110 * DEG)),
    ),
    StressSet(
        "current-head",
        "current 0.3-0.8 m/s against the course",
        _s(current_speed_range_mps=(0.3, 0.8), current_direction_range_rad=(160 * DEG, 200 * DEG)),
    ),
    StressSet(
        "gnss-noise-x3",
        "GNSS position and velocity errors ×3",
        _s(gnss_noise_scale_range=(3.0, 3.0)),
    ),
    StressSet(
        "gnss-outliers",
        "5 % of GNSS fixes are 10σ outliers",
        _s(gnss_outlier_probability_range=(0.05, 0.05)),
    ),
    StressSet(
        "gnss-dropout",
        "one GNSS outage of 15-30 s per episode",
        _s(gnss_dropout_probability=1.0, gnss_dropout_duration_range_s=(15.0, 30.0)),
    ),
    StressSet(
        "radar-clutter",
        "radar clutter, 0.1 % of pixels (~6 per frame)",
        _s(radar_clutter_range=(0.001, 0.001)),
    ),
    StressSet(
        "radar-noise",
        "radar speckle ≤ 50 %, noise ≤ 40, 20 % missed returns",
        _s(
            radar_speckle_range=(0.5, 0.5),
            radar_noise_range=(40.0, 40.0),
            radar_missed_range=(0.2, 0.2),
        ),
    ),
    StressSet(
        "two-obstacles",
        "a second pole 15-30 m from the first",
        _s(n_extra_range=(1, 1), near_primary_range_m=(15.0, 30.0), min_gap_m=0.0),
    ),
    StressSet(
        "several-obstacles",
        "3-6 more obstacles (1-3 m) in a 40 m corridor",
        _s(n_extra_range=(3, 6), extra_radius_range_m=(1.0, 3.0)),
    ),
    StressSet(
        "extended-obstacles",
        "the pole is an islet (8-25 m radius), 0-2 more islets",
        _s(primary_radius_range_m=(8.0, 25.0), n_extra_range=(0, 2), islet_probability=1.0),
    ),
    StressSet(
        "moving-vessels",
        "1-3 vessels, head-on, crossing or overtaken; no pole",
        _s(primary_obstacle=False, n_vessels_range=(1, 3)),
    ),
    StressSet("speed-slow", "cruise 1.5-2 m/s", _s(speed_range_mps=(1.5, 2.0))),
    StressSet("speed-fast", "cruise 4-5 m/s", _s(speed_range_mps=(4.0, 5.0))),
    # wind and waves (issue 38, usvsim.task.weather_draw.WEATHER_SETS)
    *(
        StressSet(name, description, _s(weather=WEATHER_SETS[name]))
        for name, description in (
            ("wind-beam", "wind 8-12 m/s on the beam (80-100° off the course), gusts 10 %"),
            ("gusts", "wind 6-10 m/s from any direction, gusts 20-30 %"),
            ("sea-state-3", "sea state 3 (H_s 0.5-1.25 m) with Beaufort 4 wind (5.5-7.9 m/s)"),
            ("sea-state-4", "sea state 4 (H_s 1.25-2.5 m) with Beaufort 5 wind (8.0-10.7 m/s)"),
        )
    ),
    StressSet("waypoints", "the multi-waypoint courses, a pole on every leg", None, "waypoints"),
    StressSet("everything", "all of the above at once (moderate levels)", _EVERYTHING),
)


def stress_set_names() -> tuple[str, ...]:
    return tuple(s.name for s in STRESS_SETS)


def stress_episodes(stress_set: StressSet, n: int, split: Split = "test") -> Sequence[Any]:
    """The ``n`` episodes of a set's ``split`` (open-water episodes, or waypoint courses;
    module docstring). The test split is refused inside
    :func:`usvsim.common.splits.selection_mode`."""
    if split == "validation":
        return _validation_episodes(stress_set, n)
    if split != "test":
        raise ValueError(f"unknown split {split!r}; choose from {', '.join(SPLITS)}")
    check_test_draw(f"stress {stress_set.name}")
    if stress_set.kind == "study":
        from usvsim.evaluation.episodes import heldout_episodes

        return from_pole_episodes(heldout_episodes(n=n))
    if stress_set.kind == "waypoints":
        from usvsim.task.waypoints import heldout_courses

        return heldout_courses(n=n)
    assert stress_set.scenario is not None
    return draw_open_water(stress_set.scenario, stress_set.seed, n)


def _validation_episodes(stress_set: StressSet, n: int) -> Sequence[Any]:
    """The validation split: the set drawn from :meth:`StressSet.split_seed` (validation)."""
    seed = stress_set.split_seed("validation")
    if stress_set.kind == "study":
        from usvsim.task.scenario import Scenario, draw_episodes

        return from_pole_episodes(draw_episodes(np.random.default_rng(seed), Scenario(), n))
    if stress_set.kind == "waypoints":
        from usvsim.task.waypoints import WaypointScenario, draw_course

        rng = np.random.default_rng(seed)
        return tuple(draw_course(rng, WaypointScenario()) for _ in range(n))
    assert stress_set.scenario is not None
    return draw_open_water(stress_set.scenario, seed, n)


def evaluate_set(helmsman: Any, stress_set: StressSet, episodes: Sequence[Any]) -> list[Any]:
    """Records of ``helmsman`` on a set's episodes, in the observation and action it declares."""
    from usvsim.evaluation.openwater import evaluate_open_water
    from usvsim.evaluation.waypoints import evaluate_waypoints
    from usvsim.helm.registry import helmsman_kinds

    obs_kind, act_kind = helmsman_kinds(helmsman)
    if stress_set.kind == "waypoints":
        return evaluate_waypoints(helmsman, episodes, observation=obs_kind, action=act_kind)
    return evaluate_open_water(helmsman, episodes, observation=obs_kind, action=act_kind)


@dataclass(frozen=True)
class StressResult:
    """Rows (one per helmsman and set, :class:`usvsim.evaluation.bench.BenchRow`) and timing."""

    rows: tuple[Any, ...]
    sets: tuple[str, ...]
    helmsmen: tuple[str, ...]
    episodes_per_set: int
    wall_s: float
    interrupted: bool = False
    skipped: tuple[str, ...] = ()
    split: Split = "test"  # which split of every set (module docstring)


def select_sets(names: Sequence[str]) -> tuple[StressSet, ...]:
    """The sets named (all for an empty list), in the suite's order; ``UserError`` if unknown."""
    from usvsim.common.errors import UserError

    known = stress_set_names()
    unknown = [n for n in names if n not in known]
    if unknown:
        raise UserError(f"unknown stress set {unknown[0]!r}; choose from {', '.join(known)}")
    return tuple(s for s in STRESS_SETS if not names or s.name in names)


def run_stress(
    factories: dict[str, Any],
    sets: Sequence[StressSet],
    n: int,
    progress: bool = True,
    skipped: Sequence[str] = (),
    split: Split = "test",
    colreg: bool = True,
) -> StressResult:
    """Every helmsman of ``factories`` (label → factory) on ``n`` episodes of every set's
    ``split`` (module docstring); ``colreg``: score the traffic sets' encounters
    (:func:`usvsim.evaluation.stress_colreg.stress_row`).

    Each set's episodes are drawn once and shared by all helmsmen; Ctrl-C ends the run early
    with the rows so far (``interrupted``).
    """
    import sys
    import time

    from tqdm import tqdm

    from usvsim.evaluation.bench import summarize_set
    from usvsim.evaluation.stress_colreg import stress_row
    from usvsim.helm.registry import helmsman_kinds

    start = time.perf_counter()
    rows: list[Any] = []
    bar = tqdm(total=len(sets) * len(factories), desc="stress", unit="run", file=sys.stderr,
               disable=not progress)  # fmt: skip
    interrupted = False
    try:
        for stress_set in sets:
            episodes = stress_episodes(stress_set, n, split)
            for name, factory in factories.items():
                bar.set_postfix_str(f"{stress_set.name} / {name}")
                t0 = time.perf_counter()
                helmsman = factory()
                records = evaluate_set(helmsman, stress_set, episodes)
                row = summarize_set(name, stress_set.name, records, time.perf_counter() - t0)
                perceives = PERCEPTION[helmsman_kinds(helmsman)[0]]
                row = replace(row, perceives=perceives)
                rows.append(stress_row(row, stress_set, records, colreg=colreg))
                bar.update()
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    return StressResult(
        tuple(rows), tuple(s.name for s in sets), tuple(factories), n,
        time.perf_counter() - start, interrupted, tuple(skipped), split,
    )  # fmt: skip


_SPLIT_NOTE = {
    "test": "Test split: the suite's reported figures (episodes of seed CRC-32 of the set's name, "
    "the study's held-out episodes, the held-out waypoint courses); never used to choose.",
    "validation": "Validation split: the sets drawn from other seeds (CRC-32 of "
    '"validation/<set>"), for choosing between models or settings; not the reported figures.',
}


def _cell(row: Any) -> str:
    return (
        f"{row.success.format_percent()}, {row.collisions} coll., "
        f"{row.min_pole_distance_median_m:.1f} m"
    )


def stress_markdown(result: StressResult) -> str:
    """The suite's table: one row per set, one column per helmsman (module docstring)."""
    by = {(r.episode_set, r.helmsman): r for r in result.rows}
    descriptions = {s.name: s.description for s in STRESS_SETS}
    title = f"# usvsim bench — stress suite, {result.split} split"
    title += " (interrupted)" if result.interrupted else ""
    lines = [
        title,
        "",
        _SPLIT_NOTE[result.split],
        "",
        f"{result.episodes_per_set} episodes per set; each cell: success [Wilson 95 % interval], "
        "collisions, median closest approach (pole-equivalent distance to the nearest obstacle; "
        "success needs >= 10 m from every obstacle, usvsim.task.openwater). Each column says "
        "in brackets what the helmsman perceives of the obstacles: the truth (the nearest, or "
        "the whole scene) or the radar (its image, or the tracks of usvsim.nav.tracker).",
        "",
        "| set | " + " | ".join(_perceives_labels(result)) + " |",
        "|---|" + "---|" * len(result.helmsmen),
    ]
    for s in result.sets:
        cells = [_cell(by[(s, h)]) if (s, h) in by else "–" for h in result.helmsmen]
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    from usvsim.evaluation.stress_colreg import colreg_markdown_table

    table = colreg_markdown_table(result.rows, result.sets, result.helmsmen)
    lines += ["", table] if table else []
    lines += ["", "Sets:", ""]
    lines += [f"- `{s}`: {descriptions[s]}" for s in result.sets]
    lines += ["", f"Run time {result.wall_s:.0f} s.", ""]
    return "\n".join(lines)


def _perceives_labels(result: StressResult) -> list[str]:
    """Column labels: each helmsman with what it perceives, e.g. ``vo-radar [radar tracks]``."""
    seen = {r.helmsman: r.perceives for r in result.rows if getattr(r, "perceives", "")}
    return [f"{h} [{seen[h]}]" if h in seen else h for h in result.helmsmen]


def stress_json(result: StressResult, files: Sequence[str] = ()) -> str:
    """Machine-readable result (NaN and ±inf as null)."""
    import json

    def safe(v: Any) -> Any:
        return None if isinstance(v, float) and not math.isfinite(v) else v

    from usvsim.evaluation.stress_colreg import colreg_overhead

    payload = {
        "suite": "stress",
        "split": result.split,
        "sets": list(result.sets),
        "helmsmen": list(result.helmsmen),
        "episodes_per_set": result.episodes_per_set,
        "rows": [{k: safe(v) for k, v in r.flat().items()} for r in result.rows],
        "wall_s": result.wall_s,
        "colreg_overhead": safe(colreg_overhead(result.rows)),  # scoring / run time, traffic sets
        "files": list(files),
        "interrupted": result.interrupted,
        "skipped": list(result.skipped),
    }
    return json.dumps(payload, indent=2, allow_nan=False)


def plot_heatmap(result: StressResult) -> Any:
    """Success rate (%) as a heat map, sets × helmsmen, each cell labelled."""
    import matplotlib.pyplot as plt
    import numpy as np

    by = {(r.episode_set, r.helmsman): 100.0 * r.success.rate for r in result.rows}
    grid = np.array([[by.get((s, h), np.nan) for h in result.helmsmen] for s in result.sets])
    fig, ax = plt.subplots(
        figsize=(1.0 + 0.9 * len(result.helmsmen), 1.2 + 0.35 * len(result.sets))
    )
    image = ax.imshow(grid, cmap="RdYlGn", vmin=0.0, vmax=100.0, aspect="auto")
    for (i, j), value in np.ndenumerate(grid):
        if np.isfinite(value):
            ax.text(j, i, f"{value:.0f}", ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(result.helmsmen)), result.helmsmen, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(result.sets)), result.sets, fontsize=8)
    fig.colorbar(image, ax=ax, label="success (%)")
    ax.set_title(
        f"usvsim stress suite ({result.split} split): success, "
        f"{result.episodes_per_set} episodes per set"
    )
    fig.tight_layout()
    return fig


def write_stress(result: StressResult, out: Any, plots: bool = True) -> list[Any]:
    """``stress.md``, ``stress.csv`` and ``stress-heatmap.png`` into ``out``, as one unit (the
    validation split: ``stress-validation.*``, so it never replaces the reported test files)."""
    from pathlib import Path

    from usvsim.common.fileio import atomic_savefig, remove_stale_temporaries, staged_dir
    from usvsim.evaluation.bench import to_csv

    if not result.rows:
        return []
    out = Path(out)
    remove_stale_temporaries(out)
    stem = "stress" if result.split == "test" else f"stress-{result.split}"
    names = [f"{stem}.md", f"{stem}.csv"]
    with staged_dir(out, stem, replaces=(f"{stem}-heatmap.png",)) as staging:
        (staging / f"{stem}.csv").write_text(to_csv(result.rows))
        if plots:
            from usvsim.common.mpl import use_file_backend_if_headless

            use_file_backend_if_headless()
            import matplotlib.pyplot as plt

            fig = plot_heatmap(result)
            atomic_savefig(fig, staging / f"{stem}-heatmap.png", dpi=110)
            plt.close(fig)
            names.append(f"{stem}-heatmap.png")
        (staging / f"{stem}.md").write_text(stress_markdown(result))
    return [out / name for name in names]


def run_stress_args(args: Any, progress: bool = True) -> StressResult:
    """The stress suite for ``usvsim bench`` options (:class:`usvsim.evaluation.bench.BenchArgs`):
    ``--helmsmen`` (:meth:`usvsim.evaluation.bench.BenchArgs.selection`), ``--sets``,
    ``--stress-episodes``, ``--split`` (validation | test, default test)."""
    import sys

    from usvsim.common.errors import UserError
    from usvsim.common.options import check_bounds
    from usvsim.evaluation.bench import loadable_helmsmen
    from usvsim.helm.registry import select_helmsmen

    check_bounds(args)
    args.check()
    sets = select_sets([n.strip() for n in args.sets.split(",") if n.strip()])

    def warn(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    names, explicit = args.selection()
    factories, skipped = loadable_helmsmen(select_helmsmen(names), explicit, warn)
    if not factories:
        raise UserError("no helmsman to compare: " + "; ".join(skipped))
    return run_stress(factories, sets, args.stress_episodes, progress, skipped, args.split)
