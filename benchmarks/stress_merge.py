"""Add the helmsmen of a later stress run to a committed ``usvsim bench --suite stress --json``
file without running the others again. Run from the repository root::

    usvsim bench --suite stress --helmsmen sb-mpc,sb-mpc-radar --json > new.json
    python benchmarks/stress_merge.py docs/data/stress.json new.json

Both files must hold the same split and episodes per set, and the new run every set of the file
(its other sets are left out: one run serves ``docs/data/stress.json`` and the weather sets'
``docs/data/stress-weather.json``). A helmsman the file lacks gets
its rows (each set's row after the helmsman before it in the registry's order; the ``helmsmen``
list likewise); a helmsman in both is left as it is, and its rows in the new run must equal the
file's in every count and distance (the same episodes; timing fields aside), otherwise nothing is
written and the exit status is 1. The file records each merge under ``merged`` (helmsmen added,
the run's helmsmen and wall-clock) and is written atomically.

``--replace-sets a,b`` instead replaces the rows of sets whose episodes changed (e.g. ``everything``
gaining weather) for every helmsman of the file, from a new run of those sets only::

    usvsim bench --suite stress --sets everything --helmsmen all --json > everything.json
    python benchmarks/stress_merge.py --replace-sets everything docs/data/stress.json \
        everything.json

The new run must hold each named set for every helmsman of the file (a model named in the file
by a former name is matched through the registry's aliases), the same split and episodes per
set; the file records the replacement under ``replaced`` (sets, wall-clock).

``--replace-helmsmen a,b`` replaces every row of the named helmsmen (a shipped file replaced by
another seed's: same name, new weights) from a new run of them on the file's sets::

    usvsim bench --suite stress --helmsmen radar-gaussian-gail-openwater --json > new.json
    python benchmarks/stress_merge.py --replace-helmsmen radar-gaussian-gail-openwater \
        docs/data/stress.json new.json

The new run must hold each named helmsman on every set of the file, the same split and episodes
per set; the file records it under ``replaced`` (helmsmen, wall-clock). The same works on the
study task's ``usvsim bench --json`` (``docs/data/bench.json``: no ``helmsmen`` list, rows per
episode set)::

    usvsim bench --helmsmen radar-gaussian-gail-openwater --json --no-plots > new.json
    python benchmarks/stress_merge.py --replace-helmsmen radar-gaussian-gail-openwater \
        docs/data/bench.json new.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

TIMING = ("wall_s", "colreg_s")  # fields that depend on the machine, not on the episodes


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    keys = (set(a) | set(b)) - set(TIMING)
    return all(a.get(k) == b.get(k) for k in keys)


def _sets(run: dict[str, Any]) -> list[str]:
    """A run's sets in order (the study bench's file has no ``sets`` list: from its rows)."""
    return run.get("sets") or list(dict.fromkeys(r["episode_set"] for r in run["rows"]))


def _helmsmen(run: dict[str, Any]) -> list[str]:
    return run.get("helmsmen") or list(dict.fromkeys(r["helmsman"] for r in run["rows"]))


def merge(base: dict[str, Any], new: dict[str, Any], order: list[str]) -> list[str]:
    """Merge ``new``'s helmsmen into ``base`` in place (module docstring); the helmsmen added.
    ``order``: the registry's order of helmsmen. ``SystemExit`` where the runs disagree."""
    if not set(_sets(base)) <= set(_sets(new)):
        raise SystemExit(
            f"stress_merge: the new run lacks sets {set(_sets(base)) - set(_sets(new))}"
        )
    for key in ("suite", "split", "episodes_per_set"):
        if base.get(key) != new.get(key):
            raise SystemExit(
                f"stress_merge: the runs differ in {key} ({base.get(key)!r}, {new.get(key)!r})"
            )
    by = {(r["episode_set"], r["helmsman"]): r for r in base["rows"]}
    sets = {s: i for i, s in enumerate(_sets(base))}
    new_rows = [r for r in new["rows"] if r["episode_set"] in sets]
    added = [h for h in _helmsmen(new) if h not in _helmsmen(base)]
    for r in new_rows:
        old = by.get((r["episode_set"], r["helmsman"]))
        if r["helmsman"] not in added and (old is None or not _same(old, r)):
            raise SystemExit(f"stress_merge: {r['helmsman']} on {r['episode_set']} differs")
    helmsmen = _helmsmen(base)
    for h in added:
        before = order[: order.index(h)] if h in order else order
        anchor = next((a for a in reversed(before) if a in helmsmen), None)
        helmsmen.insert(helmsmen.index(anchor) + 1 if anchor else len(helmsmen), h)
    rank = {h: i for i, h in enumerate(helmsmen)}
    rows = base["rows"] + [r for r in new_rows if r["helmsman"] in added]
    base["rows"] = sorted(rows, key=lambda r: (sets[r["episode_set"]], rank[r["helmsman"]]))
    if "helmsmen" in base:
        base["helmsmen"] = helmsmen
    if added:
        merged = {"helmsmen": added, "run_helmsmen": _helmsmen(new), "wall_s": new["wall_s"]}
        base["merged"] = [*base.get("merged", []), merged]
    return added


