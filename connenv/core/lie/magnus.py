"""The Lie-group step of a mechanical connection: Magnus on SO(3), nested quadrature on the solvable groups.

`Magnus` is the stepper (``integrator="magnus"``) of a system moved by a connection (see ``connenv.core.lie``),
with `fixed_rule`, the cheapest fixed rule for a caller that knows its segments, and the flows it is made of:
`magnus_flow` (SO(3)), `quadrature_flow` (SO(2), ℝ², SE(2)) and `se2_body_flow` (SE(2) in the body frame with a
fixed rule). They work on components (``connenv.core.lie.groups``): tuples of Python floats for one state or of
arrays over the rows of a batch, with the same arithmetic.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import operator
from dataclasses import dataclass, field

import numpy as np

from connenv.core.backend import floats, namespace, traced
from connenv.core.lie.connections import group_velocity
from connenv.core.lie.groups import GROUPS, Group, ops_of
from connenv.core.steppers import ConnectionSystem, Scipy, StepperError, check_finite, conforms
from connenv.core.validation import ndim

GAUSS = (0.5 - math.sqrt(3.0) / 6.0, 0.5 + math.sqrt(3.0) / 6.0)  # the Gauss–Legendre nodes on [0, 1]
BRACKET_WEIGHT = math.sqrt(3.0) / 12.0
GAUSS6 = (0.5 - math.sqrt(15.0) / 10.0, 0.5, 0.5 + math.sqrt(15.0) / 10.0)  # three nodes, for order 6
SQRT15_3 = math.sqrt(15.0) / 3.0
MAX_SUBSTEPS = 4096  # per segment: past it the shape path is too rough for the tolerance (StepperError)


def magnus_flow(group: Group, frame: str, velocity, g, s, s_dot, tau, substeps, order: int = 6):
    """g after ``substeps`` equal Magnus steps of the given order (4 or 6) over a segment of length tau on which
    s(t) = s + t ṡ; g, s, ṡ, the result and velocity(s, ṡ) (ξ) are components. Over a batch, tau and substeps may
    be one per row: each row takes its own steps, the arithmetic of the single state's, and a row that has taken
    them leaves the batch. Returns (g, ξ at the first node, whether ξ was the same at every node: a bool, or one
    per row)."""
    if np.ndim(substeps):
        return _magnus_rows(group, frame, velocity, g, s, s_dot, tau, substeps, order), None, False
    h = tau / substeps
    constant, first = True, None
    nodes = GAUSS if order == 4 else GAUSS6
    for k in range(substeps):
        xi = [velocity(_shape_at(s, s_dot, (k + c) * h), s_dot) for c in nodes]
        first = xi[0] if first is None else first
        for x in xi:
            constant = constant & _same(x, first)
        step = group.exp(magnus_omega(group, frame, h, xi))
        g = group.product(g, step) if frame == "body" else group.product(step, g)
    return g, first, constant


def _magnus_rows(group, frame, velocity, g, s, s_dot, tau, substeps, order):
    """magnus_flow's g over a batch whose rows take their own number of substeps."""
    out, rows = [np.array(c) for c in g], np.arange(len(substeps))
    h = np.broadcast_to(tau / substeps, substeps.shape)
    nodes = GAUSS if order == 4 else GAUSS6
    for k in range(int(np.max(substeps))):
        going = substeps > k
        if not np.all(going):
            for o, c in zip(out, g):
                o[rows[~going]] = c[~going]
            rows, g, s, s_dot = rows[going], tuple(c[going] for c in g), s[going], s_dot[going]
            h, substeps = h[going], substeps[going]
        xi = [velocity(_shape_at(s, s_dot, (k + c) * h), s_dot) for c in nodes]
        step = group.exp(magnus_omega(group, frame, h, xi))
        g = group.product(g, step) if frame == "body" else group.product(step, g)
    for o, c in zip(out, g):
        o[rows] = c
    return tuple(out)


