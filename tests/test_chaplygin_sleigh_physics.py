"""The Chaplygin sleigh steered by a moving mass: the derivation, the classical sleigh's closed form, energy, the
jump class by Bressan–Rampazzo's criterion, and what the class means for a jump of the mass."""

import math

import gymnasium as gym
import numpy as np
import pytest
import sympy as sp

import connenv  # noqa: F401  (registers the envs)
from connenv.core.mechanics import JumpClass
from connenv.core.steppers import Scipy
from connenv.systems.chaplygin_sleigh import ChaplyginSleigh

EXACT = Scipy("DOP853", rtol=1e-13, atol=1e-14)
M, J, A, m = 1.0, 0.1, 0.5, 0.5


def flow(system, y, u, u_dot, duration, pieces=1):
    """y after `duration` at constant u̇ from u (numbers: the rail, u₁ = 0; or pairs (u₁, u₂)), in `pieces`
    segments."""
    u, u_dot = (np.array([0.0, x]) if np.ndim(x) == 0 else np.asarray(x, float) for x in (u, u_dot))
    for i in range(pieces):
        tau = duration / pieces
        y = EXACT(system, y, u + i * tau * u_dot, u_dot, tau)
    return y


def rail(x):
    return np.array([0.0, x])


def classical(v0, omega0, t, total=M + m, inertia=J, offset=A):
    """§ the classical sleigh: v = V tanh(cVt + t₀), ω = ±V √(M_t / I_P) sech(cVt + t₀), I_P = J + M_t a²."""
    i_p = inertia + total * offset**2
    c = total * offset / i_p
    V = math.sqrt((total * v0**2 + i_p * omega0**2) / total)
    t0 = math.atanh(v0 / V)
    return V * math.tanh(c * V * t + t0), math.copysign(V * math.sqrt(total / i_p), omega0) / math.cosh(c * V * t + t0)


@pytest.mark.parametrize("v0, omega0", [(0.0, 1.0), (-0.4, 0.7), (0.3, -2.0)])
def test_with_the_mass_held_at_C_it_is_the_classical_sleigh(v0, omega0):
    system = ChaplyginSleigh(M, J, A, m)
    zero = rail(0.0)
    y = np.array([0.0, 0.0, 0.0, *system.momenta(v0, omega0, zero, zero)])
    e0 = system.energy(y, zero, zero)
    worst, drift = 0.0, 0.0
    for t in range(1, 11):
        y = flow(system, y, 0.0, 0.0, 1.0)
        v, omega = system.velocities(y, zero, zero)
        worst = max(worst, abs(v - classical(v0, omega0, t)[0]), abs(omega - classical(v0, omega0, t)[1]))
        drift = max(drift, abs(system.energy(y, zero, zero) - e0))
    assert worst < 1e-9
    assert drift < 1e-10


def test_energy_is_conserved_with_the_mass_held_off_centre():
    system = ChaplyginSleigh(M, J, A, m)
    u, zero = np.array([-0.1, 0.25]), rail(0.0)
    y = np.array([0.3, -0.2, 1.0, *system.momenta(-0.5, 1.2, u, zero)])
    e0 = system.energy(y, u, zero)
    y = flow(system, y, u, zero, 10.0, pieces=10)
    assert abs(system.energy(y, u, zero) - e0) < 1e-10


