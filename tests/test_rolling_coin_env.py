"""RollingCoin-v0 as an env: reset options, the task, bad input, the planner."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers import controller
from connenv.envs.connection import ConnectionEnv

ID = "connenv/RollingCoin-v0"


def test_it_is_a_connection_env_on_r2_with_the_exact_step_by_default():
    env = gym.make(ID).unwrapped
    assert isinstance(env, ConnectionEnv) and env.group.name == "R2"
    assert type(env.stepper).__name__ == "Exact"


def test_reset_options_set_the_state_and_the_target():
    env = gym.make(ID)
    obs, info = env.reset(options={"state": {"x": 1.0, "y": 2.0, "theta": 0.5, "phi": 3.0}, "target": (1.0, 3.0, 0.5)})
    assert info["state"] == {"x": 1.0, "y": 2.0, "theta": 0.5, "phi": 3.0, "t": 0.0}
    assert np.allclose(obs, [math.cos(0.5), -math.sin(0.5), 0.0, 1.0], atol=1e-7)  # 1 m along y: ahead and right
    assert info["distance"] == 1.0 and info["heading_error"] == 0.0


def test_the_target_is_drawn_at_1_to_3_m_with_any_heading():
    env = gym.make(ID)
    draws = np.array([env.reset(seed=s)[1]["target"] for s in range(200)])
    distance = np.hypot(draws[:, 0], draws[:, 1])
    assert distance.min() >= 1.0 and distance.max() <= 3.0
    assert draws[:, 2].min() < -2.5 and draws[:, 2].max() > 2.5


def test_parking_within_both_tolerances_terminates_and_phi_is_free():
    env = gym.make(ID)
    env.reset(options={"state": {"phi": 5.0}, "target": (0.0, 0.04, 0.04)})
    _, reward, terminated, _, info = env.step(np.zeros(2))
    assert terminated and info["is_success"] and reward == pytest.approx(1.0 - 0.01)
    env.reset(options={"target": (0.0, 0.0, 0.06)})
    assert not env.step(np.zeros(2))[2]


@pytest.mark.parametrize(
    "kwargs, name",
    [({"radius": 0.0}, "radius"), ({"max_roll_rate": -1.0}, "max_roll_rate"), ({"heading_tolerance": 4.0},
     "heading_tolerance"), ({"dt": 0.0}, "dt"), ({"integrator": "semi_implicit_euler"}, "semi_implicit_euler")],
)
def test_bad_parameters_are_refused_by_name(kwargs, name):
    with pytest.raises(ValueError, match=name):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, name",
    [({"state": {"theta": 7.0}}, "theta"), ({"state": {"z": 0.0}}, "z"), ({"target": (0.0, 1.0)}, "target"),
     ({"target": (0.0, 1.0, 9.0)}, "target"), ({"state": {"x": math.nan}}, "x"), ({"goal": 1}, "goal")],
)
def test_bad_reset_options_are_refused_by_name(options, name):
    with pytest.raises(ValueError, match=name):
        gym.make(ID).reset(options=options)


def test_a_bad_action_is_refused():
    env = gym.make(ID)
    env.reset()
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([math.inf, 0.0]))


def test_the_planner_parks_on_several_seeds_within_the_time_limit():
    env = gym.make(ID)
    planner = controller(ID, env=env)
    for seed in range(6):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(planner.predict(obs)[0])
            done = terminated or truncated
        assert info["is_success"], seed
        assert info["distance"] <= 1e-6  # the roll ends exactly; the last turn ends the episode on entering 0.05 rad


def test_renders_the_coin_from_above():
    env = gym.make(ID, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(np.array([0.5, 1.0]))
    frame = env.render()
    assert frame.shape == (500, 500, 3) and frame.std() > 0