def magnus_omega(group, frame, h, xi):
    """Ω of one Magnus step from ξ at the Gauss nodes (2: order 4, 3: order 6), for ġ = ξ^ g (space frame); the
    body frame's is the same with the bracket's sign reversed (g⁻¹ obeys the space frame's equation in −ξ)."""
    if len(xi) == 2:
        omega = [0.5 * h * (a + b) for a, b in zip(*xi)]
        if group.abelian:
            return omega
        weight = (1.0 if frame == "body" else -1.0) * BRACKET_WEIGHT * h * h
        return [o + weight * c for o, c in zip(omega, group.bracket(*xi))]
    a1, a2, a3 = ([h * c for c in x] for x in xi)
    alpha1 = a2
    alpha2 = [SQRT15_3 * (z - x) for x, z in zip(a1, a3)]
    alpha3 = [10.0 / 3.0 * (z - 2.0 * y + x) for x, y, z in zip(a1, a2, a3)]
    omega = [p + r / 12.0 for p, r in zip(alpha1, alpha3)]
    if group.abelian:
        return omega
    sign = 1.0 if frame == "space" else -1.0

    def bracket(x, y):
        return [sign * c for c in group.bracket(x, y)]

    c1 = bracket(alpha1, alpha2)
    c2 = [-c / 60.0 for c in bracket(alpha1, [2.0 * r + c for r, c in zip(alpha3, c1)])]
    outer = bracket([-20.0 * p - r + c for p, r, c in zip(alpha1, alpha3, c1)], [q + c for q, c in zip(alpha2, c2)])
    return [o + c / 240.0 for o, c in zip(omega, outer)]


def _integration_matrix(nodes):
    """Q with Q[j, k] = ∫₀^{x_j} ℓ_k(x) dx, ℓ_k the Lagrange polynomials of the nodes x on [0, 1]: ∫₀^{x_j} f ≈ Σ_k
    Q[j, k] f(x_k), exact for polynomials of degree < len(nodes)."""
    legendre = np.polynomial.legendre
    basis = np.eye(len(nodes))
    coefficients = [legendre.legfit(2.0 * nodes - 1.0, row, len(nodes) - 1) for row in basis]
    return np.array([0.5 * legendre.legval(2.0 * nodes - 1.0, legendre.legint(c, lbnd=-1.0)) for c in coefficients]).T


QUADRATURE_POINTS = 8
BLOCK_BYTES = 120_000  # se2_body_flow's temporaries over a batch: below glibc's default M_MMAP_THRESHOLD (every
# array above it is a fresh mmap, its pages faulted in anew), by taking the rows in blocks
_x, _w = np.polynomial.legendre.leggauss(QUADRATURE_POINTS)
NODES, WEIGHTS = 0.5 * (_x + 1.0), 0.5 * _w  # Gauss–Legendre on [0, 1]
INTEGRATION = _integration_matrix(NODES)
QUADRATURE_ORDER = QUADRATURE_POINTS  # of the nested quadrature in the piece length (Richardson's exponent)


def quadrature_flow(group: Group, frame: str, velocity, g, s, s_dot, tau, pieces: int):
    """g after a segment of length tau on SO2, R2 or SE2, cut into ``pieces`` equal pieces, by quadrature: these
    groups are solvable, and the flow of ġ = g ξ^ is θ(t) = θ₀ + W(t), W = ∫₀ᵗ ω, and on SE2
    p(T) = p₀ + R(θ₀) ∫₀ᵀ R(W(t)) v(t) dt (body frame), p(T) = R(W(T)) (p₀ + ∫₀ᵀ R(−W(t)) v(t) dt) (space frame);
    on R2, g(T) = g₀ + ∫ v. Each piece takes ξ at 8 Gauss–Legendre nodes (one call of velocity for all nodes of
    all pieces), W at the nodes from their interpolating polynomial, and the outer integral by the Gauss rule.
    Returns (g, ξ at the first node, whether ξ was the same at every node), as magnus_flow."""
    h = tau / pieces
    times = [np.multiply.outer((j + NODES), h) for j in range(pieces)]  # (8,) or (8, N) each
    t = np.concatenate(times)
    t = t.reshape(t.shape + (1,) * (np.ndim(s) + 1 - t.ndim))  # against s (k,) or (N, k)
    shapes = np.asarray(s)[None] + t * np.asarray(s_dot)[None]
    xi = np.stack(np.broadcast_arrays(*velocity(shapes, s_dot)))  # (dim, nodes of all pieces, ...)
    constant = np.all(xi == xi[:, :1], axis=(0, 1))
    xi = xi.reshape(len(xi), pieces, QUADRATURE_POINTS, *xi.shape[2:])
    first = tuple(xi[:, 0, 0])
    for j in range(pieces):
        g = _piece(group, frame, g, xi[:, j], h)
    return g, first, constant if np.ndim(constant) else bool(constant)


