"""The fixed-step methods (explicit and semi-implicit Euler, RK4) on systems with known answers, and adaptive
steppers that cannot meet their tolerance."""

import math

import numpy as np
import pytest

from connenv.core import StepperError, make_stepper
from connenv.systems.kozlov_shell import ReducedKozlovShell
from connenv.systems.rolling_ball import RollingBall
from connenv.systems.swing import Swing

SWING = Swing()
R = np.array([2.0])
HELD = np.zeros(1)
OMEGA = math.sqrt(SWING.g / R[0])


@pytest.mark.parametrize(
    "integrator, order, substeps, rel",
    [
        ("euler", 1, 64, 0.1),
        ("semi_implicit_euler", 1, 64, 0.1),
        ("rk4", 4, 64, 0.1),
        ("gauss6", 6, 8, 0.1),
        ("rk8", 8, 2, 0.2),
    ],
)
def test_the_global_error_falls_as_the_order_of_the_method(integrator, order, substeps, rel):
    """Doubling the substeps divides the error against the closed-form pendulum flow by 2^order (RK8: from 2 to 4
    substeps of 1 s, errors 1.1e-5 and 4.8e-8; beyond, the ratio runs past 2⁸ as rounding nears)."""
    y0 = np.array([1.0, 0.0])
    exact = SWING.exact_flow(y0, R, 1.0)
    stepped = [make_stepper(integrator, substeps=n)(SWING, y0, R, HELD, 1.0) for n in (substeps, 2 * substeps)]
    errors = [np.abs(y - exact).max() for y in stepped]
    assert errors[0] / errors[1] == pytest.approx(2.0**order, rel=rel)


def test_explicit_euler_multiplies_the_oscillators_energy_by_one_plus_omega_h_squared():
    """At small amplitude the swing is a harmonic oscillator, and Euler's step matrix has determinant 1 + (ωh)²."""
    h = 0.05
    y = np.array([1e-3, 0.0])
    lift = [SWING.lift(y, R[0])]
    for _ in range(10):
        y = make_stepper("euler")(SWING, y, R, HELD, h)
        lift.append(SWING.lift(y, R[0]))
    np.testing.assert_allclose(np.diff(np.log(lift)), math.log(1 + (OMEGA * h) ** 2), rtol=1e-5)


@pytest.mark.parametrize("integrator, area", [("semi_implicit_euler", lambda h, c: 1.0), ("euler", None)])
def test_semi_implicit_euler_preserves_phase_space_area_and_euler_does_not(integrator, area):
    """The swing's H separates, so semi-implicit Euler is symplectic: det ∂y′/∂y = 1. Euler's is
    1 + h² ω² cos θ (its step matrix [[1, h/(m r²)], [−h m g r cos θ, 1]])."""
    h, eps = 0.1, 1e-6
    stepper = make_stepper(integrator)
    y = np.array([0.7, 1.3])
    columns = [
        (stepper(SWING, y + d, R, HELD, h) - stepper(SWING, y - d, R, HELD, h)) / (2 * eps) for d in np.eye(2) * eps
    ]
    det = np.linalg.det(np.stack(columns, axis=-1))
    expected = 1.0 if area else 1.0 + h**2 * OMEGA**2 * math.cos(0.7)
    assert det == pytest.approx(expected, abs=1e-8)


def test_semi_implicit_euler_keeps_the_energy_bounded_where_euler_lets_it_grow():
    """10⁴ steps of ωh = 0.11 from θ₀ = 1: the symplectic method's energy error stays below ωh m g r."""
    energies = {}
    for integrator in ("semi_implicit_euler", "euler"):
        y, worst = np.array([1.0, 0.0]), 0.0
        e0 = SWING.energy(y, R[0])
        for _ in range(10_000 if integrator == "semi_implicit_euler" else 100):
            y = make_stepper(integrator)(SWING, y, R, HELD, 0.05)
            worst = max(worst, abs(SWING.energy(y, R[0]) - e0))
        energies[integrator] = worst / (SWING.mass * SWING.g * R[0])
    assert energies["semi_implicit_euler"] < OMEGA * 0.05 < energies["euler"]


@pytest.mark.parametrize("integrator", ["euler", "semi_implicit_euler", "rk4", "gauss6", "rk8", "rk8_energy"])
def test_fixed_step_methods_broadcast_over_a_batch(integrator):
    stepper = make_stepper(integrator, substeps=3)
    rng = np.random.default_rng(0)
    y, r, r_dot = rng.normal(size=(5, 2)), rng.uniform(1.0, 2.0, (5, 1)), rng.normal(size=(5, 1))
    batch = stepper(SWING, y, r, r_dot, 0.1)
    np.testing.assert_array_equal(batch, np.stack([stepper(SWING, *a, 0.1) for a in zip(y, r, r_dot)]))


