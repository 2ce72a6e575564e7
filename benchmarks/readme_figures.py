"""The README's picture: the stress suite's heat map beside one open-water episode.

The heat map is read from the JSON that ``usvsim bench --suite stress --helmsmen all --json``
prints (committed as ``docs/data/stress.json``); the episode is run here, deterministically (a
fixed stress set, episode index and helmsman). Run from the repository root::

    usvsim bench --suite stress --helmsmen all --json > docs/data/stress.json   # the suite
    python benchmarks/readme_figures.py                  # docs/assets/readme-figure.png

The documentation build uses :func:`open_water_episode_figure` for the environment pages too.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only: this script never opens a window

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parents[1]
STRESS_JSON = ROOT / "docs" / "data" / "stress.json"
OUT = ROOT / "docs" / "assets" / "readme-figure.png"
# the episode shown: the best learned helmsman on an episode of the hardest set
EPISODE_SET, EPISODE_INDEX, HELMSMAN = "everything", 4, "scene-gaussian-gail-trpo-openwater"


def heatmap(ax: Axes, stress: dict[str, Any]) -> Any:
    """Success (%) per set (rows) and helmsman (columns) on ``ax``; returns the image."""
    by = {(r["episode_set"], r["helmsman"]): 100.0 * r["success_rate"] for r in stress["rows"]}
    sets, helmsmen = stress["sets"], stress["helmsmen"]
    grid = np.array([[by.get((s, h), np.nan) for h in helmsmen] for s in sets])
    image = ax.imshow(grid, cmap="RdYlGn", vmin=0.0, vmax=100.0, aspect="auto")
    for (i, j), value in np.ndenumerate(grid):
        if np.isfinite(value):
            ax.text(j, i, f"{value:.0f}", ha="center", va="center", fontsize=5.5)
    ax.set_xticks(range(len(helmsmen)), helmsmen, rotation=60, ha="right", fontsize=6.5)
    ax.set_yticks(range(len(sets)), sets, fontsize=7)
    ax.set_title(f"stress suite: success (%), {stress['episodes_per_set']} episodes per set")
    return image


def run_episode(set_name: str, index: int, helmsman_name: str) -> tuple[Any, Any]:
    """(episode, record) of ``helmsman_name`` on episode ``index`` of stress set ``set_name``."""
    from usvsim.evaluation.stress import evaluate_set, select_sets, stress_episodes
    from usvsim.helm.registry import make_helmsman

    (stress_set,) = select_sets([set_name])
    episode = stress_episodes(stress_set, index + 1)[index]
    (record,) = evaluate_set(make_helmsman(helmsman_name), stress_set, [episode])
    return episode, record


def draw_open_water(ax: Axes, episode: Any, record: Any, title: str) -> None:
    """Top view (east right, north up) of an open-water episode: obstacles with their 10 m
    pole-equivalent safety margin, the vessels' tracks, the boat's true path, start and goal."""
    from usvsim.task.openwater import vessel_motion

    t = np.linspace(0.0, 2.0 * math.pi, 90)
    for x_n, y_e, radius in episode.obstacles:
        ax.fill(y_e + radius * np.sin(t), x_n + radius * np.cos(t), color="0.35")
        margin = radius + 9.0  # m: 10 m from a pole's centre = 9 m clear of a disc's edge
        ax.plot(y_e + margin * np.sin(t), x_n + margin * np.cos(t), "--", lw=0.6, color="0.5")
    times = np.linspace(0.0, record.duration_s, 60)
    for vessel in episode.vessels:
        pos, _ = vessel_motion(
            np.array([vessel.x0_n, vessel.y0_e]), np.array(vessel.course_rad),
            np.array(vessel.speed_mps), np.array(vessel.turn_rate_radps), times[:, None],
        )  # fmt: skip
        pos = pos.reshape(-1, 2)
        ax.plot(pos[:, 1], pos[:, 0], color="tab:purple", lw=1.0, alpha=0.7)
        ax.plot(pos[-1, 1], pos[-1, 0], "s", color="tab:purple", ms=4)
    xy = record.trajectory[:, :2]
    ax.plot(xy[:, 1], xy[:, 0], color="tab:blue", lw=1.6, label="boat (true path)")
    ax.plot(xy[0, 1], xy[0, 0], "o", color="tab:green", label="start")
    goal = episode.goal_ne
    ax.plot(goal[1], goal[0], "*", color="tab:orange", ms=12, label="goal")
    ax.plot([], [], color="tab:purple", label="vessels (track, end)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="east (m)", ylabel="north (m)", title=title)
    ax.legend(fontsize=7, loc="best")


def open_water_episode_figure(
    set_name: str = EPISODE_SET, index: int = EPISODE_INDEX, helmsman: str = HELMSMAN
) -> Figure:
    """One open-water episode of ``helmsman`` as a figure of its own."""
    episode, record = run_episode(set_name, index, helmsman)
    fig, ax = plt.subplots(figsize=(5.5, 5.0))
    title = f"{helmsman}, {set_name} #{index}: {record.outcome}"
    draw_open_water(ax, episode, record, title)
    fig.tight_layout()
    return fig


def readme_figure(stress: dict[str, Any]) -> Figure:
    """The heat map (left) and one episode of :data:`HELMSMAN` (right)."""
    episode, record = run_episode(EPISODE_SET, EPISODE_INDEX, HELMSMAN)
    fig, (ax_map, ax_ep) = plt.subplots(
        1, 2, figsize=(15.0, 6.4), gridspec_kw={"width_ratios": [2.3, 1.0]}
    )
    image = heatmap(ax_map, stress)
    fig.colorbar(image, ax=ax_map, fraction=0.025, pad=0.01, label="success (%)")
    title = (
        f"{HELMSMAN}\n'{EPISODE_SET}' episode {EPISODE_INDEX}: {record.outcome}, "
        f"closest {record.min_pole_distance_m:.0f} m"
    )
    draw_open_water(ax_ep, episode, record, title)
    ax_ep.title.set_fontsize(9)
    fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stress-json", type=Path, default=STRESS_JSON)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    stress = json.loads(args.stress_json.read_text())
    fig = readme_figure(stress)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=80)
    print(f"written {args.out} ({args.out.stat().st_size / 1024:.0f} KB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
