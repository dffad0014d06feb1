"""TubeTwist-v0 as a task: built on ConnectionEnv, its observation is the error from the target frame, its reward the
decrease of the tangent and twist errors, the cap loop planner solves it at the shortest length, and bad input is
refused by name."""

from __future__ import annotations

import math
import re

import gymnasium as gym
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import connenv  # noqa: F401  (registers the envs)
from agents.controllers import controller
from connenv import ConnectionEnv
from connenv.core import StepperError
from connenv.envs.tube import TIME_COST

ID = "connenv/TubeTwist-v0"


def test_it_is_a_connection_env_whose_default_step_is_the_exact_exponential():
    env = gym.make(ID).unwrapped
    assert isinstance(env, ConnectionEnv) and type(env.stepper).__name__ == "Exact"
    assert (env.group.name, env.system.frame) == ("SO3", "body")


def test_observation_is_the_error_from_the_target_frame():
    """E = Rz(ψ*)ᵀ R₀ᵀ R and (cos, sin) of ψ − ψ*: at the start E = Rz(−ψ*), from any R₀."""
    env = gym.make(ID)
    R0 = Rotation.from_rotvec([1.0, 2.0, -0.5]).as_matrix()
    obs, info = env.reset(options={"state": {"R": R0}, "target": 1.1})
    assert np.allclose(obs[:9], Rotation.from_rotvec([0, 0, -1.1]).as_matrix().ravel(), atol=1e-7)
    assert np.allclose(obs[9:], [math.cos(-1.1), math.sin(-1.1)], atol=1e-7)
    assert np.array_equal(info["state"]["R"], R0) and abs(info["twist"]) <= 1e-15 and not info["is_success"]


@pytest.mark.parametrize("name", ["cap", "square"])
def test_the_loop_planners_succeed_and_the_cap_is_nearly_the_shortest_loop(name):
    """Seeded targets: success with both errors at rounding, every reward summed to the cost's decrease less the time
    cost; the cap's bend is within 0.1 % of the circle of area ψ* (the isoperimetric bound), the square's longer."""
    env = gym.make(ID)
    agent = controller(ID, name, env)
    for seed in range(4):
        obs, info = env.reset(seed=seed)
        target, total, steps = env.unwrapped.state.target, 0.0, 0
        while True:
            obs, reward, terminated, truncated, info = env.step(agent.predict(obs)[0])
            total, steps = total + reward, steps + 1
            if terminated or truncated:
                break
        assert terminated and info["is_success"]
        assert abs(info["twist_error"]) <= 1e-6 and info["tangent_error"] <= 1e-6
        cost = info["tangent_error"] + abs(info["twist_error"])
        assert total == pytest.approx(target - cost - TIME_COST * steps, abs=1e-9)
        assert 1.0 <= info["path_ratio"] <= (1.001 if name == "cap" else 1.2)
        assert name == "cap" or info["path_ratio"] > 1.01


def test_success_needs_the_tangent_back_and_the_twist():
    """A quarter turn bent out and left there: the twist is 0 and the tangent is away, no success; the octant
    loop (T0 → N₀ → B₀ → T0) with target π/2 succeeds."""
    env = gym.make(ID, dt=math.pi / 2, max_episode_steps=None)
    env.reset(options={"target": math.pi / 2})
    info = env.step(np.array([0.0, 1.0]))[4]  # T toward N: along a great circle
    assert not info["is_success"] and abs(info["tangent_error"] - math.pi / 2) <= 1e-12 and abs(info["twist"]) <= 1e-12
    info = env.step(np.array([-1.0, 0.0]))[4]  # toward B₀
    assert not info["is_success"]
    _, _, terminated, _, info = env.step(np.array([0.0, -1.0]))  # back to T₀, turned by the octant's π/2
    assert terminated and info["is_success"]


def test_a_seed_draws_the_target_in_its_range():
    env = gym.make(ID)
    targets = [env.reset(seed=seed) and env.unwrapped.state.target for seed in range(50)]
    assert 0.3 <= min(targets) and max(targets) <= 3.0 and len(set(targets)) == 50


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"state": {"R": np.diag([1.0, 1.0, 1.1])}}, "state R="),
        ({"state": {"R": np.eye(2)}}, "state R has shape (2, 2)"),
        ({"state": {"R": np.eye(3), "s": [0.0, 0.0]}}, "unknown key(s) ['s']"),
        ({"target": 4.0}, "target=4.0 is out of range"),
        ({"target": float("nan")}, "target=nan"),
        ({"goal": 1.0}, "unknown key(s) ['goal']"),
    ],
)
def test_bad_reset_options_are_refused(options, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        gym.make(ID).reset(options=options)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"tolerance": 0.0}, "tolerance=0.0"),
        ({"max_bend_rate": -1.0}, "max_bend_rate=-1.0"),
        ({"max_bend_rate": 1e300}, "max_bend_rate=1e+300 is out of range: must be finite and in [1e-06, 1000.0]"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"integrator": "verlet"}, "integrator='verlet'"),
        ({"bend": 1.0}, "for TubeTwist-v0"),
        ({"shape_low": [0.0, 0.0]}, "['shape_low'] for TubeTwist-v0"),
    ],
)
def test_bad_parameters_are_refused(kwargs, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize("action", [np.array([np.nan, 0.0]), np.zeros(3), "bend"])
def test_bad_actions_are_refused(action):
    env = gym.make(ID)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


def test_a_stepper_that_leaves_so3_raises():
    """Explicit Euler on Ṙ = R ω̂ leaves SO(3) at once, by about (dt κ)² per step: past 1e-9 the env raises."""
    env = gym.make(ID, integrator="euler")
    env.reset(seed=0)
    with pytest.raises(StepperError, match="left SO"):
        env.step(np.array([1.0, 0.0]))
