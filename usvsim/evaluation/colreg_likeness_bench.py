"""The COLREG expert and helmsmen on the same episodes of the COLREG suite, compared
(``benchmarks/colreg_likeness.py``; issue 41, "IL against RL of the same observation").

:func:`run_likeness` draws the episodes of the chosen COLREG sets once
(:func:`usvsim.evaluation.colreg_suite.colreg_episodes`, the test split by default), runs the
expert on them (:func:`run_expert`) and every helmsman in one batch each
(:func:`usvsim.evaluation.colreg_rollout.run_encounters`), and gives per helmsman
(:class:`LikenessRow`):

* success, collisions and COLREG compliance with Wilson 95 % intervals, exactly the suite's row
  (:func:`usvsim.evaluation.colreg_suite.colreg_row`, pooled over the sets);
* the path distances to the expert's path on each episode and the side agreement over the
  expert's encounters (:mod:`usvsim.evaluation.colreg_likeness`: definitions and sources).

Seeds: ``groups`` names several helmsmen (checkpoints of one setup trained with different seeds)
as one setup; :class:`GroupFigures` gives, per metric, the interquartile mean of the members'
pooled figures with rliable's 95 % stratified-bootstrap interval
(:func:`usvsim.evaluation.seed_stats.iqm_with_interval`; Agarwal et al. 2021; needs rliable).

Experts (:data:`HUMAN_EXPERT` or any helmsman of the registry): ``sb-mpc`` (default: the
project's SB-MPC on the true scene, deterministic) or ``sb-mpc-expert`` (the SB-MPC judgement
with the family expert's human eyes and hand, :mod:`baselines.sbmpc_expert`, traits drawn from
``expert_seed``: the expert the COLREG demonstrations were recorded from; targets must hold
course, as it cannot steer reactive ones).
"""

from __future__ import annotations

import math
import os
import time
import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.errors import UserError
from usvsim.evaluation.colreg_likeness import (
    Estimate,
    SideAgreement,
    lockstep_distance_m,
    mean_interval,
    pass_sides,
    path_distance_m,
    side_agreement,
)
from usvsim.evaluation.colreg_suite import ColregRow, ColregSet, Split, colreg_episodes, colreg_row
from usvsim.evaluation.seed_stats import BOOTSTRAP_REPS

__all__ = [
    "EXPERT_SEED",
    "HUMAN_EXPERT",
    "SEED_METRICS",
    "ExpertRecord",
    "GroupFigures",
    "LikenessResult",
    "LikenessRow",
    "group_figures",
    "json_safe",
    "likeness_markdown",
    "run_expert",
    "run_likeness",
]

FloatArray = NDArray[np.float64]
HUMAN_EXPERT = "sb-mpc-expert"  # baselines.sbmpc_expert (the demonstrations' expert)
EXPERT_SEED = zlib.crc32(b"colreg-likeness-expert")  # its traits, noise and wobble
# metric -> (what it is, unit): the figures the seeds' IQM is taken of (LikenessRow.figures)
SEED_METRICS: dict[str, tuple[str, str]] = {
    "success_rate": ("success", "%"),
    "compliance_rate": ("COLREG compliance", "%"),
    "path_distance_m": ("path distance to the expert", "m"),
    "sync_mean_m": ("lock-step distance, mean", "m"),
    "side_agreement": ("side agreement", "%"),
}


@dataclass(frozen=True)
class ExpertRecord:
    """A run of :func:`baselines.sbmpc_expert.run_sbmpc_expert` as the COLREG recorder reads it:
    ``trajectory`` (K, 3) true [x_N, y_E, ψ] every 0.1 s from t = 0."""

    episode: Any
    trajectory: FloatArray
    success: bool
    collision: bool


