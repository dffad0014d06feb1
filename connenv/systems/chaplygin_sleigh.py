"""The Chaplygin sleigh steered by a moving mass: a nonholonomic constraint plus an active one.

A planar sled of mass M and moment of inertia J about its centre of mass C rests on a knife edge at the point P of
its body axis, C a distance a ahead of P. The knife edge forbids P any sideways velocity. A point mass m moves in a
box on the sled, at the body offset u = (u₁, u₂) from C (u₁ forward, u₂ left), which the controller assigns (an
*active constraint*); u₁ ≡ 0 is a transverse rail through C. The configuration is (x, y, φ): P and the heading;
e₁ = (cos φ, sin φ) points forward and e₂ = (−sin φ, cos φ) left.

**Kinetic energy.** With (v, w) the body velocity of P (forward, sideways) and ω = φ̇, C moves at v e₁ + (w + aω) e₂
and the mass at (v − ω u₂ + u̇₁) e₁ + (w + (a + u₁) ω + u̇₂) e₂, so

    T = ½ M (v² + (w + aω)²) + ½ J ω² + ½ m [(v − ω u₂ + u̇₁)² + (w + (a + u₁) ω + u̇₂)²].

The knife edge is w = 0 (not integrable: P may reach any point with any heading).

**Lagrange–d'Alembert.** The constraint force acts at P along e₂, does no work on motions with w = 0 and, with the
body frame at P, exerts no torque about P. In the body frame of SE(2) at P (Euler–Poincaré with the constraint),
the momenta Pᵥ = ∂T/∂v, P_w = ∂T/∂w, Π = ∂T/∂ω obey

    Ṗᵥ = ω P_w,    Ṗ_w = −ω Pᵥ + λ,    Π̇ = w Pᵥ − v P_w,

λ the constraint force. At w = 0 the second line only gives λ, and with p = (p₁, p₂) = (Pᵥ, Π),

    p₁ = M v + m (v − ω u₂ + u̇₁),
    p₂ = (J + M a²) ω + m [−u₂ (v − ω u₂ + u̇₁) + (a + u₁)((a + u₁) ω + u̇₂)],
    P_w = M a ω + m ((a + u₁) ω + u̇₂),
    ṗ₁ = ω P_w,    ṗ₂ = −v P_w,    ẋ = v cos φ,  ẏ = v sin φ,  φ̇ = ω.

In Bressan's notation the free velocities (v, ω) and u̇ share the metric, M_t = M + m,

    G11 = [[M_t, −m u₂], [−m u₂, J + M a² + m (u₂² + (a + u₁)²)]],   G12 = [[m, 0], [−m u₂, m (a + u₁)]],

p = G11 (v, ω) + G12 u̇, so (v, ω) = A (p − G12 u̇) with A = G11⁻¹, K = A G12. The state y = (x, y, φ, p₁, p₂) is
continuous when u̇ jumps (u continuous), (v, ω) is not. With u ≡ 0 this is the classical sleigh of mass M_t,
inertia J and offset a: v̇ = a ω², ω̇ = −M_t a ω v / (J + M_t a²). With u held (u̇ = 0), T = ½ pᵀ A p is conserved.
Every term of the equations is quadratic in (v, ω, u̇): from rest, the path of the sled depends on the path of u,
not on its speed.

**Jump class (Bressan–Rampazzo).** With a nonholonomic constraint Γ (here w = 0) and the leaves Λ_u = {u = const},
the system is fit for jumps iff the bundle orthogonal to the leaves within Γ, D = {velocities in Γ orthogonal to
Γ ∩ TΛ}, is Γ-geodesically invariant: a free motion (u free too, no force but the knife edge's) that starts with
its velocity in D keeps it there. D is p = 0 (p pairs the velocity with the leaf directions), so the test is
ṗ = 0 along D (ṗ follows from the (x, y, φ) equations alone, whatever holds u, so the steered field gives the
free motion's ṗ). On D, (v, ω) = −K u̇ and ṗ is a quadratic form in u̇; `ChaplyginSleigh.jump_class` evaluates it
and decides (the tests derive it again with sympy from the Lagrangian in inertial coordinates). On the rail
(u₁ = 0), ṗ₁|_D = −m² a M_t (M_t J + m M u₂²) u̇₂² / D² with D = det G11 > 0: fit iff a = 0. With the knife edge
behind C (a > 0), or with the mass free to move along the axis (which shifts the lever a + u₁), the sleigh is *not*
fit for jumps: u̇ enters the equations quadratically and shaking the mass acts as a force, which is what propels
it (the control is then u̇, bounded). With a = 0 on the rail, K = 0 and ṗ is affine in u̇: fit, and a jump of u
follows the jump equations dy/ds = f(y, u(s), Δu) − f(y, u(s), 0) (the terms of the field linear in u̇).

**Why a box and not the rail alone.** From rest the state is on D, where the rail's only thrust is ṗ₁ < 0: shaking
pushes P straight backward. Its turning effects are a bounded kinematic yaw, ω = −K₂ u̇₂, and the torque ṗ₂|_D,
which is m u₂ / M_t of the thrust (u₂ ≤ rail): the backward run flips over (going backward is unstable) before the
heading can follow a target off the tail. With the box, moving the mass along the axis and across it together
gives the torque ṗ₂|_D = m² J u̇₁ u̇₂ / (M_t (J + M_t a²)) at u = 0, of either sign: diagonal shaking turns the sled
(tests/test_chaplygin_sleigh_physics.py shows both).

States are y = (x, y, φ, p₁, p₂) on the last axis, u and u̇ arrays (..., 2); everything broadcasts over leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connenv.core.backend import FLOATS, namespace
from connenv.core.mechanics import JumpClass


@dataclass(frozen=True)
class ChaplyginSleigh:
    """The sleigh of the module: sled_mass M, sled_inertia J (about C), offset a (C ahead of P), mass m. The mass's
    body offset from C is u = (u₁ along the axis, u₂ across it); u₁ ≡ 0 is the transverse rail."""

    sled_mass: float = 1.0
    sled_inertia: float = 0.1
    offset: float = 0.5
    mass: float = 0.5

    def metric(self, u):
        """(G11, G12) at the mass offset u (array (..., 2)): (..., 2, 2) each."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        u1, u2 = u[..., 0], u[..., 1]
        one = np.ones_like(u1)
        G11 = np.stack([np.stack([(M + m) * one, -m * u2], -1),
                        np.stack([-m * u2, J + M * a * a + m * (u2 * u2 + (a + u1) ** 2)], -1)], -2)
        G12 = np.stack([np.stack([m * one, 0.0 * one], -1), np.stack([-m * u2, m * (a + u1)], -1)], -2)
        return G11, G12

    def velocities(self, y, u, u_dot):
        """(v, ω) = A (p − G12 u̇), u and u̇ arrays (..., 2)."""
        return self._velocities(y[..., 3], y[..., 4], u[..., 0], u[..., 1], u_dot[..., 0], u_dot[..., 1])

    def _velocities(self, p1, p2, u1, u2, d1, d2):
        """velocities on components (p₁, p₂, u₁, u₂, u̇₁, u̇₂): Python floats of one state, or arrays over rows."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        total, lever = M + m, a + u1
        p1 = p1 - m * d1
        p2 = p2 + m * u2 * d1 - m * lever * d2
        inertia = J + M * a * a + m * (u2 * u2 + lever * lever)
        det = total * inertia - m * m * u2 * u2
        return (inertia * p1 + m * u2 * p2) / det, (m * u2 * p1 + total * p2) / det

    def momenta(self, v, omega, u, u_dot):
        """p = G11 (v, ω) + G12 u̇: the momenta ∂T/∂v, ∂T/∂ω."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        u1, u2, d1, d2 = u[..., 0], u[..., 1], u_dot[..., 0], u_dot[..., 1]
        along = v - omega * u2 + d1  # the mass's velocity along the axis
        p1 = M * v + m * along
        p2 = (J + M * a * a) * omega + m * (-u2 * along + (a + u1) * ((a + u1) * omega + d2))
        return p1, p2

    def vector_field(self, y, u, u_dot):
        """ẏ = (v cos φ, v sin φ, ω, ω P_w, −v P_w), P_w = M a ω + m ((a + u₁) ω + u̇₂), under the control (u, u̇)."""
        if y.ndim == 1 and u.ndim == 1 and u_dot.ndim == 1 and type(y) is np.ndarray:  # one state: Python floats,
            return np.array(self.vector_field_one(y.tolist(), u, u_dot))  # no array calls but the result
        ops = namespace(y)  # numpy's rows (ARRAYS: numpy's cos, sin and stack), or JAX's (connenv.jax)
        rates = self._rates(y[..., 2], y[..., 3], y[..., 4], u[..., 0], u[..., 1], u_dot[..., 0], u_dot[..., 1], ops)
        return ops.stack(rates, -1)

    def vector_field_one(self, y, u, u_dot):
        """vector_field of one state y = [x, y, φ, p₁, p₂] of Python floats (u and u̇ arrays (2,)), as a list."""
        (u1, u2), (d1, d2) = u.tolist(), u_dot.tolist()
        return self._rates(y[2], y[3], y[4], u1, u2, d1, d2, FLOATS)

    def _rates(self, phi, p1, p2, u1, u2, d1, d2, ops):
        """ẏ's components at (φ, p₁, p₂) under (u, u̇) given as components: Python floats with ops=FLOATS, or rows
        with their namespace (numpy's, JAX's)."""
        M, a, m = self.sled_mass, self.offset, self.mass
        v, omega = self._velocities(p1, p2, u1, u2, d1, d2)
        lateral = M * a * omega + m * ((a + u1) * omega + d2)
        return [v * ops.cos(phi), v * ops.sin(phi), omega, omega * lateral, -v * lateral]

    def jump_field(self, y, u, delta_u):
        """(dy/ds) of a jump of u along u(s) = u + s Δu, for a system fit for jumps: the part of the vector field
        linear in u̇ (its quadratic part vanishes by fitness), at u̇ = Δu."""
        return self.vector_field(y, u, delta_u) - self.vector_field(y, u, 0.0 * delta_u)

    def energy(self, y, u, u_dot):
        """T = ½ [v ω u̇] G [v ω u̇]ᵀ, u and u̇ arrays (..., 2); with u̇ = 0, ½ pᵀ A p."""
        M, J, a, m = self.sled_mass, self.sled_inertia, self.offset, self.mass
        v, omega = self.velocities(y, u, u_dot)
        along = v - omega * u[..., 1] + u_dot[..., 0]
        across = (a + u[..., 0]) * omega + u_dot[..., 1]
        return 0.5 * (M * (v * v + a * a * omega * omega) + J * omega * omega + m * (along * along + across * across))

    def orthogonal_drift(self, u, u_dot):
        """ṗ at the velocity (v, ω, u̇) = (−K u̇, u̇) of the orthogonal bundle D = {p = 0} (u, u̇ arrays (..., 2)): the
        rate at which a free motion leaves D. The knife edge's and the (x, y, φ) equations give ṗ whatever force
        holds u, so this is the Γ-geodesic's ṗ (u free) as well as the steered one's."""
        u, u_dot = np.broadcast_arrays(np.asarray(u, float), np.asarray(u_dot, float))
        return self.vector_field(np.zeros((*u.shape[:-1], 5)), u, u_dot)[..., 3:]

    def jump_class(self, u_samples, directions=((1.0, 0.0), (0.0, 1.0), (1.0, 1.0)), rtol: float = 1e-9) -> JumpClass:
        """Bressan–Rampazzo's class, derived: fit iff D is Γ-geodesically invariant, ṗ = 0 on D at every sampled
        offset u (..., 2) for every admissible u̇ (on D, ṗ is a quadratic form in u̇: the `directions` e₁, e₂ and
        e₁ + e₂ decide it; the rail's only direction is e₂); strongly fit if moreover K u̇ = 0 and ṗ does not depend
        on u̇ off D. Zero is relative: |·| ≤ rtol (M + m) (1 + |u|)."""
        u = np.asarray(u_samples, float)[..., None, :]
        rates = np.asarray(directions, float)
        scale = rtol * (self.sled_mass + self.mass) * (1.0 + np.linalg.norm(u, axis=-1))[..., None]
        if np.any(np.abs(self.orthogonal_drift(u, rates)) > scale):
            return JumpClass.GENERAL
        G11, G12 = self.metric(u[..., 0, :])
        K = np.linalg.solve(G11, G12) @ rates.T
        y = np.array([0.0, 0.0, 0.0, 1.0, 1.0])
        moved = self.vector_field(y, u, rates) - self.vector_field(y, u, 0.0 * rates)
        if np.all(np.abs(K) <= rtol) and np.all(np.abs(moved[..., 3:]) <= scale):
            return JumpClass.STRONGLY_FIT
        return JumpClass.FIT
