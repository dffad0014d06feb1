"""A chain of three elliptic links swimming in a perfect fluid by bending its two joints (Kanso, Marsden, Rowley &
Melli-Huber 2005).

Three identical rigid elliptic links, semi-axes a (along the link) and b, mass m_l = link_density · πab and moment
of inertia J_l = m_l (a² + b²)/4 (a uniform elliptic plate) about their centres, are hinged tip to tip in a plane
and immersed in an unbounded planar ideal fluid of density ρ, at rest at infinity, without circulation. The middle
link's pose g = (x, y, θ) ∈ SE(2) is free (q); the joint angles s = (α, β) are assigned. In the middle link's
frame the rear link (1) lies at the angle φ₁ = −α, the front link (3) at φ₃ = β; their centres are

    r₁ = (−a − a cos α, a sin α),    r₃ = (a + a cos β, a sin β),

so that α = β > 0 bends the chain into a C (both ends toward body +y) and α = −β into an S.

Kinetic energy. Each link's fluid is taken as if the link were alone: the added masses λ₁ = ρπb² (along the link),
λ₂ = ρπa² (across it), λ₃ = ρπ(a² − b²)²/8 (rotation), the exterior Neumann problem of one ellipse in closed form.
The links' interaction through the fluid is neglected, as in Kanso et al.'s model; the true fluid energy of the
chain has cross terms between links, largest where the chain is folded. So link i, with body velocity ξᵢ in its
own frame, carries ½ ξᵢᵀ 𝕀ᵢ ξᵢ with 𝕀ᵢ = diag(m_l + λ₁, m_l + λ₂, J_l + λ₃) =: diag(m₁, m₂, j). With the middle
link's body velocity ξ = (v, ω) and h = (r, φ) a link's pose relative to the middle link, the link's centre moves
at v + ω J r + ṙ (J r = (−r_y, r_x)) in the middle frame, i.e. at R(−φ)(v + ω J r + ṙ) in its own, and turns at
ω + φ̇. Writing V = E ξ + D ṡ with E = [[1, 0, −r_y], [0, 1, r_x]], D = ∂r/∂s, and φ̇ = e ṡ, e = ∂φ/∂s:

    T = Σᵢ ½ ξᵢᵀ 𝕀ᵢ ξᵢ = ½ ξᵀ 𝕀_loc ξ + ξᵀ 𝕀_c ṡ + ½ ṡᵀ 𝕀_s ṡ
    𝕀_loc = Σ Eᵀ M E + j e₃e₃ᵀ,   𝕀_c = Σ Eᵀ M D + j e₃ e,   𝕀_s = Σ Dᵀ M D + j eᵀe,
    M(φ) = R(φ) diag(m₁, m₂) R(−φ)

the locked inertia 𝕀_loc(α, β) (the chain frozen in its shape, with its fluid), the coupling 𝕀_c(α, β) and the
shape inertia 𝕀_s (the middle link: r = 0, φ = 0, D = 0, e = 0; the rear link: D = [∂r₁/∂α, 0], e = (−1, 0); the
front link: D = [0, ∂r₃/∂β], e = (0, 1)).

Full model (`SnakeSwimmer`), state y = (x, y, θ, P₁, P₂, Π): μ = (P₁, P₂, Π) = 𝕀_loc ξ + 𝕀_c ṡ, the body
momentum of chain and fluid about the middle link's centre, obeys Kirchhoff's equations (Euler–Poincaré on SE(2);
the Lagrangian does not depend on g),

    ξ = 𝕀_loc⁻¹ (μ − 𝕀_c ṡ),   Ṗ₁ = ω P₂,   Ṗ₂ = −ω P₁,   Π̇ = v₂ P₁ − v₁ P₂,

reconstructed by ẋ = cos θ v₁ − sin θ v₂, ẏ = sin θ v₁ + cos θ v₂, θ̇ = ω. The spatial momentum
(R(θ) P, Π + x P_y − y P_x) is conserved.

Reduced model (`ReducedSnakeSwimmer`), state y = (x, y, θ): μ = 0 is invariant and there ξ = −𝕀_loc⁻¹ 𝕀_c ṡ, the
mechanical connection A = 𝕀_loc⁻¹ 𝕀_c on SE(2) in the body frame. A closed loop of (α, β) moves the chain by its
holonomy whatever the speed at which it is run.

In Bressan's terms, with q = (x, y, θ) and L(θ) = R(θ) ⊕ 1 (q̇ = L ξ): G11 = L 𝕀_loc Lᵀ, G12 = L 𝕀_c, G22 = 𝕀_s,
so K = L 𝕀_loc⁻¹ 𝕀_c ≠ 0 and B = 𝕀_s − 𝕀_cᵀ 𝕀_loc⁻¹ 𝕀_c does not depend on q: fit for jumps, not strongly (the
joint angles fix the shape up to a rigid motion). `connenv.core.mechanics.classify` derives it from `metric`.

The matrices are computed entry by entry on components (Python floats for one state, arrays over rows for a batch)
so that the Lie-group step evaluates the connection on floats at each quadrature node.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from connenv.core.backend import components, floats, namespace
from connenv.systems.ideal_fluid import added_masses, kirchhoff, reconstruct, space_frame, spatial_momentum

JOINT_LIMIT = 2.0 * math.pi / 3.0  # |α|, |β| ≤ 2π/3: the links' tips stay apart


@dataclass(frozen=True)
class SnakeSwimmer:
    a: float = 0.5
    b: float = 0.05
    link_density: float = 1.0
    rho: float = 1.0

    n = 3
    m = 2

    @property
    def link_mass(self) -> float:
        """m_l = link_density · πab."""
        return self.link_density * math.pi * self.a * self.b

    @property
    def link_inertia(self) -> float:
        """J_l = m_l (a² + b²)/4, a uniform elliptic plate about its centre."""
        return self.link_mass * (self.a**2 + self.b**2) / 4

    @property
    def added_masses(self) -> tuple[float, float, float]:
        """(λ₁, λ₂, λ₃) = ρπ (b², a², (a² − b²)²/8), along the link, across it, and in rotation."""
        return added_masses(self.a, self.b, self.rho)

    @functools.cached_property
    def link_inertias(self) -> tuple[float, float, float]:
        """(m₁, m₂, j) = (m_l + λ₁, m_l + λ₂, J_l + λ₃): the diagonal of each link's 𝕀ᵢ in its own frame."""
        lam1, lam2, lam3 = self.added_masses
        return self.link_mass + lam1, self.link_mass + lam2, self.link_inertia + lam3

    # -- the metric on components --------------------------------------------

    def _side_link(self, angle, sign):
        """Entries of one side link's part of 𝕀_loc (I11, I12, I13, I22, I23, I33), of its column of 𝕀_c (c1, c2, c3)
        and of 𝕀_s (its diagonal entry), the link at φ = sign · angle, its centre at
        r = (sign (a + a cos angle), a sin angle). sign −1: the rear link (φ₁ = −α), +1: the front link (φ₃ = β)."""
        ops, a = namespace(angle), self.a
        m1, m2, j = self.link_inertias
        c, s = ops.cos(angle), ops.sin(angle)
        rx, ry = sign * (a + a * c), a * s  # r₁ = (−a − a cos α, a sin α), r₃ = (a + a cos β, a sin β)
        sin_phi = sign * s  # φ = sign · angle
        M11, M22, M12 = m1 * c * c + m2 * s * s, m1 * s * s + m2 * c * c, (m1 - m2) * c * sin_phi
        dx, dy = -sign * a * s, a * c  # ∂r/∂(angle): (a sin α, a cos α) for the rear, (−a sin β, a cos β) front
        e = sign  # ∂φ/∂(angle)
        f1, f2 = M11 * dx + M12 * dy, M12 * dx + M22 * dy  # M D
        I33 = ry * ry * M11 - 2.0 * rx * ry * M12 + rx * rx * M22 + j
        locked = (M11, M12, rx * M12 - ry * M11, M22, rx * M22 - ry * M12, I33)
        coupling = (f1, f2, rx * f2 - ry * f1 + j * e)
        shape = dx * f1 + dy * f2 + j
        return locked, coupling, shape

    def _metric(self, s):
        """(𝕀_loc entries (I11, I12, I13, I22, I23, I33), 𝕀_c columns (α, β) of (c1, c2, c3), 𝕀_s diagonal (sα, sβ))
        at s = (α, β) given as components."""
        alpha, beta = s
        m1, m2, j = self.link_inertias
        rear, rear_c, rear_s = self._side_link(alpha, -1.0)
        front, front_c, front_s = self._side_link(beta, 1.0)
        locked = (m1 + rear[0] + front[0], rear[1] + front[1], rear[2] + front[2], m2 + rear[3] + front[3],
                  rear[4] + front[4], j + rear[5] + front[5])  # the middle link's diag(m₁, m₂, j) and the others'
        return locked, (rear_c, front_c), (rear_s, front_s)

    def locked_inertia(self, s):
        """𝕀_loc(α, β), shape (..., 3, 3)."""
        I11, I12, I13, I22, I23, I33 = np.broadcast_arrays(*self._metric(components(floats(s)))[0])
        return np.stack([np.stack(row, -1) for row in [[I11, I12, I13], [I12, I22, I23], [I13, I23, I33]]], -2)

    def coupling(self, s):
        """𝕀_c(α, β), shape (..., 3, 2): column k the coupling to the k-th joint's rate."""
        rear, front = self._metric(components(floats(s)))[1]
        return np.stack([np.stack(np.broadcast_arrays(*rear), -1), np.stack(np.broadcast_arrays(*front), -1)], -1)

    def shape_inertia(self, s):
        """𝕀_s(α, β), shape (..., 2, 2): diagonal (each joint's rate moves one link)."""
        s_alpha, s_beta = np.broadcast_arrays(*self._metric(components(floats(s)))[2])
        zero = np.zeros_like(s_alpha)
        return np.stack([np.stack([s_alpha, zero], -1), np.stack([zero, s_beta], -1)], -2)

    # -- the full model ------------------------------------------------------

    def _body_velocity(self, mu, s, s_dot):
        """ξ = 𝕀_loc⁻¹ w, w = μ − 𝕀_c ṡ, as components: the symmetric 3×3 solve by cofactors."""
        (I11, I12, I13, I22, I23, I33), ((ca1, ca2, ca3), (cb1, cb2, cb3)), _ = self._metric(s)
        d_alpha, d_beta = s_dot
        w1 = mu[0] - ca1 * d_alpha - cb1 * d_beta
        w2 = mu[1] - ca2 * d_alpha - cb2 * d_beta
        w3 = mu[2] - ca3 * d_alpha - cb3 * d_beta
        C11, C12, C13 = I22 * I33 - I23 * I23, I13 * I23 - I12 * I33, I12 * I23 - I13 * I22
        C22, C23, C33 = I11 * I33 - I13 * I13, I12 * I13 - I11 * I23, I11 * I22 - I12 * I12
        det = I11 * C11 + I12 * C12 + I13 * C13
        return (
            (C11 * w1 + C12 * w2 + C13 * w3) / det,
            (C12 * w1 + C22 * w2 + C23 * w3) / det,
            (C13 * w1 + C23 * w2 + C33 * w3) / det,
        )

    def body_velocity(self, mu, s, s_dot):
        """ξ = 𝕀_loc⁻¹ (μ − 𝕀_c ṡ), shape (..., 3)."""
        return np.stack(np.broadcast_arrays(*self._body_velocity(components(mu), components(s), components(s_dot))), axis=-1)

    def vector_field(self, y, s, s_dot):
        """Full model: ẏ for y = (x, y, θ, P₁, P₂, Π), Kirchhoff's equations and the reconstruction."""
        single = np.ndim(y) == 1 and np.ndim(s) == 1
        y, s, s_dot = (np.asarray(a, float).tolist() if single else components(a) for a in (y, s, s_dot))
        _, _, theta, p1, p2, pi = y
        v1, v2, omega = self._body_velocity((p1, p2, pi), s, s_dot)
        ops = namespace(theta)
        y_dot = (*reconstruct(theta, v1, v2, omega, ops), *kirchhoff(p1, p2, pi, v1, v2, omega))
        return np.array(y_dot) if single else ops.stack(ops.broadcast_arrays(*y_dot), -1)

    def spatial_momentum(self, y):
        """(R(θ) P, Π + x P_y − y P_x): the total momentum of chain and fluid in the space frame, conserved."""
        ops = namespace(y)
        return ops.stack(spatial_momentum(*(y[..., i] for i in range(6)), ops), axis=-1)

    def energy(self, mu, s, s_dot):
        """T = ½ ξᵀ 𝕀_loc ξ + ξᵀ 𝕀_c ṡ + ½ ṡᵀ 𝕀_s ṡ = ½ ξᵀ (μ + 𝕀_c ṡ) + ½ ṡᵀ 𝕀_s ṡ; conserved while s is held."""
        xi = self.body_velocity(mu, s, s_dot)
        c_s_dot = (self.coupling(s) @ s_dot[..., None])[..., 0]
        s_s_dot = (self.shape_inertia(s) @ s_dot[..., None])[..., 0]
        return 0.5 * np.sum((mu + c_s_dot) * xi, axis=-1) + 0.5 * np.sum(s_dot * s_s_dot, axis=-1)

    def link_poses(self, y, s):
        """The three links' poses (x, y, φ) in space, rear, middle, front: shape (..., 3, 3)."""
        y, s = floats(y), floats(s)
        a, (x, y_, theta), (alpha, beta) = self.a, (y[..., i] for i in range(3)), (s[..., 0], s[..., 1])
        c, sn = np.cos(theta), np.sin(theta)
        poses = []
        for rx, ry, phi in [(-a - a * np.cos(alpha), a * np.sin(alpha), -alpha), (0.0 * x, 0.0 * x, 0.0 * x),
                            (a + a * np.cos(beta), a * np.sin(beta), beta)]:  # fmt: skip
            poses.append(np.stack([x + c * rx - sn * ry, y_ + sn * rx + c * ry, theta + phi], -1))
        return np.stack(poses, -2)

    # -- Bressan's form, for connenv.core.mechanics --------------------------

    def metric(self, q, u):
        """(G11, G12, G22) in the coordinates q = (x, y, θ), u = (α, β): L 𝕀_loc Lᵀ, L 𝕀_c, 𝕀_s, L = R(θ) ⊕ 1."""
        frame = space_frame(q[..., 2])
        G11 = frame @ self.locked_inertia(u) @ np.swapaxes(frame, -1, -2)
        G12 = frame @ self.coupling(u)
        shape = np.broadcast_shapes(G11.shape[:-2], np.shape(u)[:-1])
        return G11, G12, np.broadcast_to(self.shape_inertia(u), (*shape, 2, 2))

    def potential(self, q, u):
        return np.zeros(np.broadcast_shapes(q.shape[:-1], u.shape[:-1]))


