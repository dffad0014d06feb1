"""BeadOnBar-v0's physics: the closed-form flow at constant θ̇ against an independent integration and the seed's
form, the class derived by the builder, the builder's generic route, energy where θ is held, and the inclusion
ṙ ≥ 0 of the horizontal bar."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import connenv  # noqa: F401  (registers the envs)
from connenv import ActiveConstraintEnv
from connenv.core import StepperError
from connenv.core.mechanics import JumpClass, classify
from connenv.systems.bead_on_bar import bead_on_bar, lagrangian, segment

MASS, G = 1.3, 9.81


def integrated(r0, v0, theta0, omega, tau, g=G):
    """(r, ṙ) at tau from r̈ = ω² r − g sin(θ₀ + ω t), by DOP853 at rtol = atol = 1e-13."""
    sol = solve_ivp(lambda t, z: [z[1], omega**2 * z[0] - g * math.sin(theta0 + omega * t)], (0.0, tau),
                    [r0, v0], method="DOP853", rtol=1e-13, atol=1e-13)  # fmt: skip
    return sol.y[:, -1]


@pytest.mark.parametrize("omega", [0.0, 1e-12, 1e-7, 1e-3, 0.3, -1.0, 2 * math.pi, -2 * math.pi])
@pytest.mark.parametrize("tau", [0.02, 1.0])
def test_closed_form_at_constant_rate_matches_an_independent_integration_to_1e_9(omega, tau):
    rng = np.random.default_rng(abs(hash((omega, tau))) % 2**32)
    system = bead_on_bar(MASS, G)
    for _ in range(4):
        r0, v0, theta0 = rng.uniform(-1, 1), rng.uniform(-2, 2), rng.uniform(-math.pi, math.pi)
        reference = integrated(r0, v0, theta0, omega, tau)
        one = system.exact_segment(np.array([r0, MASS * v0]), np.array([theta0]), np.array([omega]), tau)
        batch = system.exact_segment(np.array([[r0, MASS * v0]] * 2), np.array([[theta0]] * 2),
                                     np.array([[omega]] * 2), np.array([tau, tau]))  # fmt: skip
        for y in (one, *batch):
            assert np.allclose([y[0], y[1] / MASS], reference, rtol=0, atol=1e-9 * (1 + np.abs(reference).max()))


def test_closed_form_is_the_seeds_hyperbolic_form_and_the_parabola_at_zero_rate():
    """r(t) = a cosh ωt + b sinh ωt + (g/2ω²) sin(θ₀ + ωt), a = r₀ − (g/2ω²) sin θ₀, b = v₀/ω − (g/2ω²) cos θ₀,
    where it is well conditioned (ωt of order 1); at ω = 0, r = r₀ + v₀ t − ½ g sin θ₀ t², ṙ = v₀ − g sin θ₀ t."""
    r0, v0, theta0, t = 0.3, -0.4, 0.7, 0.8
    for omega in (1.5, -2.5, 4.0):
        k = G / (2 * omega**2)
        a, b = r0 - k * math.sin(theta0), v0 / omega - k * math.cos(theta0)
        x = omega * t
        r = a * math.cosh(x) + b * math.sinh(x) + k * math.sin(theta0 + x)
        v = omega * (a * math.sinh(x) + b * math.cosh(x)) + k * omega * math.cos(theta0 + x)
        y = segment(np.array([r0, MASS * v0]), np.array([theta0]), np.array([omega]), t, MASS, G)
        assert np.allclose(y, [r, MASS * v], rtol=1e-12, atol=1e-12)
    y = bead_on_bar(MASS, G).exact_segment(np.array([r0, MASS * v0]), np.array([theta0]), np.array([0.0]), t)
    parabola = [r0 + v0 * t - 0.5 * G * math.sin(theta0) * t**2, MASS * (v0 - G * math.sin(theta0) * t)]
    assert np.allclose(y, parabola, rtol=0, atol=1e-15)


def test_the_class_is_general_derived_by_the_builder_from_the_lagrangian():
    """B = G22 − G12ᵀ G11⁻¹ G12 = m r² depends on q = r: general. The builder derives it (LagrangianSystem,
    symbolically; connenv.core.mechanics.classify, numerically at sample points); nothing in the env declares
    it, and the class picks the control: θ̇ (velocity), since θ may not jump."""
    system = bead_on_bar(MASS, G)
    r = sp.Symbol("r")
    assert system.K == sp.zeros(1, 1) and sp.simplify(system.B[0, 0] - MASS * r**2) == 0
    assert system.jump_class is JumpClass.GENERAL
    assert classify(system, [[0.0], [0.5], [-0.5]], [[0.0], [1.0]]) is JumpClass.GENERAL
    for g in (G, 0.0):
        env = gym.make("connenv/BeadOnBar-v0", g=g).unwrapped
        assert env.jump_class is classify(env.system, [[0.3]], [[0.2]]) is JumpClass.GENERAL
        assert env.control == "velocity"
    with pytest.raises(ValueError, match="'general'"):
        ActiveConstraintEnv.from_lagrangian(*lagrangian(MASS, G), u_low=-1.0, u_high=1.0, control="position")


def test_env_is_the_builders_generic_route_stepped_exactly():
    """The env's closed-form steps agree to 1e-9 with ActiveConstraintEnv.from_lagrangian on the same T and V,
    stepped by DOP853 at 1e-13 through the symbolic vector field."""
    env = gym.make("connenv/BeadOnBar-v0", mass=MASS).unwrapped
    generic = ActiveConstraintEnv.from_lagrangian(*lagrangian(MASS, G), u_low=-math.inf, u_high=math.inf, dt=env.dt,
                                                  max_control_speed=env.omega_max, integrator="dop853", rtol=1e-13,
                                                  atol=1e-13)  # fmt: skip
    env.reset(seed=0, options={"state": {"r": 0.2, "r_dot": 0.1, "theta": 0.3}})
    generic.reset(options={"state": {"q": [0.2], "p": [MASS * 0.1], "u": [0.3]}})
    for a in np.random.default_rng(0).uniform(-1, 1, 40):
        _, _, _, _, info = env.step(np.array([a], np.float32))
        _, _, _, _, reference = generic.step(np.array([a], np.float32))
        state = reference["state"]
        assert np.allclose([info["state"]["r"], info["state"]["p"], info["state"]["theta"]],
                           [state["q"][0], state["p"][0], state["u"][0]], rtol=0, atol=1e-9)  # fmt: skip


def test_energy_is_conserved_while_the_bar_is_held():
    """With θ̇ = 0 the force is conservative: E = p²/(2m) + m g r sin θ is constant along the closed form."""
    system = bead_on_bar(MASS, G)
    y, theta = np.array([0.4, -0.3]), np.array([0.6])
    energy = system.energy(y, theta[0])
    for _ in range(50):
        y = system.exact_segment(y, theta, np.array([0.0]), 0.02)
    assert abs(system.energy(y, theta[0]) - energy) < 1e-12 * (1 + abs(energy))


def test_horizontal_bar_is_the_inclusion_r_dot_nonnegative():
    """g = 0: whatever the bar does, a bead starting at rest at r₀ > 0 never moves inward and never slows down
    (r̈ = r θ̇² ≥ 0); vibrating the bar (θ̇ alternating in sign, θ staying put on average) pushes it outward."""
    env = gym.make("connenv/BeadOnBar-v0", g=0.0, max_episode_steps=10**6).unwrapped
    rng = np.random.default_rng(1)
    env.reset(seed=1, options={"state": {"r": 0.1}, "target": 0.9})
    speeds = [0.0]
    for a in rng.uniform(-0.3, 0.3, 150):
        _, _, terminated, _, info = env.step(np.array([a], np.float32))
        speeds.append(info["state"]["r_dot"])
        if terminated:
            break
    assert min(np.diff(speeds)) >= -1e-15 and info["state"]["r"] > 0.1
    env.reset(options={"state": {"r": 0.3}, "target": 0.9})
    for k in range(20):
        _, _, _, _, info = env.step(np.array([(-1.0) ** k], np.float32))
    assert abs(info["state"]["theta"]) < 1e-12 and info["state"]["r_dot"] > 0.0 and info["state"]["r"] > 0.3


@pytest.mark.parametrize("omega_max, dt", [(1.0, 0.2), (2 * math.pi, 0.02), (50.0, 0.005)])
def test_default_stepper_follows_a_tight_integration_across_rates_and_steps(omega_max, dt):
    """Random rates up to omega_max for 50 steps: the closed form within 1e-9 (relative to the state's size) of
    DOP853 at 1e-13 on the same env."""
    ends = []
    for options in ({}, {"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}):
        env = gym.make("connenv/BeadOnBar-v0", omega_max=omega_max, dt=dt, half_length=1e3, **options).unwrapped
        env.reset(seed=0, options={"state": {"r": 0.3}})
        for a in np.random.default_rng(0).uniform(-1, 1, 50):
            env.step(np.array([a], np.float32))
        ends.append(env.state.y)
    assert np.abs(ends[0] - ends[1]).max() <= 1e-9 * (1.0 + np.abs(ends[1]).max())


def test_a_diverging_stepper_raises_naming_it_and_the_rate():
    """Explicit Euler at omega_max dt = 500 multiplies the state by about 2.5e5 a step until it overflows: a
    StepperError naming the stepper and omega_max, and every observation before it finite."""
    env = gym.make("connenv/BeadOnBar-v0", g=0.0, omega_max=500.0, dt=1.0, integrator="euler").unwrapped
    env.reset(seed=0)
    with pytest.raises(StepperError, match=r"Euler.*omega_max = 500"), np.errstate(over="ignore", invalid="ignore"):
        for _ in range(200):
            assert np.all(np.isfinite(env.step(np.ones(1, np.float32))[0]))
