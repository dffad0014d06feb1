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

from connenv.core.backend import ARRAYS, floats, is_traced, namespace, traced
from connenv.core.lie.groups import GROUPS
from connenv.core.validation import check_returned, probe, real_array


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
        s = floats(s)
        if type(s) is not np.ndarray and traced(ops := namespace(s)):  # JAX's rows (connenv.jax)
            A = self.connection(s) if self.vectorized else ops.stack(
                [self.connection(r) for r in s.reshape(-1, s.shape[-1])]).reshape(*s.shape[:-1], -1, s.shape[-1])
            xi = -(floats(A) * s_dot[..., None, :]).sum(axis=-1)
            return tuple(xi[..., i] for i in range(xi.shape[-1]))
        if s.ndim == 1 or self.vectorized:
            A = self.connection(s)
        else:
            rows = s.reshape(-1, s.shape[-1])
            A = np.stack([self.connection(r) for r in rows]).reshape(*s.shape[:-1], -1, s.shape[-1])
        xi = -np.sum(floats(A) * _rows(s_dot)[..., None, :], axis=-1)
        return tuple(xi.tolist()) if xi.ndim == 1 and not _traced(xi) else tuple(np.moveaxis(xi, -1, 0))

    def vector_field(self, y, s, s_dot):
        """ẏ of the coordinates of g (for the generic steppers: RK4, scipy's): θ̇ = ω on SO2; on SE2 (ẋ, ẏ) = R(θ) v
        (body) or v + ω (−y, x) (space), θ̇ = ω; Ṙ = R ω̂ (body) or ω̂ R (space) on SO3; ẋ = v on R2."""
        y = floats(y)
        ops = ARRAYS if type(y) is np.ndarray else namespace(y)  # numpy's functions on numpy's arrays; JAX's rows'
        xi = ops.stack(ops.broadcast_arrays(*self.group_velocity(s, s_dot)), -1)
        if self.group in ("SO2", "R2"):
            return ops.broadcast_to(xi, y.shape).copy()
        if self.group == "SE2":
            x, y_, theta = y[..., 0], y[..., 1], y[..., 2]
            v1, v2, w = xi[..., 0], xi[..., 1], xi[..., 2]
            if self.frame == "body":
                c, s_ = ops.cos(theta), ops.sin(theta)
                return ops.stack([c * v1 - s_ * v2, s_ * v1 + c * v2, w + 0 * theta], -1)
            return ops.stack([v1 - w * y_, v2 + w * x, w + 0 * theta], -1)
        R = y.reshape(*y.shape[:-1], 3, 3)
        if traced(ops):  # JAX's rows: W built whole (its arrays take no assignment)
            zero = ops.zeros_like(xi[..., 0])
            W = ops.stack([zero, -xi[..., 2], xi[..., 1], xi[..., 2], zero, -xi[..., 0], -xi[..., 1], xi[..., 0], zero],
                          -1).reshape(*xi.shape[:-1], 3, 3)
        else:
            W = np.zeros((*xi.shape[:-1], 3, 3), xi.dtype)
            W[..., 0, 1], W[..., 0, 2], W[..., 1, 2] = -xi[..., 2], xi[..., 1], -xi[..., 0]
            W = W - np.swapaxes(W, -1, -2)
        return (R @ W if self.frame == "body" else W @ R).reshape(y.shape)


def _traced(x) -> bool:
    """Whether x is a traced array (connenv.jax's), not a float nor a numpy array."""
    return not isinstance(x, (float, np.ndarray, np.generic)) and traced(namespace(x))


def _rows(x):
    """x as numpy's array, a traced array as itself."""
    return x if _traced(x) else np.asarray(x)


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
        xi = floats(s_dot) @ -self.A.T
        return tuple(xi.tolist()) if xi.ndim == 1 else tuple(np.moveaxis(xi, -1, 0))

    def exact_segment(self, y, s, s_dot, tau):
        group, single = GROUPS[self.group], np.ndim(y) == 1
        xi = self.group_velocity(s, s_dot)
        if single:
            g, tau = tuple(np.asarray(y, float).tolist()), float(tau)
        else:
            g, tau = tuple(np.moveaxis(floats(y), -1, 0)), floats(tau)
        step = group.exp([tau * c for c in xi])
        g = group.product(g, step) if self.frame == "body" else group.product(step, g)
        if single:
            return np.array(g)
        if _traced(g[0]):  # traced rows (connenv.jax): every coordinate a row already
            return namespace(g[0]).stack(g, -1)
        return np.stack(np.broadcast_arrays(*g), -1)


def bound_traced(function) -> bool:
    """Whether function is a partial with a traced argument bound (an env's connection of physical parameters that
    connenv.jax traces), which cannot be tried on numbers: the same function was tried at the make-time values."""
    return isinstance(function, functools.partial) and any(map(is_traced, function.keywords.values()))


