"""Reports of the COLREG suite (:mod:`usvsim.evaluation.colreg_suite`): Markdown tables, the
terminal summary, JSON, the heat map, and the files ``colreg.md``, ``colreg.csv`` and
``colreg-heatmap.png`` written as one unit."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from usvsim.evaluation.colreg_suite import COLREG_SETS, ColregSuiteResult
from usvsim.evaluation.stats import Proportion

__all__ = ["colreg_json", "colreg_markdown", "colreg_table", "plot_colreg_heatmap", "write_colreg"]


def _pct(p: Proportion) -> str:
    return "–" if p.n == 0 else p.format_percent()


def colreg_markdown(result: ColregSuiteResult) -> str:
    """The suite's tables: success, compliance and collisions (sets × helmsmen), then the
    Imazu problems pooled per helmsman."""
    by = {(r.episode_set, r.helmsman): r for r in result.rows}
    descriptions = {s.name: s.description for s in COLREG_SETS}
    head = "| set | " + " | ".join(_labels(result)) + " |"
    rule = "|---|" + "---|" * len(result.helmsmen)
    lines = [
        "# usvsim bench — COLREG suite" + (" (interrupted)" if result.interrupted else ""),
        "",
        f"{result.episodes_per_set} episodes per set ({result.split} split), targets "
        + ("reactive (vo)" if result.reactive_targets else "holding course and speed")
        + ". Each cell: success [Wilson 95 %] / COLREG compliance of the scored encounters "
        "[Wilson 95 %] / collisions (usvsim.evaluation.colreg, after Woerner et al. 2019).",
        "",
        head,
        rule,
    ]
    for s in result.sets:
        cells = []
        for h in result.helmsmen:
            r = by.get((s, h))
            cells.append(
                "–" if r is None else f"{_pct(r.success)} / {_pct(r.compliance)} / {r.collisions}"
            )
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Imazu problems pooled:",
        "",
        "| helmsman | success | compliance |",
        "|---|---|---|",
    ]
    for h, label in zip(result.helmsmen, _labels(result), strict=True):
        s_p, c_p = result.pooled(h)
        lines.append(f"| {label} | {_pct(s_p)} | {_pct(c_p)} |")
    unfit = [(h, f) for h, f in result.fitness.items() if not f.meets_traffic]
    if unfit:
        lines += ["", "† not made to meet traffic (run and scored all the same):", ""]
        lines += [f"- `{h}` ({f.trained_for}, {f.perceives}): {f.why}" for h, f in unfit]
    lines += ["", "Sets:", ""]
    lines += [f"- `{s}`: {descriptions.get(s, '')}" for s in result.sets]
    lines += ["", f"Run time {result.wall_s:.0f} s.", ""]
    return "\n".join(lines)


def _labels(result: ColregSuiteResult) -> list[str]:
    """Column labels: a helmsman not made to meet traffic gets a dagger (†)."""
    fit = result.fitness
    return [h + ("†" if h in fit and not fit[h].meets_traffic else "") for h in result.helmsmen]


def colreg_table(result: ColregSuiteResult) -> str:
    """Fixed-width terminal summary: per helmsman the Imazu sets pooled, then the other sets."""
    others = [s for s in result.sets if not s.startswith("imazu-")]
    head = ["helmsman", "traffic", "Imazu success", "Imazu compliance", "coll."]
    head += [f"{s} success / compliance" for s in others]
    by = {(r.episode_set, r.helmsman): r for r in result.rows}
    lines = [head]
    for h in result.helmsmen:
        s_p, c_p = result.pooled(h)
        coll = sum(r.collisions for r in result.rows if r.helmsman == h)
        fit = result.fitness.get(h)
        made = "–" if fit is None else ("yes" if fit.meets_traffic else "no")
        cells = [h, made, _pct(s_p), _pct(c_p), str(coll)]
        for s in others:
            r = by.get((s, h))
            cells.append("–" if r is None else f"{_pct(r.success)} / {_pct(r.compliance)}")
        lines.append(cells)
    widths = [max(len(row[i]) for row in lines) for i in range(len(head))]
    text = [
        "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in lines
    ]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)


def colreg_json(result: ColregSuiteResult, files: Sequence[str] = ()) -> str:
    """Machine-readable result (NaN and ±inf as null), with the pooled Imazu figures."""
    import json

    from usvsim.common.fileio import json_safe

    pooled = {}
    for h in result.helmsmen:
        s_p, c_p = result.pooled(h)
        pooled[h] = {"success": asdict(s_p), "compliance": asdict(c_p)}
    payload = {
        "suite": "colreg",
        "sets": list(result.sets),
        "helmsmen": list(result.helmsmen),
        "episodes_per_set": result.episodes_per_set,
        "split": result.split,
        "reactive_targets": result.reactive_targets,
        "rows": [r.flat() for r in result.rows],
        "imazu_pooled": pooled,
        "helmsmen_traffic": {h: asdict(f) for h, f in result.fitness.items()},
        "wall_s": result.wall_s,
        "files": list(files),
        "interrupted": result.interrupted,
        "skipped": list(result.skipped),
    }
    return json.dumps(json_safe(payload), indent=2, allow_nan=False)


def plot_colreg_heatmap(result: ColregSuiteResult) -> Any:
    """Success (%), compliance (%) and collisions as three heat maps, sets × helmsmen."""
    import matplotlib.pyplot as plt

    by = {(r.episode_set, r.helmsman): r for r in result.rows}
    panels = (
        ("success (%)", lambda r: 100.0 * r.success.rate, "RdYlGn", 100.0),
        ("COLREG compliance (%)", lambda r: 100.0 * r.compliance.rate, "RdYlGn", 100.0),
        ("collisions", lambda r: float(r.collisions), "Reds", float(result.episodes_per_set)),
    )
    h, s = len(result.helmsmen), len(result.sets)
    fig, axes = plt.subplots(1, 3, figsize=(3.0 + 3 * 0.55 * h, 1.5 + 0.3 * s), sharey=True)
    for ax, (label, value, cmap, vmax) in zip(axes, panels, strict=True):
        grid = np.array(
            [
                [value(by[(st, hm)]) if (st, hm) in by else np.nan for hm in result.helmsmen]
                for st in result.sets
            ]
        )
        image = ax.imshow(grid, cmap=cmap, vmin=0.0, vmax=vmax, aspect="auto")
        for (i, j), v in np.ndenumerate(grid):
            if np.isfinite(v):
                ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=6)
        ax.set_xticks(range(h), result.helmsmen, rotation=60, ha="right", fontsize=7)
        ax.set_yticks(range(s), result.sets, fontsize=7)
        ax.set_title(label, fontsize=9)
        fig.colorbar(image, ax=ax, fraction=0.05)
    fig.suptitle(f"usvsim COLREG suite, {result.episodes_per_set} episodes per set")
    fig.tight_layout()
    return fig


def write_colreg(result: ColregSuiteResult, out: Any, plots: bool = True) -> list[Path]:
    """``colreg.md``, ``colreg.csv`` and ``colreg-heatmap.png`` into ``out``, as one unit."""
    import csv
    import io

    from usvsim.common.fileio import atomic_savefig, remove_stale_temporaries, staged_dir

    if not result.rows:
        return []
    out = Path(out)
    remove_stale_temporaries(out)
    names = ["colreg.md", "colreg.csv"]
    flat = [r.flat() for r in result.rows]
    keys = list(dict.fromkeys(k for row in flat for k in row))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=keys, lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
    with staged_dir(out, "colreg", replaces=("colreg-heatmap.png",)) as staging:
        (staging / "colreg.csv").write_text(buffer.getvalue())
        if plots:
            from usvsim.common.mpl import use_file_backend_if_headless

            use_file_backend_if_headless()
            import matplotlib.pyplot as plt

            fig = plot_colreg_heatmap(result)
            atomic_savefig(fig, staging / "colreg-heatmap.png", dpi=110)
            plt.close(fig)
            names.append("colreg-heatmap.png")
        (staging / "colreg.md").write_text(colreg_markdown(result))
    return [out / name for name in names]
