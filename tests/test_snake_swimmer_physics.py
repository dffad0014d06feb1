"""The three-link chain swimming in a perfect fluid: its kinetic energy from the links', Kirchhoff's equations, the
jump class, conservation laws, the mechanical connection, its holonomy and the chain's symmetries."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv.core import JumpClass, bressan_matrices, classify, make_stepper, vector_field
from connenv.core.lie import GROUPS
from connenv.systems.snake_swimmer import JOINT_LIMIT, ReducedSnakeSwimmer, SnakeSwimmer

TIGHT = {"integrator": "dop853", "rtol": 1e-12, "atol": 1e-14}
LOOP = [(0.8, 0.8), (-0.6, 0.9), (-0.9, -0.7), (0.3, -1.0), (0.5, 0.2), (0.0, 0.0)]  # a closed loop, action units


def make(**kwargs):
    return gym.make("connenv/SnakeSwimmer-v0", **kwargs).unwrapped


def run(env, actions, state=None):
    """The middle link's (x, y, θ) after the actions, from the origin at rest and straight (or `state`); each
    action repeated until the joints get there."""
    env.reset(options={"state": state or {}})
    for action in actions:
        target = np.array(action) * JOINT_LIMIT
        while np.max(np.abs(env.state.s - target)) > 0.0:
            env.step(np.array(action, float))
    return env.state.pose


def exp_se2(g, xi):
    """g exp(ξ^) on SE(2), g and ξ as (x, y, θ) and (v₁, v₂, ω)."""
    return np.array(GROUPS["SE2"].product(tuple(g), GROUPS["SE2"].exp(tuple(xi))))


def test_kinetic_energy_is_the_sum_of_the_links_own():
    """½ ξᵀ𝕀_loc ξ + ξᵀ𝕀_c ṡ + ½ ṡᵀ𝕀_s ṡ equals Σ ½ (m₁ w₁² + m₂ w₂² + j φ̇ᵢ²), each link's body velocity
    (w₁, w₂, φ̇ᵢ) taken by central differences of its pose in space along g exp(tξ), s + tṡ."""
    system = SnakeSwimmer(a=0.6, b=0.1, link_density=1.7, rho=1.3)
    lam1, lam2, lam3 = system.added_masses
    assert (lam1, lam2, lam3) == pytest.approx(1.3 * math.pi * np.array([0.01, 0.36, (0.36 - 0.01) ** 2 / 8]))
    assert system.link_mass == pytest.approx(1.7 * math.pi * 0.06)
    m1, m2, j = system.link_inertias
    rng, h = np.random.default_rng(0), 1e-6
    for _ in range(5):
        g, s, xi, s_dot = rng.normal(size=3), rng.uniform(-2, 2, 2), rng.normal(size=3), rng.normal(size=2)
        links = system.link_poses(g, s)
        rates = (system.link_poses(exp_se2(g, h * xi), s + h * s_dot) - system.link_poses(exp_se2(g, -h * xi),
                 s - h * s_dot)) / (2 * h)  # fmt: skip
        direct = 0.0
        for (_, _, phi), (dx, dy, dphi) in zip(links, rates):
            w1, w2 = math.cos(phi) * dx + math.sin(phi) * dy, -math.sin(phi) * dx + math.cos(phi) * dy
            direct += 0.5 * (m1 * w1**2 + m2 * w2**2 + j * dphi**2)
        mu = system.locked_inertia(s) @ xi + system.coupling(s) @ s_dot
        assert system.energy(mu, s, s_dot) == pytest.approx(direct, rel=1e-9)
        assert system.body_velocity(mu, s, s_dot) == pytest.approx(xi, abs=1e-13)


def test_kirchhoff_equations_are_hamiltons_equations_of_bressans_hamiltonian():
    """With p = L(θ) μ the momenta conjugate to (x, y, θ), the hand-written Kirchhoff equations and the core's
    Hamiltonian vector field of H_u (derivatives by scipy.differentiate) agree."""
    system = SnakeSwimmer()
    rng = np.random.default_rng(1)
    q, mu = rng.uniform(-1, 1, (4, 3)), rng.normal(size=(4, 3))
    s, s_dot = rng.uniform(-2, 2, (4, 2)), rng.normal(size=(4, 2))
    y_dot = system.vector_field(np.concatenate([q, mu], -1), s, s_dot)
    c, sn, w = np.cos(q[:, 2]), np.sin(q[:, 2]), y_dot[:, 2]
    p = np.stack([c * mu[:, 0] - sn * mu[:, 1], sn * mu[:, 0] + c * mu[:, 1], mu[:, 2]], -1)
    p_dot = np.stack([c * y_dot[:, 3] - sn * y_dot[:, 4] - w * (sn * mu[:, 0] + c * mu[:, 1]),
                      sn * y_dot[:, 3] + c * y_dot[:, 4] + w * (c * mu[:, 0] - sn * mu[:, 1]), y_dot[:, 5]], -1)  # fmt: skip
    reference = vector_field(system, np.concatenate([q, p], -1), s, s_dot)
    assert np.abs(reference[:, :3] - y_dot[:, :3]).max() < 1e-12
    assert np.abs(reference[:, 3:] - p_dot).max() < 1e-8


def test_core_derives_fit_for_jumps_from_the_metric():
    """Bressan's class from the metric blocks in (x, y, θ; α, β) by the generic core: K = L 𝕀_loc⁻¹ 𝕀_c ≠ 0 and
    B = 𝕀_s − 𝕀_cᵀ 𝕀_loc⁻¹ 𝕀_c the same at every pose (the joints fix the shape up to a rigid motion)."""
    system = SnakeSwimmer()
    shapes = [[0.0, 0.0], [1.2, -0.4], [-2.0, 1.9]]
    assert classify(system, [[0.0, 0.0, 0.0], [1.0, -2.0, 0.7]], shapes) is JumpClass.FIT
    rng = np.random.default_rng(2)
    s = rng.uniform(-2, 2, (5, 2))
    _, K, B = bressan_matrices(system, rng.uniform(-3, 3, (5, 3)), s)
    _, _, B_elsewhere = bressan_matrices(system, rng.uniform(-3, 3, (5, 3)), s)
    assert np.abs(B - B_elsewhere).max() < 1e-14 and np.abs(K).max() > 0.1


@pytest.mark.parametrize("integrator", [TIGHT, {}])
def test_full_model_conserves_the_spatial_momentum(integrator):
    """Over 100 steps of random joint commands from a nonzero momentum, to 1e-10 of its norm: DOP853 at rtol 1e-12
    and the default stepper (DOP853 at rtol 1e-10 on the full model)."""
    env = make(**integrator)
    _, info = env.reset(options={"state": {"x": 0.3, "theta": 0.4, "alpha": 0.5, "momentum": (0.3, -0.1, 0.05)}})
    assert info["model"] == "full"
    start = np.array(info["spatial_momentum"])
    rng, worst = np.random.default_rng(3), 0.0
    for _ in range(100):
        _, _, _, _, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        worst = max(worst, np.abs(np.array(info["spatial_momentum"]) - start).max())
    assert worst / np.linalg.norm(start) < 1e-10
    assert np.abs(np.array(info["state"]["momentum"]) - (0.3, -0.1, 0.05)).max() > 1e-2  # the body components moved


def test_energy_is_conserved_while_the_joints_are_held():
    env = make(**TIGHT)
    held = np.array([0.25, -0.5])  # (α, β) = (π/6, −π/3)
    _, info = env.reset(options={"state": {"alpha": held[0] * JOINT_LIMIT, "beta": held[1] * JOINT_LIMIT,
                                           "momentum": (0.5, 0.2, -0.3)}})  # fmt: skip

    def energy(info):
        state = info["state"]
        return env.full_system.energy(np.array(state["momentum"]), np.array([state["alpha"], state["beta"]]),
                                      np.zeros(2))  # fmt: skip

    e0 = energy(info)
    for _ in range(100):
        _, _, _, _, info = env.step(held.astype(np.float32))
    assert energy(info) == pytest.approx(e0, rel=1e-10)
    assert abs(info["state"]["theta"]) > 0.1  # it turned meanwhile


def test_full_and_reduced_models_agree_at_zero_momentum():
    """μ = 0 is invariant under Kirchhoff's equations, and there the full model moves as the connection says."""
    full, reduced = SnakeSwimmer(), ReducedSnakeSwimmer()
    stepper = make_stepper("dop853", rtol=1e-12, atol=1e-14)
    rng = np.random.default_rng(4)
    y_full, y_reduced, s = np.zeros(6), np.zeros(3), np.zeros(2)
    worst = 0.0
    for _ in range(20):
        s_cmd = rng.uniform(-1, 1, 2) * JOINT_LIMIT
        y_full = stepper(full, y_full, s, (s_cmd - s) / 0.5, 0.5)
        y_reduced = stepper(reduced, y_reduced, s, (s_cmd - s) / 0.5, 0.5)
        s = s_cmd
        worst = max(worst, np.abs(y_full[:3] - y_reduced).max(), np.abs(y_full[3:]).max())
    assert worst < 1e-10
    assert np.hypot(*y_reduced[:2]) > 0.1  # it went somewhere