def connection_system(group, frame, connection, vectorized, exact_segment, shapes, dt, speed) -> Connection:
    """The system of a connection given as a builder's argument, checked: a constant A (ConstantConnection), a
    callable s -> A(s) (Connection), or one with its exact_segment (ExactConnection). The callables are tried at the
    sample shapes (the first the start shape; exact_segment over dt, at rest and at the top shape speed); what they
    return wrong is a ValueError (TypeError for what is no real numbers) naming the argument."""
    algebra = GROUPS[group]
    if not callable(connection):
        if exact_segment is not None:
            raise ValueError(f"exact_segment={exact_segment!r} is for a callable connection; a constant A "
                             "has its own exact step (one exponential)")  # fmt: skip
        return ConstantConnection(group, frame, A=_check_constant(connection, algebra, shapes.shape[-1]))
    if bound_traced(connection):  # an env's own connection of traced parameters (connenv.jax): checked at make
        return Connection(group, frame, connection, vectorized) if exact_segment is None else ExactConnection(
            group, frame, connection, vectorized, exact_segment)
    connection = _check_connection(connection, algebra, shapes, vectorized)
    if exact_segment is None:
        return Connection(group, frame, connection, vectorized)
    exact_segment = _check_exact_segment(exact_segment, algebra, shapes[0], dt, speed)
    return ExactConnection(group, frame, connection, vectorized, exact_segment)


def _check_constant(connection, group, k):
    """A constant connection as a float array, if it is real, finite, of shape (dim 𝔤, k)."""
    expected = (
        f"a callable s -> A(s) or a constant A: finite, of shape {(group.dim, k)} (dim 𝔤, k) for group {group.name} "
        f"and a shape of {k} coordinates"
    )
    A = real_array("connection", connection, expected)
    if A.shape != (group.dim, k) or not np.all(np.isfinite(A)):
        raise ValueError(f"connection={connection!r} must be {expected}")
    return A


def _check_connection(connection, group, shapes, vectorized):
    """The connection, if it is callable and A(s) at each sample shape is real, finite, of shape (dim 𝔤, k); with
    vectorized, A of the batch of samples is (N, dim 𝔤, k) and row i is A of shape i (to rounding). Else
    ValueError (TypeError for what is no real numbers) naming connection, or vectorized."""
    if not callable(connection):
        raise ValueError(f"connection={connection!r} must be a callable s -> A(s)")
    shape = (group.dim, shapes.shape[-1])
    expected = (f"A(s), finite real numbers of shape {shape} (dim 𝔤, k) for group {group.name} and a shape of "
                f"{shape[1]} coordinates")  # fmt: skip
    single = []
    for s in shapes:
        name = f"connection(s) at s={s}"
        single.append(check_returned(name, probe(name, connection, s.copy()), shape, expected))
    if vectorized:
        name = f"connection(s) at a batch of {len(shapes)} shapes s={shapes.tolist()} (vectorized=True)"
        expected = f"(N, dim 𝔤, k) = {(len(shapes), *shape)}, A of each shape, or vectorized=False"
        batch = check_returned(name, probe(name, connection, shapes.copy()), (len(shapes), *shape), expected)
        if not np.allclose(batch, single, rtol=1e-9, atol=1e-12 * (1.0 + np.max(np.abs(single)))):
            raise ValueError(f"{name} returned {batch.tolist()}, not A of each shape {np.stack(single).tolist()}; "
                             "expected A of each row, or vectorized=False")  # fmt: skip
    return connection


def _check_exact_segment(exact_segment, group, s, dt, speed):
    """exact_segment, if it is callable and from g = identity at the shape s gives a real, finite g of its group's
    size after τ = dt, both at ṡ = 0 and with every shape coordinate at the top speed."""
    if not callable(exact_segment):
        raise ValueError(f"exact_segment={exact_segment!r} must be a callable (g, s, ṡ, τ) -> g, or None")
    identity = np.array(group.identity(), dtype=float)
    expected = f"the coordinates of g on {group.name}: finite real numbers of shape {identity.shape}"
    for s_dot in (np.zeros_like(s), np.full_like(s, speed)):
        name = f"exact_segment={exact_segment!r} at g = identity, s={s}, ṡ={s_dot}, τ={dt}"
        check_returned(name, probe(name, exact_segment, identity.copy(), s.copy(), s_dot, dt), identity.shape, expected)
    return exact_segment


def group_velocity(system, s, s_dot):
    """ξ = −A(s) ṡ as components: the system's own ``group_velocity`` if it has one (a closed form), else from its
    ``connection``."""
    if hasattr(system, "group_velocity"):
        return system.group_velocity(s, s_dot)
    return Connection(system.group, system.frame, system.connection).group_velocity(s, s_dot)
