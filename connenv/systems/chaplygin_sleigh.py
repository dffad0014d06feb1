"""The Chaplygin sleigh steered by a moving mass: a nonholonomic constraint plus an active one.

A planar sled of mass M and moment of inertia J about its centre of mass C rests on a knife edge at the point P of
its body axis, C a distance a ahead of P. The knife edge forbids P any sideways velocity. A point mass m rides on a
rail across the sled through C, at the body offset u (left positive), which the controller assigns (an *active
constraint*). The configuration is (x, y, φ): P and the heading; e₁ = (cos φ, sin φ) points forward and
e₂ = (−sin φ, cos φ) left.

**Kinetic energy.** With (v, w) the body velocity of P (forward, sideways) and ω = φ̇, C moves at v e₁ + (w + aω) e₂
and the mass, at C + u e₂, at (v − ωu) e₁ + (w + aω + u̇) e₂, so

    T = ½ M (v² + (w + aω)²) + ½ J ω² + ½ m [(v − ωu)² + (w + aω + u̇)²].

The knife edge is w = 0 (not integrable: P may reach any point with any heading).

**Lagrange–d'Alembert.** The constraint force acts at P along e₂, does no work on motions with w = 0 and, with the
body frame at P, exerts no torque about P. In the body frame of SE(2) at P (Euler–Poincaré with the constraint),
the momenta Pᵥ = ∂T/∂v, P_w = ∂T/∂w, Π = ∂T/∂ω obey

    Ṗᵥ = ω P_w,    Ṗ_w = −ω Pᵥ + λ,    Π̇ = w Pᵥ − v P_w,

λ the constraint force. At w = 0 the second line only gives λ, and with M_t = M + m

    p₁ = Pᵥ = M_t v − m u ω,
    p₂ = Π  = (J + M_t a² + m u²) ω − m u v + m a u̇,
    P_w = M_t a ω + m u̇,
    ṗ₁ = ω P_w,    ṗ₂ = −v P_w,    ẋ = v cos φ,  ẏ = v sin φ,  φ̇ = ω.

In Bressan's notation the free velocities (v, ω) and u̇ share the metric

    G11 = [[M_t, −m u], [−m u, J + M_t a² + m u²]],   G12 = [0, m a]ᵀ,   G22 = m,

p = G11 (v, ω) + G12 u̇, so (v, ω) = A (p − G12 u̇) with A = G11⁻¹, K = A G12. The state y = (x, y, φ, p₁, p₂) is
continuous when u̇ jumps (u continuous), (v, ω) is not. With u ≡ 0 this is the classical sleigh of mass M_t,
inertia J and offset a: v̇ = a ω², ω̇ = −M_t a ω v / (J + M_t a²). With u held (u̇ = 0), T = ½ pᵀ A p is conserved.

**Jump class (Bressan–Rampazzo).** With a nonholonomic constraint Γ (here w = 0) and the leaves Λ_u = {u = const},
the system is fit for jumps iff the bundle orthogonal to the leaves within Γ, D = {velocities in Γ orthogonal to
Γ ∩ TΛ}, is Γ-geodesically invariant: a free motion (u free too, no force but the knife edge's) that starts with
its velocity in D keeps it there. D is p = 0 (p pairs the velocity with the leaf directions), so the test is
ṗ = 0 along D (ṗ follows from the (x, y, φ) equations alone, whatever holds u, so the steered field gives the
free motion's ṗ). On D, (v, ω) = −K u̇ and ṗ is a quadratic form in u̇; `ChaplyginSleigh.jump_class` evaluates it
and decides (the tests derive it again with sympy from the Lagrangian in inertial coordinates). Here ṗ₁|_D = −m² a M_t (M_t J + m M u²) u̇² / D² with
D = det G11 > 0: fit iff a = 0. With the knife edge behind C (a > 0) the sleigh is *not* fit for jumps: u̇ enters
the equations quadratically and shaking the mass acts as a force, which is what propels the sleigh (the control is
then u̇, bounded). With a = 0, K = 0 and ṗ is affine in u̇: fit, and a jump of u follows the jump equations
dp/ds = [f(y, u(s), Δu) − f(y, u(s), 0)]_p (the terms of the field linear in u̇; dg/ds = 0 since K = 0).

States are y = (x, y, φ, p₁, p₂) on the last axis, u and u̇ arrays (..., 1); everything broadcasts over leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connenv.core.mechanics import JumpClass


@dataclass(frozen=True)
class ChaplyginSleigh:
    """The sleigh of the module: sled_mass M, sled_inertia J (about C), offset a (C ahead of P), mass m."""

    sled_mass: float = 1.0
    sled_inertia: float = 0.1
    offset: float = 0.5
    mass: float = 0.5

    def metric(self, u):
        """(G11, G12) at the mass offset u (array (...)): (..., 2, 2) and (..., 2)."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        total = M + m
        one = np.ones_like(u)
        G11 = np.stack([np.stack([total * one, -m * u], -1), np.stack([-m * u, J + total * a * a + m * u * u], -1)], -2)
        return G11, np.stack([0.0 * one, m * a * one], -1)

    def velocities(self, y, u, u_dot):
        """(v, ω) = A (p − G12 u̇), u and u̇ arrays (...) of the mass's offset and velocity."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        total = M + m
        p1, p2 = y[..., 3], y[..., 4] - m * a * u_dot
        inertia = J + total * a * a + m * u * u
        det = total * inertia - m * m * u * u
        return (inertia * p1 + m * u * p2) / det, (m * u * p1 + total * p2) / det

    def momenta(self, v, omega, u, u_dot):
        """p = G11 (v, ω) + G12 u̇."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        total = M + m
        return total * v - m * u * omega, (J + total * a * a + m * u * u) * omega - m * u * v + m * a * u_dot

    def vector_field(self, y, u, u_dot):
        """ẏ = (v cos φ, v sin φ, ω, ω P_w, −v P_w), P_w = M_t a ω + m u̇, under the control (u, u̇) (arrays (..., 1))."""
        u, u_dot = u[..., 0], u_dot[..., 0]
        v, omega = self.velocities(y, u, u_dot)
        phi = y[..., 2]
        lateral = (self.sled_mass + self.mass) * self.offset * omega + self.mass * u_dot
        return np.stack([v * np.cos(phi), v * np.sin(phi), omega, omega * lateral, -v * lateral], -1)

    def jump_field(self, y, u, delta_u):
        """(dy/ds) of a jump of u along u(s) = u + s Δu, for a system fit for jumps: the part of the vector field
        linear in u̇ (its quadratic part vanishes by fitness), at u̇ = Δu."""
        return self.vector_field(y, u, delta_u) - self.vector_field(y, u, 0.0 * delta_u)

    def energy(self, y, u, u_dot):
        """T = ½ [v ω u̇] G [v ω u̇]ᵀ, u and u̇ arrays (...); with u̇ = 0, ½ pᵀ A p."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        v, omega = self.velocities(y, u, u_dot)
        return 0.5 * (M * (v * v + a * a * omega * omega) + J * omega * omega
                      + m * ((v - omega * u) ** 2 + (a * omega + u_dot) ** 2))

    def orthogonal_drift(self, u, u_dot):
        """ṗ at the velocity (v, ω, u̇) = (−K u̇, u̇) of the orthogonal bundle D = {p = 0} (u, u̇ arrays (...)): the
        rate at which a free motion leaves D. The knife edge's and the (x, y, φ) equations give ṗ whatever force
        holds u, so this is the Γ-geodesic's ṗ (u free) as well as the steered one's."""
        y = np.zeros((*np.shape(u), 5))
        return self.vector_field(y, np.asarray(u, float)[..., None], np.asarray(u_dot, float)[..., None])[..., 3:]

    def jump_class(self, u_samples, rtol: float = 1e-9) -> JumpClass:
        """Bressan–Rampazzo's class, derived: fit iff D is Γ-geodesically invariant, ṗ = 0 on D at every sampled
        offset u (on D, ṗ is a quadratic form in u̇: u̇ = 1 decides); strongly fit if moreover K = A G12 = 0 and
        ṗ does not depend on u̇ off D. Zero is relative: |·| ≤ rtol · (M + m) (1 + |u|)."""
        u = np.asarray(u_samples, float)
        scale = rtol * (self.sled_mass + self.mass) * (1.0 + np.abs(u))[..., None]
        if np.any(np.abs(self.orthogonal_drift(u, np.ones_like(u))) > scale):
            return JumpClass.GENERAL
        G11, G12 = self.metric(u)
        K = np.linalg.solve(G11, G12[..., None])[..., 0]
        y = np.broadcast_to(np.array([0.0, 0.0, 0.0, 1.0, 1.0]), (*u.shape, 5))
        moved = self.vector_field(y, u[..., None], np.ones_like(u)[..., None]) - self.vector_field(
            y, u[..., None], np.zeros_like(u)[..., None])
        if np.all(np.abs(K) <= rtol) and np.all(np.abs(moved[..., 3:]) <= scale):
            return JumpClass.STRONGLY_FIT
        return JumpClass.FIT
