"""RollingCoin-v0's physics: the closed-form step against the constraints, the rectangle's holonomy, the curvature."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import quad

import connenv  # noqa: F401
from connenv.systems import rolling_coin

R = 0.5


def make(**kwargs):
    return gym.make("connenv/RollingCoin-v0", **kwargs).unwrapped


def drive(env, actions, start=None):
    env.reset(seed=0, options={"state": start or {}})
    for a in actions:
        env.step(np.asarray(a, np.float64))
    return env.state


@pytest.mark.parametrize("theta0, delta_theta, delta_phi", [(0.3, 0.7, 1.1), (-2.0, -1.3, 0.4), (1.0, 2.5, -3.0)])
def test_a_rectangle_in_theta_phi_moves_the_coin_by_the_closed_form(theta0, delta_theta, delta_phi):
    """Roll Δφ at θ₀, steer Δθ, roll back, steer back: R Δφ (sin θ₀ − sin(θ₀+Δθ), cos θ₀ − cos(θ₀+Δθ))."""
    env = make(max_steer_rate=abs(delta_theta) / 0.1, max_roll_rate=abs(delta_phi) / 0.1)
    side = [(0.0, np.sign(delta_phi)), (np.sign(delta_theta), 0.0), (0.0, -np.sign(delta_phi)),
            (-np.sign(delta_theta), 0.0)]  # fmt: skip
    state = drive(env, side, {"theta": theta0})
    expected = rolling_coin.rectangle_displacement(theta0, delta_theta, delta_phi, R)
    assert np.max(np.abs(state.g - expected)) <= 1e-12
    assert abs(state.s[0] - theta0) <= 1e-15 and abs(state.s[1]) <= 1e-15  # the shape is back


def test_a_small_loop_moves_the_coin_by_curvature_times_area():
    """Stokes: a small counterclockwise loop's displacement Δg = −∮A ≈ −dA = (R cos θ, −R sin θ) times the enclosed
    area (the curvature dA = (−R cos θ, R sin θ) dθ ∧ dφ)."""
    theta0, h = 0.8, 1e-3
    env = make(max_steer_rate=h / 0.1, max_roll_rate=h / 0.1)
    state = drive(env, [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)], {"theta": theta0})  # counter-clockwise
    minus_curvature = R * np.array([math.cos(theta0 + h / 2), -math.sin(theta0 + h / 2)])
    assert np.allclose(state.g / h**2, minus_curvature, rtol=0, atol=1e-6)


@pytest.mark.parametrize("omega, nu", [(0.7, -1.9), (1e-9, 2.0), (-1.0, 0.0), (0.0, 1.3)])
def test_the_step_is_the_integral_of_the_constraints(omega, nu):
    """ẋ = R sin θ φ̇, ẏ = R cos θ φ̇ integrated by quadrature over steps of both rates, near θ̇ = 0 too."""
    theta0, dt, steps = 0.4, 0.1, 7
    env = make(max_steer_rate=1.0, max_roll_rate=2.0, dt=dt)
    state = drive(env, [(omega, nu / 2.0)] * steps, {"theta": theta0, "x": 0.3, "y": -0.2})
    T = dt * steps
    x = 0.3 + quad(lambda t: R * nu * math.sin(theta0 + omega * t), 0, T, epsabs=1e-13, epsrel=1e-13)[0]
    y = -0.2 + quad(lambda t: R * nu * math.cos(theta0 + omega * t), 0, T, epsabs=1e-13, epsrel=1e-13)[0]
    assert np.max(np.abs(state.g - [x, y])) <= 1e-13
    assert abs(state.s[0] - (theta0 + omega * T)) <= 1e-14


def test_steering_alone_never_moves_the_coin_and_rolling_alone_moves_it_along_its_heading():
    env = make()
    assert np.all(drive(env, [(1.0, 0.0)] * 13, {"x": 1.0, "y": 2.0}).g == [1.0, 2.0])
    theta = 2.2
    state = drive(env, [(0.0, 1.0)] * 10, {"theta": theta})
    assert np.max(np.abs(state.g - 2.0 * R * np.array([math.sin(theta), math.cos(theta)]))) <= 1e-14


def test_a_float64_action_is_used_at_its_precision():
    """An action not representable in float32 moves the coin as its float64 value says."""
    a = 0.1 + 1e-12
    env = make()
    state = drive(env, [(0.0, a)])
    assert abs(state.s[1] - a * 2.0 * 0.1) <= 1e-17
    assert float(np.float32(a)) != a


def test_exact_magnus_and_rk4_agree_on_a_random_episode():
    """Three steppers, one flow: the closed form, the Lie-group quadrature (to its tolerance) and RK4 (to its order)."""
    actions = np.random.default_rng(3).uniform(-1, 1, (40, 2))
    exact = drive(make(), actions).g
    assert np.max(np.abs(drive(make(integrator="magnus", atol=1e-12), actions).g - exact)) <= 1e-11
    assert np.max(np.abs(drive(make(integrator="rk4", substeps=8), actions).g - exact)) <= 1e-7


def test_the_vector_env_steps_every_row_as_the_single_env():
    actions = np.random.default_rng(5).uniform(-1, 1, (10, 3, 2))
    vec = gym.make_vec("connenv/RollingCoin-v0", num_envs=3, vectorization_mode="vector_entry_point")
    vec.reset(seed=7)
    for a in actions:
        vec.step(a)
    for i in range(3):
        env = make()
        env.reset(seed=7 + i)
        for a in actions[:, i]:
            env.step(a)
        assert np.array_equal(vec.unwrapped.state.g[i], env.state.g)