def lagrange_dalembert():
    """ṗ = d/dt (∂T/∂v, ∂T/∂ω) from T in inertial coordinates (x, y, φ, u₁, u₂) with the knife edge's multiplier,
    u assigned (u, u̇, ü given), at φ = 0 (rotation invariance); and the free motion's (u free too)."""
    t = sp.Symbol("t")
    x, y, phi, u1, u2 = (sp.Function(name)(t) for name in ("x", "y", "phi", "u1", "u2"))
    e1, e2 = sp.Matrix([sp.cos(phi), sp.sin(phi)]), sp.Matrix([-sp.sin(phi), sp.cos(phi)])
    C = sp.Matrix([x, y]) + sp.nsimplify(A) * e1
    mass = C + u1 * e1 + u2 * e2
    speed2 = lambda r: (r.diff(t).T * r.diff(t))[0]  # noqa: E731
    L = sp.nsimplify(M) * speed2(C) / 2 + sp.nsimplify(J) * phi.diff(t) ** 2 / 2 + sp.nsimplify(m) * speed2(mass) / 2
    lam = sp.Symbol("lambda")
    knife = [-sp.sin(phi), sp.cos(phi), 0, 0, 0]  # −sin φ ẋ + cos φ ẏ = 0
    coords = (x, y, phi, u1, u2)
    equations = [L.diff(c.diff(t)).diff(t) - L.diff(c) - lam * w for c, w in zip(coords, knife)]
    s1, s2, v, w, d1, d2, a1, a2, vd, wd = sp.symbols("u1 u2 v omega d1 d2 a1 a2 v_dot omega_dot", real=True)
    on_constraint = {x.diff(t, 2): vd * sp.cos(phi) - v * w * sp.sin(phi), y.diff(t, 2): vd * sp.sin(phi)
                     + v * w * sp.cos(phi), phi.diff(t, 2): wd, u1.diff(t, 2): a1, u2.diff(t, 2): a2,
                     x.diff(t): v * sp.cos(phi), y.diff(t): v * sp.sin(phi), phi.diff(t): w, u1.diff(t): d1,
                     u2.diff(t): d2}
    equations = [sp.expand(e.subs(on_constraint).subs({u1: s1, u2: s2, phi: 0})) for e in equations]
    steered = sp.solve(equations[:3], [vd, wd, lam], dict=True)[0]
    free = sp.solve(equations, [vd, wd, a1, a2, lam], dict=True)[0]
    T = L.subs(on_constraint).subs({u1: s1, u2: s2, phi: 0})
    p = sp.Matrix([sp.expand(T).diff(v), sp.expand(T).diff(w)])  # ∂T/∂v, ∂T/∂ω on the constraint
    p_rate = {}
    for name, acc in (("steered", steered), ("free", free)):
        rates = {s1: d1, s2: d2, v: acc[vd], w: acc[wd], d1: acc.get(a1, a1), d2: acc.get(a2, a2)}
        p_rate[name] = [sp.simplify(sum(e.diff(k) * r for k, r in rates.items())) for e in p]
    return (s1, s2, v, w, d1, d2, a1, a2), p, p_rate


@pytest.fixture(scope="module")
def derivation():
    return lagrange_dalembert()


def test_the_module_equations_are_lagrange_dalembert(derivation):
    """The module's ṗ = (ω P_w, −v P_w) is d/dt of the momenta under the constrained Lagrangian motion, whatever ü."""
    (s1, s2, v, w, d1, d2, a1, a2), p, p_rate = derivation
    system = ChaplyginSleigh(M, J, A, m)
    rng = np.random.default_rng(0)
    for _ in range(5):
        numbers = rng.uniform(-1, 1, 8)
        values = dict(zip((s1, s2, v, w, d1, d2, a1, a2), numbers))
        u, u_dot = numbers[:2], numbers[4:6]
        y = np.array([0.0, 0.0, 0.0, *(float(e.subs(values)) for e in p)])
        assert system.momenta(numbers[2], numbers[3], u, u_dot) == pytest.approx(y[3:], abs=1e-12)
        expected = [float(e.subs(values)) for e in p_rate["steered"]]
        assert system.vector_field(y, u, u_dot)[3:] == pytest.approx(expected, abs=1e-12)
        assert system.velocities(y, u, u_dot) == pytest.approx(numbers[2:4], abs=1e-12)


def test_bressan_rampazzo_the_orthogonal_bundle_is_not_geodesically_invariant(derivation):
    """D = {p = 0}: a free motion (u free too) starting in D leaves it at the rate the module's orthogonal_drift
    gives, ∝ u̇², not 0, with the knife edge behind C (a > 0): not fit for jumps. The class follows."""
    (s1, s2, v, w, d1, d2, a1, a2), p, p_rate = derivation
    system = ChaplyginSleigh(M, J, A, m)
    for u, u_dot in (((0.0, 0.2), (0.0, 1.5)), ((0.1, -0.2), (1.0, 1.0))):
        G11, G12 = system.metric(np.array(u))
        on_d = -np.linalg.solve(G11, G12 @ np.array(u_dot))  # (v, ω) = −K u̇: p = 0
        values = {s1: u[0], s2: u[1], v: on_d[0], w: on_d[1], d1: u_dot[0], d2: u_dot[1]}
        free = np.array([float(e.subs(values)) for e in p_rate["free"]])
        assert free == pytest.approx(system.orthogonal_drift(u, u_dot), abs=1e-12)
        assert np.max(np.abs(free)) > 0.02  # not 0: D is not invariant
    on_rail = [(0.0, x) for x in np.linspace(-0.3, 0.3, 7)]
    assert system.jump_class(on_rail, directions=[(0.0, 1.0)]) is JumpClass.GENERAL
    assert ChaplyginSleigh(M, J, 0.0, m).jump_class(on_rail, directions=[(0.0, 1.0)]) is JumpClass.FIT  # a = 0
    assert gym.make("connenv/ChaplyginSleigh-v0").unwrapped.control == "velocity"
    assert gym.make("connenv/ChaplyginSleigh-v0", box=0.0, offset=0.0).unwrapped.control == "position"
    assert gym.make("connenv/ChaplyginSleigh-v0", offset=0.0).unwrapped.control == "velocity"  # the box: u₁ shifts a