def _piece(group, frame, g, xi, h):
    """g after one piece of length h with ξ given at the 8 nodes (arrays (8,) or (8, N))."""
    if group.name == "R2":
        increment = tuple(h * _weighted(c) for c in xi)
        return group.product(g, increment)
    omega = xi[-1]
    turn = h * _weighted(omega)
    if group.name == "SO2":
        return group.product(g, (turn,))
    W = h * (INTEGRATION @ omega)
    v1, v2 = xi[0], xi[1]
    if frame == "body":
        c, s_ = np.cos(W), np.sin(W)
        increment = (h * _weighted(c * v1 - s_ * v2), h * _weighted(s_ * v1 + c * v2), turn)
        return group.product(g, increment)
    c, s_ = np.cos(W), np.sin(W)
    a1, a2 = h * _weighted(c * v1 + s_ * v2), h * _weighted(c * v2 - s_ * v1)  # ∫ R(−W) v
    ops = ops_of(turn)
    ct, st = ops.cos(turn), ops.sin(turn)
    return group.product((ct * a1 - st * a2, st * a1 + ct * a2, turn), g)


@functools.cache
def gauss_rule(points: int):
    """The Gauss–Legendre rule of that many points on [0, 1]: (nodes, weights, Q) as arrays and as lists of floats,
    Q the integration matrix of the nodes (``_integration_matrix``)."""
    x, w = np.polynomial.legendre.leggauss(points)
    nodes, weights = 0.5 * (x + 1.0), 0.5 * w
    Q = _integration_matrix(nodes)
    return nodes, weights, Q, nodes.tolist(), weights.tolist(), Q.tolist()


