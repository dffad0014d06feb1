"""ElroysBeanie-v0 as an env: reset options, the hold, bad input, the dead-beat law."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers import controller
from connenv.envs.connection import ConnectionEnv

ID = "connenv/ElroysBeanie-v0"


def test_it_is_a_connection_env_on_so2_with_the_exact_step_by_default():
    env = gym.make(ID).unwrapped
    assert isinstance(env, ConnectionEnv) and env.group.name == "SO2"
    assert type(env.stepper).__name__ == "Exact"


def test_reset_draws_a_nonzero_momentum_in_its_documented_range():
    env = gym.make(ID)
    mu = np.array([env.reset(seed=s)[1]["state"]["momentum"] for s in range(100)])
    assert np.all((np.abs(mu) >= 0.25) & (np.abs(mu) <= 1.0)) and (mu > 0).any() and (mu < 0).any()


def test_reset_options_set_the_state_and_the_target():
    env = gym.make(ID)
    _, info = env.reset(options={"state": {"theta": 0.5, "psi": -1.0, "momentum": 0.3}, "target": 1.0})
    assert info["state"] == {"theta": 0.5, "psi": -1.0, "momentum": 0.3, "t": 0.0}
    assert info["target"] == 1.0 and info["error"] == pytest.approx(0.5)


def test_theta_and_psi_are_unwrapped():
    env = gym.make(ID)
    env.reset(options={"state": {"momentum": 0.0}})
    for _ in range(40):
        info = env.step(np.array([1.0]))[4]
    assert info["state"]["psi"] == pytest.approx(40 * 0.05 * 4 * math.pi)
    assert info["state"]["theta"] == pytest.approx(-0.2 * 40 * 0.05 * 4 * math.pi)


def test_holding_for_the_hold_time_within_the_tolerance_succeeds():
    """On the target with ψ̇ = μ/I₂: 20 steps of 0.05 s end the episode, not 19; a break restarts the count."""
    env = gym.make(ID)
    mu = 0.5
    env.reset(options={"state": {"momentum": mu}, "target": 0.0})
    hold = np.array([mu / 0.25 / (4 * math.pi)])
    for k in range(19):
        assert not env.step(hold)[2]
    _, reward, terminated, _, info = env.step(hold)
    assert terminated and info["is_success"] and info["held"] == pytest.approx(1.0)
    assert reward == pytest.approx(1.0)
    # a break: ψ̇ = μ/I₂ ± δ turns the body by ∓ I₂/(I₁+I₂) δ dt = 0.03 rad (past the tolerance) and back
    env.reset(options={"state": {"momentum": mu}, "target": 0.0})
    for _ in range(10):
        info = env.step(hold)[4]
    assert info["held"] == pytest.approx(0.5)
    delta = np.array([3.0 / (4 * math.pi)])
    _, _, terminated, _, info = env.step(hold + delta)
    assert abs(info["error"]) == pytest.approx(0.03) and info["held"] == 0.0 and not terminated
    info = env.step(hold - delta)[4]
    assert abs(info["error"]) <= 1e-12 and info["held"] == pytest.approx(0.05)  # the count restarts
    for k in range(18):
        assert not env.step(hold)[2]
    assert env.step(hold)[2]  # 20 steps on target after the break, not the 10 before it


@pytest.mark.parametrize(
    "kwargs, name",
    [({"body_inertia": 0.0}, "body_inertia"), ({"max_beanie_speed": 1.0}, "max_beanie_speed"),
     ({"tolerance": 0.0}, "tolerance"), ({"hold_time": 0.0}, "hold_time"), ({"dt": -1.0}, "dt")],
)
def test_bad_parameters_are_refused_by_name(kwargs, name):
    with pytest.raises(ValueError, match=name):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, name",
    [({"state": {"momentum": 3.0}}, "momentum"), ({"state": {"psi": 9.0}}, "psi"), ({"target": 7.0}, "target"),
     ({"state": {"omega": 0.0}}, "omega")],
)
def test_bad_reset_options_are_refused_by_name(options, name):
    with pytest.raises(ValueError, match=name):
        gym.make(ID).reset(options=options)


def test_the_dead_beat_law_turns_and_holds_on_several_seeds():
    env = gym.make(ID)
    law = controller(ID, env=env)
    for seed in range(6):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(law.predict(obs)[0])
            done = terminated or truncated
        assert info["is_success"], seed
        assert abs(info["error"]) <= 1e-5


def test_renders_the_two_bodies():
    env = gym.make(ID, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(np.array([0.5]))
    frame = env.render()
    assert frame.shape == (500, 500, 3) and frame.std() > 0
