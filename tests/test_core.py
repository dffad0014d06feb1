"""Bressan's equations and classification, checked on systems with known answers."""

from dataclasses import dataclass

import numpy as np
import pytest

from connenv.core import JumpClass, StepperError, classify, make_stepper, vector_field
from connenv.systems.swing import Swing

rng = np.random.default_rng(12345)


@dataclass(frozen=True)
class Bead:
    """Bead of mass m on a bar whose angle u = θ is assigned; q = r (Bressan, slide 21)."""

    mass: float = 1.3
    n = 1
    m = 1

    def metric(self, q, u):
        one = np.ones(np.broadcast_shapes(q.shape, u.shape)[:-1] + (1, 1))
        return self.mass * one, 0.0 * one, self.mass * q[..., :1, None] ** 2 * one

    def potential(self, q, u):
        return 0.0 * q[..., 0]


@dataclass(frozen=True)
class Beanie:
    """Elroy's beanie: body angle q, beanie angle u relative to it; T = ½I₁q̇² + ½I₂(q̇ + u̇)²."""

    I1: float = 2.0
    I2: float = 0.5
    n = 1
    m = 1

    def metric(self, q, u):
        one = np.ones(np.broadcast_shapes(q.shape, u.shape)[:-1] + (1, 1))
        return (self.I1 + self.I2) * one, self.I2 * one, self.I2 * one

    def potential(self, q, u):
        return 0.0 * q[..., 0]


@dataclass(frozen=True)
class VerticalKapitza:
    """Pendulum of length l whose pivot height u is assigned: T = ½m(u̇² + 2lθ̇u̇ sin θ + l²θ̇²)."""

    mass: float = 1.0
    length: float = 1.0
    g: float = 9.81
    n = 1
    m = 1

    def metric(self, q, u):
        one = np.ones(np.broadcast_shapes(q.shape, u.shape)[:-1] + (1, 1))
        ml = self.mass * self.length
        return ml * self.length * one, ml * np.sin(q[..., :1, None]) * one, self.mass * one

    def potential(self, q, u):
        return self.mass * self.g * (u[..., 0] - self.length * np.cos(q[..., 0]))


def test_swing_generic_equations_equal_hand_derived():
    swing = Swing(mass=0.7, g=9.81)
    y = rng.normal(scale=2.0, size=(50, 2))
    u = rng.uniform(0.5, 3.0, size=(50, 1))
    u_dot = rng.normal(scale=3.0, size=(50, 1))
    np.testing.assert_allclose(vector_field(swing, y, u, u_dot), swing.vector_field(y, u, u_dot), rtol=1e-9, atol=1e-9)


def test_bead_is_pushed_out_by_the_centrifugal_term():
    """ṙ = p/m, ṗ = m r θ̇²: the force quadratic in the control velocity."""
    bead = Bead()
    r, p = rng.uniform(0.1, 2.0, 20), rng.normal(size=20)
    theta_dot = rng.normal(scale=2.0, size=20)
    f = vector_field(bead, np.stack([r, p], -1), rng.normal(size=(20, 1)), theta_dot[:, None])
    np.testing.assert_allclose(f, np.stack([p / bead.mass, bead.mass * r * theta_dot**2], -1), rtol=1e-9)


def test_beanie_turns_by_the_mechanical_connection():
    """At zero angular momentum θ̇ = −I₂ u̇/(I₁+I₂): −2π I₂/(I₁+I₂) per turn of the beanie."""
    beanie = Beanie()
    u_dot = rng.normal(size=(10, 1))
    f = vector_field(beanie, np.zeros((10, 2)), rng.normal(size=(10, 1)), u_dot)
    np.testing.assert_allclose(f[:, 0], -beanie.I2 / (beanie.I1 + beanie.I2) * u_dot[:, 0], rtol=1e-12)
    np.testing.assert_allclose(f[:, 1], 0.0, atol=1e-9)


def test_vibrating_pivot_matches_newton():
    """With the pivot at u(t), p = ml²θ̇ + ml u̇ sin θ and Newton's θ̈ = −(g + ü) sin θ / l."""
    sys = VerticalKapitza()
    theta, theta_dot = 0.4, 1.1
    omega, amp = 7.0, 0.05
    t = 0.3
    u, u_dot, u_ddot = amp * np.cos(omega * t), -amp * omega * np.sin(omega * t), -amp * omega**2 * np.cos(omega * t)

    def p_of(th, th_dot, ud):
        return sys.mass * sys.length * (sys.length * th_dot + ud * np.sin(th))

    y = np.array([theta, p_of(theta, theta_dot, u_dot)])
    q_dot, p_dot = vector_field(sys, y, np.array([u]), np.array([u_dot]))
    theta_ddot = -(sys.g + u_ddot) * np.sin(theta) / sys.length
    # ṗ = d/dt [ml(lθ̇ + u̇ sin θ)] along Newton's motion
    expected_p_dot = sys.mass * sys.length * (
        sys.length * theta_ddot + u_ddot * np.sin(theta) + u_dot * np.cos(theta) * theta_dot
    )
    assert q_dot == pytest.approx(theta_dot, rel=1e-12)
    assert p_dot == pytest.approx(expected_p_dot, rel=1e-8)


@pytest.mark.parametrize(
    "system, q_range, u_range, expected",
    [
        (Swing(), (-3, 3), (0.5, 3.0), JumpClass.STRONGLY_FIT),
        (Beanie(), (-3, 3), (-3, 3), JumpClass.FIT),
        (Bead(), (0.1, 2.0), (-3, 3), JumpClass.GENERAL),
        (VerticalKapitza(), (-3, 3), (-0.1, 0.1), JumpClass.GENERAL),
    ],
)
def test_classification_from_the_metric(system, q_range, u_range, expected):
    q = rng.uniform(*q_range, size=(6, system.n))
    u = rng.uniform(*u_range, size=(3, system.m))
    assert classify(system, q, u) is expected


@dataclass(frozen=True)
class BlowUp:
    """ẏ = y², which leaves every bound at t = 1/y₀."""

    def vector_field(self, y, u, u_dot):
        return y**2


@pytest.mark.filterwarnings("ignore:overflow encountered")  # the blow-up itself
@pytest.mark.parametrize("integrator, options", [("rk4", {"substeps": 4}), ("dop853", {}), ("lsoda", {})])
def test_a_diverging_stepper_raises_instead_of_returning_garbage(integrator, options):
    stepper = make_stepper(integrator, **options)
    with pytest.raises(StepperError, match=integrator.upper() if integrator != "rk4" else "RK4"):
        stepper(BlowUp(), np.array([1e3]), np.zeros(1), np.zeros(1), 10.0)


@pytest.mark.parametrize(
    "integrator, options, message",
    [
        ("midpoint", {}, "integrator=.midpoint."),
        ("rk4", {"substeps": 0}, "substeps=0"),
        ("rk4", {"substeps": 2.5}, "substeps=2.5"),
        ("rk4", {"rtol": 1e-6}, "rtol"),
        ("dop853", {"rtol": -1.0}, "rtol=-1.0"),
        ("dop853", {"atol": float("nan")}, "atol=nan"),
        ("lsoda", {"substeps": 4}, "substeps"),
    ],
)
def test_bad_stepper_options_are_named(integrator, options, message):
    with pytest.raises(ValueError, match=message):
        make_stepper(integrator, **options)


def test_exact_needs_a_closed_form_flow():
    with pytest.raises(ValueError, match="Bead"):
        make_stepper("exact", Bead())
