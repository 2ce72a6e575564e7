"""usvsim perf: the open-water batch's throughput figures (issue 16)."""

from __future__ import annotations

import pytest

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


def test_everything_set_throughput_is_a_rate():
    rate = perf.stress_set_throughput("everything", "radar+goal", 4, seconds=0.05)
    assert 0 < rate < float("inf")


def test_profile_names_where_each_workload_spends_its_step():
    result = perf.profile_steps(seconds=0.05, n_boats=4, top=5)
    assert list(result) == [f"{label}, {kind}" for label, _, kind in perf.PROFILE_WORKLOADS]
    for figures in result.values():
        top = figures["top"]
        assert len(top) == 5 and figures["ms_per_step"] > 0
        shares = [row["share"] for row in top]
        assert shares == sorted(shares, reverse=True) and 0 < sum(shares) <= 1.0 + 1e-9
        assert sum(row["ms_per_step"] for row in top) <= figures["ms_per_step"] * 1.05
    names = [row["function"] for f in result.values() for row in f["top"]]
    assert any(name.startswith("usvsim/") for name in names)  # the package's own functions


def test_scene_radar_rates_compare_the_kernel_with_numpy():
    rates = perf.scene_radar_rates(8, seconds=0.05)
    assert rates["numpy images/s"] > 0
    if "compiled images/s" in rates:  # a C compiler built the kernel
        assert rates["compiled_over_numpy"] == pytest.approx(
            rates["compiled images/s"] / rates["numpy images/s"], rel=0.01
        )


def test_env_figures_carry_issue_17s_bars_and_say_which_noise_path_ran(monkeypatch):
    from usvsim.task.noise_kernel import load_kernel

    monkeypatch.setattr(perf, "env_throughput", lambda obs, n, seconds: 10.0 * n)
    monkeypatch.setattr(perf, "open_water_env_throughput", lambda obs, n, seconds: 5.0 * n)
    env = perf._env_figures(0.05)
    assert env["targets"] == {"positional N=256": 200_000, "radar+goal N=256": 100_000}
    assert env["decision_steps_per_s"]["positional N=256"] == 2560
    assert env["sensor_noise"] == ("numpy" if load_kernel() is None else "compiled")


def test_open_water_speed_table_puts_each_env_beside_the_study_task():
    result = perf.open_water_speed_table(sizes=(4,), seconds=0.06, rounds=2)
    (row,) = result["rows"]
    rates = row["decision_steps_per_s"]
    assert row["n_boats"] == 4 and set(rates) == {
        "study task positional",
        "OpenWater-v0 scene",
        "OpenWater-v0 radar+goal",
    }
    assert all(r > 0 for r in rates.values())
    for name, share in row["over_study_task"].items():
        assert share == pytest.approx(rates[name] / rates["study task positional"], rel=0.01)
    assert result["target_N=256"] == 150_000