def test_the_energy_projection_keeps_the_level_and_the_phase_of_rk8():
    """1000 steps of 0.1 s (ωh = 0.22) from θ₀ = 2.5: RK8's energy drifts (2.5e-9 m g r), the projected step's
    stays at rounding (6e-15), and its error along the level is smaller (5e-9 against 1.4e-6); the closed form is
    the reference."""
    y0, steps, h = np.array([2.5, 0.0]), 1000, 0.1
    exact = SWING.exact_flow(y0, R, steps * h)
    scale = SWING.mass * SWING.g * R[0]
    drift, error = {}, {}
    for integrator in ("rk8", "rk8_energy"):
        options = {"atol": 1.0} if "energy" in integrator else {}
        y, stepper = y0, make_stepper(integrator, SWING, substeps=1, **options)
        for _ in range(steps):
            y = stepper(SWING, y, R, HELD, h)
        drift[integrator] = abs(SWING.energy(y, R[0]) - SWING.energy(y0, R[0])) / scale
        error[integrator] = np.abs(y - exact).max()
    assert drift["rk8_energy"] < 1e-13 < 1e-10 < drift["rk8"]
    assert error["rk8_energy"] < 0.01 * error["rk8"]


def test_the_projected_step_doubles_its_substeps_where_its_energy_error_passes_atol():
    """A row far from the others (a fast rotation) needs more substeps to meet atol; in a batch it gets what it
    gets alone, and the rows around it keep theirs."""
    stepper = make_stepper("rk8_energy", SWING, substeps=1, atol=1e-9)
    y = np.array([[0.3, 0.0], [1.0, 40.0], [-0.5, 2.0]])
    batch = stepper(SWING, y, np.full((3, 1), 2.0), np.zeros((3, 1)), 0.2)
    np.testing.assert_array_equal(batch, np.stack([stepper(SWING, row, R, HELD, 0.2) for row in y]))
    once = make_stepper("rk8", substeps=1)(SWING, y[1], R, HELD, 0.2)
    excess = abs(SWING.energy(once, R[0]) - SWING.energy(y[1], R[0]))
    assert excess > 1e-9 and abs(SWING.energy(batch[1], R[0]) - SWING.energy(y[1], R[0])) < 1e-12 * scale_of(y[1])
    np.testing.assert_allclose(batch[1], SWING.exact_flow(y[1], R, 0.2), atol=1e-9)


def scale_of(y):
    return SWING.mass * SWING.g * R[0] + abs(SWING.energy(y, R[0]))


def test_the_energy_projection_is_refused_without_a_hamiltonian():
    with pytest.raises(ValueError, match="rk8_energy.*hamiltonian.*RollingBall"):
        make_stepper("rk8_energy", RollingBall())


def test_semi_implicit_euler_is_euler_on_the_shells_reduced_model():
    """At zero momentum there is no p to update first: the method is explicit Euler on the pose."""
    shell, rng = ReducedKozlovShell(), np.random.default_rng(1)
    y, u, u_dot = rng.normal(size=3), rng.uniform(-0.2, 0.2, 2), rng.normal(size=2)
    np.testing.assert_array_equal(
        make_stepper("semi_implicit_euler", substeps=4)(shell, y, u, u_dot, 0.1),
        make_stepper("euler", substeps=4)(shell, y, u, u_dot, 0.1),
    )


def test_semi_implicit_euler_is_refused_on_the_kinematic_ball():
    with pytest.raises(ValueError, match="semi_implicit_euler.*RollingBall.*'euler'"):
        make_stepper("semi_implicit_euler", RollingBall())


@pytest.mark.parametrize(
    "integrator, message",
    [
        ("dop853", "Required step size"),
        ("rk45", "Required step size"),
        ("radau", "Required step size"),
        ("lsoda", "cannot meet its tolerance: 100000 evaluations"),
    ],
)
def test_an_adaptive_stepper_that_cannot_meet_its_tolerance_says_so(integrator, message):
    """A swing whose radius is pulled to 0 at 1 m/s keeps p, so θ̇ = p/(m r²) diverges at t = r₀: θ winds
    infinitely often in finite time. No step size meets the tolerance there; the stepper raises naming itself.
    scipy gives up on DOP853, RK45 and Radau; LSODA creeps on toward t = r₀ and is stopped by the evaluation
    budget."""
    stepper = make_stepper(integrator, rtol=1e-8, atol=1e-10)
    with pytest.raises(StepperError, match=rf"method='{stepper.method}'.*{message}"):
        stepper(SWING, np.array([0.1, 0.1]), np.array([1.0]), np.array([-1.0]), 2.0)
