"""The planners of agents.mpc: they solve what random actions cannot, iLQR's iteration is right on a case with a known
answer, seeded runs repeat to the bit, and bad budgets are refused by name."""

from __future__ import annotations

from typing import ClassVar

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.evaluate import RandomPolicy, check_policy, run_episode
from agents.mpc import ILQR, MPPI, Hyper, check_planner, planner

SKIER = "connenv/Skier-v0"


def episode(policy, env_id=SKIER, seed=100_000, steps=None):
    env = gym.make(env_id, **({} if steps is None else {"max_episode_steps": steps}))
    return run_episode(env, policy, seed)


BUDGET = 250  # steps (12.5 s) of the skier; the analytic pumping takes about 170
SMALL = {"horizon": 5, "repeat": 4}  # a plan of 1 s, made every 0.2 s: a small budget, so that the tests are fast


def test_mppi_pumps_the_skier_out_where_random_actions_do_not():
    assert episode(MPPI(SKIER, seed=0, samples=16, **SMALL), seed=100_002, steps=BUDGET).success
    assert not episode(RandomPolicy(gym.make(SKIER).action_space, 0), seed=100_002, steps=BUDGET).success


def test_ilqr_pumps_the_skier_out_on_the_models_jacobians():
    assert episode(ILQR(SKIER, seed=0, **SMALL), seed=100_002, steps=BUDGET).success


class Linear:
    """A model with x′ = x + a (one entry each) and reward −x′²: the best one-step action from x is −x, which one
    Newton step of iLQR finds exactly (the reward is quadratic and the dynamics linear)."""

    entries: ClassVar[list] = [type("Entry", (), {"real": True, "size": 1})()]

    def step(self, X, A):
        return X + A

    def reward(self, X, A, X_next):
        return -(X_next[:, 0] ** 2)

    def terminated(self, X):
        return np.zeros(len(X), bool)

    def jacobians(self, X, A):
        return np.ones((len(X), 1, 1)), np.ones((len(X), 1, 1))


def test_one_ilqr_iteration_solves_a_linear_quadratic_case():
    policy = ILQR(SKIER, horizon=1, iterations=1)
    policy.model, policy.low, policy.high = Linear(), np.array([-5.0]), np.array([5.0])
    policy.real, policy.mu = np.array([True]), 1e-9
    U = policy.optimize(np.array([2.0]), np.zeros((1, 1)))
    assert U[0, 0] == pytest.approx(-2.0, abs=1e-6)


@pytest.mark.parametrize("name", ["mpc", "ilqr"])
def test_seeded_planners_repeat_to_the_bit(name):
    runs = [episode(planner(name, SKIER, seed=7, samples=8, horizon=5), steps=20) for _ in range(2)]
    assert runs[0] == runs[1]


def test_mppi_seeds_differ():
    runs = [episode(planner("mpc", SKIER, seed=s, samples=8, horizon=5), steps=20).ret for s in (1, 2)]
    assert runs[0] != runs[1]


@pytest.mark.parametrize(
    ("field", "value"), [("samples", 1), ("horizon", 0), ("temperature", 0.0), ("noise", -0.1), ("repeat", 2.5)]
)
def test_bad_hyperparameters_are_refused_with_their_range(field, value):
    with pytest.raises(ValueError, match=rf"{field}={value!r} is (outside|not an integer in) \["):
        Hyper(**{field: value})


def test_a_planner_must_be_bound_before_it_plans():
    with pytest.raises(RuntimeError, match="call bind"):
        MPPI(SKIER).predict(np.zeros(3))


def test_ilqr_is_refused_where_the_model_cannot_differentiate(monkeypatch):
    env = gym.make(SKIER).unwrapped
    model_type = type(env.model)

    def refuse(self, x, a):
        raise TypeError("LSODA cannot step complex rows")

    monkeypatch.setattr(model_type, "jacobians", refuse)
    with pytest.raises(ValueError, match="planner 'ilqr' cannot run on connenv/Skier-v0: TypeError: LSODA"):
        check_planner(SKIER, "ilqr")
    with pytest.raises(ValueError, match="cannot run"):
        check_policy(SKIER, "ilqr")
    check_planner(SKIER, "mpc")