@pytest.mark.parametrize("integrator, tolerance", [(TIGHT, 1e-10), ({}, 1e-10)])
def test_net_motion_of_a_closed_loop_does_not_depend_on_its_speed(integrator, tolerance):
    """The loop of joint angles run at 3 rad/s with dt = 0.05 s and at 0.7 rad/s with dt = 0.13 s ends at the same
    pose, to 1e-10 (the default Lie-group step and DOP853 at rtol 1e-12)."""
    fast, slow = make(**integrator), make(max_joint_speed=0.7, dt=0.13, **integrator)
    g_fast, g_slow = run(fast, LOOP), run(slow, LOOP)
    assert np.abs(g_slow - g_fast).max() < tolerance
    assert abs(g_fast[2]) > 0.1 and math.hypot(*g_fast[:2]) > 0.1  # and the loop did move the chain


def test_with_momentum_the_speed_of_the_loop_matters():
    """The contrast: the full model drifts with its momentum, so the same loop run slower ends elsewhere."""
    state = {"momentum": (0.1, 0.0, 0.0)}
    rk4 = {"integrator": "rk4", "substeps": 2}  # the contrast is far above its error
    g_fast, g_slow = run(make(**rk4), LOOP, state), run(make(max_joint_speed=0.7, **rk4), LOOP, state)
    assert np.abs(g_slow - g_fast).max() > 1e-2


