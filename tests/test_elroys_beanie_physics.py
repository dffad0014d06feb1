"""ElroysBeanie-v0's physics: the geometric phase of a flat connection, the dynamic phase, momentum conservation."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401

I1, I2 = 1.0, 0.25
SPEED = 4 * math.pi


def make(**kwargs):
    return gym.make("connenv/ElroysBeanie-v0", **kwargs).unwrapped


def run(env, actions, momentum=0.0, theta=0.0):
    env.reset(seed=0, options={"state": {"theta": theta, "momentum": momentum}, "target": 0.0})
    for a in actions:
        env.step(np.array([a], np.float64))
    return env.state


def test_one_turn_of_the_beanie_turns_the_body_by_the_geometric_phase():
    """ψ: 0 → 2π at μ = 0 turns the body by −2π I₂/(I₁+I₂)."""
    steps = 10
    state = run(make(max_beanie_speed=2 * math.pi / (steps * 0.05)), [1.0] * steps)
    assert abs(state.s[0] - 2 * math.pi) <= 1e-12
    assert abs(state.g[0] - (-2 * math.pi * I2 / (I1 + I2))) <= 1e-12


@pytest.mark.parametrize("momentum", [0.3, -0.8])
def test_with_a_momentum_the_dynamic_phase_adds(momentum):
    """The same turn with μ ≠ 0 over T: −2π I₂/(I₁+I₂) + μ T/(I₁+I₂)."""
    steps = 10
    state = run(make(max_beanie_speed=2 * math.pi / (steps * 0.05)), [1.0] * steps, momentum)
    T = steps * 0.05
    assert abs(state.g[0] - (-2 * math.pi * I2 + momentum * T) / (I1 + I2)) <= 1e-12


@pytest.mark.parametrize("winding", [1, -2, 3])
def test_loops_of_any_speed_profile_with_one_winding_number_give_one_geometric_phase(winding):
    """Random speed profiles, scaled to wind ψ w times (back and forth allowed), over different durations: the
    body turns by −2π w I₂/(I₁+I₂) every time."""
    rng = np.random.default_rng(abs(winding))
    for steps in (120 * abs(winding), 150 * abs(winding) + 7):
        profile = rng.uniform(-0.3, 1.0, steps)  # back and forth, mostly forth
        actions = np.sign(winding) * profile * 2 * math.pi * abs(winding) / (SPEED * 0.05 * profile.sum())
        assert np.max(np.abs(actions)) <= 1.0  # not clipped
        state = run(make(), actions)
        assert abs(state.s[0] - 2 * math.pi * winding) <= 1e-11
        assert abs(state.g[0] - (-2 * math.pi * winding * I2 / (I1 + I2))) <= 1e-11


def test_the_momentum_is_conserved_and_spinning_at_mu_over_i2_holds_the_body():
    """μ = (I₁+I₂) θ̇ + I₂ ψ̇ from the finite differences of a step; ψ̇ = μ/I₂ keeps θ."""
    env = make()
    mu = 0.7
    a = np.random.default_rng(0).uniform(-1, 1, 20)
    env.reset(options={"state": {"momentum": mu}})
    for action in a:
        before = env.state
        env.step(np.array([action]))
        theta_dot = (env.state.g[0] - before.g[0]) / env.dt
        psi_dot = (env.state.s[0] - before.s[0]) / env.dt
        assert abs((I1 + I2) * theta_dot + I2 * psi_dot - mu) <= 1e-12
    state = run(env, [mu / I2 / SPEED] * 20, mu, theta=0.4)
    assert abs(state.g[0] - 0.4) <= 1e-14


def test_the_vector_env_steps_every_row_as_the_single_env():
    actions = np.random.default_rng(5).uniform(-1, 1, (10, 3, 1))
    vec = gym.make_vec("connenv/ElroysBeanie-v0", num_envs=3, vectorization_mode="vector_entry_point")
    vec.reset(seed=7)
    for a in actions:
        vec.step(a)
    for i in range(3):
        env = make()
        env.reset(seed=7 + i)
        for a in actions[:, i]:
            env.step(a)
        assert np.array_equal(vec.unwrapped.state.g[i], env.state.g)
        assert vec.unwrapped.state.held[i] == env.state.held
