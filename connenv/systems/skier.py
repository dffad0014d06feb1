"""Bressan's skier: a barycentre at assigned height h above a trail y = f(x), along its normal.

x is the free coordinate (q = x), h the assigned one (u = h). With σ = √(1 + f′²),
κ = f″/σ³, tan φ = f′ and the normal n = (−sin φ, cos φ), the barycentre is
P = (x, f) + h n, and Ṗ = (1 − κh) σ ẋ t + ḣ n, so

    T = ½ m [w² ẋ² + ḣ²],   w = (1 − κh) σ,   V = m g (f + h cos φ) = m g (f + h/σ)

G12 = 0 and G22 = m: the skier is strongly fit for jumps, and a jump of h leaves
(x, p) unchanged, p = m w² ẋ. Hamilton's equations of H = p²/(2 m w²) + V:

    ẋ = p / (m w²),    ṗ = p² w′ / (m w³) − m g f′ (1 − κh)

with w′ = (1 − κh) σ′ − h κ′ σ, σ′ = f′ f″/σ, κ′ = f‴/σ³ − 3 f′ f″²/σ⁵, and
V′ = m g (f′ − h f′ f″/σ³) = m g f′ (1 − κh). The model holds while 1 − κh > 0:
at 1 − κh = 0 the barycentre sits on the centre of curvature and w = 0.

States are y = (x, p) on the last axis; everything broadcasts over leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from connenv.core.backend import namespace
from connenv.core.validation import ndim
from connenv.systems.trails import Trail


@dataclass(frozen=True)
class Skier:
    trail: Trail
    mass: float = 70.0
    g: float = 9.81

    n = 1
    m = 1

    def geometry(self, x, h):
        """(f, f′, σ, κ, 1 − κh, w, w′) at x for barycentre height h."""
        f, f1, f2, f3 = self.trail.derivatives(x)
        sigma_2 = 1.0 + f1 * f1
        sigma = sigma_2**0.5
        sigma_3 = sigma_2 * sigma  # products, not powers: a power of an array costs several products
        kappa = f2 / sigma_3
        lever = 1.0 - kappa * h
        sigma_1 = f1 * f2 / sigma
        kappa_1 = (f3 - 3.0 * f1 * f2 * f2 / sigma_2) / sigma_3
        return f, f1, sigma, kappa, lever, lever * sigma, lever * sigma_1 - h * kappa_1 * sigma

    def metric(self, q, u):
        w = self.geometry(q[..., 0], u[..., 0])[5]
        one = np.ones_like(w)[..., None, None]
        return self.mass * w[..., None, None] ** 2 * one, 0.0 * one, self.mass * one

    def potential(self, q, u):
        f, _, sigma, *_ = self.geometry(q[..., 0], u[..., 0])
        return self.mass * self.g * (f + u[..., 0] / sigma)

    def vector_field(self, y, u, u_dot):
        """Hand-derived (ẋ, ṗ); u_dot is accepted for the common interface and drops out."""
        if y.ndim == 1 and type(y) is np.ndarray:  # one state: Python floats, which the trail evaluates without
            return np.array(self.vector_field_one(y.tolist(), u, u_dot))  # array calls
        # numpy's rows, or JAX's (connenv.jax)
        return namespace(y).stack(self._rates(y[..., 0], y[..., 1], u[..., 0]), axis=-1)

    def vector_field_one(self, y, u, u_dot):
        """vector_field of one state y = [x, p] of Python floats, as a list."""
        return self._rates(*y, float(u[0]))

    def _rates(self, x, p, h):
        """[ẋ, ṗ] at (x, p) and height h."""
        _, f1, _, _, lever, w, w_1 = self.geometry(x, h)
        x_dot = p / (self.mass * w * w)
        return [x_dot, x_dot * x_dot * self.mass * w * w_1 - self.mass * self.g * f1 * lever]

    def velocity(self, y, h):
        """ẋ = p / (m w²)."""
        return self.kinematics(y, h)[1]

    def energy(self, y, h):
        """E = p²/(2 m w²) + m g (f + h cos φ), zero with the barycentre at the trail's level y = 0."""
        return self.kinematics(y, h)[0]

    def hamiltonian(self, y, u):
        """H(y, u) = E(y, h), the energy as the steppers' projection takes it (u = (h,))."""
        return self.energy(y, u[..., 0])

    def kinematics(self, y, h):
        """(E, ẋ, f′, σ, κ) at (y, h), from one evaluation of the trail's geometry."""
        if ndim(y) == 1 and type(y) is np.ndarray:  # one state: Python floats (a 0-d array would take the trail's
            # array path); one traced state (connenv.jax's start) its entries
            (x, p), h = y.tolist(), float(h)
        else:
            x, p = y[..., 0], y[..., 1]
        f, f1, sigma, kappa, _, w, _ = self.geometry(x, h)
        x_dot = p / (self.mass * w * w)
        return 0.5 * p * x_dot + self.mass * self.g * (f + h / sigma), x_dot, f1, sigma, kappa


def barycentre_height(trail: Trail, x, h):
    """The barycentre's height at x at height h above the trail: f + h cos φ = f + h/σ (over x's axes)."""
    f, f1, _, _ = trail.profile(x)
    return f + h / np.sqrt(1.0 + f1**2)


class Reach(NamedTuple):
    """What a skier of heights [h_min, h_max] meets over a trail's grid: its lowest point x_bottom, the barycentre's
    lowest height z_floor (at h_min), the largest |κ| h_max and the least lever 1 − κ h_max."""

    x_bottom: float
    z_floor: float
    kappa_bound: float
    min_lever: float


def reach(trail: Trail, h_min: float, h_max: float) -> Reach:
    """The trail's Reach for heights [h_min, h_max]; ValueError where 1 − κ h_max ≤ 0 (the barycentre would reach the
    centre of curvature, where w = 0 and the metric degenerates), naming the worst point."""
    xs = trail.grid()
    f, f1, f2, _ = trail.profile(xs)
    sigma = np.sqrt(1.0 + f1**2)
    kappa = f2 / sigma**3
    worst = int(np.argmax(kappa))
    if 1.0 - kappa[worst] * h_max <= 0.0:
        raise ValueError(
            f"h_max={h_max} reaches the trail's centre of curvature: at x={xs[worst]:.6g} the curvature is "
            f"{kappa[worst]:.6g}/m (radius {1 / kappa[worst]:.6g} m), so 1 − κ h_max = {1 - kappa[worst] * h_max:.3g} "
            f"≤ 0 and the metric degenerates; h_max must stay below {1 / kappa[worst]:.6g} m on this trail"
        )
    z_floor, kappa_bound = float(np.min(f + h_min / sigma)), float(np.max(np.abs(kappa))) * h_max
    return Reach(float(xs[np.argmin(f)]), z_floor, kappa_bound, float(np.min(1.0 - kappa * h_max)))