def test_a_retraced_path_returns_to_its_start():
    """An open path of joint angles followed by the same path backwards: the holonomy of a path and of its reverse
    are inverse, and the default step (Gauss–Legendre quadrature, a symmetric rule) brings the chain back to 1e-12."""
    env = make()
    path = [(0.9, 0.1), (0.2, -0.8), (-1.0, -0.3), (-0.4, 0.7)]
    start = {"x": 0.7, "y": -0.2, "theta": 0.3, "alpha": 0.5 * JOINT_LIMIT, "beta": -0.2 * JOINT_LIMIT}
    out = run(env, path, start)
    assert np.abs(out - [0.7, -0.2, 0.3]).max() > 0.1  # it did move on the way out
    back = run(env, [*path[::-1][1:], (0.5, -0.2)], {**start, "x": out[0], "y": out[1], "theta": out[2],
                                                     "alpha": path[-1][0] * JOINT_LIMIT,
                                                     "beta": path[-1][1] * JOINT_LIMIT})  # fmt: skip
    assert np.abs(back - [0.7, -0.2, 0.3]).max() < 1e-12


def test_mirrored_and_reversed_gaits_mirror_and_reverse_the_motion():
    """Reflection across the middle link's axis maps (α, β) to (−α, −β) and the motion (x, y, θ) to (x, −y, −θ);
    turning the chain end for end maps (α, β) to (−β, −α) and the motion to (−x, −y, θ): the same loop under
    either map moves the chain so, with the default step, to rounding."""
    env = make()
    g = run(env, LOOP)
    mirrored = run(env, [(-p, -q) for p, q in LOOP])
    reversed_ = run(env, [(-q, -p) for p, q in LOOP])
    assert np.abs(mirrored - g * [1, -1, -1]).max() < 1e-12
    assert np.abs(reversed_ - g * [-1, -1, 1]).max() < 1e-12
    assert np.min(np.abs(g)) > 0.01


