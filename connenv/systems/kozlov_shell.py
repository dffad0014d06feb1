"""An elliptic shell in an ideal fluid, steered by a point mass moving inside it (Kozlov & Ramodanov 2001).

The shell, semi-axes a (body x) and b (body y), mass M and moment of inertia J about its centre, moves in an
unbounded planar ideal fluid of density ρ, at rest at infinity, without circulation. Its configuration
g = (x, y, θ) ∈ SE(2) is free (q); the body-frame position u = (u₁, u₂) of a point mass m inside it is assigned.
ξ = (v₁, v₂, ω) is the shell's body velocity and μ = (P₁, P₂, Π) its body momentum (shell, fluid and mass
together, about the shell's centre). The fluid acts only through the added masses λ₁ = ρπb², λ₂ = ρπa²,
λ₃ = ρπ(a² − b²)²/8 (the exterior Neumann problem of an ellipse, in closed form), and

    T = ½ ξᵀ I(u) ξ + ξᵀ C(u) u̇ + ½ m |u̇|²,    μ = I(u) ξ + C(u) u̇
    I(u) = [[M+m+λ₁, 0, −m u₂], [0, M+m+λ₂, m u₁], [−m u₂, m u₁, J+λ₃+m|u|²]]    the locked inertia
    C(u) = m [[1, 0], [0, 1], [−u₂, u₁]]                                           the coupling

Full model (`KozlovShell`), state y = (x, y, θ, P₁, P₂, Π): Kirchhoff's equations, Euler–Poincaré on SE(2),

    ξ = I⁻¹ (μ − C u̇),   Ṗ₁ = ω P₂,   Ṗ₂ = −ω P₁,   Π̇ = v₂ P₁ − v₁ P₂,

and the reconstruction ẋ = cos θ v₁ − sin θ v₂, ẏ = sin θ v₁ + cos θ v₂, θ̇ = ω. The spatial momentum
(R(θ) P, Π + x P_y − y P_x) is conserved.

Reduced model (`ReducedKozlovShell`), state y = (x, y, θ): μ = 0 is invariant, and there ξ = −I⁻¹ C u̇, the
mechanical connection. The motion is then geometric: a closed loop of u moves the shell by the connection's
holonomy, whatever the speed at which it is run.

In Bressan's terms, with q = (x, y, θ) and L(θ) = R(θ) ⊕ 1 (so that q̇ = L ξ), G11 = L I Lᵀ, G12 = L C, G22 = m:
K = L I⁻¹ C ≠ 0 and B = m − Cᵀ I⁻¹ C does not depend on q, so the shell is fit for jumps, not strongly.

States carry their coordinates on the last axis; everything broadcasts over leading axes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from connenv.core.backend import ARRAYS, components, namespace
from connenv.systems.ideal_fluid import added_masses, kirchhoff, reconstruct, space_frame, spatial_momentum


@dataclass(frozen=True)
class KozlovShell:
    a: float = 1.0
    b: float = 0.5
    shell_mass: float = 1.0
    shell_inertia: float | None = None  # J; None: M (a² + b²)/4, a uniform elliptic disc
    rho: float = 1.0
    mass: float = 1.0

    n = 3
    m = 2

    @property
    def J(self) -> float:
        return self.shell_mass * (self.a**2 + self.b**2) / 4 if self.shell_inertia is None else self.shell_inertia

    @property
    def added_masses(self) -> tuple[float, float, float]:
        """(λ₁, λ₂, λ₃) = ρπ (b², a², (a² − b²)²/8)."""
        return added_masses(self.a, self.b, self.rho)

    def _diagonal(self, u1, u2):
        """(α, β, γ): the diagonal of I(u)."""
        lam1, lam2, lam3 = self.added_masses
        total = self.shell_mass + self.mass
        return total + lam1, total + lam2, self.J + lam3 + self.mass * (u1 * u1 + u2 * u2)

    def locked_inertia(self, u):
        """I(u), shape (..., 3, 3)."""
        alpha, beta, gamma = self._diagonal(u[..., 0], u[..., 1])
        m1, m2 = self.mass * u[..., 0], self.mass * u[..., 1]
        alpha, beta = np.full_like(gamma, alpha), np.full_like(gamma, beta)
        zero = np.zeros_like(gamma)
        rows = [[alpha, zero, -m2], [zero, beta, m1], [-m2, m1, gamma]]
        return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)

    def coupling(self, u):
        """C(u), shape (..., 3, 2)."""
        one, zero = np.ones_like(u[..., 0]), np.zeros_like(u[..., 0])
        rows = [[one, zero], [zero, one], [-u[..., 1], u[..., 0]]]
        return self.mass * np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)

    def body_velocity(self, mu, u, u_dot):
        """ξ = I(u)⁻¹ (μ − C(u) u̇), by eliminating ω (the Schur complement of I's diagonal block)."""
        return np.stack(self._body_velocity(components(mu), components(u), components(u_dot)), axis=-1)

    def _body_velocity(self, mu, u, u_dot):
        (p1, p2, pi), (u1, u2), (u1_dot, u2_dot), m = mu, u, u_dot, self.mass
        w1, w2, w3 = p1 - m * u1_dot, p2 - m * u2_dot, pi - m * (u1 * u2_dot - u2 * u1_dot)
        alpha, beta, gamma = self._diagonal(u1, u2)
        omega = (w3 + m * u2 * w1 / alpha - m * u1 * w2 / beta) / (gamma - m * m * (u2 * u2 / alpha + u1 * u1 / beta))
        return (w1 + m * u2 * omega) / alpha, (w2 - m * u1 * omega) / beta, omega

    def vector_field(self, y, u, u_dot):
        """Full model: ẏ for y = (x, y, θ, P₁, P₂, Π), Kirchhoff's equations and the reconstruction."""
        _, _, theta, p1, p2, pi = components(y)
        v1, v2, omega = self._body_velocity((p1, p2, pi), components(u), components(u_dot))
        ops = ARRAYS if isinstance(theta, float) else namespace(theta)  # numpy's, on one state too; JAX's on its rows
        return ops.stack([*reconstruct(theta, v1, v2, omega, ops), *kirchhoff(p1, p2, pi, v1, v2, omega)], axis=-1)

    def spatial_momentum(self, y):
        """(R(θ) P, Π + x P_y − y P_x): the total momentum in the space frame, conserved by the full model."""
        ops = namespace(y)
        return ops.stack(spatial_momentum(*(y[..., i] for i in range(6)), ops), axis=-1)

    def energy(self, mu, u, u_dot):
        """T = ½ ξᵀ I ξ + ξᵀ C u̇ + ½ m |u̇|² = ½ ξᵀ (μ + C u̇) + ½ m |u̇|²; conserved while u is held."""
        xi = self.body_velocity(mu, u, u_dot)
        c_u_dot = (self.coupling(u) @ u_dot[..., None])[..., 0]
        return 0.5 * np.sum((mu + c_u_dot) * xi, axis=-1) + 0.5 * self.mass * np.sum(u_dot * u_dot, axis=-1)

    # -- Bressan's form, for connenv.core.mechanics --------------------------

    def metric(self, q, u):
        """(G11, G12, G22) in the coordinates q = (x, y, θ): L I Lᵀ, L C, m 1, with L = R(θ) ⊕ 1."""
        frame = space_frame(q[..., 2])
        G11 = frame @ self.locked_inertia(u) @ np.swapaxes(frame, -1, -2)
        G12 = frame @ self.coupling(u)
        G22 = self.mass * np.broadcast_to(np.eye(2), G12.shape[:-2] + (2, 2))
        return G11, G12, G22

    def potential(self, q, u):
        return np.zeros(np.broadcast_shapes(q.shape[:-1], u.shape[:-1]))


@dataclass(frozen=True)
class ReducedKozlovShell(KozlovShell):
    """The shell at zero momentum: state y = (x, y, θ) and ξ = −I⁻¹ C u̇, the mechanical connection A = I⁻¹ C on
    SE(2) in the body frame (a ``connenv.core.steppers.ConnectionSystem``: the Magnus stepper's)."""

    group = "SE2"
    frame = "body"

    def connection(self, u):
        """A(u) = I(u)⁻¹ C(u), shape (..., 3, 2)."""
        return np.linalg.solve(self.locked_inertia(u), self.coupling(u))

    def group_velocity(self, u, u_dot):
        """ξ = −A(u) u̇ = −I⁻¹ C u̇ in closed form, as components (v₁, v₂, ω): floats for one u (a tuple of floats or
        a 1-D array), arrays over rows for a batch (..., 2). With μ = 0 in `_body_velocity`,

            ω = (b′ u₂ u̇₁ − a′ u₁ u̇₂) / (c + a′ u₁² + b′ u₂²),   v₁ = m (u₂ ω − u̇₁)/α,   v₂ = −m (u₁ ω + u̇₂)/β,

        a′ = m (1 − m/β), b′ = m (1 − m/α), c = J + λ₃, α = M + m + λ₁, β = M + m + λ₂."""
        if isinstance(u, np.ndarray):
            u, u_dot = components(u), components(u_dot)
        (u1, u2), (u1_dot, u2_dot) = u, u_dot
        m_alpha, m_beta, a_, b_, c = self._connection_constants
        omega = (b_ * u2 * u1_dot - a_ * u1 * u2_dot) / (c + a_ * u1 * u1 + b_ * u2 * u2)
        return m_alpha * (u2 * omega - u1_dot), -m_beta * (u1 * omega + u2_dot), omega

    def segment_velocity(self, u, u_dot, t):
        """ξ at u + t u̇ over a batch, components of shape t.shape: u, u̇ of shape (N, 2), t (nodes, N) or (nodes, 1).
        Along the straight path group_velocity's ω is a rational function of t,

            ω(t) = (n₀ + n₁ t) / (C₀ + t (B + A t)),   n₀ = b′ u₂ u̇₁ − a′ u₁ u̇₂,   n₁ = (b′ − a′) u̇₁ u̇₂,
            C₀ = c + a′ u₁² + b′ u₂²,   B = 2 (a′ u₁ u̇₁ + b′ u₂ u̇₂),   A = a′ u̇₁² + b′ u̇₂²,

        whose coefficients are per row, so that few operations run over the nodes."""
        m_alpha, m_beta, a_, b_, c = self._connection_constants
        rows = type(u) is np.ndarray  # else JAX's traced rows (connenv.jax): the same arithmetic, not in place
        (u1, u2), (d1, d2) = (np.ascontiguousarray(u.T), np.ascontiguousarray(u_dot.T)) if rows else (u.T, u_dot.T)
        denominator = (a_ * d1 * d1 + b_ * d2 * d2) * t  # in place over the nodes: see se2_body_flow
        denominator += 2.0 * (a_ * u1 * d1 + b_ * u2 * d2)
        denominator *= t
        denominator += c + a_ * u1 * u1 + b_ * u2 * u2
        omega = (b_ - a_) * d1 * d2 * t
        omega += b_ * u2 * d1 - a_ * u1 * d2
        omega /= denominator
        v1 = (m_alpha * d2) * t
        v1 += m_alpha * u2
        v1 *= omega
        v1 -= m_alpha * d1
        v2 = np.multiply(-m_beta * d1, t, out=denominator) if rows else -m_beta * d1 * t
        v2 -= m_beta * u1
        v2 *= omega
        v2 -= m_beta * d2
        return v1, v2, omega

    @functools.cached_property
    def _connection_constants(self):
        """(m/α, m/β, a′, b′, c) of group_velocity."""
        alpha, beta, _ = self._diagonal(0.0, 0.0)
        m, lam3 = self.mass, self.added_masses[2]
        return m / alpha, m / beta, m * (1.0 - m / beta), m * (1.0 - m / alpha), self.J + lam3

    def vector_field(self, y, u, u_dot):
        """Reduced model: ẏ for y = (x, y, θ), the connection ξ = −I⁻¹ C u̇ reconstructed on SE(2)."""
        xi = self._body_velocity((0.0, 0.0, 0.0), components(u), components(u_dot))
        ops = ARRAYS if isinstance(components(y)[2], float) else namespace(components(y)[2])  # as vector_field's
        return ops.stack(ops.broadcast_arrays(*reconstruct(components(y)[2], *xi, ops)), axis=-1)
