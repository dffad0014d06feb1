"""Planar rigid bodies in an unbounded ideal fluid at rest at infinity, without circulation: what the Kozlov shell
and the snake swimmer share.

A body's pose g = (x, y, θ) ∈ SE(2) moves with its body velocity ξ = (v₁, v₂, ω) by ġ = g ξ; q̇ = L(θ) ξ with
L(θ) = R(θ) ⊕ 1. The fluid acts only through added masses, which for an ellipse of semi-axes a (body x) and b
(body y) and fluid density ρ are λ₁ = ρπb², λ₂ = ρπa², λ₃ = ρπ(a² − b²)²/8 (the exterior Neumann problem of the
ellipse, in closed form). The body momentum μ = (P₁, P₂, Π) obeys Kirchhoff's equations, and the spatial momentum
(R(θ) P, Π + x P_y − y P_x) is conserved.

The functions take components (``connenv.core.backend``: floats of one state, arrays over rows) and ``ops``.
"""

from __future__ import annotations

import math

import numpy as np


def added_masses(a: float, b: float, rho: float) -> tuple[float, float, float]:
    """(λ₁, λ₂, λ₃) = ρπ (b², a², (a² − b²)²/8): along body x (the semi-axis a), along body y, and in rotation."""
    a2, b2 = a**2, b**2
    return rho * math.pi * b2, rho * math.pi * a2, rho * math.pi * (a2 - b2) ** 2 / 8


def space_frame(theta):
    """L(θ) = R(θ) ⊕ 1, shape (..., 3, 3): body components to space components."""
    c, s = np.cos(theta), np.sin(theta)
    one, zero = np.ones_like(c), np.zeros_like(c)
    rows = [[c, -s, zero], [s, c, zero], [zero, zero, one]]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def reconstruct(theta, v1, v2, omega, ops):
    """ġ = g ξ on SE(2): (cos θ v₁ − sin θ v₂, sin θ v₁ + cos θ v₂, ω)."""
    c, s = ops.cos(theta), ops.sin(theta)
    return c * v1 - s * v2, s * v1 + c * v2, omega


def kirchhoff(p1, p2, pi, v1, v2, omega):
    """μ̇ = ad*_ξ μ on se(2)*: (ω P₂, −ω P₁, v₂ P₁ − v₁ P₂)."""
    return omega * p2, -omega * p1, v2 * p1 - v1 * p2


def spatial_momentum(x, y, theta, p1, p2, pi, ops):
    """(R(θ) P, Π + x P_y − y P_x): the body momentum μ = (P₁, P₂, Π) at the pose (x, y, θ), in the space frame."""
    c, s = ops.cos(theta), ops.sin(theta)
    px, py = c * p1 - s * p2, s * p1 + c * p2
    return px, py, pi + x * py - y * px
