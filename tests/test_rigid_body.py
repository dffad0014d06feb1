"""The free rigid body: the elliptic solution solves Euler's equations and keeps E and |M|, its period, and the
phase of the attitude over one period, Δθ = 2ET/|M| − Λ (Montgomery 1991), near the stable axes and the
separatrix."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from connenv.core import StepperError
from connenv.systems.rigid_body import (
    RigidBody,
    advance,
    energy,
    euler,
    make_stepper,
    orbit,
    state,
)

BODIES = ((1.0, 2.0, 2.5), (0.3, 0.9, 1.0), (2.0, 2.1, 3.5))


def start(inertia, two_E, sign=1.0):
    """The |M| = 1 on the plane M₂ = 0 (every orbit crosses it) with Σ M_i²/I_i = 2E; sign: that of M₃."""
    I1, _, I3 = inertia
    x = (1.0 / I3 - two_E) / (1.0 / I3 - 1.0 / I1)
    return np.array([math.sqrt(x), 0.0, sign * math.sqrt(1.0 - x)])


def regimes(inertia):
    """(name, M(0)) near both stable axes, at M² = 2 E I₂ (1 ± 1e-4) on both sides of the separatrix, and between."""
    I1, I2, I3 = inertia
    return {
        "near axis 3": start(inertia, (1.0 + 1e-3) / I3),
        "near axis 1": start(inertia, (1.0 - 1e-3) / I1, -1.0),
        "above separatrix": start(inertia, 1.0 / (I2 * (1.0 + 1e-4)), -1.0),
        "below separatrix": start(inertia, 1.0 / (I2 * (1.0 - 1e-4))),
        "between": start(inertia, 0.5 * (1.0 / I2 + 1.0 / I3)),
    }


CASES = [(inertia, name, M) for inertia in BODIES for name, M in regimes(inertia).items()]
IDS = [f"{inertia}-{name}" for inertia, name, _ in CASES]


POINTS = 4096  # of the midpoint rule for Λ


def solid_angle(M, inertia, axis):
    """Λ/T, the mean of a·(n × ṅ)/(1 + a·n) over one period of M(t) sampled at the midpoints of equal intervals
    (M of shape (points, 3)), n = M/|M|, ṅ from Euler's equations, a the axis the loop circles: Λ is the area the
    loop encloses, counterclockwise about a positive. The integrand is smooth and periodic: the midpoint rule is
    spectrally accurate."""
    n = M / np.linalg.norm(M, axis=-1, keepdims=True)
    n_dot = euler(M, inertia) / np.linalg.norm(M, axis=-1, keepdims=True)
    return np.mean(np.cross(n, n_dot) @ axis / (1.0 + n @ axis))


@pytest.mark.parametrize("inertia, name, M0", CASES, ids=IDS)
def test_attitude_turns_by_dynamic_minus_geometric_phase(inertia, name, M0):
    """Over one period T of M, R(T) R(0)ᵀ (the attitude reconstructed by the Magnus steps) is a turn about the
    spatial momentum m = R M by Δθ = 2ET/|M| − Λ mod 2π, to 1e-8."""
    body = RigidBody(inertia)
    path = orbit(M0, body.inertia)
    T = float(path.period)
    R0 = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    R1 = advance(body, state(M0, R0), T)[3:].reshape(3, 3)
    turn = R1 @ R0.T
    m = R0 @ M0
    rotvec = Rotation.from_matrix(turn).as_rotvec()
    assert np.linalg.norm(turn @ m - m) <= 1e-10
    assert np.linalg.norm(np.cross(rotvec, m / np.linalg.norm(m))) <= 1e-9
    measured = rotvec @ m / np.linalg.norm(m)
    axis = path.sign * (np.array([0.0, 0.0, 1.0]) if path.r3 else np.array([1.0, 0.0, 0.0]))
    Lambda = solid_angle(path.momentum((np.arange(POINTS) + 0.5) * T / POINTS), body.inertia, axis) * T
    predicted = 2.0 * energy(M0, body.inertia) * T / np.linalg.norm(M0) - Lambda
    assert abs(math.remainder(measured - predicted, 2.0 * math.pi)) <= 1e-8


@pytest.mark.parametrize("inertia, name, M0", CASES[:5], ids=IDS[:5])
def test_elliptic_solution_solves_eulers_equations(inertia, name, M0):
    """M(t) agrees with DOP853 at rtol 1e-13 over a period, its central differences with M × I⁻¹M, and it keeps E
    and |M| to 1e-12."""
    path = orbit(M0, inertia)
    T = float(path.period)
    solution = solve_ivp(lambda t, M: euler(M, inertia), (0.0, T), M0, "DOP853", rtol=1e-13, atol=1e-15,
                         dense_output=True)  # fmt: skip
    t = np.linspace(0.0, T, 101)
    M = path.momentum(t)
    assert np.max(np.abs(M - solution.sol(t).T)) <= 1e-10
    h = 1e-5
    difference = (path.momentum(t + h) - path.momentum(t - h)) / (2.0 * h)
    assert np.max(np.abs(difference - euler(M, inertia))) <= 1e-8
    assert np.max(np.abs(energy(M, inertia) / energy(M0, inertia) - 1.0)) <= 1e-12
    assert np.max(np.abs(np.linalg.norm(M, axis=-1) - 1.0)) <= 1e-12


@pytest.mark.parametrize("inertia", BODIES)
def test_period(inertia):
    """M(T) = M(0) to 1e-12; half a period on, M is its mirror through the axis it circles (cn and sn change sign,
    dn not); near the axis of largest inertia T tends to the small-oscillation period 2π/Ω,
    Ω² = (M/I₃)² (I₃ − I₁)(I₃ − I₂)/(I₁ I₂), to first order in the amplitude squared."""
    for M0 in regimes(inertia).values():
        path = orbit(M0, inertia)
        T = float(path.period)
        assert np.max(np.abs(path.momentum(T) - M0)) <= 1e-12
        mirror = np.array([-1.0, -1.0, 1.0]) if path.r3 else np.array([1.0, -1.0, -1.0])
        assert np.max(np.abs(path.momentum(T / 2) - mirror * M0)) <= 1e-12
    I1, I2, I3 = inertia
    M0 = start(inertia, (1.0 + 1e-6) / I3)
    small = 2.0 * math.pi / math.sqrt((1.0 / I3) ** 2 * (I3 - I1) * (I3 - I2) / (I1 * I2))
    assert float(orbit(M0, inertia).period) == pytest.approx(small, rel=1e-5)


def test_exact_flow_agrees_with_dop853_and_keeps_the_spatial_momentum():
    """Over 10 steps of 2 s the exact flow (elliptic M, Magnus R) matches DOP853 at rtol 1e-13 on (M, R) to 1e-10,
    keeps m = R M to 1e-12 and R on SO(3); a batch of states steps row by row as the single states (to
    rounding: one state goes through Python floats)."""
    body = RigidBody()
    y = state([0.4, -0.8, 0.5], Rotation.from_rotvec([0.1, 0.7, -0.4]).as_matrix())
    reference, exact = y, y
    tight = make_stepper("dop853", rtol=1e-13, atol=1e-15)
    for _ in range(10):
        exact, reference = advance(body, exact, 2.0), advance(body, reference, 2.0, tight)
    assert np.max(np.abs(exact - reference)) <= 1e-10
    m0, m1 = body.invariants(y)[2], body.invariants(exact)[2]
    assert np.max(np.abs(m1 - m0)) <= 1e-12
    R = exact[3:].reshape(3, 3)
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-13
    batch = np.stack([y, state([-1.0, 0.2, 0.1])])
    stepped = advance(body, batch, 2.0)
    assert np.max(np.abs(stepped[0] - advance(body, y, 2.0))) <= 1e-13


def test_splitting_keeps_norm_and_spatial_momentum_and_is_second_order():
    """Strang's splitting keeps |M| and m = R M to rounding at any step; its error after 4 s falls 4-fold per
    halving of the step (second order)."""
    body = RigidBody()
    y = state([0.4, -0.8, 0.5])
    exact = advance(body, y, 4.0)
    errors = []
    for substeps in (20, 40, 80):
        split = advance(body, y, 4.0, make_stepper("splitting", substeps=substeps))
        E, norm, m = body.invariants(split)
        assert abs(norm - body.invariants(y)[1]) <= 1e-14
        assert np.max(np.abs(m - body.invariants(y)[2])) <= 1e-14
        errors.append(np.max(np.abs(split - exact)))
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.05)


def test_unstable_equilibrium_is_handed_to_dop853():
    """M along the middle axis (on the separatrix, where the elliptic formula is singular) stays there."""
    body = RigidBody()
    y = state([0.0, 1.0, 0.0])
    assert np.array_equal(advance(body, y, 1.0)[:3], [0.0, 1.0, 0.0])


def test_bad_input_and_divergence():
    """Bad inertias, momenta, attitudes, steps and stepper names get a ValueError naming them; a diverging stepper
    raises StepperError."""
    for inertia, word in (((2.0, 1.0, 2.5), "increasing"), ((1.0, 1.0, 1.5), "increasing"),
                          ((1.0, 2.0, 3.5), "I₃"), ((1.0, math.nan, 2.0), "inertia"), ((1.0, 2.0), "inertia")):  # fmt: skip
        with pytest.raises(ValueError, match=word):
            RigidBody(inertia)
    with pytest.raises(ValueError, match="max_turn"):
        RigidBody(max_turn=0.0)
    with pytest.raises(ValueError, match="M="):
        state([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="R="):
        state([1.0, 0.0, 0.0], 2.0 * np.eye(3))
    with pytest.raises(ValueError, match="tau"):
        advance(RigidBody(), state([1.0, 0.0, 0.0]), -1.0)
    with pytest.raises(ValueError, match="integrator"):
        make_stepper("verlet")
    with pytest.raises(ValueError, match="substeps"):
        make_stepper("splitting", substeps=0)
    y, rk4 = state([0.4, -0.8, 0.5]), make_stepper("rk4")
    with pytest.raises(StepperError), np.errstate(all="ignore"):
        for _ in range(100):
            y = advance(RigidBody(), y, 50.0, rk4)


def test_bench_charts_the_exact_flow_below_splitting_and_rk4s_limit_below_it(tmp_path):
    """The bench on short runs: after 3 steps of 0.5 s the exact flow errs by less than 1e-10 and Strang's splitting
    with one substep by more than 1e-6; on the stability map the exact flow holds at dt = 1 s where RK4 needs a
    shorter step."""
    from connenv.bench import rigid_body

    steppers = [rigid_body.DEFAULT, ("splitting", {"substeps": 1})]
    rows, csv_path, png_path = rigid_body.precision_chart(tmp_path, fraction=0.05, steppers=steppers)
    exact, split = rows
    assert exact["default"] and exact["error"] < 1e-10 < 1e-6 < split["error"]
    assert csv_path.exists() and png_path.stat().st_size > 10_000
    methods = [("exact", {"max_turn": 0.05}), ("rk4", {"substeps": 1})]
    maps = rigid_body.stability_chart(tmp_path, smallest=1e-2, values=(10.0,), methods=methods)[0]
    assert maps["exact max_turn 0.05"][10.0] == 1.0 and 0.0 < maps["rk4 ×1"][10.0] < 1.0
