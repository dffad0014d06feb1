"""BeadOnBar-v0's task: starts and targets, the hold, leaving the bar, reset options, the reference controller,
the builder's steppers through integrator=, rendering, and bad input."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from agents import evaluate
from agents.controllers import controller

ID = "connenv/BeadOnBar-v0"
STILL = np.zeros(1, np.float32)


def test_starts_at_rest_with_a_target_at_least_a_fifth_of_the_bar_away():
    env = gym.make(ID)
    for seed in range(30):
        _, info = env.reset(seed=seed)
        r, target = info["state"]["r"], info["target"]
        assert info["state"]["r_dot"] == 0.0 and info["state"]["theta"] == 0.0 and info["state"]["t"] == 0.0
        assert abs(r) <= 0.8 and abs(target) <= 0.8 + 1e-12 and abs(target - r) >= 0.2 - 1e-12
    assert set(info["state"]) == {"r", "r_dot", "p", "theta", "t"}


def test_horizontal_bar_targets_lie_farther_out_on_the_same_side():
    env = gym.make(ID, g=0.0, half_length=2.0)
    for seed in range(30):
        _, info = env.reset(seed=seed)
        r, target = info["state"]["r"], info["target"]
        assert 0.2 <= abs(r) <= 1.2 and np.sign(r) == np.sign(target) and 0.4 <= abs(target) - abs(r) <= 0.6


def test_success_needs_the_hold_time_at_rest_within_the_tolerances():
    """At θ = 0 a bead at rest is in equilibrium: on the target it succeeds once it has been there hold_time, on
    the 25th step at dt = 0.02, and not before."""
    env = gym.make(ID)
    env.reset(seed=0, options={"state": {"r": 0.5}, "target": 0.51})
    for k in range(1, 26):
        _, reward, terminated, _, info = env.step(STILL)
        assert terminated == (k == 25) == info["is_success"]
        assert info["hold"] == pytest.approx(0.02 * k) and reward == 0.0  # at rest in the tolerances: Φ constant, no time cost
    env.reset(seed=0, options={"state": {"r": 0.5, "r_dot": 0.06}, "target": 0.5})
    _, _, terminated, _, info = env.step(STILL)
    assert not terminated and info["hold"] == 0.0  # too fast to count as at rest


def test_horizontal_bar_succeeds_on_arrival_without_a_hold():
    env = gym.make(ID, g=0.0)
    _, info = env.reset(seed=0, options={"state": {"r": 0.4795, "r_dot": 0.045}, "target": 0.5})
    assert not info["is_success"]
    _, _, terminated, _, info = env.step(STILL)  # coasting 0.0009 m: 0.0196 m from the target
    assert terminated and info["is_success"] and info["state"]["r"] == pytest.approx(0.4804)


def test_reward_is_the_potentials_change_less_the_time_outside():
    """10 (Φ′ − Φ) − 0.01 with Φ = −(|r − r*| + 0.1 |ṙ|)/L: the bead sliding toward the target on a tilted bar."""
    env = gym.make(ID, half_length=2.0)
    _, before = env.reset(seed=0, options={"state": {"r": 1.0, "theta": 0.2}, "target": -1.0})
    _, reward, _, _, after = env.step(STILL)

    def potential(info):
        return -(abs(info["state"]["r"] - info["target"]) + 0.1 * abs(info["state"]["r_dot"])) / 2.0

    assert reward == pytest.approx(10 * (potential(after) - potential(before)) - 0.01, rel=1e-12)
    total = reward
    for _ in range(9):
        _, reward, _, _, info = env.step(STILL)
        total += reward
    assert total == pytest.approx(10 * (potential(info) - potential(before)) - 0.1, rel=1e-12)  # it telescopes


def test_v1_is_v0_with_the_bar_turning_at_most_one_radian_a_second():
    v1, v0 = gym.make("connenv/BeadOnBar-v1"), gym.make(ID, omega_max=1.0)
    assert v1.unwrapped.omega_max == 1.0
    rng = np.random.default_rng(0)
    for env in (v0, v1):
        env.reset(seed=5)
    for _ in range(50):
        action = rng.uniform(-1, 1, 1).astype(np.float32)
        step0, step1 = v0.step(action), v1.step(action)
        np.testing.assert_array_equal(step1[0], step0[0])
        assert step1[1:4] == step0[1:4] and step1[4]["state"] == step0[4]["state"]
        if step0[2] or step0[3]:
            break


def test_v1_keeps_random_exploration_on_the_bar_and_costs_the_tilt_law_nothing():
    """At 2π rad/s the centrifugal m r θ̇² reaches 4 m g at the bar's end: random actions fling the bead off in a
    fraction of the time they take at 1 rad/s. The tilt law is clipped to omega_max and parks as fast under both."""
    v0, v1 = gym.make(ID), gym.make("connenv/BeadOnBar-v1")
    lengths = {}
    for name, env in (("v0", v0), ("v1", v1)):
        random = evaluate.RandomPolicy(env.action_space, 0)
        lengths[name] = np.mean([evaluate.run_episode(env, random, seed).length for seed in range(20)])
        law = controller(env.spec.id, "tilt", env)
        episodes = [evaluate.run_episode(env, law, seed) for seed in range(10)]
        assert all(episode.success for episode in episodes)
        lengths[name + " tilt"] = [episode.length for episode in episodes]
    assert lengths["v1"] > 3 * lengths["v0"]
    assert np.abs(np.subtract(lengths["v1 tilt"], lengths["v0 tilt"])).max() <= 5  # steps: 0.1 s


def test_leaving_the_bar_terminates_with_the_penalty():
    env = gym.make(ID, exit_penalty=12.5)
    env.reset(seed=0, options={"state": {"r": 0.99, "theta": -0.5}, "target": 0.0})
    for _ in range(100):
        _, reward, terminated, _, info = env.step(STILL)
        if terminated:
            break
    assert info["left_bar"] and not info["is_success"] and reward == -12.5 and info["state"]["r"] > 1.0


def test_reset_options_set_the_state_and_target_exactly():
    env = gym.make(ID, mass=2.0)
    obs, info = env.reset(seed=3, options={"state": {"r": -0.3, "r_dot": 0.25, "theta": 1.0}, "target": 0.7})
    assert info["state"] == {"r": -0.3, "r_dot": 0.25, "p": 0.5, "theta": 1.0, "t": 0.0} and info["target"] == 0.7
    assert np.allclose(obs, [-0.3, 1.0, 0.25, math.sin(1.0), math.cos(1.0), 0.0], atol=1e-7)


@pytest.mark.parametrize("g", [9.81, 0.0])
def test_reference_controller_succeeds(g):
    env = gym.make(ID, g=g)
    policy = controller(ID, "analytic", env.unwrapped)
    for seed in range(4):
        obs, _ = env.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = env.step(policy.predict(obs)[0])
        assert info["is_success"], (g, seed, info)


def test_the_builders_steppers_stay_available_and_agree():
    exact, rk4 = gym.make(ID).unwrapped, gym.make(ID, integrator="rk4", substeps=4).unwrapped
    assert type(exact.stepper).__name__ == "Exact" and type(rk4.stepper).__name__ == "RK4"
    exact.reset(seed=5)
    rk4.reset(seed=5)
    for a in np.random.default_rng(5).uniform(-1, 1, 30):
        first, second = exact.step(np.array([a], np.float32))[4], rk4.step(np.array([a], np.float32))[4]
    assert abs(first["state"]["r"] - second["state"]["r"]) < 1e-7


@pytest.mark.parametrize("mode", ["rgb_array", "human"])
def test_renders_the_bar_and_the_bead(mode, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = gym.make(ID, render_mode=mode)
    env.reset(seed=0)
    env.step(np.ones(1, np.float32))
    frame = env.render()
    if mode == "rgb_array":
        red = (frame[..., 0] > 180) & (frame[..., 1] < 110)  # the bead
        assert frame.shape == (500, 500, 3) and red.sum() > 50
    env.close()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"half_length": 0.0}, "half_length=0.0"),
        ({"g": -1.0}, "g=-1.0"),
        ({"mass": math.nan}, "mass=nan"),
        ({"omega_max": 0}, "omega_max=0"),
        ({"omega_max": 1e3}, r"omega_max=1000.0.*\[6.28318530718e-06, 500.0\]"),
        ({"hold_time": -0.5}, "hold_time=-0.5"),
        ({"exit_penalty": -1.0}, "exit_penalty=-1.0"),
        ({"dt": 2.0}, "dt=2.0"),
        ({"integrator": "leapfrog"}, "integrator='leapfrog'"),
        ({"substeps": 4}, "substeps"),
        ({"omega": 3.0}, "omega.*for BeadOnBar;"),  # the stem: v0 and v1 are one class
    ],
)
def test_bad_parameters_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"state": {"r": 1.5}}, r"state r=1.5.*\[-1.0, 1.0\]"),
        ({"state": {"theta": math.inf}}, "state theta=inf"),
        ({"state": {"r_dot": "fast"}}, "state r_dot='fast'"),
        ({"state": {"q": [0.1]}}, "unknown key"),
        ({"target": -2.0}, "target=-2.0"),
        ({"goal": 0.5}, "unknown key"),
    ],
)
def test_bad_reset_options_are_named(options, message):
    with pytest.raises(ValueError, match=message):
        gym.make(ID).reset(options=options)


@pytest.mark.parametrize(
    "action, message",
    [(np.array([0.1, 0.2], np.float32), "shape"), (np.array([np.nan], np.float32), "not finite")],
)
def test_bad_actions_are_named(action, message):
    env = gym.make(ID)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)
