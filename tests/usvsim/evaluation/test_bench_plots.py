"""Bench path plots: a legend that names every mark, failures drawn over successes."""

from __future__ import annotations

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np

from usvsim.evaluation.bench import plot_pole_paths, plot_waypoint_paths


def _record(success: bool, offset: float) -> SimpleNamespace:
    x = np.linspace(-80.0, 140.0, 50)
    path = np.stack([x, offset + 15.0 * np.exp(-((x / 30.0) ** 2))], axis=1)
    return SimpleNamespace(
        success=success,
        pole_ne=np.zeros(2),
        goal_ne=np.array([140.0, 0.0]),
        trajectory=np.hstack([path, np.zeros((50, 1))]),
    )


def test_pole_paths_legend_and_failures_on_top() -> None:
    records = [_record(True, k) for k in range(5)] + [_record(False, -20.0)]
    fig = plot_pole_paths(records, "x — validation")
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["success (5)", "failure (1)", "goal", "pole", "10 m safety circle"]
    lines = ax.get_lines()
    ok = [ln.get_zorder() for ln in lines if ln.get_color() == "tab:green"]
    bad = [ln.get_zorder() for ln in lines[:6] if ln.get_color() == "tab:red"]
    assert len(ok) == 5 and len(bad) == 1 and min(bad) > max(ok)
    stars = [ln for ln in lines if ln.get_marker() == "*"]
    assert len(stars) == 1 and len(stars[0].get_xdata()) == 6  # every episode's goal
    assert ax.get_title() == "x — validation: 5/6 successes"
    plt.close(fig)


def test_waypoint_paths_have_one_legend() -> None:
    course = SimpleNamespace(
        waypoints_ne=np.array([[0.0, 0.0], [100.0, 0.0]]), poles_ne=np.array([[50.0, 0.0]])
    )

    def record(success: bool) -> SimpleNamespace:
        return SimpleNamespace(
            course=course,
            success=success,
            trajectory=np.array([[0.0, 0.0, 0.0], [50.0, 2.0, 0.0]]),
            outcome="goal" if success else "collision",
            min_pole_distance_m=2.0,
        )

    fig = plot_waypoint_paths([record(True), record(False), record(False)], "x — waypoints")
    assert len(fig.legends) == 1
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["waypoints", "pole", "10 m safety circle", "path, success", "path, failure"]
    plt.close(fig)
