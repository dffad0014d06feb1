"""The benchmark's statistics (agents.score) state what rliable's do, and the shipped score page is what the command
writes from the shipped evaluations."""

import json
from pathlib import Path

import numpy as np
import pytest

from agents import baselines, score

DOCS = Path(__file__).resolve().parent.parent / "docs" / "baselines"


def test_normalized_score_is_zero_for_random_and_one_for_the_controller():
    assert score.normalized([-3.0, -1.0], -2.0, 4.0) == 0.0
    assert score.normalized([4.0], -2.0, 4.0) == 1.0
    assert score.normalized([7.0], -2.0, 4.0) == 1.5


def test_iqm_is_the_mean_of_the_middle_half():
    x = np.arange(100.0)
    assert score.iqm(x) == pytest.approx(np.mean(x[25:75]))
    assert score.iqm(np.r_[np.zeros(8), 1e9, -1e9]) == 0.0  # outliers in the outer quarters do not count


def test_optimality_gap_counts_a_score_above_the_controller_as_the_controller():
    assert score.optimality_gap(np.array([1.5, 0.5])) == pytest.approx(0.25)
    assert score.optimality_gap(np.array([1.0, 2.0])) == 0.0


def test_probability_of_improvement_of_a_run_over_a_run_of_the_same_env():
    better, worse = np.array([0.9, 1.0, 0.8]), np.array([0.1, 0.2])
    assert score.improvement(better, worse) == 1.0
    assert score.improvement(worse, better) == 0.0
    x, y = np.array([0.3, 0.5, 0.7]), np.array([0.4, 0.5, 0.9])
    assert score.improvement(x, y) + score.improvement(y, x) == pytest.approx(1.0)  # ties count half
    assert score.improvement(x, x) == 0.5
    # averaged over envs: one env won outright, one lost outright
    assert score.improvement(better, worse, worse, better) == 0.5


def test_performance_profile_weighs_every_env_alike():
    many_good, one_bad = np.ones(5), np.zeros(1)
    fractions = score.profile(many_good, one_bad)
    taus = score.PROFILE_TAUS
    assert fractions[taus < 0.0].size == 0 and fractions[0] == 0.5  # τ = 0: the bad run is not above it
    assert fractions[np.searchsorted(taus, 0.5)] == 0.5  # not 5/6: each env weighs one half
    assert fractions[-1] == 0.0 and np.all(np.diff(fractions) <= 0)


def test_the_bootstrap_is_stratified_every_resample_keeps_every_env():
    """Env A's runs score 0 or 0.1, env B's 1 or 1.1: resampled within each env, the pooled mean stays in
    [0.5, 0.6]; resampled across envs, it would range over [0, 1.1]."""
    a, b = np.array([0.0, 0.1, 0.0, 0.1]), np.array([1.0, 1.1, 1.0, 1.1])
    point, low, high = score.interval(score.pooled(lambda x, axis=-1: np.mean(x, axis=axis)), [a, b])
    assert point == pytest.approx(0.55)
    assert 0.5 <= low < point < high <= 0.6


def test_interval_of_runs_that_all_agree_is_the_point():
    assert score.mean_interval([1.0, 1.0, 1.0]) == (1.0, 1.0, 1.0)


def test_score_page_is_what_the_command_writes_from_the_shipped_evaluations(tmp_path):
    data = json.loads((DOCS / "unseen.json").read_text())
    written = score.write(data, tmp_path, score.latest(list(baselines.ENVS + baselines.UNTRAINED)), baselines.ALGOS + baselines.JAX_ALGOS)
    assert written == (DOCS / "score.md").read_text()
    assert (tmp_path / "score_aggregates.png").stat().st_size > 0


def test_a_task_counts_once_in_its_latest_version():
    ids = ["connenv/A-v0", "connenv/B-v0", "connenv/A-v1", "connenv/A-v10"]
    assert score.latest(ids) == ["connenv/B-v0", "connenv/A-v10"]
