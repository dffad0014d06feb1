"""The falling cat's physics: its connection is what the two bodies' zero angular momentum gives, it turns the cat
only about the spine, a loop's roll does not depend on the speed it is run at, small loops roll the cat by the
curvature times their area, and the exact step's quadrature is adaptive quadrature's to rounding."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm, expm_frechet

import connenv  # noqa: F401  (registers the envs)
from connenv.systems import falling_cat as cat

ID = "connenv/FallingCat-v0"
I, J, MASS, ELL = 0.01, 0.0003, 1.5, 0.12  # noqa: E741  (the transverse inertia I)
INERTIAS = {"transverse_inertia": I, "axial_inertia": J}
SHAPES = [(0.3, 0.1), (-0.2, 0.5), (1.0, -0.3), (1e-4, 2e-4), (0.0, -1.2)]


def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def bodies(s, s_dot):
    """Each half (Q, Q̇, inertia, joint → centre, its velocity) from scipy's expm and its Fréchet derivative: an
    independent account of the halves exp(±(β/2) n̂), n = (0, −sin γ, cos γ)."""
    out = []
    for sign in (1.0, -1.0):
        v, v_dot = (sign * 0.5 * np.array([0.0, -a[1], a[0]]) for a in (s, s_dot))
        Q, Q_dot = expm_frechet(hat(v), hat(v_dot))
        out.append((Q, Q_dot, Q @ np.diag([J, I, I]) @ Q.T, sign * ELL * Q[:, 0], sign * ELL * Q_dot[:, 0]))
    return out


def momentum(s, s_dot, omega):
    """The angular momentum in the cat frame about the centre of mass: the halves' spins and their centres'
    motions, the cat frame turning at Ω."""
    parts = bodies(np.asarray(s, float), np.asarray(s_dot, float))
    centre = sum(p[3] for p in parts) / 2
    centre_dot = sum(p[4] for p in parts) / 2
    total = np.zeros(3)
    for Q, Q_dot, inertia, r, r_dot in parts:
        w = Q_dot @ Q.T
        total += inertia @ (omega + np.array([w[2, 1], w[0, 2], w[1, 0]]))
        r, r_dot = r - centre, r_dot - centre_dot
        total += MASS * np.cross(r, np.cross(omega, r) + r_dot)
    return total


@pytest.mark.parametrize("s", SHAPES)
def test_the_connection_is_the_two_bodies_zero_momentum(s):
    """Ω = −A(s) ṡ solves L(Ω, ṡ) = 0 for the two bodies, L linear in (Ω, ṡ): A = I_loc⁻¹ (∂L/∂ṡ) with the
    locked inertia I_loc = ∂L/∂Ω; A has only the spine's row, f(β)/β² (−y, x)."""
    locked = np.stack([momentum(s, np.zeros(2), e) for e in np.eye(3)], -1)
    coupling = np.stack([momentum(s, e, np.zeros(3)) for e in np.eye(2)], -1)
    A = np.linalg.solve(locked, coupling)
    assert np.allclose(cat.connection(np.array(s), **INERTIAS), A, rtol=1e-12, atol=1e-13)
    beta = math.hypot(*s)
    f = cat.roll_fraction(beta, **INERTIAS)
    assert np.allclose(A[0], f / beta**2 * np.array([-s[1], s[0]]), rtol=1e-8) and np.all(A[1:] == 0.0)
    assert np.allclose(locked[0, 0], 2 * (I * math.sin(beta / 2) ** 2 + J * math.cos(beta / 2) ** 2), rtol=1e-12)


def test_angular_momentum_stays_zero_along_an_episode():
    """At every step of random bending, the two bodies' angular momentum (computed here from scipy's exponentials
    and in the env's info) is 0 to 1e-12; had the cat frame not turned, it would not be."""
    env = gym.make(ID)
    env.reset(seed=3)
    rng = np.random.default_rng(3)
    moved = 0.0
    for _ in range(25):
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2))
        state = env.unwrapped.state
        omega = -cat.connection(state.s, **INERTIAS) @ state.s_dot
        assert np.abs(momentum(state.s, state.s_dot, omega)).max() <= 1e-12
        assert np.abs(info["angular_momentum"]).max() <= 1e-12
        moved = max(moved, np.abs(momentum(state.s, state.s_dot, np.zeros(3))).max())
    assert moved > 1e-4