def se2_body_flow(velocity, g, s, s_dot, tau, pieces: int, points: int = QUADRATURE_POINTS):
    """quadrature_flow's g on SE2 in the body frame with a Gauss rule of ``points`` nodes per piece, lean: the
    increment of the whole segment at once (θ at the nodes of piece j offset by the turns of the pieces before it),
    then one product. One state as tuples of Python floats (math, no numpy: velocity(s, ṡ) gets and gives floats),
    or a batch as arrays over rows (s, ṡ of shape (N, k), tau a float or one per row). velocity(s, ṡ, t) is ξ at
    s + t ṡ as components: floats at a float t for one state, arrays at all nodes at once for a batch (t of shape
    (nodes, N) or (nodes, 1): components of shape (nodes, N))."""
    if isinstance(g[0], float):
        return _se2_body_floats(velocity, g, s, s_dot, tau, pieces, points)
    block = max(1, BLOCK_BYTES // (8 * pieces * points))
    if len(s) > block and type(s) is np.ndarray:  # numpy's rows in blocks of bounded memory; JAX's rows whole
        increments = np.empty((3, len(s)), np.result_type(s, s_dot, tau))
        for i in range(0, len(s), block):
            rows = slice(i, i + block)
            increments[:, rows] = _se2_body_increment(velocity, s[rows], s_dot[rows], tau[rows] if np.ndim(tau) else
                                                      tau, pieces, points)  # fmt: skip
        return GROUPS["SE2"].product(g, tuple(increments))
    return GROUPS["SE2"].product(g, _se2_body_increment(velocity, s, s_dot, tau, pieces, points))


def _se2_body_increment(velocity, s, s_dot, tau, pieces, points):
    """The body-frame increment (dx, dy, turn) of se2_body_flow over a batch of rows."""
    if type(s) is not np.ndarray and traced(ops := namespace(s)):
        return _se2_body_increment_traced(velocity, s, s_dot, tau, pieces, points, ops)
    nodes, weights, Q = gauss_rule(points)[:3]
    h = floats(tau / pieces)
    t = (np.arange(pieces)[:, None] + nodes).reshape(-1, 1) * h  # (pieces · points, N) or (pieces · points, 1)
    shape = (len(t), len(s))
    v1, v2, omega = (c if np.shape(c) == shape else np.broadcast_to(c, shape) for c in velocity(s, s_dot, t))
    omega = omega.reshape(pieces, points, -1)
    turns = h * (weights @ omega)  # (pieces, N)
    W = Q @ omega
    W *= h
    if pieces > 1:
        W[1:] += np.cumsum(turns[:-1], axis=0)[:, None, :]
    c, s_ = _cos_sin(W.reshape(v1.shape))
    ax, ay = c * v1, s_ * v1  # in place from here on: few fresh temporaries
    c *= v2
    s_ *= v2
    ax -= s_  # cos W v₁ − sin W v₂
    ay += c  # sin W v₁ + cos W v₂
    dx = h * (weights @ ax.reshape(omega.shape)).sum(axis=0)
    dy = h * (weights @ ay.reshape(omega.shape)).sum(axis=0)
    return dx, dy, turns.sum(axis=0)


def _se2_body_increment_traced(velocity, s, s_dot, tau, pieces, points, ops):
    """_se2_body_increment on traced rows (connenv.jax): the same quadrature without numpy's in-place arithmetic,
    cos and sin taken directly (the numpy rows' half-angle tangent agrees to a few ulps)."""
    nodes, weights, Q = gauss_rule(points)[:3]
    h = tau / pieces
    t = (np.arange(pieces)[:, None] + nodes).reshape(-1, 1) * h
    shape = (len(t), len(s))
    v1, v2, omega = (ops.broadcast_to(c, shape) for c in velocity(s, s_dot, t))
    omega = omega.reshape(pieces, points, -1)
    turns = h * (weights @ omega)  # (pieces, N)
    W = (Q @ omega) * h
    if pieces > 1:  # each piece's θ offset by the turns of the pieces before it (numpy's cumsum, in its order)
        parts, offset = [W[0]], turns[0]
        for j in range(1, pieces):
            parts.append(W[j] + offset)
            offset = offset + turns[j]
        W = ops.stack(parts)
    W = W.reshape(v1.shape)
    c, s_ = ops.cos(W), ops.sin(W)
    ax, ay = c * v1 - s_ * v2, s_ * v1 + c * v2
    dx = h * (weights @ ax.reshape(omega.shape)).sum(axis=0)
    dy = h * (weights @ ay.reshape(omega.shape)).sum(axis=0)
    return dx, dy, turns.sum(axis=0)


def _cos_sin(angle):
    """(cos, sin) of an array of angles (overwritten) from one transcendental call, τ = tan(angle/2):
    cos = (1 − τ²)/(1 + τ²), sin = 2τ/(1 + τ²), to a few units in the last place (and near angle = ±π, where τ is
    large, to the spacing of floats there); numpy's cos and sin are the dearest operations of the quadrature."""
    angle *= 0.5
    tau = np.tan(angle, out=angle)
    tau_squared = tau * tau
    scale = np.divide(1.0, tau_squared + 1.0)
    cos = 1.0 - tau_squared
    cos *= scale
    scale *= 2.0
    tau *= scale
    return cos, tau


def _se2_body_floats(velocity, g, s, s_dot, tau, pieces, points):
    """se2_body_flow on one state of Python floats."""
    nodes, weights, Q = gauss_rule(points)[3:]
    h, dx, dy, turn = tau / pieces, 0.0, 0.0, 0.0
    for j in range(pieces):
        xi = [velocity(s, s_dot, (j + c) * h) for c in nodes]
        omega = [w for _, _, w in xi]
        for (v1, v2, _), weight, row in zip(xi, weights, Q):
            W = turn + h * sum(map(operator.mul, row, omega))
            c, s_ = math.cos(W), math.sin(W)
            dx += weight * (c * v1 - s_ * v2)
            dy += weight * (s_ * v1 + c * v2)
        turn += h * sum(map(operator.mul, weights, omega))
    return GROUPS["SE2"].product(g, (h * dx, h * dy, turn))


def _weighted(values):
    """Σ_k w_k values[k] over the nodes (axis 0)."""
    total = WEIGHTS @ values
    return float(total) if np.ndim(total) == 0 else total


@dataclass(frozen=True)
class Magnus:
    """The Lie-group stepper of systems with a connection (``connenv.core.steppers.ConnectionSystem``; see the
    module): Magnus of ``order`` 6 (three Gauss points, the default) or 4 (two) on SO3, nested quadrature (order 8
    in the piece length, spectral in practice) on SO2, R2 and SE2. Other systems (the shell's full model) go to
    ``fallback``.

    Substeps: each segment is stepped with one and with two substeps; their difference d (max-norm of the
    coordinates of g) estimates the error of the two-step result as d/(2^order − 1) (Richardson). Where that is
    ≤ atol the two-step result is taken; elsewhere the segment is stepped again with
    n = ⌈1.2 · 2 (d/((2^order − 1) atol))^(1/order)⌉ substeps, the count that brings the error to atol, and checked
    against 2n substeps: while their difference (times 2^order/(2^order − 1), Richardson's estimate of the error
    with n) is past atol, n doubles (StepperError past MAX_SUBSTEPS). The estimate from one and two substeps holds
    where the error already falls as h^order; on a long segment of a curved connection it may not yet, and where A
    has a pole on the shape's path it never does (the flow diverges while every quadrature of it is finite). Where
    ξ is the same at every node (A constant along the path) the step is one exponential, the exact flow. Rows of a
    batch choose their substeps alone.

    With ``pieces`` given, every segment is stepped once with that many pieces (substeps on SO3), without the
    estimate: for a caller that knows its admissible segments and has chosen the rule for them once (`fixed_rule`),
    as KozlovShellEnv does. SE2's body frame then takes `se2_body_flow` with ``points`` Gauss nodes per piece, one
    state on Python floats throughout.
    """

    atol: float = 1e-10
    fallback: object = field(default=Scipy(), compare=False)
    order: int = 6
    pieces: int | None = None
    points: int = QUADRATURE_POINTS

    def __call__(self, system, y, u, u_dot, tau):
        if not conforms(system, ConnectionSystem):
            return self.fallback(system, y, u, u_dot, tau)
        if self.pieces is not None:
            return self._fixed(system, y, u, u_dot, tau)
        y = floats(y)
        if not np.any(u_dot):
            return y.copy()
        group, frame, order = GROUPS[system.group], system.frame, self.order
        single = y.ndim == 1
        if single:
            g, tau = tuple(y.tolist()), float(tau)
        else:
            g = tuple(np.moveaxis(y, -1, 0))
            tau = np.broadcast_to(np.reshape(tau, -1), y.shape[:1]) if np.ndim(tau) else tau

        def velocity(s, s_dot):
            return group_velocity(system, s, s_dot)

        if group.name == "SO3":
            order = self.order

            def flow(g, s, s_dot, tau, n):
                return magnus_flow(group, frame, velocity, g, s, s_dot, tau, n, order)
        else:
            order = QUADRATURE_ORDER

            def flow(g, s, s_dot, tau, n):
                if np.ndim(n) == 0:
                    return quadrature_flow(group, frame, velocity, g, s, s_dot, tau, n)
                out = [np.array(c) for c in g]  # rows grouped by their number of pieces
                for count in np.unique(n):
                    rows = np.flatnonzero(n == count)
                    rows_tau = tau[rows] if np.ndim(tau) else tau
                    part = quadrature_flow(group, frame, velocity, tuple(c[rows] for c in g), s[rows], s_dot[rows],
                                           rows_tau, int(count))[0]  # fmt: skip
                    for o, c in zip(out, part):
                        o[rows] = c
                return tuple(out), None, False

        one, first_one, constant_one = flow(g, u, u_dot, tau, 1)
        two, first_two, constant_two = flow(g, u, u_dot, tau, 2)
        constant = constant_one & constant_two & _same(first_one, first_two)
        if np.any(constant):  # ξ the same at every node: one exponential, exact
            step = group.exp([tau * c for c in first_one])
            exact = group.product(g, step) if frame == "body" else group.product(step, g)
        if single:
            error = max(abs(a - b) for a, b in zip(one, two)) / (2**order - 1)
            if constant:
                return check_finite(np.array(exact), self)
            if error <= self.atol:
                return check_finite(np.array(two), self)
            checked = self._checked(flow, g, u, u_dot, tau, self._substeps(error, order), order)
            return check_finite(np.array(checked), self)
        error = np.max(np.abs(np.real(np.subtract(one, two))), axis=0) / (2**order - 1)  # the real parts' choice
        out = np.stack(two, -1)
        if np.any(constant):
            out = np.where(constant[:, None], np.stack(exact, -1), out)
        rough = np.flatnonzero(~constant & (error > self.atol))
        if rough.size:
            g_rows, tau_rows = tuple(c[rough] for c in g), tau[rough] if np.ndim(tau) else tau
            counts = self._substeps(error[rough], order)
            out[rough] = np.stack(self._checked(flow, g_rows, u[rough], u_dot[rough], tau_rows, counts, order), -1)
        return check_finite(out, self)

    def _checked(self, flow, g, s, s_dot, tau, n, order):
        """flow's g after n substeps, checked against 2n: while |g(2n) − g(n)| 2^order/(2^order − 1), the
        (Richardson) estimate of g(n)'s error, is past atol, n doubles; past MAX_SUBSTEPS, StepperError. The
        estimate from one and two substeps that chose n assumes that the error already falls as h^order, which it
        may not yet on a long segment of a curved connection, and never does where A has a pole on the shape's
        path: there g(n) is a finite, wrong number, and more substeps keep moving it. One state (n an int) or rows
        (n one per row, each doubling alone); a result that passes is the one its n gave."""
        scale = 2**order / (2**order - 1)
        coarse = flow(g, s, s_dot, tau, n)[0]
        if np.ndim(n) == 0:
            while True:
                fine = flow(g, s, s_dot, tau, 2 * n)[0]
                error = max(abs(a - b) for a, b in zip(coarse, fine)) * scale
                if error <= self.atol:
                    return coarse
                if 2 * n > MAX_SUBSTEPS:
                    raise self._diverging(error, n)
                n, coarse = 2 * n, fine
        out, rows, n = [np.array(c) for c in coarse], np.arange(len(n)), np.array(n)
        while rows.size:
            rows_tau = tau[rows] if np.ndim(tau) else tau
            fine = flow(tuple(c[rows] for c in g), s[rows], s_dot[rows], rows_tau, 2 * n[rows])[0]
            error = np.max(np.abs(np.real(np.subtract([o[rows] for o in out], fine))), axis=0) * scale
            failed = ~(error <= self.atol)
            if np.any(2 * n[rows[failed]] > MAX_SUBSTEPS):
                raise self._diverging(np.max(error[failed]), np.max(n[rows[failed]]))
            for o, c in zip(out, fine):
                o[rows[failed]] = c[failed]
            n[rows[failed]] *= 2
            rows = rows[failed]
        return tuple(out)

    def _diverging(self, error, n):
        return StepperError(
            f"{self} cannot meet atol: with {n} substeps the estimated error is {error:.3g}, and doubling them up to "
            f"{MAX_SUBSTEPS} does not bring it down (a connection with a pole on the shape's path?)"
        )

    def _fixed(self, system, y, u, u_dot, tau):
        """One flow of ``pieces`` pieces: floats for one state, arrays over rows for a batch."""
        group, frame = GROUPS[system.group], system.frame
        single = ndim(y) == 1
        if single:
            g, u, u_dot = (tuple(np.asarray(a, float).tolist()) for a in (y, u, u_dot))
            tau = float(tau)
        else:
            g = tuple(np.moveaxis(floats(y), -1, 0))
            u, u_dot = floats(u), floats(u_dot)
            tau = np.reshape(tau, -1) if np.ndim(tau) else tau

        def velocity(s, s_dot):
            return group_velocity(system, s, s_dot)

        if group.name == "SE2" and frame == "body":
            g = se2_body_flow(along(system), g, u, u_dot, tau, self.pieces, self.points)
        elif group.name == "SO3":
            u, u_dot = np.asarray(u), np.asarray(u_dot)
            g = magnus_flow(group, frame, velocity, g, u, u_dot, tau, self.pieces, self.order)[0]
        else:
            g = quadrature_flow(group, frame, velocity, g, np.asarray(u), np.asarray(u_dot), tau, self.pieces)[0]
        if single:
            if not all(map(math.isfinite, g)):
                raise StepperError(f"{self} produced a non-finite value {g}")
            return np.array(g)
        return check_finite(np.stack(g, -1), self)

    def _substeps(self, error, order):
        """The substeps for an estimated two-step error (a float, or an array over rows) of a method of that order."""
        n = np.ceil(1.2 * 2.0 * (np.asarray(error) / self.atol) ** (1.0 / order))
        if not np.all(n <= MAX_SUBSTEPS):
            worst = np.max(error)
            raise StepperError(f"{self} needs > {MAX_SUBSTEPS} substeps on a segment: estimated error {worst:.3g}")
        return n.astype(int) if np.ndim(n) else int(n)


def fixed_rule(system, segments, atol: float = 1e-10, stepper=None, max_points: int = 16):
    """The cheapest fixed rule, (pieces, points) with the fewest nodes pieces × points, with which the Lie-group
    step of ``system`` (a ConnectionSystem on SE2 in the body frame) meets atol on every control segment (u, u̇, τ)
    given: those a caller's task admits, its worst among them (for a box of u and a step dt: corner to corner in
    one step). The error of a rule is estimated by Richardson, |g(pieces) − g(2 pieces)| (max-norm of the
    coordinates of g from the identity), g(2 pieces) being 2^points times more accurate. StepperError past
    MAX_SUBSTEPS pieces."""
    if (system.group, system.frame) != ("SE2", "body"):
        raise ValueError(f"fixed_rule is for SE2 in the body frame; got group={system.group!r}, frame={system.frame!r}")
    stepper = stepper or Magnus(atol)
    identity = np.array(GROUPS[system.group].identity(), float)
    segments = [(np.asarray(u, float), np.asarray(u_dot, float), tau) for u, u_dot, tau in segments]
    for nodes in range(QUADRATURE_POINTS, QUADRATURE_POINTS * MAX_SUBSTEPS + 1):
        for points in range(QUADRATURE_POINTS, max_points + 1):
            if nodes % points:
                continue
            step = dataclasses.replace(stepper, pieces=nodes // points, points=points)
            finer = dataclasses.replace(step, pieces=2 * step.pieces)
            error = max(np.max(np.abs(step(system, identity, *s) - finer(system, identity, *s))) for s in segments)
            if error <= atol:
                return step.pieces, points
    raise StepperError(f"the Lie-group step needs > {MAX_SUBSTEPS} pieces for atol {atol} on the segments given")


def along(system):
    """velocity(s, ṡ, t) of se2_body_flow: ξ at s + t ṡ, the system's own ``segment_velocity`` for a batch if it has
    one (a closed form along the straight path), else group_velocity at the shapes."""
    if hasattr(system, "segment_velocity"):
        closed_form = system.group_velocity

        def velocity(s, s_dot, t):
            if isinstance(t, float):
                return closed_form([a + t * d for a, d in zip(s, s_dot)], s_dot)
            return system.segment_velocity(s, s_dot, t)

        return velocity

    def velocity(s, s_dot, t):
        if isinstance(t, float):
            return group_velocity(system, tuple(a + t * d for a, d in zip(s, s_dot)), s_dot)
        if type(s) is not np.ndarray and traced(namespace(s)):  # JAX's rows (connenv.jax): no in-place copies
            return group_velocity(system, (s.T[:, None, :] + t * s_dot.T[:, None, :]).transpose(1, 2, 0), s_dot)
        shapes = np.ascontiguousarray(s.T)[:, None, :] + t * np.ascontiguousarray(s_dot.T)[:, None, :]
        return group_velocity(system, np.moveaxis(shapes, 0, -1), s_dot)  # components contiguous along the rows

    return velocity


def _shape_at(s, s_dot, t):
    """s + t ṡ, t a float or one per row."""
    return s + (t[..., None] if np.ndim(t) else t) * s_dot


def _same(a, b):
    """Whether the components a and b are equal: a bool, or one per row."""
    same = True
    for x, y in zip(a, b):
        same = same & (x == y)
    return same
