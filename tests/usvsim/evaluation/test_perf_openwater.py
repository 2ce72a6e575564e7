"""usvsim perf: the open-water batch's throughput figures (issue 16)."""

from __future__ import annotations

from usvsim.evaluation import perf


def test_open_water_figures_cover_one_pole_and_a_busy_scene(monkeypatch):
    calls = []

    def fake(observation, n_boats, n_extra, n_vessels, seconds=2.0):
        calls.append((observation, n_boats, n_extra, n_vessels))
        return 1000.0 + n_extra

    monkeypatch.setattr(perf, "open_water_throughput", fake)
    figures = perf.open_water_figures(0.1)["decision_steps_per_s"]
    assert figures["positional N=256, 6 obstacles + 3 vessels"] == 1005
    assert figures["radar+goal N=256, 1 pole"] == 1000
    assert {c[1] for c in calls} == {256} and ("scene", 256, 5, 3) in calls


def test_open_water_throughput_is_a_rate():
    rate = perf.open_water_throughput("radar+goal", 4, 2, 1, seconds=0.05)
    assert rate > 0 and rate == rate  # finite, not NaN
