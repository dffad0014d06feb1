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

from dataclasses import dataclass

import numpy as np
from scipy.special import ellipj, ellipk, ellipkinc


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
        theta, p, r = y[..., 0], y[..., 1], u[..., 0]
        return np.stack([p / (self.mass * r**2), -self.mass * self.g * r * np.sin(theta)], axis=-1)

    def energy(self, y, r):
        """E = p²/(2 m r²) − m g r cos θ (zero at pivot height)."""
        theta, p = y[..., 0], y[..., 1]
        return p**2 / (2 * self.mass * r**2) - self.mass * self.g * r * np.cos(theta)

    def lift(self, y, r):
        """h = (E + m g r)/(m g r), energy above the bottom in units of m g r; 1 − cos A while librating."""
        return (self.energy(y, r) + self.mass * self.g * r) / (self.mass * self.g * r)

    def amplitude(self, y, r):
        """Amplitude A implied by the energy at radius r: arccos(1 − h), and π once the swing goes over."""
        return np.arccos(np.clip(1.0 - self.lift(y, r), -1.0, 1.0))

    def exact_flow(self, y, r, tau):
        """The pendulum flow at constant r over time tau, in closed form.

        With ω² = g/r and the modulus k² = sin²(θ/2) + θ̇²/(4ω²) (= h/2):
        libration (k < 1): sin(θ/2) = k sn(ωt + t₀ | k²), θ̇ = 2kω cn;
        rotation (k > 1): θ/2 = am(kωt + t₀ | 1/k²), θ̇ = 2kω dn (with the sign of θ̇).
        The phase t₀ is scipy's incomplete elliptic integral F; sn, cn, dn and
        the amplitude am are scipy's ellipj. Accurate to rounding away from the
        separatrix k = 1, where the period diverges.
        """
        theta, p = y[..., 0], y[..., 1]
        r = np.asarray(r, float)[..., 0]
        omega = np.sqrt(self.g / r)
        theta_dot = p / (self.mass * r**2)
        k2 = np.sin(theta / 2) ** 2 + (theta_dot / (2 * omega)) ** 2
        k = np.sqrt(k2)
        rotating = k2 > 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            # libration: amplitude angle φ with sn = sin φ = sin(θ/2)/k, cn = cos φ = θ̇/(2kω)
            wrapped = np.arctan2(np.sin(theta), np.cos(theta))
            phi = np.arctan2(np.sin(wrapped / 2) / k, theta_dot / (2 * omega * k))
            sn, cn, dn, _ = ellipj(ellipkinc(phi, k2) + omega * tau, k2)
            theta_lib = theta - wrapped + 2 * np.arctan2(k * sn, dn)
            dot_lib = 2 * k * omega * cn
            # rotation: θ/2 = am(u | 1/k²), mirrored so that θ̇ > 0
            s = np.where(theta_dot < 0, -1.0, 1.0)
            _, _, dn_rot, am = ellipj(ellipkinc(s * theta / 2, 1 / k2) + k * omega * tau, 1 / k2)
            theta_rot = 2 * s * am
            dot_rot = 2 * s * k * omega * dn_rot
        at_rest = k2 == 0.0
        theta_new = np.where(at_rest, theta, np.where(rotating, theta_rot, theta_lib))
        dot_new = np.where(at_rest, 0.0, np.where(rotating, dot_rot, dot_lib))
        return np.stack([theta_new, self.mass * r**2 * dot_new], axis=-1)

    def quarter_period(self, r, amplitude):
        """Time from the bottom to the extreme at amplitude A: K(sin²(A/2)) √(r/g)."""
        return ellipk(np.sin(np.asarray(amplitude) / 2) ** 2) * np.sqrt(np.asarray(r) / self.g)
