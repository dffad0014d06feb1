"""FallingCat-v0 as a task: built on ConnectionEnv with its closed-form step, dropped upside down at rest, the
reward pays the landing error's decrease, Kane and Scher's motion lands it on every seed, the bend stops at its
bound, and bad input is refused by name."""

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
from connenv.envs.falling_cat import ROLL_OFFSET, SUCCESS_BONUS
from connenv.systems import falling_cat

ID = "connenv/FallingCat-v0"


def test_it_is_a_connection_env_whose_default_step_is_the_closed_form():
    env = gym.make(ID).unwrapped
    assert isinstance(env, ConnectionEnv) and type(env.stepper).__name__ == "Exact"
    assert (env.group.name, env.system.frame) == ("SO3", "body")
    assert gym.spec(ID).max_episode_steps == round(env.fall_time / env.dt)


def test_the_cat_starts_upside_down_straight_and_at_rest():
    """Roll π + δ, |δ| ≤ 0.2, the spine horizontal at a random heading; E = Hᵀ g = Rx(π + δ); R = g Q_A."""
    env = gym.make(ID)
    headings = []
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        assert math.pi - ROLL_OFFSET <= abs(info["roll"]) <= math.pi
        R, g = info["state"]["R"], env.unwrapped.state.g.reshape(3, 3)
        assert np.array_equal(R, g) and abs(g[2, 0]) <= 1e-16 and np.all(info["state"]["bend"] == 0.0)
        assert np.allclose(obs[:9], Rotation.from_rotvec([info["roll"], 0, 0]).as_matrix().ravel(), atol=1e-7)
        assert np.array_equal(obs[9:], [0.0, 0.0, 1.0]) and not info["is_success"]
        headings.append(math.atan2(g[1, 0], g[0, 0]))
    assert np.ptp(headings) > 1.0


def test_reset_options_set_the_front_half_and_the_bend_exactly():
    env = gym.make(ID)
    R = Rotation.from_euler("zx", [0.4, 2.0]).as_matrix()
    _, info = env.reset(options={"state": {"R": R, "bend": [0.3, -0.2]}})
    assert np.allclose(info["state"]["R"], R, atol=1e-15) and np.array_equal(info["state"]["bend"], [0.3, -0.2])
    g = env.unwrapped.state.g.reshape(3, 3)
    assert np.allclose(g @ falling_cat.halves(np.array([0.3, -0.2]))[0], R, atol=1e-15)


@pytest.mark.parametrize("seed", range(6))
def test_kane_and_scher_land_the_cat_on_every_seed(seed):
    """Success before the landing, roll to 1e-6, the rewards summed to e₀ − e_T + the bonus."""
    env = gym.make(ID)
    agent = controller(ID, "kane_scher", env)
    obs, info = env.reset(seed=seed)
    start, total = info["roll_error"], 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(agent.predict(obs)[0])
        total += reward
        if terminated or truncated:
            break
    assert terminated and not truncated and info["is_success"] and info["state"]["t"] < env.unwrapped.fall_time
    assert abs(info["roll"]) <= 1e-6 and info["spine_error"] <= 1e-12
    error = info["roll_error"] + info["spine_error"] + info["bend_angle"]
    assert total == pytest.approx(start - error + SUCCESS_BONUS, abs=1e-12)


def test_the_controller_lands_every_row_of_the_vector_env():
    env = gym.make_vec(ID, 4, vectorization_mode="vector_entry_point")
    agent = controller(ID, "kane_scher", gym.make(ID))
    obs, _ = env.reset(seed=10)
    done = np.zeros(4, bool)
    for _ in range(60):
        obs, _, terminated, truncated, info = env.step(agent.predict(obs)[0])
        assert not np.any(terminated & ~info["is_success"] & ~done)
        done |= terminated
        if done.all():
            break
    assert done.all()


def test_holding_still_lands_upside_down_at_fall_time():
    """No bend, no roll: the landing at t = fall_time ends the episode (terminated, not truncated), unsuccessful."""
    env = gym.make(ID, fall_time=0.1)
    env.reset(seed=0)
    for step in range(10):
        _, reward, terminated, truncated, info = env.step(np.zeros(2))
        assert reward == 0.0 and terminated == (step == 9) and not truncated
    assert not info["is_success"] and abs(info["roll"]) >= math.pi - ROLL_OFFSET


def test_the_bend_stops_at_max_bend():
    """Pushed outward from the edge it stays; from inside it stops on the circle β = max_bend, at rest."""
    env = gym.make(ID, max_bend=0.1)
    env.reset(seed=0, options={"state": {"bend": [0.08, 0.0]}})
    _, _, _, _, info = env.step([1.0, 1.0])
    assert info["bend_angle"] == pytest.approx(0.1, abs=1e-15) and np.all(env.unwrapped.state.s_dot == 0.0)
    before = env.unwrapped.state.g.copy()
    _, _, _, _, info = env.step([1.0, 0.5])
    assert info["bend_angle"] == pytest.approx(0.1, abs=1e-15) and np.array_equal(env.unwrapped.state.g, before)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"transverse_inertia": 0.0}, "transverse_inertia=0.0"),
        ({"axial_inertia": 0.02}, "axial_inertia=0.02 .*transverse_inertia=0.01"),
        ({"mass": -1.0}, "mass=-1.0"),
        ({"cm_distance": math.nan}, "cm_distance=nan"),
        ({"max_bend": 3.5}, "max_bend=3.5"),
        ({"max_bend_speed": 0.0}, "max_bend_speed=0.0"),
        ({"fall_time": 0.0}, "fall_time=0.0"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"tolerance": 4.0}, "tolerance=4.0"),
        ({"integrator": "leapfrog"}, "leapfrog"),
    ],
)
def test_bad_parameters_are_refused_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, match",
    [
        ({"state": {"R": np.ones((3, 3))}}, "state R"),
        ({"state": {"R": np.eye(3)[:, [2, 1, 0]] * [1, 1, -1]}}, "spine vertical"),
        ({"state": {"bend": [1.0, 1.0]}}, re.escape("β = 1.41421 > max_bend=1.2")),
        ({"state": {"bend": [2.0, 0.0]}}, "state bend"),
        ({"state": {"omega": 1.0}}, "omega"),
        ({"target": 1.0}, "target"),
    ],
)
def test_bad_reset_options_are_refused_by_name(options, match):
    with pytest.raises(ValueError, match=match):
        gym.make(ID).reset(options=options)


def test_rgb_array_draws_the_cat():
    env = gym.make(ID, render_mode="rgb_array")
    env.reset(seed=0)
    env.step([1.0, 0.0])
    frame = env.render()
    assert frame.shape == (500, 500, 3) and len(np.unique(frame.reshape(-1, 3), axis=0)) > 3