def polyline(vertices, speed, dt):
    """Bend velocities (k, 2), one per step, along the polyline at that speed, each leg ending on its vertex."""
    velocities = []
    for start, end in zip(vertices[:-1], vertices[1:]):
        leg = np.asarray(end, float) - start
        steps = math.ceil(np.linalg.norm(leg) / (speed * dt))
        velocities += [leg / (steps * dt)] * steps
    return np.array(velocities)


def run(velocities, dt, speed=6.0):
    env = gym.make(ID, dt=dt, fall_time=100.0)
    env.reset(options={"state": {"R": np.eye(3)}})
    for v in velocities:
        env.step(v / speed)
    return env.unwrapped.state


LOOP = [(0.0, 0.0), (0.4, 0.0), (0.1, 0.5), (-0.35, 0.2), (-0.2, -0.4), (0.4, 0.0), (0.0, 0.0)]


def test_a_closed_loop_rolls_the_cat_by_the_same_angle_at_any_speed():
    """The holonomy is geometric: the same loop at full speed, at half of it and with dt thrice smaller ends at
    the same attitude to 1e-10, back straight, turned about the spine only."""
    ends = [run(polyline(LOOP, speed, dt), dt) for speed, dt in ((6.0, 0.01), (3.0, 0.01), (6.0, 0.0033))]
    for state in ends:
        assert np.abs(state.s).max() <= 1e-14
        assert np.abs(state.g - ends[0].g).max() <= 1e-10
    g = ends[0].g.reshape(3, 3)
    assert np.allclose(g[:, 0], [1.0, 0.0, 0.0], atol=1e-15) and abs(cat.roll(g)) > 0.1


@pytest.mark.parametrize("beta", [0.2, 0.5, 1.0])
def test_small_loops_roll_the_cat_by_the_curvature_times_their_area(beta):
    """Stokes: a square of side ε centred at s, run counterclockwise, rolls the cat by −F(β) ε², F = f′(β)/β, with
    an error of order ε⁴ (relative ε²: it shrinks fourfold when ε halves)."""
    centre = beta * np.array([math.cos(0.7), math.sin(0.7)])

    def square_roll(eps):
        corners = centre + 0.5 * eps * np.array([(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)])
        return float(np.sum(cat.segment_roll(corners[:-1], np.diff(corners, axis=0), 1.0, **INERTIAS, pieces=4)))

    expected = [-cat.curvature(beta, **INERTIAS) * eps**2 for eps in (0.02, 0.01)]
    errors = [abs(square_roll(eps) / e - 1) for eps, e in zip((0.02, 0.01), expected)]
    assert errors[1] <= 1e-3 and 3.5 <= errors[0] / errors[1] <= 4.5
    h = 1e-6
    slope = (cat.roll_fraction(beta + h, **INERTIAS) - cat.roll_fraction(beta - h, **INERTIAS)) / (2 * h)
    assert cat.curvature(beta, **INERTIAS) == pytest.approx(slope / beta, rel=1e-8)