def run_expert(
    expert: str,
    episodes: Sequence[Any],
    *,
    reactive_targets: bool = False,
    seed: int = EXPERT_SEED,
) -> Any:
    """The expert's :class:`usvsim.evaluation.colreg_rollout.EncounterRun` on ``episodes``
    (module docstring); ``UserError`` for an unknown name or ``sb-mpc-expert`` with reactive
    targets."""
    from usvsim.evaluation.colreg_rollout import EncounterRun, encounter_tracks, run_encounters
    from usvsim.helm.registry import make_helmsman

    if expert != HUMAN_EXPERT:
        return run_encounters(make_helmsman(expert), episodes, reactive_targets=reactive_targets)
    if reactive_targets:
        raise UserError(
            f"--expert {HUMAN_EXPERT} cannot steer reactive targets; use --expert sb-mpc or "
            "leave out --reactive-targets"
        )
    from baselines.sbmpc_expert import run_sbmpc_expert

    runs = run_sbmpc_expert(episodes, seed=seed)
    records = [ExpertRecord(r.episode, r.trajectory[:, 1:4], r.success, r.collision) for r in runs]
    return EncounterRun(records, encounter_tracks(records))


@dataclass(frozen=True)
class LikenessRow:
    """One helmsman against the expert on every episode (module docstring)."""

    helmsman: str
    group: str  # the setup whose seed it is ("" for none)
    suite: ColregRow  # success, collisions, compliance: the COLREG suite's row, pooled
    path_distance: Estimate  # m, mean over episodes
    sync_mean: Estimate  # m
    sync_max: Estimate  # m
    sides: SideAgreement

    def figures(self) -> dict[str, float]:
        """The pooled figures :data:`SEED_METRICS` names (rates in [0, 1]; NaN if none)."""
        side = self.sides.overall
        return {
            "success_rate": self.suite.success.rate,
            "compliance_rate": self.suite.compliance.rate,
            "path_distance_m": self.path_distance.mean,
            "sync_mean_m": self.sync_mean.mean,
            "side_agreement": math.nan if side is None else side.rate,
        }

    def to_json(self) -> dict[str, Any]:
        return {
            "helmsman": self.helmsman,
            "group": self.group,
            **self.suite.flat(),
            "path_distance_m": self.path_distance.to_json(),
            "sync_mean_m": self.sync_mean.to_json(),
            "sync_max_m": self.sync_max.to_json(),
            "side_agreement": self.sides.to_json(),
        }


@dataclass(frozen=True)
class GroupFigures:
    """A setup's seeds: per metric of :data:`SEED_METRICS`, the IQM over its members with
    rliable's 95 % interval and each member's figure (None where a member has none)."""

    group: str
    members: tuple[str, ...]
    iqm: dict[str, Estimate | None]
    per_seed: dict[str, tuple[float, ...]]

    def to_json(self) -> dict[str, Any]:
        return {
            "group": self.group,
            "members": list(self.members),
            "statistic": (
                "IQM over seeds of each seed's pooled figure (scipy trim_mean 25 %), rliable's "
                "95 % stratified-bootstrap percentile interval (usvsim.evaluation.seed_stats)"
            ),
            "iqm": {k: None if v is None else v.to_json() for k, v in self.iqm.items()},
            "per_seed": {k: list(v) for k, v in self.per_seed.items()},
        }


def group_figures(
    group: str, rows: Sequence[LikenessRow], reps: int = BOOTSTRAP_REPS
) -> GroupFigures:
    """:class:`GroupFigures` of the ``rows`` of one setup's seeds (needs rliable)."""
    from usvsim.evaluation.seed_stats import iqm_with_interval

    per_seed = {m: tuple(r.figures()[m] for r in rows) for m in SEED_METRICS}
    iqm: dict[str, Estimate | None] = {}
    for metric, values in per_seed.items():
        v = np.array(values, dtype=float)[:, None]  # (seeds, 1 task)
        if not np.all(np.isfinite(v)):
            iqm[metric] = None
            continue
        point, ci = iqm_with_interval(v, reps)
        iqm[metric] = Estimate(point, ci, len(values))
    return GroupFigures(group, tuple(r.helmsman for r in rows), iqm, per_seed)


