"""A vertical coin rolling without slipping on a surface z(x, y) under gravity, steered by its heading.

The coin (radius R, mass m, a uniform disk) touches the surface at (x, y); θ is its heading, measured from the
y-axis, and φ its rolling angle. Rolling without slipping is the nonholonomic constraint

    ẋ = R sin θ φ̇,    ẏ = R cos θ φ̇,

and on a gently sloping surface (the coin's plane vertical, its height read at the contact point; Hand & Finch,
pp. 62–64) the Lagrangian is

    L = ¾ m R² φ̇² + ⅛ m R² θ̇² − m g z(x, y):

¾ m R² φ̇² is the kinetic energy of rolling (translation ½ m R² φ̇² and spin ¼ m R² φ̇²), ⅛ m R² θ̇² that of
turning about the vertical diameter. The heading is assigned by the controller (an active constraint: u = θ),
and the constraint forces do no work along the motions the constraints allow, so the Lagrange–d'Alembert equation
for φ, with the constraints eliminated, is

    (3/2) m R² φ̈ = − m g R (z_x sin θ + z_y cos θ),

the slope along the heading driving the roll. The mass drops out, and θ̇ enters nowhere: turning the coin changes
where gravity pushes it but does no work on it, so its energy

    E = ¾ m R² φ̇² + m g z(x, y)

is conserved whatever the steering (dE/dt = (3/2) m R² φ̇ φ̈ + m g R φ̇ (z_x sin θ + z_y cos θ) = 0).

With v = R φ̇, the rolling speed (signed: v > 0 rolls along the heading (sin θ, cos θ)), the state is
y = (x, y, φ, φ̇) and the vector field ẏ = (v sin θ, v cos θ, φ̇, −(2 g/(3 R)) (z_x sin θ + z_y cos θ)).

**Plane, exact.** On a plane, (z_x, z_y) = (sx, sy) is constant, and over a step at θ̇ = Ω constant the motion
has a closed form. In complex notation ζ = y + i x, s = sy + i sx, ζ̇ = v e^{iθ} and v̇ = −k Re(s̄ e^{iθ}),
k = 2 g/3. With θ = θ₀ + Ωt, a = s̄ e^{iθ₀} and the φ-functions φ₁(z) = (e^z − 1)/z, φ₂(z) = (e^z − 1 − z)/z²
at z = iΩτ, integrating twice gives

    v(τ) = v₀ − k τ Re(a φ₁),
    ζ(τ) = ζ₀ + e^{iθ₀} τ [v₀ φ₁ − (k τ/2) (a φ₁²/2 + ā φ₂)],
    R (φ(τ) − φ₀) = v₀ τ − k τ² Re(a φ₂),

(∫₀^τ ∫₀^σ e^{iΩ(r+σ)} dr dσ = τ² φ₁²/2, ∫₀^τ ∫₀^σ e^{iΩ(σ−r)} dr dσ = τ² φ₂), which hold at Ω = 0 too
(φ₁ = 1, φ₂ = ½: the coin rolls down a straight line, uniformly accelerated). φ₁ and φ₂ are evaluated without
cancellation at small Ωτ (half-angle forms and a series), so the step is exact to rounding for any Ω and τ.

States are y = (x, y, φ, φ̇) on the last axis, u = (θ,), u̇ = (θ̇,); everything broadcasts over leading axes.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np

from connenv.core.backend import FLOATS, floats, namespace, traced
from connenv.systems.surfaces import Surface

SERIES_BELOW = 0.3  # |Ωτ| under which (Ωτ − sin Ωτ)/(Ωτ)² is summed as its series (no cancellation)


@dataclass(frozen=True)
class RollingCoinSurface:
    """The coin on ``surface`` (a connenv.systems.surfaces.Surface)."""

    surface: Surface
    radius: float = 0.5
    mass: float = 1.0
    g: float = 9.81

    n = 3  # q = (x, y, φ); φ̇, the last entry, is the momentum (3/2) m R² φ̇ up to its constant factor

    def vector_field(self, y, u, u_dot):
        """ẏ = (R sin θ φ̇, R cos θ φ̇, φ̇, −(2 g/(3 R)) (z_x sin θ + z_y cos θ)); u_dot drops out."""
        if y.ndim == 1 and type(y) is np.ndarray:  # one state: Python floats, no array calls but the result
            return np.array(self.vector_field_one(y.tolist(), u, u_dot))
        ops = namespace(y)  # numpy's rows (ARRAYS: numpy's own functions), or JAX's (connenv.jax)
        return ops.stack(ops.broadcast_arrays(*self._rates(y[..., 0], y[..., 1], y[..., 3], u[..., 0], ops)), axis=-1)

    def vector_field_one(self, y, u, u_dot):
        """vector_field of one state y = [x, y, φ, φ̇] of Python floats, as a list."""
        x, yy, _, phi_dot = y
        return self._rates(x, yy, phi_dot, float(u[0]), FLOATS)

    def _rates(self, x, y, phi_dot, theta, ops):
        """ẏ's components at (x, y), φ̇ and heading θ: Python floats with ops=FLOATS, or rows with their namespace
        (ARRAYS, or JAX's)."""
        _, z_x, z_y = self.surface.height(x, y)
        s, c = ops.sin(theta), ops.cos(theta)
        v = self.radius * phi_dot
        return [v * s, v * c, phi_dot, -2.0 * self.g / (3.0 * self.radius) * (z_x * s + z_y * c)]

    def energy(self, y):
        """E = ¾ m R² φ̇² + m g z(x, y), J: z = 0 is the reference height."""
        v = self.radius * y[..., 3]
        return self.mass * (0.75 * v * v + self.g * self.surface.height(y[..., 0], y[..., 1])[0])


@dataclass(frozen=True)
class RollingCoinPlane(RollingCoinSurface):
    """The coin on a plane (surface a connenv.systems.surfaces.Plane), with its closed-form step."""

    def exact_segment(self, y, u, u_dot, tau):
        """The state after τ at θ = θ₀ + Ω t (the module's closed form), over leading axes (numpy's rows, or JAX's:
        ``connenv.jax``, the same arithmetic in their namespace)."""
        if np.ndim(y) == 1 and np.ndim(tau) == 0 and type(y) is np.ndarray and y.dtype.kind == "f":
            return self._exact_one(y, float(u[0]), float(u_dot[0]), float(tau))
        if traced(ops := namespace(y)):
            theta0, omega = u[..., 0], u_dot[..., 0]
        else:  # float rows, or a complex-step Jacobian's complex ones (kept complex: no cast to float)
            ops, y = np, floats(y)
            theta0, omega = floats(u)[..., 0], floats(u_dot)[..., 0]
        # The closed form's complex numbers (a plane vector x + i y) as pairs of real ones: the complex step's own
        # imaginary part must not mix with them. turn = e^{iθ₀}, a = (sy − i sx) turn, φ₁, φ₂ = phi_pairs.
        sx, sy = self.surface.slope
        k, R = 2.0 * self.g / 3.0, self.radius
        v0 = R * y[..., 3]
        p1r, p1i, p2r, p2i = phi_pairs(omega * tau, ops)
        c0, s0 = ops.cos(theta0), ops.sin(theta0)
        ar, ai = sy * c0 + sx * s0, sy * s0 - sx * c0
        v = v0 - k * tau * (ar * p1r - ai * p1i)  # v₀ − k τ Re(a φ₁)
        q_r, q_i = p1r * p1r - p1i * p1i, 2.0 * p1r * p1i  # φ₁²
        w = 0.5 * k * tau  # inner = v₀ φ₁ − ½ k τ (½ a φ₁² + ā φ₂)
        in_r = v0 * p1r - w * (0.5 * (ar * q_r - ai * q_i) + (ar * p2r + ai * p2i))
        in_i = v0 * p1i - w * (0.5 * (ar * q_i + ai * q_r) + (ar * p2i - ai * p2r))
        zeta_r, zeta_i = tau * (c0 * in_r - s0 * in_i), tau * (c0 * in_i + s0 * in_r)  # ζ = turn τ inner
        roll = (v0 * tau - k * tau * tau * (ar * p2r - ai * p2i)) / R
        rows = (y[..., 0] + zeta_i, y[..., 1] + zeta_r, y[..., 2] + roll, v / R)
        return ops.stack(ops.broadcast_arrays(*rows), -1)


    def _exact_one(self, y, theta0, omega, tau):
        """exact_segment for one state, on Python floats and complex numbers (no array calls but the result)."""
        sx, sy = self.surface.slope
        k, R = 2.0 * self.g / 3.0, self.radius
        v0 = R * float(y[3])
        phi1, phi2 = phi_one(omega * tau)
        turn = cmath.exp(1j * theta0)
        a = complex(sy, -sx) * turn
        v = v0 - k * tau * (a * phi1).real
        zeta = turn * tau * (v0 * phi1 - 0.5 * k * tau * (0.5 * a * phi1 * phi1 + a.conjugate() * phi2))
        roll = (v0 * tau - k * tau * tau * (a * phi2).real) / R
        return np.array([y[0] + zeta.imag, y[1] + zeta.real, y[2] + roll, v / R])


def phi_one(alpha: float):
    """phi_pairs of one float, as complex numbers (φ₁, φ₂)."""
    h = 0.5 * alpha
    half = math.sin(h) / h if h != 0.0 else 1.0
    versine = 0.5 * half * half
    a2 = alpha * alpha
    if abs(alpha) < SERIES_BELOW:
        odd = odd_series(alpha)
    else:
        odd = (alpha - math.sin(alpha)) / a2
    sinc = math.sin(alpha) / alpha if alpha != 0.0 else 1.0
    return complex(sinc, alpha * versine), complex(versine, odd)


def odd_series(alpha):
    """(α − sin α)/α² = α/3! − α³/5! + … to α¹¹/13!, for |α| < SERIES_BELOW (the next term is below 1e-19 there)."""
    a2 = alpha * alpha
    return alpha * (1 / 6 - a2 * (1 / 120 - a2 * (1 / 5040 - a2 * (1 / 362880 - a2 * (1 / 39916800 - a2 / 6227020800)))))


def phi_pairs(angle, xp=np):
    """The real and imaginary parts (Re φ₁, Im φ₁, Re φ₂, Im φ₂) of φ₁(i α), φ₂(i α) for real α = Ωτ, without
    cancellation: φ₁ = sin α/α + i (1 − cos α)/α, φ₂ = (1 − cos α)/α² + i (α − sin α)/α², the half-angle forms and,
    for |α| < SERIES_BELOW, the series of (α − sin α)/α². Each is an analytic function of α, so a complex α (a
    complex-step Jacobian's) carries its derivative. xp: numpy, or JAX's namespace on its rows (``connenv.jax``)."""
    alpha = angle if traced(xp) else floats(angle)
    half = xp.sinc(alpha / (2.0 * math.pi))  # sin(α/2)/(α/2)
    versine = 0.5 * half * half  # (1 − cos α)/α²
    a2 = alpha * alpha
    series = odd_series(alpha)
    small = xp.abs(alpha if traced(xp) else alpha.real) < SERIES_BELOW  # the real part on complex-step rows
    with np.errstate(divide="ignore", invalid="ignore"):  # a2 = 0 only where the series is taken: 1 there, so
        direct = (alpha - xp.sin(alpha)) / xp.where(small, 1.0, a2)  # that no 0/0 reaches reverse mode's product
    odd = xp.where(small, series, direct)
    return xp.sinc(alpha / math.pi), alpha * versine, versine, odd