def test_from_rest_the_rail_pushes_straight_back_and_diagonal_shaking_turns():
    """On D the rail's thrust is backward (ṗ₁ < 0) with a torque only m u₂/M_t of it; shaking along and across
    together gives the torque m² J u̇₁ u̇₂ / (M_t (J + M_t a²)) at u = 0, its sign that of u̇₁ u̇₂."""
    system = ChaplyginSleigh(M, J, A, m)
    total, i_p = M + m, J + (M + m) * A**2
    thrust, torque = system.orthogonal_drift((0.0, 0.3), (0.0, 2.0))
    assert thrust < 0.0 and abs(torque) == pytest.approx(m * 0.3 / total * abs(thrust), rel=1e-12)
    for sign in (1.0, -1.0):
        assert system.orthogonal_drift((0.0, 0.0), (sign, 1.0))[1] == pytest.approx(
            sign * m**2 * J / (total * i_p), rel=1e-12)


def momentum_after_ramp(speed, offset=A):
    """p after the mass moves across from u = 0 to 0.2 at the given speed, the sleigh at rest before."""
    system = ChaplyginSleigh(M, J, offset, m)
    return flow(system, np.zeros(5), 0.0, speed, 0.2 / speed)[3:]


def test_not_fit_a_fast_move_of_the_mass_is_a_kick_growing_with_its_speed():
    """General class: from rest, p after a move of the mass grows in proportion to its speed (the ṗ ∝ u̇² term),
    so no jump limit exists; the sleigh is pushed backward (p₁ < 0)."""
    slow, fast = momentum_after_ramp(1.0), momentum_after_ramp(100.0)
    assert fast[0] < 0.0
    assert fast == pytest.approx(100.0 * slow, rel=1e-6)


def test_fit_at_zero_offset_a_jump_is_the_limit_of_ever_faster_moves():
    """a = 0: fit. A jump of the mass (max_mass_speed=None) is the limit of ramps at speed → ∞ from a moving state."""
    state = {"v": 0.4, "omega": -0.8}
    rail_only = {"offset": 0.0, "box": 0.0}
    env = gym.make("connenv/ChaplyginSleigh-v0", **rail_only, max_mass_speed=None, dt=1e-9).unwrapped
    env.reset(options={"state": state})
    _, _, _, _, jumped = env.step(np.array([0.0, 0.5]))
    errors = []
    for speed in (1e3, 1e4):
        env = gym.make("connenv/ChaplyginSleigh-v0", **rail_only, max_mass_speed=speed, dt=0.15 / speed).unwrapped
        env.reset(options={"state": state})
        _, _, _, _, ramped = env.step(np.array([0.0, 0.5]))
        errors.append(max(abs(ramped["state"][k] - jumped["state"][k]) for k in ("x", "y", "phi", "v", "omega")))
    assert errors[1] < errors[0] / 5 and errors[1] < 1e-4
    assert jumped["state"]["u"] == 0.15 and abs(jumped["state"]["omega"] + 0.8) > 1e-3  # the jump moves the sleigh


def test_paths_from_rest_do_not_depend_on_the_speed_of_the_mass():
    """Every term of the equations is quadratic in (v, ω, u̇): from rest, u(t/λ) traces the same path as u(t)."""
    system = ChaplyginSleigh(M, J, A, m)
    paths = []
    for speed in (1.0, 3.0):
        y = flow(system, np.zeros(5), (0.0, 0.0), (speed, speed), 0.3 / speed)
        y = flow(system, y, (0.3, 0.3), (-speed, 0.0), 0.5 / speed)
        paths.append(y)
    assert paths[1][:3] == pytest.approx(paths[0][:3], abs=1e-11)
    assert paths[1][3:] == pytest.approx(3.0 * paths[0][3:], abs=1e-11)
