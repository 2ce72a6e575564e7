"""The COLREG suite's tables for docs/guide/colreg-suite.md, from ``usvsim bench --suite colreg
--json`` output: one row per helmsman (made for traffic or not, what it perceives, the Imazu
problems pooled: success and compliance with Wilson 95 % intervals, collisions; the trafficgen
sets), then the overtaking Imazu problems per helmsman. Run from the repository root::

    usvsim bench --suite colreg --helmsmen all --colreg-episodes 20 --json > colreg.json
    python benchmarks/colreg_table.py colreg.json                      # print the tables
    python benchmarks/colreg_table.py colreg.json --write docs/guide/colreg-suite.md

``--write`` replaces the text between the markers ``<!-- colreg-table:begin -->`` and
``<!-- colreg-table:end -->`` (and ``colreg-overtaking:...``) of that file, atomically. Given
the JSON of ``usvsim bench --suite stress --sets moving-vessels,everything --json``, it makes
the stress suite's COLREG table instead (markers ``colreg-stress``).

``--merge`` adds the helmsmen of a later run to the tables already in the file without
running the others again: a helmsman the tables lack gets its row (column in the overtaking
table) after the helmsman before it in the registry's order, and a note under the table says
which run it came from; a helmsman the tables already hold is left as it is, and its row from
the new run must equal the table's (the same episodes; otherwise the merge stops, exit 1)::

    usvsim bench --suite colreg --helmsmen sb-mpc,sb-mpc-radar --colreg-episodes 20 --json >new.json
    python benchmarks/colreg_table.py new.json --merge docs/guide/colreg-suite.md

``--replace`` is ``--merge`` where a helmsman in both takes the new run's row (a shipped file
replaced by another seed's: same name, new weights); the note says which rows were replaced.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

# Imazu problems with an overtaking target (own ship faster, same course; usvsim.evaluation.imazu)
OVERTAKING_PROBLEMS = (3, 7, 15, 17, 20, 22)
BASELINES = ("los", "los-avoid", "vo", "vo-radar", "sb-mpc", "sb-mpc-radar")


def _pct(successes: int, n: int, low: float | None, high: float | None) -> str:
    if n == 0 or low is None or high is None:
        return "–"
    return f"{100 * successes / n:.1f} [{100 * low:.1f}, {100 * high:.1f}]"


def _pooled(rows: list[dict[str, Any]]) -> tuple[int, int, int, int, int]:
    """Successes, episodes, compliant, encounters, collisions summed over ``rows``."""
    keys = ("successes", "episodes", "compliant", "encounters", "collisions")
    return tuple(sum(int(r[k]) for r in rows) for k in keys)  # type: ignore[return-value]


def _wilson(successes: int, n: int) -> tuple[float | None, float | None]:
    """Wilson 95 % interval (the suite's own, usvsim.evaluation.stats) of pooled counts."""
    if n == 0:
        return None, None
    from usvsim.evaluation.stats import proportion

    p = proportion(successes, n)
    return p.lower, p.upper


def helmsman_table(payload: dict[str, Any]) -> str:
    """One row per helmsman (module docstring)."""
    traffic = payload.get("helmsmen_traffic", {})
    sets = payload["sets"]
    others = [s for s in sets if not s.startswith("imazu-")]
    lines = [
        "| helmsman | made for traffic | trained for | perceives | Imazu success % | "
        "Imazu compliance % | Imazu coll. | "
        + " | ".join(f"{s} success / compliance %" for s in others)
        + " |",
        "|---" * (7 + len(others)) + "|",
    ]
    for h in payload["helmsmen"]:
        rows = [r for r in payload["rows"] if r["helmsman"] == h]
        imazu = [r for r in rows if r["episode_set"].startswith("imazu-")]
        ok, n, comp, enc, coll = _pooled(imazu)
        fit = traffic.get(h, {})
        made = {True: "yes", False: "no"}.get(fit.get("meets_traffic"), "–")
        cells = [
            f"`{h}`",
            made,
            fit.get("trained_for", "–"),
            fit.get("perceives", "–"),
            _pct(ok, n, *_wilson(ok, n)),
            _pct(comp, enc, *_wilson(comp, enc)),
            str(coll),
        ]
        for s in others:
            r = next((r for r in rows if r["episode_set"] == s), None)
            if r is None:
                cells.append("–")
                continue
            s_pct = f"{100 * r['successes'] / r['episodes']:.0f}"
            c_pct = f"{100 * r['compliance_rate']:.0f}" if r["encounters"] else "–"
            cells.append(f"{s_pct} / {c_pct}")
        lines.append("| " + " | ".join(cells) + " |")
    head = (
        f"{payload['episodes_per_set']} episodes per set, {payload['split']} split, targets "
        + ("reactive" if payload["reactive_targets"] else "holding course and speed")
        + f"; {len(payload['helmsmen'])} helmsmen, run time {payload['wall_s']:.0f} s."
    )
    return head + "\n\n" + "\n".join(lines) + "\n"


def overtaking_table(payload: dict[str, Any], helmsmen: tuple[str, ...] = BASELINES) -> str:
    """Per overtaking Imazu problem and helmsman: compliance % of all the problem's encounters
    / overtaking (give-way) encounters scored / of those failed / overtaking encounters that
    crossed the target's course line less than ``ahead_range_m`` ahead of its bow (penalty
    ``overtaking_ahead``)."""
    chosen = [h for h in helmsmen if h in payload["helmsmen"]]
    by = {(r["episode_set"], r["helmsman"]): r for r in payload["rows"]}
    lines = [
        "| problem | " + " | ".join(f"`{h}`" for h in chosen) + " |",
        "|---" * (1 + len(chosen)) + "|",
    ]
    for p in OVERTAKING_PROBLEMS:
        name = f"imazu-{p:02d}"
        cells = []
        for h in chosen:
            r = by.get((name, h))
            if r is None:
                cells.append("–")
                continue
            n_ot = int(r.get("encounters_overtaking_give_way", 0))
            failed = int(r.get("violations_overtaking_give_way_failed", 0))
            ahead = int(r.get("violations_overtaking_ahead", 0))
            comp = f"{100 * r['compliance_rate']:.0f}" if r["encounters"] else "–"
            cells.append(f"{comp} / {n_ot} / {failed} / {ahead}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def stress_table(payload: dict[str, Any]) -> str:
    """From ``usvsim bench --suite stress --json``: per helmsman and traffic set, success % and
    COLREG compliance % [Wilson 95 %] of the scored encounters (n)."""
    rows = [r for r in payload["rows"] if r.get("colreg_encounters")]
    sets = [s for s in payload["sets"] if any(r["episode_set"] == s for r in rows)]
    by = {(r["episode_set"], r["helmsman"]): r for r in rows}
    lines = [
        f"{payload['episodes_per_set']} episodes per set, {payload['split']} split; each cell: "
        "success % / COLREG compliance % [Wilson 95 %] (encounters scored).",
        "",
        "| helmsman | " + " | ".join(sets) + " |",
        "|---" * (1 + len(sets)) + "|",
    ]
    for h in payload["helmsmen"]:
        cells = []
        for s in sets:
            r = by.get((s, h))
            if r is None:
                cells.append("–")
                continue
            low, high = r["colreg_compliance_ci95_low"], r["colreg_compliance_ci95_high"]
            comp = _pct(r["colreg_compliant"], r["colreg_encounters"], low, high)
            cells.append(f"{100 * r['success_rate']:.0f} / {comp} ({r['colreg_encounters']})")
        lines.append(f"| `{h}` | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _line(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def _anchor(name: str, present: list[str], order: list[str]) -> str | None:
    """The helmsman of ``present`` that comes last before ``name`` in ``order``."""
    before = order[: order.index(name)] if name in order else order
    return next((h for h in reversed(before) if h in present), None)


def merge_block(
    old: str, new: str, note: str, order: list[str], columns: bool = False, replace: bool = False
) -> str:
    """``old`` (a generated block: text, one Markdown table, text) with the helmsmen of ``new``
    (the same kind of block from another run) merged in (module docstring): rows keyed by their
    first cell, or with ``columns`` columns keyed by their header cell, each placed after the
    helmsman before it in ``order``. ``SystemExit`` where a helmsman in both differs, unless
    ``replace``: then its row takes the new run's."""
    old_lines = old.splitlines()
    table = [i for i, ln in enumerate(old_lines) if ln.startswith("|")]
    rows = [_cells(old_lines[i]) for i in table]
    new_rows = [_cells(ln) for ln in new.splitlines() if ln.startswith("|")]
    if columns:  # transpose: one entry per column, its header first
        rows, new_rows = (
            [list(c) for c in zip(*rows, strict=True)],
            [list(c) for c in zip(*new_rows, strict=True)],
        )
    keys = [r[0].strip("`") for r in rows]
    added = []
    for r in new_rows[1:]:  # the first: the table's header row (or its first column)
        key = r[0].strip("`")
        if set(key) <= {"-"}:  # the separator row
            continue
        if key in keys:
            if rows[keys.index(key)] != r:
                if not replace:
                    raise SystemExit(
                        f"colreg_table: {key}: the new run's row differs from the file's"
                    )
                rows[keys.index(key)] = r
                added.append(f"`{key}`")
            continue
        anchor = _anchor(key, keys, order)
        at = keys.index(anchor) + 1 if anchor else len(rows)
        rows.insert(at, r)
        keys.insert(at, key)
        added.append(f"`{key}`")
    if not added:
        return old
    if columns:
        rows = [list(c) for c in zip(*rows, strict=True)]
    body = [_line(r) if set(r) != {"---"} else "|---" * len(r) + "|" for r in rows]
    end = table[-1] + 1
    tail = _without_replaced_notes(old_lines[end:], added) if replace else old_lines[end:]
    out = [*old_lines[: table[0]], *body, "", note.format(", ".join(added)), *tail]
    return "\n".join(out) + "\n"


def _without_replaced_notes(lines: list[str], replaced: list[str]) -> list[str]:
    """``lines`` without the earlier replacement notes of helmsmen whose rows are replaced now
    (each with the blank line after it): the table says what is true now, one note per row."""
    kept: list[str] = []
    skip_blank = False
    for line in lines:
        named, sep, _ = line.partition(" replaced (`benchmarks/colreg_table.py --replace`")
        if sep and set(named.split(", ")) <= set(replaced):
            skip_blank = True
            continue
        if skip_blank and not line.strip():
            skip_blank = False
            continue
        skip_blank = False
        kept.append(line)
    return kept


def _note(payload: dict[str, Any], replace: bool = False) -> str:
    helmsmen = ", ".join(f"`{h}`" for h in payload["helmsmen"])
    run = (
        f"{helmsmen}, {payload['episodes_per_set']} episodes per set, {payload['split']} split, "
        f"run time {payload['wall_s']:.0f} s"
    )
    if replace:
        return (
            "{} replaced (`benchmarks/colreg_table.py --replace`; a new shipped file) by a "
            f"later run of {run}."
        )
    return (
        "{} merged in (`benchmarks/colreg_table.py --merge`) from a later run of "
        f"{run}; the rows of a helmsman in both runs are equal."
    )


def _replace(text: str, marker: str, body: str) -> str:
    pattern = re.compile(rf"(<!-- {marker}:begin -->\n).*?(<!-- {marker}:end -->)", flags=re.DOTALL)
    if not pattern.search(text):
        raise SystemExit(f"colreg_table: no <!-- {marker}:begin/end --> markers in the file")
    return pattern.sub(lambda m: m.group(1) + body + m.group(2), text)


def _block(text: str, marker: str) -> str:
    found = re.search(rf"<!-- {marker}:begin -->\n(.*?)<!-- {marker}:end -->", text, re.DOTALL)
    if not found:
        raise SystemExit(f"colreg_table: no <!-- {marker}:begin/end --> markers in the file")
    return found.group(1)


def main(argv: list[str]) -> int:
    modes = ("--write", "--merge", "--replace")
    if len(argv) not in (1, 3) or (len(argv) == 3 and argv[1] not in modes):
        print(
            "usage: python benchmarks/colreg_table.py COLREG_JSON [--write DOC | --merge DOC | "
            "--replace DOC]",
            file=sys.stderr,
        )
        return 2
    payload = json.loads(Path(argv[0]).read_text())
    if payload.get("suite") == "stress":
        tables = {"colreg-stress": stress_table(payload)}
    else:
        tables = {
            "colreg-table": helmsman_table(payload),
            "colreg-overtaking": overtaking_table(payload),
        }
    if len(argv) == 1:
        print("\n".join(tables.values()), end="")
        return 0
    from usvsim.helm.registry import available_helmsmen

    doc = Path(argv[2])
    text = doc.read_text()
    for marker, body in tables.items():
        if argv[1] in ("--merge", "--replace"):
            columns = marker == "colreg-overtaking"
            if columns and not set(payload["helmsmen"]) & set(BASELINES):
                continue  # the overtaking table holds the baselines only: nothing of this run
            order = list(BASELINES) if columns else list(available_helmsmen())
            replace = argv[1] == "--replace"
            note = _note(payload, replace)
            body = merge_block(_block(text, marker), body, note, order, columns, replace)
        text = _replace(text, marker, body)
    from usvsim.common.fileio import atomic_write_text

    atomic_write_text(doc, text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
