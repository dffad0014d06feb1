"""A swing whose radius is assigned: a point mass on a massless rod of controlled length.

θ is the angle from the downward vertical (free, q = θ), r the rod length
(assigned, u = r), p = m r² θ̇ the angular momentum about the pivot:

    L = ½ m (ṙ² + r² θ̇²) + m g r cos θ,    θ̇ = p / (m r²),    ṗ = −m g r sin θ

G12 = 0 and G22 = m, so ṙ drops out of the (θ, p) equations: the swing is
strongly fit for jumps, and a jump of r leaves (θ, p) unchanged. At constant r
the flow is the pendulum's, which `exact_flow` gives in closed form with
Jacobi elliptic functions.

States are y = (θ, p) on the last axis; everything broadcasts over leading axes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipeinc, ellipj, ellipk

from connenv.core.backend import FLOATS, floats, is_complex, namespace, traced
from connenv.core.validation import ndim

try:  # scipy's ellipj on one float without the ufunc's per-call machinery: the same function, the same bits
    from scipy.special.cython_special import _ellipj_pywrap as ellipj_one
except ImportError:  # a scipy without it: the ufunc
    ellipj_one = ellipj

SEPARATRIX_BAND = 1e-6
"""|k² − 1| below which exact_flow declines: nearer the separatrix scipy's ellipj switches to a first-order expansion
in 1 − m and its error grows without bound (tests/test_swing_physics.py checks the fallback there)."""


@dataclass(frozen=True)
class Swing:
    mass: float = 1.0
    g: float = 9.81

    n = 1
    m = 1

    def metric(self, q, u):
        r = u[..., 0]
        one = np.ones_like(q[..., :1, None] * r[..., None, None])
        return self.mass * r[..., None, None] ** 2 * one, 0.0 * one, self.mass * one

    def potential(self, q, u):
        return -self.mass * self.g * u[..., 0] * np.cos(q[..., 0])

    def vector_field(self, y, u, u_dot):
        """Hand-derived (θ̇, ṗ); u_dot is accepted for the common interface and drops out."""
        theta, p, r, ops = y[..., 0], y[..., 1], u[..., 0], namespace(y)
        return ops.stack([p / (self.mass * r**2), -self.mass * self.g * r * ops.sin(theta)], axis=-1)

    def energy(self, y, r):
        """E = p²/(2 m r²) − m g r cos θ (zero at pivot height): one state on Python floats, rows as arrays."""
        if type(y) is np.ndarray and y.ndim == 1 and (type(r) is float or ndim(r) == 0):  # one state
            (theta, p), ops = y.tolist(), FLOATS
        else:
            theta, p, ops = y[..., 0], y[..., 1], namespace(y)
        return p**2 / (2 * self.mass * r**2) - self.mass * self.g * r * ops.cos(theta)

    def hamiltonian(self, y, u):
        """H(y, u) = E(y, r) (u = (r,)), the level the steppers' energy projection keeps."""
        return self.energy(y, u[..., 0])

    def lift(self, y, r):
        """h = (E + m g r)/(m g r), energy above the bottom in units of m g r; 1 − cos A while librating."""
        return (self.energy(y, r) + self.mass * self.g * r) / (self.mass * self.g * r)

    def exact_flow(self, y, r, tau):
        """The pendulum flow at constant r over time tau, in closed form.

        With ω² = g/r and the modulus k² = sin²(θ/2) + θ̇²/(4ω²) (= h/2):
        libration (k < 1): sin(θ/2) = k sn(ωt + t₀ | k²), θ̇ = 2kω cn;
        rotation (k > 1): θ/2 = am(kωt + t₀ | 1/k²), θ̇ = 2kω dn (with the sign of θ̇).
        The two are one solution under Jacobi's reciprocal-modulus transformation.
        At t₀ the amplitude φ = am(t₀) is known from the state, hence sn, cn, dn
        of t₀; Jacobi's addition theorem gives them at t₀ + w from one call of
        scipy's ellipj at w, the step's own phase (the incomplete integral t₀ =
        F(φ) is never needed). A rotation's winding over the step is the
        whole turns nearest φ + πw/(2K) (the am's mean rate; the rest of am
        is periodic and below π/2 in size), K from scipy's ellipk. Within
        SEPARATRIX_BAND of k² = 1, where the period diverges, scipy's ellipj
        loses its accuracy (it switches to a first-order expansion in 1 − m):
        there the answer is NaN, which the exact stepper hands to its
        numerical fallback.
        """
        if ndim(y) == 1 and ndim(r) == 1:  # one state (the env's case)
            theta, p = y.tolist() if type(y) is np.ndarray else map(float, y)
            return np.array(self.pendulum_flow(theta, p, float(r[0]), tau, FLOATS))
        ops = namespace(y)
        r = r[..., 0] if traced(ops) else floats(r)[..., 0]
        return ops.stack(self.pendulum_flow(y[..., 0], y[..., 1], r, tau, ops), axis=-1)

    def pendulum_flow(self, theta, p, r, tau, ops):
        """exact_flow's (θ, p) of the state (θ, p) at radius r, as components: Python floats for one state with
        ops=FLOATS, or arrays over rows with ops=ARRAYS (`connenv.core.backend`); the branches (libration or
        rotation, the separatrix band) are taken on the real parts, as on a Jacobian's complex rows they must be."""
        one = isinstance(theta, float)
        omega = ops.sqrt(self.g / r)
        v = p / (2 * omega * self.mass * r**2)  # θ̇/(2ω)
        wrapped = ops.atan2(ops.sin(theta), ops.cos(theta))  # θ in (−π, π]
        k2 = ops.sin(wrapped / 2) ** 2 + v**2
        rotating = k2.real > 1.0
        s = ops.copysign(1.0, v)  # rotation is mirrored so that θ̇ > 0
        # amplitude angle φ at t₀: libration sin φ = sin(θ/2)/k, cos φ = θ̇/(2kω); rotation φ = ±θ/2
        phi = ops.where(rotating, s * wrapped / 2, ops.atan2(ops.sin(wrapped / 2), v))
        stretch = ops.maximum(k2, 1.0)  # 1 while librating, k² while rotating
        m = k2 / stretch**2  # the parameter: k² or 1/k²
        w = ops.sqrt(stretch) * omega * tau
        sn1, cn1 = ops.sin(phi), ops.cos(phi)
        dn1 = ops.sqrt(1.0 - m * sn1 * sn1)
        sn2, cn2, dn2, _ = ellipj_one(w, m) if one else getattr(ops, "ellipj", jacobi_elliptic)(w, m)  # scipy's
        if one:
            sn2, cn2, dn2 = float(sn2), float(cn2), float(dn2)
        outside = abs(k2.real - 1.0) < SEPARATRIX_BAND
        denominator = ops.where(outside, 1.0, 1.0 - m * (sn1 * sn2) ** 2)  # 0 at the separatrix
        sn = (sn1 * cn2 * dn2 + sn2 * cn1 * dn1) / denominator
        cn = (cn1 * cn2 - sn1 * dn1 * sn2 * dn2) / denominator
        dn = (dn1 * dn2 - m * sn1 * cn1 * sn2 * cn2) / denominator
        k = ops.sqrt(k2)
        half = ops.atan2(k * sn, dn)  # libration: θ/2
        if ops.any(rotating):  # am = atan2(sn, cn) plus the whole turns
            wrapped_am = ops.atan2(sn, cn)
            complete = getattr(ops, "ellipk", ellipk)  # scipy's, or the namespace's traceable one
            mean_am = phi + math.pi / 2 * w / complete(ops.where(rotating, m.real, 0.0))  # only rounded: its real part
            turns = ops.round((mean_am - wrapped_am) / (2 * math.pi))
            half = ops.where(rotating, s * (wrapped_am + 2 * math.pi * turns), half)
        theta_dot = 2 * k * omega * ops.where(rotating, s * dn, cn)
        theta = ops.where(outside, math.nan, theta - wrapped + 2 * half)
        p = ops.where(outside, math.nan, self.mass * r**2 * theta_dot)
        return theta, p

    def quarter_period(self, r, amplitude):
        """Time from the bottom to the extreme at amplitude A: K(sin²(A/2)) √(r/g)."""
        return ellipk(np.sin(np.asarray(amplitude) / 2) ** 2) * np.sqrt(np.asarray(r) / self.g)