def test_without_fluid_the_centre_of_mass_stays_put():
    """ρ = 0: the linear momentum is the chain's mass times its centre of mass's velocity, 0 from rest, so no gait
    moves the centre of mass (a loop may still turn the chain, as a falling cat turns); in the fluid the same loop
    moves it (the added masses differ along and across each link)."""
    moved = {}
    for rho in (0.0, 1.0):
        env = make(rho=rho)
        run(env, [])
        before = env.full_system.link_poses(env.state.pose, env.state.s)[:, :2].mean(axis=0)
        run(env, LOOP)
        after = env.full_system.link_poses(env.state.pose, env.state.s)[:, :2].mean(axis=0)
        moved[rho] = (np.abs(after - before).max(), abs(env.state.pose[2]))
    assert moved[0.0][0] < 1e-9 and moved[0.0][1] > 0.05
    assert moved[1.0][0] > 0.1


@pytest.mark.parametrize("ratio", [2.0, 100.0])
def test_default_follows_the_reference_at_every_aspect_ratio(ratio):
    """The full model with links of aspect ratio a/b from 2 to 100 (the stability map's range), 50 random steps
    from a momentum: the default (DOP853 at rtol 1e-10) stays within 1e-9 of DOP853 at rtol 1e-13 and keeps the
    spatial momentum to 1e-10 of its norm."""
    shape = np.array([0.8, -0.4])
    momentum = SnakeSwimmer(b=0.5 / ratio).locked_inertia(shape) @ np.array([0.3, 0.1, 0.05])
    options = {"state": {"alpha": shape[0], "beta": shape[1], "momentum": tuple(momentum.tolist())}}
    poses = []
    for integrator in ({}, {"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}):
        env = make(b=0.5 / ratio, **integrator)
        start = np.array(env.reset(seed=0, options=options)[1]["spatial_momentum"])
        rng = np.random.default_rng(7)
        for _ in range(50):
            info = env.step(rng.uniform(-1, 1, 2))[4]
        poses.append(env.state.pose)
        assert np.linalg.norm(np.array(info["spatial_momentum"]) - start) <= 1e-10 * np.linalg.norm(start)
    assert np.abs(poses[0] - poses[1]).max() <= 1e-9


# -- the reduced model's Lie-group step (the default) --------------------------------------------------------------


@pytest.mark.parametrize("kwargs", [{}, {"max_joint_speed": 8.0, "dt": 0.2}])
def test_default_rule_meets_1e_10_on_top_speed_steps(kwargs):
    """The fixed quadrature rule SnakeSwimmer-v0 chooses at construction steps joint motions at top speed from
    random shapes to 1e-10 of DOP853 at rtol 1e-13, one state and a batch alike."""
    env = make(**kwargs)
    stepper, system, dt, speed = env.stepper, env.reduced_system, env.dt, env.max_joint_speed
    reference = make_stepper("dop853", system, rtol=1e-13, atol=1e-15)
    rng = np.random.default_rng(5)
    directions = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j], float)
    s_dot = speed * directions[rng.integers(0, 8, 6)]
    s = np.clip(rng.uniform(-1, 1, (6, 2)) * JOINT_LIMIT, -JOINT_LIMIT + speed * dt, JOINT_LIMIT - speed * dt)
    y = np.tile([0.4, -0.3, 2.0], (len(s), 1))
    exact = np.array([reference(system, *row, dt) for row in zip(y, s, s_dot)])
    alone = np.array([stepper(system, *row, dt) for row in zip(y, s, s_dot)])
    assert np.max(np.abs(alone - exact)) <= 1e-10
    assert np.max(np.abs(stepper(system, y, s, s_dot, dt) - exact)) <= 1e-10


def test_connection_on_floats_and_arrays_is_the_locked_inertia_solve():
    """group_velocity (the cofactor solve on components) equals −𝕀_loc⁻¹ 𝕀_c ṡ by numpy's solve, on floats and
    on a batch."""
    system, rng = ReducedSnakeSwimmer(a=0.7, b=0.2, link_density=2.0), np.random.default_rng(6)
    s, s_dot = rng.uniform(-2, 2, (6, 2)), rng.normal(size=(6, 2))
    solved = -(system.connection(s) @ s_dot[..., None])[..., 0]
    batch = np.stack(system.group_velocity(s, s_dot), -1)
    floats = np.array([system.group_velocity(tuple(a.tolist()), tuple(b.tolist())) for a, b in zip(s, s_dot)])
    assert np.max(np.abs(batch - solved)) <= 1e-14 and np.max(np.abs(floats - batch)) <= 1e-15
