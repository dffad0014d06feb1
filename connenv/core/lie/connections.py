"""Systems moved by a mechanical connection: ξ = −A(s) ṡ from a connection A, on a group of
``connenv.core.lie.groups``.

A mechanical connection A(s) (Lawton) turns shape changes ṡ into a group velocity ξ = −A(s) ṡ, which moves the
group element g by ġ = g ξ^ (body frame: ξ in the moving body's coordinates) or ġ = ξ^ g (space frame). A
`Connection` is such a system for the steppers (``connenv.core.steppers.ConnectionSystem``): its state y the
coordinates of g, its assigned coordinates u = s the shape.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from connenv.core.lie.groups import GROUPS


@dataclass(frozen=True)
class Connection:
    """A system moved by a mechanical connection: ``connection(s)`` is A(s) of shape (dim 𝔤, dim S), the state
    y the coordinates of g (see the module), the assigned coordinates u = s the shape. With ``vectorized`` the
    connection takes a batch of shapes (N, dim S) to (N, dim 𝔤, dim S) (as solve_ivp's vectorized); without it,
    a batch is evaluated one shape at a time."""

    group: str
    frame: str
    connection: object = field(compare=False)
    vectorized: bool = False

    def group_velocity(self, s, s_dot):
        """ξ = −A(s) ṡ, as components (floats for one shape, arrays over the rows of a batch)."""
        s = np.asarray(s, float)
        if s.ndim == 1 or self.vectorized:
            A = self.connection(s)
        else:
            rows = s.reshape(-1, s.shape[-1])
            A = np.stack([self.connection(r) for r in rows]).reshape(*s.shape[:-1], -1, s.shape[-1])
        xi = -np.sum(np.asarray(A, float) * np.asarray(s_dot)[..., None, :], axis=-1)
        return tuple(xi.tolist()) if xi.ndim == 1 else tuple(np.moveaxis(xi, -1, 0))

    def vector_field(self, y, s, s_dot):
        """ẏ of the coordinates of g (for the generic steppers: RK4, scipy's): θ̇ = ω on SO2; on SE2 (ẋ, ẏ) = R(θ) v
        (body) or v + ω (−y, x) (space), θ̇ = ω; Ṙ = R ω̂ (body) or ω̂ R (space) on SO3; ẋ = v on R2."""
        y = np.asarray(y, float)
        xi = np.stack(np.broadcast_arrays(*self.group_velocity(s, s_dot)), -1)
        if self.group in ("SO2", "R2"):
            return np.broadcast_to(xi, y.shape).copy()
        if self.group == "SE2":
            x, y_, theta = y[..., 0], y[..., 1], y[..., 2]
            v1, v2, w = xi[..., 0], xi[..., 1], xi[..., 2]
            if self.frame == "body":
                c, s_ = np.cos(theta), np.sin(theta)
                return np.stack([c * v1 - s_ * v2, s_ * v1 + c * v2, w + 0 * theta], -1)
            return np.stack([v1 - w * y_, v2 + w * x, w + 0 * theta], -1)
        R, W = y.reshape(*y.shape[:-1], 3, 3), np.zeros((*xi.shape[:-1], 3, 3))
        W[..., 0, 1], W[..., 0, 2], W[..., 1, 2] = -xi[..., 2], xi[..., 1], -xi[..., 0]
        W = W - np.swapaxes(W, -1, -2)
        return (R @ W if self.frame == "body" else W @ R).reshape(y.shape)


@dataclass(frozen=True)
class ExactConnection(Connection):
    """A Connection that knows its flow in closed form: ``exact_segment(g, s, ṡ, τ)`` is the coordinates of g after
    a segment of length τ at constant ṡ from shape s, for one state (arrays (size,), (k,), (k,), a float τ) or a
    batch of rows (leading axes, τ a float or one per row). The Exact stepper (``integrator="exact"``) takes it."""

    exact_segment: object = field(default=None, compare=False)


def constant_connection(s, A):
    """A at every shape s (…, k): the array A (dim 𝔤, k) broadcast over the leading axes of s."""
    return np.broadcast_to(A, (*np.shape(s)[:-1], *np.shape(A)))


@dataclass(frozen=True)
class ConstantConnection(Connection):
    """A connection the same at every shape, the array ``A`` (dim 𝔤, k) (``connection`` is constant_connection at
    A, vectorized): ξ = −A ṡ is constant over a segment of constant ṡ, and the flow over it is one exponential,
    g exp(τ ξ^) (body frame) or exp(τ ξ^) g (space frame), exact: the ``exact_segment`` of
    ``connenv.core.steppers.Exact``."""

    connection: object = field(init=False, repr=False, compare=False)
    vectorized: bool = field(init=False, default=True)
    A: np.ndarray = field(kw_only=True, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "connection", functools.partial(constant_connection, A=self.A))

    def group_velocity(self, s, s_dot):
        """ξ = −A ṡ as components: floats for one shape, arrays over the rows of a batch."""
        xi = np.asarray(s_dot, float) @ -self.A.T
        return tuple(xi.tolist()) if xi.ndim == 1 else tuple(np.moveaxis(xi, -1, 0))

    def exact_segment(self, y, s, s_dot, tau):
        group, single = GROUPS[self.group], np.ndim(y) == 1
        xi = self.group_velocity(s, s_dot)
        if single:
            g, tau = tuple(np.asarray(y, float).tolist()), float(tau)
        else:
            g, tau = tuple(np.moveaxis(np.asarray(y, float), -1, 0)), np.asarray(tau, float)
        step = group.exp([tau * c for c in xi])
        g = group.product(g, step) if self.frame == "body" else group.product(step, g)
        return np.array(g) if single else np.stack(np.broadcast_arrays(*g), -1)


def group_velocity(system, s, s_dot):
    """ξ = −A(s) ṡ as components: the system's own ``group_velocity`` if it has one (a closed form), else from its
    ``connection``."""
    if hasattr(system, "group_velocity"):
        return system.group_velocity(s, s_dot)
    return Connection(system.group, system.frame, system.connection).group_velocity(s, s_dot)