def jacobi_elliptic(w, m):
    """scipy's ellipj(w, m) = (sn, cn, dn, φ) over rows. On complex rows (a Jacobian's), its value at the real parts
    with the derivatives carried in the imaginary parts: φ = am(w|m) moves by dn along w and, from F(φ|m) = w, by
    −dn ∂F/∂m along m, with ∂F/∂m = (E(φ|m) − (1 − m) w)/(2m(1 − m)) − sn cn/(2(1 − m) dn) (Byrd & Friedman 710.00;
    DLMF 19.4.2), its limit (2φ − sin 2φ)/8 at m = 0; then sn, cn and dn move with φ, and dn with m (dn² = 1 − m sn²).
    Near m = 0 the difference loses about ε/m of its value, far below the Jacobian's tolerances at a swing's m."""
    if not (is_complex(w) or is_complex(m)):
        return ellipj(w, m)
    w, dw, m, dm = np.real(w), np.imag(w), np.real(m), np.imag(m)
    sn, cn, dn, phi = ellipj(w, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        dF = (ellipeinc(phi, m) - (1.0 - m) * w) / (2.0 * m * (1.0 - m)) - sn * cn / (2.0 * (1.0 - m) * dn)
    dF = np.where(m == 0.0, (2.0 * phi - np.sin(2.0 * phi)) / 8.0, dF)
    d_phi = dn * (dw - dF * dm)
    d_dn = -(m * sn * cn * d_phi + 0.5 * sn * sn * dm) / dn
    return sn + 1j * cn * d_phi, cn - 1j * sn * d_phi, dn + 1j * d_dn, phi + 1j * d_phi