def test_the_exact_step_is_adaptive_quadrature_to_rounding():
    """Gauss–Legendre on the env's pieces against scipy.integrate.quad of −(s₀ × v) ∫ f/β² over random segments as
    long as a step at full speed allows, some close by the straight cat: to quad's own tolerance, 2e-14 relative."""
    rng = np.random.default_rng(0)
    pieces = cat.pieces_for(math.sqrt(2) * 6.0 * 0.01, **INERTIAS)
    worst = 0.0
    for k in range(24):
        s = rng.uniform(-0.8, 0.8, 2) if k % 4 else np.zeros(2) + 1e-3 * rng.normal(size=2)
        v = rng.uniform(-6.0, 6.0, 2)
        if k % 4 == 0:
            s = s - 0.005 * v  # the segment passes close by β = 0
        density = quad(lambda t: cat.roll_density(np.sum((s + t * v) ** 2), **INERTIAS), 0.0, 0.01,
                       epsabs=0.0, epsrel=2e-14, limit=200)[0]  # fmt: skip
        expected = -(s[0] * v[1] - s[1] * v[0]) * density
        worst = max(worst, abs(cat.segment_roll(s, v, 0.01, **INERTIAS, pieces=pieces) / expected - 1))
    assert worst <= 2e-14


def test_radial_bends_do_not_turn_the_cat_and_a_sweep_rolls_it_by_2pi_f():
    """Closed forms: a bend straight out and back rolls by exactly 0; a circle of radius β (as n chords) rolls by
    −2π f(β) with an error of order 1/n²; f(β₀) = 1/2 at the closed-form half-turn bend, ≈ 2√(J/I) when J ≪ I;
    f/β² → (2I − J)/(8J) at the straight cat."""
    assert cat.segment_roll(np.array([0.2, 0.1]), np.array([4.0, 2.0]), 0.05, **INERTIAS) == 0.0
    beta = 0.6
    errors = []
    for n in (200, 400):
        angles = 2 * math.pi * np.arange(n + 1) / n
        points = beta * np.stack([np.cos(angles), np.sin(angles)], -1)
        rolled = np.sum(cat.segment_roll(points[:-1], np.diff(points, axis=0), 1.0, **INERTIAS, pieces=2))
        errors.append(abs(rolled + 2 * math.pi * cat.roll_fraction(beta, **INERTIAS)))
    assert errors[1] <= 1e-4 and 3.5 <= errors[0] / errors[1] <= 4.5
    beta0 = cat.bend_for_roll(math.pi, **INERTIAS)
    c = math.cos(beta0 / 2)
    assert c == pytest.approx((math.sqrt(I * I - I * J + J * J) - J) / (I - J), rel=1e-14)
    assert cat.roll_fraction(beta0, **INERTIAS) == pytest.approx(0.5, rel=1e-13)
    slender = cat.bend_for_roll(math.pi, transverse_inertia=1.0, axial_inertia=1e-6)
    assert slender == pytest.approx(2 * math.sqrt(1e-6), rel=1e-3)
    assert cat.roll_density(0.0, **INERTIAS) == pytest.approx((2 * I - J) / (8 * J), rel=1e-15)


def test_the_magnus_and_exact_steps_agree_and_keep_the_spine():
    """The builder's sixth-order Magnus step on A(s) and the closed form give the same episode to 1e-9; both only
    ever turn the cat about its spine."""
    states = []
    for integrator in ("exact", "magnus"):
        env = gym.make(ID, integrator=integrator)
        env.reset(seed=5)
        rng = np.random.default_rng(5)
        for _ in range(40):
            env.step(rng.uniform(-1, 1, 2))
        states.append(env.unwrapped.state)
    assert np.abs(states[0].g - states[1].g).max() <= 1e-9
    spine = states[0].g.reshape(3, 3)[:, 0]
    assert np.allclose(spine, states[0].heading.reshape(3, 3)[:, 0], atol=1e-14)


def test_the_halves_bend_without_twist():
    """Q_Aᵀ Q_B is a rotation by β about the bend axis n, perpendicular to both halves' axes."""
    s = np.array([0.5, -0.7])
    Q_A, Q_B = cat.halves(s)
    relative = Q_A.T @ Q_B
    beta, gamma = math.hypot(*s), math.atan2(s[1], s[0])
    n = np.array([0.0, -math.sin(gamma), math.cos(gamma)])
    assert np.allclose(relative, expm(-beta * hat(n)), atol=1e-15)
    assert abs(n @ Q_A[:, 0]) <= 1e-15 and abs(n @ Q_B[:, 0]) <= 1e-15
