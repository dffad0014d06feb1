"""Behaviour cloning into PPO's policy (agents.imitate): the clone reproduces a Markov controller, is a model zip the
evaluation CLI loads, and the diagnosis on the reference-results page is the committed JSON formatted."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from agents import baselines, evaluate, imitate
from agents.controllers import controller

DIAGNOSIS = baselines.DOCS / "diagnosis.json"


@pytest.fixture(scope="module")
def bead_clone(tmp_path_factory):
    """BeadOnBar-v0's tilt law cloned from 10 demonstrations, without DAgger."""
    plan = imitate.Budget(demonstrations=10, epochs=30, rounds=0)
    return imitate.imitate("connenv/BeadOnBar-v0", plan, seed=0, out=tmp_path_factory.mktemp("imitate"))


def test_clone_of_the_tilt_law_matches_it_on_held_out_demonstrations(bead_clone):
    """The tilt law is a smooth function of the observation, so the MLP fits it: on demonstration episodes kept out
    of training, the clone's RMS action error is under a third of the spread of the law's actions (an untrained
    policy's is about the spread)."""
    record = bead_clone["record"]
    assert record["demonstration_success"] == 1.0
    assert record["held_out_rmse"] < record["held_out_label_std"] / 3


def test_clone_is_a_ppo_zip_that_the_evaluation_loads_with_its_normalizer_and_parks_the_bead(bead_clone):
    """The saved clone, loaded by agents.evaluate (its algorithm from args.yml, the observation statistics of the
    demonstrations from vecnormalize.pkl), acts as the clone in memory and brings the bead to rest on unseen
    episodes."""
    label, policy = evaluate.make_policy(str(bead_clone["path"]), "connenv/BeadOnBar-v0", 0)
    assert label == "ppo:BeadOnBar-v0_bc_s0"
    assert isinstance(policy, evaluate.NormalizedPolicy)
    env = gym.make("connenv/BeadOnBar-v0")
    obs, _ = env.reset(seed=imitate.EVAL_SEED)
    np.testing.assert_array_equal(policy.predict(obs)[0], bead_clone["policy"].predict(obs)[0])
    episodes = evaluate.evaluate("connenv/BeadOnBar-v0", policy, 5, imitate.EVAL_SEED)
    assert all(episode.success for episode in episodes)


def test_greedy_reward_ascent_stays_at_the_start_of_rolling_ball_pose():
    """From the centre at the origin, a roll of length ℓ turns the ball by at most ℓ/ρ and moves the centre ℓ away:
    the reward e − e′ − ℓ/ρ − 0.01 is at most the standing ball's −0.01. So the one-step greedy policy stands
    still, and stays so, while the holonomy planner's first step pays less than standing: the way to the target
    starts downhill in the reward."""
    env = gym.make("connenv/RollingBallPose-v0")
    obs, _ = env.reset(seed=imitate.EVAL_SEED)
    action, _ = imitate.GreedyReward(env).predict(obs)
    np.testing.assert_array_equal(action, np.zeros(2))
    planned, _ = controller("connenv/RollingBallPose-v0", env=env).predict(obs)
    assert env.step(planned)[1] < -0.01


def test_holonomy_planner_keeps_a_plan_that_the_memoryless_one_does_not_follow():
    """Inside its plan the holonomy planner's action is not the one it plans afresh from the same state: it keeps a
    plan, so it cannot label states it did not plan for (no DAgger on RollingBallPose-v0). Made memoryless it
    answers as a new planner does."""
    env = gym.make("connenv/RollingBallPose-v0")
    law = controller("connenv/RollingBallPose-v0", env=env)
    obs, _ = env.reset(seed=imitate.EVAL_SEED)
    for _ in range(10):
        obs = env.step(law.predict(obs)[0])[0]
    planned = law.predict(obs)[0]
    afresh = controller("connenv/RollingBallPose-v0", env=env).predict(obs)[0]
    assert np.abs(planned - afresh).max() > 0.1
    np.testing.assert_array_equal(imitate.Memoryless(law).predict(obs)[0], afresh)


def test_reference_results_page_has_the_committed_diagnosis_formatted():
    reports = json.loads(DIAGNOSIS.read_text())
    assert sorted(report["env"] for report in reports) == sorted(imitate.DIAGNOSED)  # in the order diagnose wrote them
    page = (baselines.REPO / "docs" / "guides" / "reference-results.md").read_text()
    assert imitate.format_diagnosis(reports) in page


def test_diagnosis_clone_seeds_and_evaluation_seeds_are_disjoint_from_the_demonstrations():
    """Unseen seeds: the evaluation's episodes are neither demonstrations nor the table's seeds 0..99."""
    for report in json.loads(DIAGNOSIS.read_text()):
        first, last = report["eval_seeds"]
        assert first == imitate.EVAL_SEED and last < imitate.DEMO_SEED and first > baselines.EPISODES
        assert [clone["seed"] for clone in report["clones"]] == list(imitate.CLONE_SEEDS)