@dataclass(frozen=True)
class ReducedSnakeSwimmer(SnakeSwimmer):
    """The chain at zero momentum: state y = (x, y, θ) of the middle link and ξ = −𝕀_loc⁻¹ 𝕀_c ṡ, the mechanical
    connection A = 𝕀_loc⁻¹ 𝕀_c on SE(2) in the body frame (a ``connenv.core.steppers.ConnectionSystem``: the
    Lie-group stepper's)."""

    group = "SE2"
    frame = "body"

    def connection(self, s):
        """A(s) = 𝕀_loc(s)⁻¹ 𝕀_c(s), shape (..., 3, 2)."""
        return np.linalg.solve(self.locked_inertia(s), self.coupling(s))

    def group_velocity(self, s, s_dot):
        """ξ = −A(s) ṡ as components (v₁, v₂, ω): floats for one shape (a tuple of floats or a 1-D array), arrays
        over rows for a batch (..., 2)."""
        if isinstance(s, np.ndarray) or (type(s) is not tuple and hasattr(s, "shape")):  # numpy's or JAX's rows
            s, s_dot = components(s), components(s_dot)
        return self._body_velocity((0.0, 0.0, 0.0), s, s_dot)

    def vector_field(self, y, s, s_dot):
        """Reduced model: ẏ for y = (x, y, θ), the connection reconstructed on SE(2)."""
        single = np.ndim(y) == 1 and np.ndim(s) == 1
        y, s, s_dot = (np.asarray(a, float).tolist() if single else components(a) for a in (y, s, s_dot))
        ops = namespace(y[2])
        y_dot = reconstruct(y[2], *self._body_velocity((0.0, 0.0, 0.0), s, s_dot), ops)
        return np.array(y_dot) if single else ops.stack(ops.broadcast_arrays(*y_dot), axis=-1)
