"""A bead sliding on a straight bar that turns about a fixed pivot in a vertical plane (Bressan's general class).

The bar passes through the pivot O and extends to ±L on both sides; θ is its angle from the horizontal, assigned
by the controller (u = θ); the bead of mass m slides on it without friction at signed distance r from O (q = r).
With the bead at (r cos θ, r sin θ):

    T = ½ m (ṙ² + r² θ̇²),   V = m g r sin θ,   p = ∂L/∂ṙ = m ṙ,
    G11 = m,  G12 = 0,  G22 = m r²,   so  A = 1/m,  K = 0,  B = m r²,
    ṙ = p / m,   ṗ = m r θ̇² − m g sin θ.

B depends on q: the system is *general*, quadratic in u̇. θ must move at a bounded speed (no jumps), and a fast
vibration of θ pushes the bead away from the pivot through the centrifugal term m r θ̇² ≥ 0. These equations, the
metric and the class are not written here by hand: `BeadOnBar` is connenv.core.lagrangian's `LagrangianSystem` of
the T and V above (`lagrangian`), which derives them. What this module adds is the closed form of the flow.

At constant θ̇ = ω over a segment, θ(t) = θ₀ + ω t and r̈ − ω² r = −g sin(θ₀ + ω t), a linear equation with

    r(t) = a cosh ωt + b sinh ωt + (g / 2ω²) sin(θ₀ + ωt),
    a = r₀ − (g / 2ω²) sin θ₀,   b = v₀/ω − (g / 2ω²) cos θ₀.

As written it loses every digit as ω → 0 (the g/2ω² terms cancel). Grouped by initial data it reads, with x = ωt,

    r(t) = r₀ cosh x + v₀ t shc(x) − ½ g t² [sin θ₀ c(x) + cos θ₀ x s(x)],
    ṙ(t) = r₀ ω sinh x + v₀ cosh x − ½ g t [sin θ₀ (shc(x) + snc(x)) + cos θ₀ x c(x)],

    shc(x) = sinh x / x,   snc(x) = sin x / x,
    c(x) = (cosh x − cos x)/x² = ½ [shc(x/2)² + snc(x/2)²],   s(x) = (sinh x − sin x)/x³ = 2 Σₖ x⁴ᵏ/(4k+3)!,

where c is computed through the half-angle identity and s through its series for |x| < 1, so that no difference
of nearly equal numbers is ever taken. At ω = 0 (c = 1, s = 1/3) it is the parabola r̈ = −g sin θ₀. `exact_segment`
is this step; the env's default stepper (connenv.core.steppers.Exact) uses it.

States are y = (r, p) on the last axis; everything broadcasts over leading axes.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from connenv.core.backend import floats, namespace
from connenv.core.lagrangian import LagrangianSystem

SERIES_RADIUS = 1.0
"""|x| = |ω t| below which s(x) is summed as its series (the direct difference loses a factor 1/x² in accuracy)."""
SERIES_TERMS = tuple(2.0 / math.factorial(4 * k + 3) for k in range(6))
"""s(x) = Σₖ SERIES_TERMS[k] x⁴ᵏ; at |x| < 1 the first omitted term is below 1e-20 of the sum."""


def lagrangian(mass: float, g: float):
    """(T, V, q, u) as sympy expressions and symbol lists, as ActiveConstraintEnv.from_lagrangian takes them."""
    import sympy as sp

    r, r_dot, theta, theta_dot = sp.symbols("r r_dot theta theta_dot")
    kinetic = sp.Float(mass) * (r_dot**2 + r**2 * theta_dot**2) / 2
    return kinetic, sp.Float(mass) * sp.Float(g) * r * sp.sin(theta), [r], [theta]


class BeadOnBar(LagrangianSystem):
    """The LagrangianSystem of `lagrangian(mass, g)` with its closed-form step `exact_segment` (see the module)."""

    def __init__(self, mass: float = 1.0, g: float = 9.81):
        super().__init__(*lagrangian(mass, g))
        self.mass, self.g = float(mass), float(g)

    def __reduce__(self):
        return bead_on_bar, (self.mass, self.g)

    def __repr__(self):
        return f"BeadOnBar(mass={self.mass}, g={self.g})"

    def energy(self, y, theta):
        """E = p²/(2m) + m g r sin θ, conserved where θ is held."""
        sin = np.sin if type(y) is np.ndarray else namespace(y).sin  # numpy's, or JAX's on traced rows
        return y[..., 1] ** 2 / (2.0 * self.mass) + self.mass * self.g * y[..., 0] * sin(theta)

    def exact_segment(self, y, u, u_dot, tau):
        """(r, p) after time tau at θ̇ = u_dot from θ = u, in closed form (the module's grouped formula)."""
        if type(y) is np.ndarray and np.ndim(y) == 1 and np.ndim(tau) == 0:
            return np.array(
                segment_scalar(float(y[0]), float(y[1]), float(u[0]), float(u_dot[0]), float(tau), self.mass, self.g)
            )
        return segment(y, u, u_dot, tau, self.mass, self.g)


@functools.lru_cache(maxsize=16)
def bead_on_bar(mass: float = 1.0, g: float = 9.81) -> BeadOnBar:
    """The system for (mass, g), derived once per process (sympy takes a while) and shared: it holds no state."""
    return BeadOnBar(mass, g)


def _s_series(x4):
    """s(x) from x⁴ by its series (Horner)."""
    total = 0.0
    for term in reversed(SERIES_TERMS):
        total = total * x4 + term
    return total


def segment_scalar(r, p, theta, omega, tau, mass, g):
    """exact_segment on Python floats (one state): (r, p) after tau; inf where the growth overflows a float (as
    numpy's functions answer in `segment`), which the stepper reports."""
    try:
        return _segment_scalar(r, p, theta, omega, tau, mass, g)
    except OverflowError:
        return math.inf, math.inf


def _segment_scalar(r, p, theta, omega, tau, mass, g):
    x, v = omega * tau, p / mass
    if x == 0.0:
        shc = snc = c = 1.0
        s = SERIES_TERMS[0]
    else:
        half = 0.5 * x
        shc, snc = math.sinh(x) / x, math.sin(x) / x
        c = 0.5 * ((math.sinh(half) / half) ** 2 + (math.sin(half) / half) ** 2)
        s = _s_series(x**4) if abs(x) < SERIES_RADIUS else (math.sinh(x) - math.sin(x)) / x**3
    cosh, sin0, cos0 = math.cosh(x), math.sin(theta), math.cos(theta)
    r_end = r * cosh + v * tau * shc - 0.5 * g * tau * tau * (sin0 * c + cos0 * x * s)
    v_end = r * omega * x * shc + v * cosh - 0.5 * g * tau * (sin0 * (shc + snc) + cos0 * x * c)
    return r_end, mass * v_end


def segment(y, u, u_dot, tau, mass, g):
    """exact_segment over a batch: y (..., 2), u and u_dot (..., 1), tau a number or one per row; numpy's rows or
    JAX's (their namespace's functions, branch-free as written)."""
    y = floats(y)  # complex on a Jacobian's rows, whose branches follow the real parts
    ops = namespace(y)  # ARRAYS (numpy's functions) or JAX's (connenv.jax)
    r, v = y[..., 0], y[..., 1] / mass
    theta, omega = floats(u)[..., 0], floats(u_dot)[..., 0]
    tau = floats(tau)
    x = omega * tau
    zero = x.real == 0.0  # s, shc, snc and c are even in x: their derivative there is 0
    safe = ops.where(zero, 1.0, x)
    half = 0.5 * safe
    shc = ops.where(zero, 1.0, ops.sinh(safe) / safe)
    snc = ops.where(zero, 1.0, ops.sin(safe) / safe)
    c = ops.where(zero, 1.0, 0.5 * ((ops.sinh(half) / half) ** 2 + (ops.sin(half) / half) ** 2))
    near = abs(x.real) < SERIES_RADIUS
    far = ops.where(near, 1.0, x)
    s = ops.where(near, _s_series(x**4), (ops.sinh(far) - ops.sin(far)) / far**3)
    cosh, sin0, cos0 = ops.cosh(x), ops.sin(theta), ops.cos(theta)
    r_end = r * cosh + v * tau * shc - 0.5 * g * tau * tau * (sin0 * c + cos0 * x * s)
    v_end = r * omega * x * shc + v * cosh - 0.5 * g * tau * (sin0 * (shc + snc) + cos0 * x * c)
    return ops.stack(ops.broadcast_arrays(r_end, mass * v_end), axis=-1)