@dataclass(frozen=True)
class LikenessResult:
    """One comparison run: the expert's own row, a row per helmsman, the seeds' figures."""

    expert: str
    expert_row: ColregRow
    rows: tuple[LikenessRow, ...]
    groups: tuple[GroupFigures, ...]
    sets: tuple[str, ...]
    episodes_per_set: int
    split: str
    reactive_targets: bool
    wall_s: float
    load: tuple[float, float] = (math.nan, math.nan)  # 1-min load average at start and end

    def to_json(self, command: str = "") -> dict[str, Any]:
        """Strict JSON (NaN written as null) that :func:`likeness_markdown` reads."""
        return json_safe(
            {
                "expert": self.expert,
                "expert_row": self.expert_row.flat(),
                "sets": list(self.sets),
                "episodes_per_set": self.episodes_per_set,
                "split": self.split,
                "reactive_targets": self.reactive_targets,
                "definitions": "usvsim.evaluation.colreg_likeness (module docstring)",
                "rows": [r.to_json() for r in self.rows],
                "groups": [g.to_json() for g in self.groups],
                "wall_s": self.wall_s,
                "load_1min": list(self.load),
                "cpus": os.cpu_count(),
                "command": command,
            }
        )


def run_likeness(
    factories: Mapping[str, Callable[[], Any]],
    sets: Sequence[ColregSet],
    n: int,
    *,
    groups: Mapping[str, Sequence[str]] | None = None,
    split: Split = "test",
    expert: str = "sb-mpc",
    expert_seed: int = EXPERT_SEED,
    reactive_targets: bool = False,
    reps: int = BOOTSTRAP_REPS,
    progress: Callable[[str], None] | None = None,
) -> LikenessResult:
    """Every helmsman of ``factories`` (label → factory) against ``expert`` on ``n`` episodes of
    every set of ``sets`` (module docstring); ``groups``: setup → labels of its seeds among
    ``factories``. ``progress(message)`` is told what runs."""
    groups = dict(groups or {})
    unknown = [h for members in groups.values() for h in members if h not in factories]
    if unknown:
        raise UserError(f"seed group member {unknown[0]!r} is not among the helmsmen")
    say = progress or (lambda message: None)
    start, load0 = time.perf_counter(), os.getloadavg()[0]
    episodes = [e for s in sets for e in colreg_episodes(s, n, split)]
    label = ",".join(s.name for s in sets) if len(sets) <= 3 else f"{len(sets)} sets"
    say(f"expert {expert} on {len(episodes)} episodes")
    t0 = time.perf_counter()
    ex = run_expert(expert, episodes, reactive_targets=reactive_targets, seed=expert_seed)
    expert_row = colreg_row(expert, label, ex, time.perf_counter() - t0)
    from usvsim.evaluation.colreg import evaluate_colreg
    from usvsim.evaluation.colreg_rollout import run_encounters

    ex_tracks = ex.tracks
    ex_encounter = evaluate_colreg(ex_tracks).encounter
    ex_sides = pass_sides(ex_tracks)
    rows = []
    for name, factory in factories.items():
        say(f"{name} on {len(episodes)} episodes")
        t0 = time.perf_counter()
        run = run_encounters(factory(), episodes, reactive_targets=reactive_targets)
        wall = time.perf_counter() - t0
        tr = run.tracks
        dist = path_distance_m(tr.own_north_east_m, tr.valid, ex_tracks.own_north_east_m,
                               ex_tracks.valid)  # fmt: skip
        sync_mean, sync_max = lockstep_distance_m(
            tr.own_north_east_m, tr.valid, ex_tracks.own_north_east_m, ex_tracks.valid
        )
        group = next((g for g, members in groups.items() if name in members), "")
        rows.append(
            LikenessRow(
                name, group, colreg_row(name, label, run, wall), mean_interval(dist),
                mean_interval(sync_mean), mean_interval(sync_max),
                side_agreement(pass_sides(tr), ex_sides, ex_encounter),
            )
        )  # fmt: skip
    figures = tuple(
        group_figures(g, [r for r in rows if r.helmsman in members], reps)
        for g, members in groups.items()
    )
    return LikenessResult(
        expert, expert_row, tuple(rows), figures, tuple(s.name for s in sets), n, split,
        reactive_targets, time.perf_counter() - start, (load0, os.getloadavg()[0]),
    )  # fmt: skip


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float replaced by None (strict JSON)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def _pct(rate: Any, ci: Any) -> str:
    """``"93.3 % [70.2, 98.8]"`` of a rate in [0, 1] and its interval; "–" for none."""
    if rate is None or ci is None or None in ci:
        return "–"
    return f"{100 * rate:.1f} % [{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]"


