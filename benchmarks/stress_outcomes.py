"""How helmsmen fail on stress sets: each episode's outcome (success, collision, goal reached
after passing inside the safety distance, out of the area, time limit) counted per set and
helmsman, with the nearest distances of the unsafe passes and the time-limit failures that are
goal orbits (the track came within ``--orbit-m``, default 25 m, of the goal but never inside its
10 m circle: the boat passed the goal and circled it; ``docs/notes/2026-12-traffic.md``), and per
outcome the episodes in which a target vessel passes through the goal circle within the time
limit (its centre within 15 m of the goal); JSON and a Markdown table::

    python benchmarks/stress_outcomes.py --sets several-obstacles,everything \\
        --helmsmen vo-radar,run/seed0.pt --split test --out benchmarks/data/il-owcr/outcomes

The episodes are the stress suite's (:func:`usvsim.evaluation.stress.stress_episodes`, 100 a
set unless ``--episodes``), so the success counts equal ``usvsim bench --suite stress``'s.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from usvsim.evaluation.stress import evaluate_set, select_sets, stress_episodes
from usvsim.helm.registry import make_helmsman
from usvsim.task.openwater import vessel_motion

OUTCOMES = ("success", "goal-unsafe", "collision", "time-limit", "out-of-area")
ORBIT_M = 25.0  # m: a time-limit failure that came this close to the goal is a goal orbit


def closest_goal_approach_m(record: Any) -> float:
    """The least distance (m) between an open-water record's true track and its goal."""
    track, goal = record.trajectory, np.asarray(record.episode.goal_ne, dtype=float)
    return float(np.hypot(track[:, 0] - goal[0], track[:, 1] - goal[1]).min())


THROUGH_GOAL_M = 15.0  # m: a vessel centre this close passes through the 10 m goal circle


def vessel_positions_ne(episode: Any, t_s: np.ndarray) -> np.ndarray:
    """Every target vessel's centre (V, T, 2) m at the episode times ``t_s`` (T,) s."""
    v = episode.vessels
    p0 = np.array([[x.x0_n, x.y0_e] for x in v])[:, None, :]
    course, speed, turn = (
        np.array([getattr(x, f) for x in v])[:, None]
        for f in ("course_rad", "speed_mps", "turn_rate_radps")
    )
    pos, _ = vessel_motion(p0, course, speed, turn, t_s[None, :])
    return pos


def nearest_vessel_to_goal_m(episode: Any, step_s: float = 0.5) -> float:
    """The least distance (m) between the goal and any target vessel's centre within the
    episode's time limit, sampled every ``step_s`` (``inf`` without vessels)."""
    if not episode.vessels:
        return float("inf")
    pos = vessel_positions_ne(episode, np.arange(0.0, episode.time_limit_s + step_s / 2, step_s))
    goal = np.asarray(episode.goal_ne, dtype=float)
    return float(np.hypot(pos[..., 0] - goal[0], pos[..., 1] - goal[1]).min())


def tally(
    sets: list[str], helmsmen: list[str], split: str, episodes: int, orbit_m: float = ORBIT_M
) -> list[dict]:
    """One row per set and helmsman: outcome counts, the unsafe passes' nearest distances, and
    the time-limit failures' closest approaches to the goal with the goal orbits among them."""
    rows = []
    for stress_set in select_sets(sets):
        drawn = stress_episodes(stress_set, episodes, split)  # type: ignore[arg-type]
        for name in helmsmen:
            records = evaluate_set(make_helmsman(name), stress_set, drawn)
            counts = Counter(r.outcome for r in records)
            unsafe = sorted(
                round(float(r.min_pole_distance_m), 2)
                for r in records
                if r.outcome == "goal-unsafe"
            )
            failed = [r for r in records if r.outcome == "time-limit"]
            approach = sorted(round(closest_goal_approach_m(r), 2) for r in failed)
            through = Counter(
                r.outcome for r in records if nearest_vessel_to_goal_m(r.episode) < THROUGH_GOAL_M
            )
            rows.append(
                {
                    "set": stress_set.name,
                    "helmsman": Path(name).stem if name.endswith(".pt") else name,
                    "episodes": len(records),
                    **{o: counts.get(o, 0) for o in OUTCOMES},
                    "goal_orbits": sum(d < orbit_m for d in approach),
                    "unsafe_nearest_m": unsafe,
                    "time_limit_goal_approach_m": approach,
                    "traffic_through_goal": {o: through.get(o, 0) for o in OUTCOMES},
                }
            )
    return rows


def markdown(rows: list[dict]) -> str:
    head = (
        "| set | helmsman | "
        + " | ".join(OUTCOMES)
        + " | of the time limits goal orbits | unsafe passes: nearest (m) |"
    )
    lines = [head, "|" + "---|" * (len(OUTCOMES) + 4)]
    for r in rows:
        near = ", ".join(f"{d:.1f}" for d in r["unsafe_nearest_m"]) or "–"
        counts = " | ".join(str(r[o]) for o in OUTCOMES)
        lines.append(f"| {r['set']} | {r['helmsman']} | {counts} | {r['goal_orbits']} | {near} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sets", required=True, help="stress sets, comma-separated")
    parser.add_argument("--helmsmen", required=True, help="names or checkpoint files")
    parser.add_argument("--split", choices=("validation", "test"), default="test")
    parser.add_argument("--episodes", type=int, default=100, help="per set")
    parser.add_argument(
        "--orbit-m", type=float, default=ORBIT_M, help="goal orbit: closest approach below, m"
    )
    parser.add_argument("--out", type=Path, required=True, help="folder: outcomes.json, .md")
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {args.episodes}")
    if not 10.0 < args.orbit_m < float("inf"):
        parser.error(f"--orbit-m must be a distance > 10 m (the goal circle), got {args.orbit_m}")
    rows = tally(
        args.sets.split(","), args.helmsmen.split(","), args.split, args.episodes, args.orbit_m
    )
    args.out.mkdir(parents=True, exist_ok=True)
    record = {
        "split": args.split,
        "episodes_per_set": args.episodes,
        "orbit_m": args.orbit_m,
        "rows": rows,
    }
    files = {"outcomes.json": json.dumps(record, indent=1), "outcomes.md": markdown(rows)}
    for name, text in files.items():
        part = args.out / (name + ".part")
        part.write_text(text)
        part.replace(args.out / name)
    print(markdown(rows), end="")


if __name__ == "__main__":
    main()
