"""The shell swimming in an ideal fluid: its kinetic energy, Kirchhoff's equations, conservation laws, the
mechanical connection and its holonomy."""

import dataclasses
import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv.core import JumpClass, bressan_matrices, classify, make_stepper, vector_field
from connenv.core.lie import QUADRATURE_POINTS
from connenv.systems.kozlov_shell import KozlovShell, ReducedKozlovShell

U_MAX = np.array([0.5, 0.25])
TIGHT = {"integrator": "dop853", "rtol": 1e-12, "atol": 1e-14}
# The figure-eight, in action units: the right half of the box counter-clockwise, then its mirror clockwise.
RIGHT_LOOP = [(0, -1), (1, -1), (1, 1), (0, 1), (0, 0)]
LEFT_LOOP = [(0, -1), (-1, -1), (-1, 1), (0, 1), (0, 0)]


def make(**kwargs):
    return gym.make("connenv/KozlovShell-v0", **kwargs).unwrapped


def frame(theta):
    """L(θ) = R(θ) ⊕ 1."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def net_motion(env, actions, state=None):
    """(x, y, θ) after the actions, from the origin at rest with the mass at the centre (or `state`)."""
    env.reset(options={"state": state or {}})
    for action in actions:
        env.step(np.array(action, np.float32))
    return env.state.pose


def test_kinetic_energy_is_that_of_shell_fluid_and_mass():
    """½ ξᵀIξ + ξᵀCu̇ + ½m|u̇|² = ½M|v|² + ½Jω² + ½(λ₁v₁² + λ₂v₂² + λ₃ω²) + ½m|v + ω×u + u̇|²."""
    shell = KozlovShell(a=1.3, b=0.4, shell_mass=2.0, rho=1.5, mass=0.7)
    rng = np.random.default_rng(0)
    xi, u, u_dot = rng.normal(size=3), rng.uniform(-0.3, 0.3, 2), rng.normal(size=2)
    lam1, lam2, lam3 = shell.added_masses
    assert (lam1, lam2, lam3) == pytest.approx(1.5 * math.pi * np.array([0.4**2, 1.3**2, (1.3**2 - 0.4**2) ** 2 / 8]))
    v1, v2, omega = xi
    mass_velocity = np.array([v1 - omega * u[1], v2 + omega * u[0]]) + u_dot
    direct = 0.5 * shell.shell_mass * (v1**2 + v2**2) + 0.5 * shell.J * omega**2
    direct += 0.5 * (lam1 * v1**2 + lam2 * v2**2 + lam3 * omega**2) + 0.5 * shell.mass * mass_velocity @ mass_velocity
    mu = shell.locked_inertia(u) @ xi + shell.coupling(u) @ u_dot
    assert shell.energy(mu, u, u_dot) == pytest.approx(direct, rel=1e-14)
    assert shell.J == pytest.approx(2.0 * (1.3**2 + 0.4**2) / 4)
    assert shell.body_velocity(mu, u, u_dot) == pytest.approx(xi, rel=1e-13)


def test_kirchhoff_equations_are_hamiltons_equations_of_bressans_hamiltonian():
    """With p = L(θ) μ the momenta conjugate to (x, y, θ), the hand-written Kirchhoff equations and the core's
    Hamiltonian vector field of H_u (derivatives by scipy.differentiate) agree."""
    shell = KozlovShell()
    rng = np.random.default_rng(1)
    q, mu = rng.uniform(-1, 1, (4, 3)), rng.normal(size=(4, 3))
    u, u_dot = rng.uniform(-0.25, 0.25, (4, 2)), rng.normal(size=(4, 2))
    y_dot = shell.vector_field(np.concatenate([q, mu], -1), u, u_dot)
    q_dot, mu_dot = y_dot[:, :3], y_dot[:, 3:]
    frames = np.array([frame(theta) for theta in q[:, 2]])
    frame_dot = np.array([(frame(th + 1e-7) - frame(th - 1e-7)) / 2e-7 * w for th, w in zip(q[:, 2], q_dot[:, 2])])
    p = (frames @ mu[..., None])[..., 0]
    p_dot = (frame_dot @ mu[..., None] + frames @ mu_dot[..., None])[..., 0]
    reference = vector_field(shell, np.concatenate([q, p], -1), u, u_dot)
    assert np.abs(reference[:, :3] - q_dot).max() < 1e-12
    assert np.abs(reference[:, 3:] - p_dot).max() < 1e-8


def test_metric_blocks_make_the_shell_fit_for_jumps_but_not_strongly():
    """From the core's A, K, B of G = [[L I Lᵀ, L C], [Cᵀ Lᵀ, m]]: K = L I⁻¹ C ≠ 0, and B = m − Cᵀ I⁻¹ C is the
    same at every pose q, so ∂B/∂q = 0 (Bressan's 'fit for jumps')."""
    shell = KozlovShell()
    rng = np.random.default_rng(2)
    u = rng.uniform(-0.25, 0.25, (5, 2))
    _, K, B = bressan_matrices(shell, rng.uniform(-3, 3, (5, 3)), u)
    _, _, B_elsewhere = bressan_matrices(shell, rng.uniform(-3, 3, (5, 3)), u)
    I, C = shell.locked_inertia(u), shell.coupling(u)
    assert np.abs(B - B_elsewhere).max() < 1e-14
    assert np.abs(B - (shell.mass * np.eye(2) - np.swapaxes(C, -1, -2) @ np.linalg.solve(I, C))).max() < 1e-14
    assert np.abs(K).max() > 0.1


def test_core_classifies_the_shell_as_fit_for_jumps():
    """Bressan's classification by the generic core, from the metric blocks in (x, y, θ; u)."""
    assert classify(KozlovShell(), [[0.0, 0.0, 0.0], [1.0, -2.0, 0.7]], [[0.1, 0.2], [-0.3, 0.1]]) is JumpClass.FIT


@pytest.mark.parametrize("integrator, tolerance", [(TIGHT, 1e-10), ({}, 1e-8)])
def test_full_model_conserves_the_spatial_momentum(integrator, tolerance):
    """Over a 300-step episode of random mass motions from a nonzero momentum; the default stepper is held to
    the 1e-8 it was chosen by."""
    env = make(**integrator)
    _, info = env.reset(options={"state": {"x": 0.3, "theta": 0.4, "momentum": (0.3, -0.1, 0.05)}})
    assert info["model"] == "full"
    start = np.array(info["spatial_momentum"])
    rng, worst = np.random.default_rng(3), 0.0
    for _ in range(300):
        _, _, _, _, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        worst = max(worst, np.abs(np.array(info["spatial_momentum"]) - start).max())
    assert worst / np.linalg.norm(start) < tolerance
    assert np.abs(np.array(info["state"]["momentum"]) - (0.3, -0.1, 0.05)).max() > 1e-2  # the body components moved


def test_energy_and_linear_momentum_magnitude_are_conserved_while_the_mass_is_held():
    env = make(**TIGHT)
    _, info = env.reset(options={"state": {"u": (0.25, -0.125), "momentum": (0.5, 0.2, -0.3)}})
    held = np.array([0.5, -0.5], np.float32)  # u = (0.25, −0.125) exactly

    def energy(info):
        return env.full_system.energy(np.array(info["state"]["momentum"]), np.array(info["state"]["u"]), np.zeros(2))

    e0, p0 = energy(info), math.hypot(*info["state"]["momentum"][:2])
    for _ in range(100):
        _, _, _, _, info = env.step(held)
    assert energy(info) == pytest.approx(e0, rel=1e-10)
    assert math.hypot(*info["state"]["momentum"][:2]) == pytest.approx(p0, rel=1e-10)
    assert abs(info["state"]["theta"]) > 0.1  # it spun meanwhile


def test_full_and_reduced_models_agree_at_zero_momentum():
    """μ = 0 is invariant under Kirchhoff's equations, and there the full model moves as the connection says.
    (The adaptive steps differ: the error norm averages over 6 components in one and 3 in the other.)"""
    full, reduced = KozlovShell(), ReducedKozlovShell()
    stepper = make_stepper("dop853", rtol=1e-12, atol=1e-14)
    rng = np.random.default_rng(4)
    y_full, y_reduced, u = np.zeros(6), np.zeros(3), np.zeros(2)
    worst = 0.0
    for _ in range(200):
        u_cmd = rng.uniform(-1, 1, 2) * U_MAX
        y_full = stepper(full, y_full, u, (u_cmd - u) / 0.1, 0.1)
        y_reduced = stepper(reduced, y_reduced, u, (u_cmd - u) / 0.1, 0.1)
        u = u_cmd
        worst = max(worst, np.abs(y_full[:3] - y_reduced).max(), np.abs(y_full[3:]).max())
    assert worst < 1e-10
    assert np.hypot(*y_reduced[:2]) > 0.01  # it went somewhere


def test_env_picks_the_model_the_start_needs():
    env = make()
    assert env.reset(seed=0)[1]["model"] == "reduced"
    assert env.reset(options={"state": {"momentum": (0.0, 0.0, 0.0)}})[1]["model"] == "reduced"
    assert env.reset(options={"state": {"momentum": (0.0, 0.0, 1e-3)}})[1]["model"] == "full"


LOOP = [(1, -1), (1, 1), (-1, 1), (-0.3, -1), (0.2, 0.4), (0, 0)]  # an irregular closed loop of the mass


@pytest.mark.parametrize("integrator, tolerance", [(TIGHT, 1e-10), ({}, 1e-8)])
def test_net_motion_of_a_closed_loop_does_not_depend_on_its_speed(integrator, tolerance):
    """Run 3.7 times slower, the loop ends at the same pose (the default stepper within its 1e-8)."""
    slow, fast = make(dt=0.37, **integrator), make(dt=0.1, **integrator)
    g_slow, g_fast = net_motion(slow, LOOP), net_motion(fast, LOOP)
    assert np.abs(g_slow - g_fast).max() < tolerance
    assert abs(g_slow[2]) > 0.1  # and the loop did turn the shell


def test_with_momentum_the_speed_of_the_loop_matters():
    """The contrast: the full model drifts with its momentum, so the same loop run slower ends elsewhere."""
    state = {"momentum": (0.1, 0.0, 0.0)}
    g_slow, g_fast = net_motion(make(dt=0.37, **TIGHT), LOOP, state), net_motion(make(dt=0.1, **TIGHT), LOOP, state)
    assert np.abs(g_slow - g_fast).max() > 1e-2


def test_figure_eight_translates_without_net_turn():
    """The right loop turns the shell; its mirror image, run the other way, undoes the turn exactly
    (x ↦ −x, θ ↦ −θ, by the mirror symmetry of the ellipse), and the figure-eight is left with a translation."""
    env = make(**TIGHT)
    right, left = net_motion(env, RIGHT_LOOP), net_motion(env, LEFT_LOOP)
    eight = net_motion(env, RIGHT_LOOP + LEFT_LOOP)
    assert abs(right[2]) > 0.5
    assert np.abs(left - right * [-1, 1, -1]).max() < 1e-10
    assert abs(eight[2]) <= 1e-10
    assert math.hypot(*eight[:2]) > 0.05
    twice = net_motion(env, 2 * (RIGHT_LOOP + LEFT_LOOP))  # translations add along a straight line
    assert twice[:2] == pytest.approx(2 * eight[:2], abs=1e-10) and abs(twice[2]) <= 1e-10


def test_a_circular_shell_cannot_swim():
    """a = b: λ₁ = λ₂, and (M + m + λ) x + m R(θ) u is conserved, so a loop of u that starts and ends at the
    centre leaves the centre where it was, although it may turn the shell."""
    env = make(a=0.8, b=0.8, u1_max=0.4, u2_max=0.4, **TIGHT)
    rng = np.random.default_rng(5)
    loop = [*rng.uniform(-1, 1, (20, 2)), (0, 0)]
    g = net_motion(env, loop)
    assert np.abs(g[:2]).max() < 1e-10
    assert abs(g[2]) > 1e-3


@pytest.mark.parametrize("axis, action", [(0, (1.0, 0.0)), (1, (0.0, -1.0))])
def test_moving_the_mass_along_a_principal_axis_shifts_the_shell_back_by_the_mass_ratio(axis, action):
    """u moved by Δ along body x (y) from the centre: the shell moves by −m Δ/(M + m + λ₁) (λ₂), without turning."""
    env = make()
    g = net_motion(env, [action])
    shell = env.full_system
    delta = action[axis] * U_MAX[axis]
    expected = -shell.mass * delta / (shell.shell_mass + shell.mass + shell.added_masses[axis])
    assert g[axis] == pytest.approx(expected, rel=1e-12) and g[1 - axis] == 0.0 and g[2] == 0.0


# -- the reduced model's Lie-group step (the default) --------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs", [{}, {"mass": 5.0, "dt": 0.25}, {"a": 1.5, "b": 0.3, "u1_max": 1.2, "u2_max": 0.15, "dt": 0.05}]
)
def test_default_rule_meets_1e_10_on_corner_to_corner_steps_and_is_the_cheapest(kwargs):
    """The fixed quadrature rule KozlovShell-v0 chooses at construction (pieces × Gauss points, by Richardson)
    steps every straight motion between two corners of the box in one dt, the fastest admissible, to 1e-10 of
    DOP853 at rtol 1e-13, one state and a batch alike; the rule with one Gauss point fewer misses 1e-10."""
    env = gym.make("connenv/KozlovShell-v0", **kwargs).unwrapped
    stepper, system, dt = env.stepper, env.reduced_system, env.dt
    reference = make_stepper("dop853", system, rtol=1e-13, atol=1e-15)
    corners = [np.array([i, j]) * env.u_max for i in (-1, 1) for j in (-1, 1)]
    u = np.array([a for a in corners for b in corners if np.any(a != b)])
    u_dot = np.array([(b - a) / dt for a in corners for b in corners if np.any(a != b)])
    y = np.tile([0.4, -0.3, 2.0], (len(u), 1))
    exact = np.array([reference(system, *row, dt) for row in zip(y, u, u_dot)])
    alone = np.array([stepper(system, *row, dt) for row in zip(y, u, u_dot)])
    assert np.max(np.abs(alone - exact)) <= 1e-10
    assert np.max(np.abs(stepper(system, y, u, u_dot, dt) - exact)) <= 1e-10
    coarser = dataclasses.replace(stepper, points=stepper.points - 1)
    if stepper.points > QUADRATURE_POINTS:
        assert max(np.max(np.abs(coarser(system, *row, dt) - e)) for *row, e in zip(y, u, u_dot, exact)) > 1e-10


def test_connection_along_a_straight_path_is_the_connection_at_its_points():
    """segment_velocity's rational ω(t) and its (v₁, v₂) along u + t u̇ equal group_velocity at those shapes (to
    rounding), and group_velocity on floats equals it on arrays."""
    system, rng = ReducedKozlovShell(a=1.2, b=0.4, mass=0.7), np.random.default_rng(3)
    u, u_dot, t = rng.uniform(-0.3, 0.3, (6, 2)), rng.normal(size=(6, 2)) * 5, rng.uniform(0, 0.1, (9, 1))
    along = np.stack(system.segment_velocity(u, u_dot, t))
    at_points = np.stack(system.group_velocity(u + t[..., None] * u_dot, np.broadcast_to(u_dot, (9, 6, 2))))
    assert np.max(np.abs(along - at_points)) <= 1e-14
    floats = [system.group_velocity(tuple(a.tolist()), tuple(b.tolist())) for a, b in zip(u, u_dot)]
    assert np.max(np.abs(np.array(floats).T - np.stack(system.group_velocity(u, u_dot)))) <= 1e-15