def _metres(e: Any) -> str:
    """``"12.3 [10.1, 14.8]"`` of an :class:`Estimate`'s JSON; "–" for none."""
    if not e or e.get("mean") is None or None in e["ci95"]:
        return "–"
    return f"{e['mean']:.1f} [{e['ci95'][0]:.1f}, {e['ci95'][1]:.1f}]"


def _suite_cells(row: Mapping[str, Any]) -> str:
    s = _pct(row["success_rate"], [row["success_ci95_low"], row["success_ci95_high"]])
    c = _pct(row["compliance_rate"], [row["compliance_ci95_low"], row["compliance_ci95_high"]])
    return f"{s} | {row['collisions']} | {c} ({row['encounters']})"


def _set_list(sets: Sequence[str]) -> str:
    """``"imazu-01, imazu-02"``, or ``"imazu-01 … imazu-22"`` for more than four."""
    return ", ".join(sets) if len(sets) <= 4 else f"{sets[0]} … {sets[-1]}"


def likeness_markdown(payload: Mapping[str, Any]) -> str:
    """The comparison as Markdown from its JSON (:meth:`LikenessResult.to_json`): a row per
    helmsman (the expert's own first), then the seeds' IQM table."""
    sets = payload["sets"]
    targets = "reactive (vo)" if payload["reactive_targets"] else "holding course and speed"
    lines = [
        f"# Expert-likeness in traffic: against `{payload['expert']}`",
        "",
        f"{len(sets)} COLREG sets ({_set_list(sets)}), {payload['episodes_per_set']} episodes "
        f"each, {payload['split']} split, targets {targets}. Definitions: "
        "`usvsim.evaluation.colreg_likeness`.",
        "",
        "| helmsman | seed of | success [95 % CI] | collisions | compliance [95 % CI] "
        "(encounters) | path distance m [95 % CI] | lock-step mean m | lock-step max m | "
        "side agreement [95 % CI] (encounters) |",
        "|---|---|---|---|---|---|---|---|---|",
        f"| {payload['expert']} (expert) | | {_suite_cells(payload['expert_row'])} "
        "| – | – | – | – |",
    ]
    for row in payload["rows"]:
        side = row["side_agreement"]
        lines.append(
            f"| {row['helmsman']} | {row['group']} | {_suite_cells(row)} | "
            f"{_metres(row['path_distance_m'])} | {_metres(row['sync_mean_m'])} | "
            f"{_metres(row['sync_max_m'])} | {_pct(side['rate'], side['ci95'])} "
            f"({side['encounters']}) |"
        )
    if payload["groups"]:
        header = " | ".join(f"{what} IQM [95 % CI]" for what, _ in SEED_METRICS.values())
        lines += [
            "",
            "Across seeds: the interquartile mean of the seeds' pooled figures with rliable's "
            "95 % stratified-bootstrap interval.",
            "",
            f"| setup | seeds | {header} |",
            "|---|---|" + "---|" * len(SEED_METRICS),
        ]
        for g in payload["groups"]:
            cells = []
            for metric, (_, unit) in SEED_METRICS.items():
                e = g["iqm"][metric]
                cells.append(_pct(e and e["mean"], e and e["ci95"]) if unit == "%" else _metres(e))
            lines.append(f"| {g['group']} | {len(g['members'])} | {' | '.join(cells)} |")
    load = payload.get("load_1min") or [None, None]
    at = (
        f" at load {load[0]:.1f}-{load[1]:.1f} on {payload.get('cpus')} cores (1-min average)"
        if None not in load
        else ""
    )
    lines += ["", f"Wall-clock {payload['wall_s']:.0f} s{at}."]
    if payload.get("command"):
        lines += ["", f"Command: `{payload['command']}`"]
    return "\n".join(lines) + "\n"
