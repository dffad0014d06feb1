"""A pendulum whose pivot is assigned: Kapitza's pendulum, the general (quadratic in u̇) class of active constraints.

θ is the angle of the rod from the downward vertical (free, q = θ); the pivot's position u = (u₁, u₂),
horizontal and vertical, is assigned. The bob of mass m sits at u + l (sin θ, −cos θ), so with
n(θ) = (cos θ, sin θ) the direction in which the bob moves as θ grows,

    T = ½ m (|u̇|² + 2 l θ̇ u̇·n + l² θ̇²),    V = m g (u₂ − l cos θ)
    G11 = m l²,   G12 = m l nᵀ,   G22 = m I,    p = m l² θ̇ + m l u̇·n

Bressan's B = G22 − G21 A G12 = m (I − n nᵀ) depends on θ: the system is *general*, u̇ enters the (θ, p)
equations quadratically and fast vibrations of the pivot act as an effective force. Vibrated vertically,
u₂ = a cos ωt with a ≪ l, the averaged motion feels U = −m g l cos θ + ¼ m a²ω² sin²θ, so the inverted pendulum is
stable when a²ω² > 2 g l (Kapitza 1951). Hamilton's equations of H_u = (p − m l u̇·n)²/(2 m l²) − ½ m |u̇|² + V are

    θ̇ = (p − m l u̇·n) / (m l²),    ṗ = m l θ̇ u̇·n′ − m g l sin θ − c θ̇

with n′ = (−sin θ, cos θ) and c an optional viscous damping at the pivot (torque −c θ̇). Only u̇ appears, not
ü: a pivot velocity that is piecewise constant is admissible, and p is continuous across its jumps while θ̇
jumps by −Δu̇·n/l. Eliminating p gives Newton's θ̈ = −(g sin θ + ü·n)/l − c θ̇/(m l²).

While u̇ is constant the pivot moves uniformly, a Galilean frame: the rod swings as a plain pendulum, and its
energy in that frame, E = ½ m l² θ̇² − m g l cos θ, is conserved. So a segment at constant u̇ has a closed form,
the pendulum's elliptic-function flow (`exact_segment`).

States are y = (θ, p) on the last axis, controls u and u̇ = (u̇₁, u̇₂); everything broadcasts over leading axes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from connenv.core.backend import ARRAYS, FLOATS, floats, is_traced, namespace, traced
from connenv.systems.swing import Swing

FLOAT = np.dtype(float)  # the dtype of the states numpy makes, one object: `_frame` tells it by identity
SEPARATRIX_STEP = 0.01  # ω₀h of the RK4 steps near the separatrix, where the elliptic flow declines


@dataclass(frozen=True)
class KapitzaPendulum:
    length: float = 1.0
    mass: float = 1.0
    g: float = 9.81
    damping: float = 0.0  # c, N·m·s: torque −c θ̇ at the pivot; 0 for the envs' tasks

    n = 1
    m = 2

    def metric(self, q, u):
        theta = q[..., 0] + 0.0 * u[..., 0]
        ml = self.mass * self.length
        G11 = np.full(theta.shape + (1, 1), ml * self.length)
        G12 = ml * np.stack([np.cos(theta), np.sin(theta)], axis=-1)[..., None, :]
        G22 = self.mass * np.broadcast_to(np.eye(2), theta.shape + (2, 2))
        return G11, G12, G22

    def potential(self, q, u):
        return self.mass * self.g * (u[..., 1] - self.length * np.cos(q[..., 0]))

    def theta_dot(self, y, u_dot):
        """θ̇ = (p − m l u̇·n) / (m l²): one state on Python floats, or rows."""
        return self._frame(y, u_dot)[1] / (self.mass * self.length * self.length)

    def _frame(self, y, u_dot):
        """(θ, m l² θ̇, u̇₁, u̇₂, ops), m l² θ̇ = p − m l u̇·n the momentum in the frame of the pivot's velocity:
        Python floats and FLOATS for one state (a float array is taken as it is), arrays and ARRAYS for rows (complex
        on a Jacobian's), or JAX's namespace where y is traced (rows, or a reset's one state)."""
        if not (type(y) is np.ndarray and y.dtype is FLOAT and type(u_dot) is np.ndarray and u_dot.dtype is FLOAT):
            if traced(ops := namespace(y)):
                theta, p, v1, v2 = y[..., 0], y[..., 1], u_dot[..., 0], u_dot[..., 1]
                return theta, p - self.mass * self.length * (v1 * ops.cos(theta) + v2 * ops.sin(theta)), v1, v2, ops
            y, u_dot = floats(y), floats(u_dot)
        if y.ndim == 1 and u_dot.ndim == 1:
            (theta, p), (v1, v2), ops = y.tolist(), u_dot.tolist(), FLOATS
        else:
            (theta, p), (v1, v2), ops = (y[..., 0], y[..., 1]), (u_dot[..., 0], u_dot[..., 1]), ARRAYS
        return theta, p - self.mass * self.length * (v1 * ops.cos(theta) + v2 * ops.sin(theta)), v1, v2, ops

    def momentum(self, theta, theta_dot, u_dot):
        """p = m l² θ̇ + m l u̇·n: numpy's on one state's float too, JAX's on a traced θ (a reset's)."""
        ops = namespace(theta) if traced(namespace(theta)) else np
        along = u_dot[..., 0] * ops.cos(theta) + u_dot[..., 1] * ops.sin(theta)
        return self.mass * self.length * (self.length * theta_dot + along)

    def vector_field(self, y, u, u_dot):
        """Hand-derived (θ̇, ṗ); u enters only through u̇ (the potential's slope in θ does not depend on u)."""
        theta, ops = y[..., 0], namespace(y)
        theta_dot = self.theta_dot(y, u_dot)
        across = -u_dot[..., 0] * ops.sin(theta) + u_dot[..., 1] * ops.cos(theta)  # u̇·n′
        ml = self.mass * self.length
        p_dot = ml * theta_dot * across - ml * self.g * ops.sin(theta) - self.damping * theta_dot
        return ops.stack([theta_dot, p_dot], axis=-1)

    def energy(self, y, u_dot):
        """E = ½ m l² θ̇² − m g l cos θ, the pendulum's energy in the frame moving with the pivot's velocity u̇
        (zero at pivot height); conserved while u̇ is constant and there is no damping. One state on Python floats,
        or rows."""
        theta, spin, _, _, ops = self._frame(y, u_dot)
        m, ell = self.mass, self.length
        theta_dot = spin / (m * ell * ell)
        return 0.5 * m * ell * ell * theta_dot * theta_dot - m * self.g * ell * ops.cos(theta)

    def exact_segment(self, y, u, u_dot, tau):
        """The state after a segment of length tau at constant pivot velocity u̇.

        In the frame moving with u̇ the rod swings as a plain pendulum: θ̇ is read off p, the pendulum flows by
        `Swing.exact_flow` (Jacobi elliptic functions) at radius l, and p is rebuilt from the new (θ, θ̇). Within
        that flow's band about the separatrix, where it declines, lies the task's own state, the pendulum held
        inverted; there the frame's pendulum is stepped by RK4 at ω₀h ≤ SEPARATRIX_STEP (`_near_separatrix`).
        With damping, which has no closed form, the answer is NaN and the exact stepper hands the state to its
        numerical fallback.
        """
        if self.damping != 0.0:
            return np.full(np.broadcast_shapes(np.shape(y), np.shape(u_dot)[:-1] + (2,)), math.nan)
        theta, spin, v1, v2, ops = self._frame(y, u_dot)
        if ops is ARRAYS:
            theta, spin, v1, v2 = np.broadcast_arrays(theta, spin, v1, v2)
        flowed, flowed_spin = self._pendulum.pendulum_flow(theta, spin, self.length, tau, ops)
        near = ops.isnan(flowed)
        if traced(ops):  # RK4 where some row is near (every row under vmap), the near ones taken by where
            stepped, stepped_spin = ops.branch(near, lambda *rows: self._near_separatrix(*rows, ops),
                                               lambda theta, spin, tau: (flowed, flowed_spin), theta, spin, tau)
            flowed, flowed_spin = ops.where(near, stepped, flowed), ops.where(near, stepped_spin, flowed_spin)
        elif ops.any(near):  # the state (or those rows) by RK4
            if ops is ARRAYS:
                flowed, flowed_spin = flowed.copy(), flowed_spin.copy()
                rows = (theta[near], spin[near], np.broadcast_to(tau, near.shape)[near])
                flowed[near], flowed_spin[near] = self._near_separatrix(*rows, ARRAYS)
            else:
                flowed, flowed_spin = self._near_separatrix(theta, spin, tau, ops)
        p = flowed_spin + self.mass * self.length * (v1 * ops.cos(flowed) + v2 * ops.sin(flowed))
        return np.array([flowed, p]) if ops is FLOATS else ops.stack([flowed, p], axis=-1)

    def _near_separatrix(self, theta, spin, tau, ops):
        """The plain pendulum (θ, m l² θ̇) after tau by RK4 with steps h, ω₀h ≤ SEPARATRIX_STEP, ω₀ = √(g/l): a
        local error of (ω₀h)⁵/120 ≈ 1e-12 of the state (tests/test_kapitza_physics.py)."""
        if traced(ops):
            return self._near_separatrix_traced(theta, spin, tau, ops)
        substeps = max(1, math.ceil(math.sqrt(self.g / self.length) * float(np.max(np.real(tau))) / SEPARATRIX_STEP))
        h = tau / substeps
        for _ in range(substeps):
            theta, spin = self._rk4_step(theta, spin, h, ops.sin)
        return theta, spin

    def _rk4_step(self, theta, spin, h, sin):
        """One RK4 step of length h of the plain pendulum (θ, m l² θ̇)."""
        inertia, weight = self.mass * self.length**2, self.mass * self.g * self.length
        k1, l1 = spin / inertia, -weight * sin(theta)
        k2, l2 = (spin + 0.5 * h * l1) / inertia, -weight * sin(theta + 0.5 * h * k1)
        k3, l3 = (spin + 0.5 * h * l2) / inertia, -weight * sin(theta + 0.5 * h * k2)
        k4, l4 = (spin + h * l3) / inertia, -weight * sin(theta + h * k3)
        return theta + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), spin + h / 6.0 * (l1 + 2.0 * l2 + 2.0 * l3 + l4)

    def _near_separatrix_traced(self, theta, spin, tau, ops):
        """_near_separatrix on traced rows: each row's substeps from its own τ (the numpy code's count for one
        state), run with the rows past theirs held by ``where`` up to a fixed trip count, the count of the longest
        segment the step can have (its dt: the same arithmetic, monotone in τ), so that reverse mode differentiates it;
        a row needing more is a failure (ops.repeat)."""
        tau = tau + 0.0 * theta  # a length per row
        substeps = ops.maximum(1.0, ops.ceil(ops.sqrt(self.g / self.length) * ops.real_part(tau) / SEPARATRIX_STEP))
        h = tau / substeps
        longest = ops.longest_segment()  # the step's dt: a static bound on τ, so on the count (monotone in τ)
        # traced g or length (connenv.jax's traced parameters) have no static bound: a loop to the largest count
        static = longest is not None and not (is_traced(self.g) or is_traced(self.length))
        most = max(1, math.ceil(math.sqrt(self.g / self.length) * longest / SEPARATRIX_STEP)) if static else None

        def substep(i, state):
            stepped, taken = self._rk4_step(*state, h, ops.sin), i < substeps
            return tuple(ops.where(taken, new, old) for new, old in zip(stepped, state))

        return ops.repeat(substeps, substep, (theta, spin), most)

    @cached_property
    def _pendulum(self) -> Swing:
        """The plain pendulum the rod is in the frame of a uniformly moving pivot."""
        return Swing(mass=self.mass, g=self.g)
