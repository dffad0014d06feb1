"""Reference results: the pretrained models load offline, one per (env, algorithm), and reproduce the committed
table (docs/guides/reference-results.md)."""

from __future__ import annotations

import json
import re

import pytest
import yaml

from agents import baselines, evaluate


@pytest.mark.parametrize("env_id", baselines.ENVS)
def test_every_env_has_a_pretrained_model_per_algorithm_that_loads_offline(env_id):
    models = evaluate.pretrained_models(env_id)
    assert [model.parent.name for model in models] == [f"{baselines.short(env_id)}_{algo}" for algo in baselines.ALGOS]
    for model in models:
        evaluate.load_model(model, env_id)  # the algorithm from its args.yml, its spaces checked against the env's


RETURN_RTOL = 1e-6
"""A network policy runs in float32 through torch's CPU kernels, which round by the CPU's SIMD set: its actions move
in their last float32 bit (6e-8) from one CPU to another, and an episode's return by a little more."""


def test_pretrained_models_reproduce_the_committed_swing_rows():
    """Seeded episodes replay the committed rows: the successes and the measure (a count of steps) exactly, the
    returns to RETURN_RTOL."""
    (committed,) = [
        r for r in json.loads((baselines.DOCS / "results.json").read_text()) if r["env"] == "connenv/Swing-v0"
    ]
    report = baselines.evaluate_env("connenv/Swing-v0")
    assert [row["label"] for row in report["policies"]] == ["random", "pumping (analytic)", "PPO", "SAC"]
    for row, expected in zip(report["policies"], committed["policies"], strict=True):
        for key in ("success_rate", "measure"):
            assert row[key] == expected[key], (row["label"], key)
        for key in ("return_mean", "return_std"):
            assert row[key] == pytest.approx(expected[key], rel=RETURN_RTOL, abs=0), (row["label"], key)


def test_pretrained_policy_without_models_names_the_env_and_folder(monkeypatch, tmp_path):
    monkeypatch.setattr(evaluate, "PRETRAINED", tmp_path)
    with pytest.raises(ValueError, match=re.escape(f"no model for connenv/Swing-v0 under {tmp_path}")):
        evaluate.compare("connenv/Swing-v0", ["pretrained"], episodes=1)


def test_readme_table_is_the_committed_results_formatted():
    reports = json.loads((baselines.DOCS / "results.json").read_text())
    assert sorted(report["env"] for report in reports) == sorted(baselines.ENVS)  # in the order `table` wrote them
    table = baselines.format_results(reports)
    assert (baselines.DOCS / "results.md").read_text() == table + "\n"
    assert table in (baselines.REPO / "docs" / "guides" / "reference-results.md").read_text()


def test_pretrained_zips_keep_their_own_algorithm_when_algo_is_given():
    """--algo applies to zips given by path; 'pretrained' reads each model's algorithm from its folder."""
    pairs = evaluate.expand_pretrained(["analytic", "pretrained"], "connenv/Swing-v0", "ppo")
    assert [(spec.split("/")[-2] if spec.endswith(".zip") else spec, algo) for spec, algo in pairs] == [
        ("analytic", "ppo"),
        ("Swing-v0_ppo", None),
        ("Swing-v0_sac", None),
    ]


@pytest.mark.parametrize("env_id", baselines.ENVS + baselines.UNTRAINED)
def test_every_trainable_env_has_hyperparameters_an_analytic_controller_and_a_physical_measure(env_id):
    for algo in baselines.ALGOS:
        assert int(float(baselines.hyperparams(algo, env_id)["n_timesteps"])) > 0
    assert env_id in baselines.CONTROLLERS and env_id in baselines.MEASURES


def test_train_py_leaves_out_the_budget_curve_and_a_curve_trains_with_it(tmp_path):
    """An env's `long` key in ppo.yml is what its budget curve changes: train.py reads the env's entry without it
    (the run's config.yml, which collect compares with `hyperparams`), and the curve's run with it over the rest."""
    from agents import train

    env_id = "connenv/RollingCoin-v0"
    entry = yaml.safe_load(baselines.hyperparams_file("ppo").read_text())[env_id]
    own = {key: value for key, value in entry.items() if key != baselines.LONG}
    for book, expected in (("", own), (baselines.LONG, {**own, **entry[baselines.LONG]})):
        args = train.parse_args(baselines.train_argv(env_id, "ppo", 0, tmp_path, book=book))
        hyperparams, saved = train.experiment(args).read_hyperparameters()
        assert dict(saved) == expected == baselines.hyperparams("ppo", env_id, book)
        assert baselines.LONG not in hyperparams
    assert expected["n_timesteps"] > own["n_timesteps"]