def replace_sets(
    base: dict[str, Any], new: dict[str, Any], sets: list[str], aliases: dict[str, str]
) -> None:
    """Replace, in place, ``base``'s rows of ``sets`` by ``new``'s (module docstring);
    ``aliases``: former model name -> current name, for helmsmen the file names by an old name.
    ``SystemExit`` where ``new`` lacks a set or a helmsman's row, or the runs differ in kind."""
    for key in ("suite", "split", "episodes_per_set"):
        if base.get(key) != new.get(key):
            raise SystemExit(
                f"stress_merge: the runs differ in {key} ({base.get(key)!r}, {new.get(key)!r})"
            )
    unknown = [s for s in sets if s not in base["sets"]]
    if unknown:
        raise SystemExit(f"stress_merge: {unknown} are not sets of the file ({base['sets']})")
    fresh = {(r["episode_set"], r["helmsman"]): r for r in new["rows"]}
    rows = []
    for r in base["rows"]:
        if r["episode_set"] not in sets:
            rows.append(r)
            continue
        h = r["helmsman"]
        row = fresh.get((r["episode_set"], h)) or fresh.get((r["episode_set"], aliases.get(h, h)))
        if row is None:
            raise SystemExit(f"stress_merge: the new run has no row for {h} on {r['episode_set']}")
        rows.append({**row, "helmsman": h})
    base["rows"] = rows
    base["replaced"] = [*base.get("replaced", []), {"sets": sets, "wall_s": new.get("wall_s")}]


def replace_helmsmen(base: dict[str, Any], new: dict[str, Any], helmsmen: list[str]) -> None:
    """Replace, in place, every row of ``helmsmen`` in ``base`` by ``new``'s (module docstring).
    ``SystemExit`` where a helmsman is not in the file, ``new`` lacks one of its rows, or the
    runs differ in kind."""
    for key in ("suite", "split", "episodes_per_set"):
        if base.get(key) != new.get(key):
            raise SystemExit(
                f"stress_merge: the runs differ in {key} ({base.get(key)!r}, {new.get(key)!r})"
            )
    present = base.get("helmsmen") or list(dict.fromkeys(r["helmsman"] for r in base["rows"]))
    unknown = [h for h in helmsmen if h not in present]
    if unknown:
        raise SystemExit(f"stress_merge: {unknown} are not helmsmen of the file")
    fresh = {(r["episode_set"], r["helmsman"]): r for r in new["rows"]}
    rows = []
    for r in base["rows"]:
        if r["helmsman"] in helmsmen:
            row = fresh.get((r["episode_set"], r["helmsman"]))
            if row is None:
                raise SystemExit(
                    f"stress_merge: the new run has no row for {r['helmsman']} on "
                    f"{r['episode_set']}"
                )
            r = row
        rows.append(r)
    base["rows"] = rows
    base["replaced"] = [
        *base.get("replaced", []),
        {"helmsmen": helmsmen, "wall_s": new.get("wall_s")},
    ]


def main(argv: list[str]) -> int:
    sets: list[str] = []
    helmsmen: list[str] = []
    if argv[:1] == ["--replace-sets"] and len(argv) > 1:
        sets, argv = [s for s in argv[1].split(",") if s], argv[2:]
    elif argv[:1] == ["--replace-helmsmen"] and len(argv) > 1:
        helmsmen, argv = [h for h in argv[1].split(",") if h], argv[2:]
    if len(argv) != 2:
        print(
            "usage: python benchmarks/stress_merge.py [--replace-sets A,B | --replace-helmsmen "
            "A,B] STRESS_JSON NEW_JSON",
            file=sys.stderr,
        )
        return 2
    from usvsim.common.fileio import atomic_write_text
    from usvsim.helm.registry import available_helmsmen, model_aliases

    path = Path(argv[0])
    base, new = json.loads(path.read_text()), json.loads(Path(argv[1]).read_text())
    if helmsmen:
        replace_helmsmen(base, new, helmsmen)
        atomic_write_text(path, json.dumps(base, indent=2) + "\n")
        print(f"replaced the rows of {', '.join(helmsmen)} in {path}")
        return 0
    if sets:
        replace_sets(base, new, sets, dict(model_aliases()))
        atomic_write_text(path, json.dumps(base, indent=2) + "\n")
        print(f"replaced the rows of {', '.join(sets)} in {path}")
        return 0
    added = merge(base, new, list(available_helmsmen()))
    if added:
        atomic_write_text(path, json.dumps(base, indent=2) + "\n")
    print(f"added {', '.join(added) or 'nothing'} to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
