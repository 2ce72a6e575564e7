"""The sweep report's statistics (learning.experiments.sweep_report) against rliable, the
library they restate: IQM, probability of improvement, performance profiles, bootstrap
intervals."""

from __future__ import annotations

import numpy as np
import pytest

from learning.experiments.sweep_report import iqm, probability_of_improvement


def test_iqm_equals_rliable() -> None:
    metrics = pytest.importorskip("rliable.metrics")  # the sweep extra

    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 5, 8, 13):
        x = rng.uniform(size=n)
        assert iqm(x) == pytest.approx(float(metrics.aggregate_iqm(x[:, None])), abs=1e-12)


def test_probability_of_improvement_equals_rliable() -> None:
    metrics = pytest.importorskip("rliable.metrics")  # the sweep extra
    rng = np.random.default_rng(1)
    for nx, ny in ((1, 1), (3, 5), (5, 5), (4, 2)):
        x = np.round(rng.uniform(size=nx), 1)  # ties on purpose
        y = np.round(rng.uniform(size=ny), 1)
        expected = float(metrics.probability_of_improvement(x[:, None], y[:, None]))
        assert probability_of_improvement(x, y) == pytest.approx(expected, abs=1e-12)
    assert probability_of_improvement(np.ones(3), np.ones(3)) == 0.5


def test_performance_profile_equals_rliable() -> None:
    rly = pytest.importorskip("rliable.library")  # the sweep extra
    from learning.experiments.sweep_report import score_distribution

    rng = np.random.default_rng(2)
    taus = np.linspace(0.0, 1.0, 101)
    scores = {"a": np.round(rng.uniform(size=(5, 1)), 2), "b": rng.uniform(size=(3, 1))}
    for x in scores.values():
        assert score_distribution(x, taus) == pytest.approx(rly.score_distributions(x, taus))
    np.random.seed(3)  # noqa: NPY002 (rliable resamples with the global generator)
    ours = rly.get_interval_estimates(scores, lambda x: score_distribution(x, taus), reps=200)
    np.random.seed(3)  # noqa: NPY002
    theirs = rly.get_interval_estimates(
        scores, lambda x: rly.score_distributions(x, taus), reps=200
    )
    for k in scores:
        assert ours[0][k] == pytest.approx(theirs[0][k])
        assert ours[1][k] == pytest.approx(theirs[1][k])


def test_bootstrap_intervals_are_reproducible_and_leave_numpy_alone() -> None:
    pytest.importorskip("rliable")  # the sweep extra
    from learning.experiments.sweep_report import bootstrap_intervals

    x = {"a": np.random.default_rng(0).uniform(size=(5, 1))}
    state = np.random.get_state()  # noqa: NPY002
    first = bootstrap_intervals(x, lambda s: np.array([iqm(s[:, 0])]), 300)[1]["a"]
    again = bootstrap_intervals(x, lambda s: np.array([iqm(s[:, 0])]), 300)[1]["a"]
    assert np.array_equal(first, again)  # seeded: was different on every call before
    after = np.random.get_state()  # noqa: NPY002
    assert all(np.array_equal(a, b) for a, b in zip(state[1:], after[1:], strict=True))
