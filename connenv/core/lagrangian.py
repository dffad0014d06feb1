"""An active-constraint system from its Lagrangian, as sympy expressions.

``LagrangianSystem(kinetic, potential, q, u)``: T and V are sympy expressions in the free coordinates q, the
assigned ones u (lists of Symbols) and their velocities, the velocity of a coordinate s being the Symbol named
``s.name + "_dot"``. Every other number (masses, lengths, g) is a number in the expressions. From them, once and
symbolically:

- the metric blocks G11, G12, G22, the Hessian of T in (q̇, u̇), after checking that T is a quadratic form in the
  velocities and V depends on no velocity;
- Hamilton's equations of H_u (``connenv.core.mechanics``) with exact gradients, ṗ = −∂H_u/∂q;
- Bressan's class (``jump_class``): K ≡ 0? ∂B/∂q ≡ 0? after simplification;
- the jump flow of a fit system: along a straight path u(s) = u + s Δu, s ∈ [0, 1],
  dq/ds = −K(q, u(s)) Δu,  dp/ds = ∂/∂q [pᵀ K(q, u(s))] Δu (``jump_field``).

All of them are lambdified to numpy and broadcast over leading batch axes (coordinates on the last axis); on JAX
arrays (``connenv.jax``), to JAX (sympy's ``modules="jax"``, built on the first traced call), from the same
expressions, so that a system built here traces. A system pickles as its expressions and is derived again when
unpickled.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from connenv.core.backend import floats, namespace, traced
from connenv.core.mechanics import JumpClass


class LagrangianSystem:
    """Bressan's system of T(q, u, q̇, u̇) = ½ [q̇ u̇] G [q̇ u̇]ᵀ and V(q, u): see the module."""

    def __init__(self, kinetic, potential, q, u):
        self.args = (kinetic, potential, q, u)
        q, u = _symbols("q", q), _symbols("u", u)
        if set(q) & set(u):
            raise ValueError(f"q={q} and u={u} share the symbol(s) {sorted(map(str, set(q) & set(u)))}")
        kinetic, potential = _expression("kinetic", kinetic), _expression("potential", potential)
        q_dot, u_dot = _velocities(q), _velocities(u)
        coordinates = set(q) | set(u)
        kinetic = _check_symbols("kinetic", kinetic, coordinates | set(q_dot) | set(u_dot), q, u)
        potential = _check_symbols("potential", potential, coordinates, q, u)
        velocities = sp.Matrix(q_dot + u_dot)
        G = sp.hessian(kinetic, velocities)
        if sp.simplify(kinetic - (velocities.T * G * velocities)[0] / 2) != 0 or any(
            (entry.free_symbols & set(velocities)) for entry in G
        ):
            raise ValueError(f"kinetic={kinetic} is not a quadratic form in the velocities {list(velocities)}")
        self.n, self.m = len(q), len(u)
        n = self.n
        G11, G12, G22 = G[:n, :n], G[:n, n:], G[n:, n:]
        if G11.det() == 0:
            raise ValueError(f"kinetic={kinetic}: its block G11 = {G11.tolist()} (in q̇) is singular")
        A = G11.inv()
        K = (A * G12).applyfunc(sp.simplify)
        B = (G22 - G12.T * A * G12).applyfunc(sp.simplify)
        self.K, self.B = K, B
        p = sp.Matrix(sp.symbols(f"p0:{n}", real=True))
        w = p - G12 * sp.Matrix(u_dot)
        H = (w.T * A * w)[0] / 2 - (sp.Matrix(u_dot).T * G22 * sp.Matrix(u_dot))[0] / 2 + potential
        q_rate = A * w
        p_rate = [-sp.diff(H, s) for s in q]
        y, delta = list(q) + list(p), sp.Matrix(sp.symbols(f"du0:{self.m}", real=True))
        pK = (p.T * K * delta)[0]
        jump = [-(K * delta)[i] for i in range(n)] + [sp.diff(pK, s) for s in q]
        for name, expressions in (("the vector field", p_rate), ("the jump equations", jump)):
            stuck = [e for e in expressions if e.has(sp.Derivative)]
            if stuck:
                raise ValueError(
                    f"{name} has a derivative sympy cannot evaluate, {stuck[0]}: T and V must be differentiable in q "
                    f"(kinetic={kinetic}, potential={potential})"
                )
        self._metric = _lambdify([q, u], [G11, G12, G22])
        self._potential = _lambdify([q, u], [[potential]])
        self._field = _lambdify([y, u, u_dot], [list(q_rate) + p_rate])
        self._jump = _lambdify([y, u, list(delta)], [jump])
        k_zero = all(entry == 0 for entry in K)
        b_flat = all(sp.simplify(sp.diff(entry, s)) == 0 for entry in B for s in q)
        self.jump_class = JumpClass.GENERAL if not b_flat else JumpClass.STRONGLY_FIT if k_zero else JumpClass.FIT

    def __reduce__(self):
        return type(self), self.args

    def __repr__(self):
        kinetic, potential, q, u = self.args
        return f"LagrangianSystem(kinetic={kinetic}, potential={potential}, q={list(q)}, u={list(u)})"

    def metric(self, q, u):
        """(G11, G12, G22) at (q, u): arrays (..., n, n), (..., n, m), (..., m, m)."""
        G11, G12, G22 = self._metric(q, u)
        n, m = self.n, self.m
        return G11.reshape(G11.shape[:-1] + (n, n)), G12.reshape(G12.shape[:-1] + (n, m)), G22.reshape(
            G22.shape[:-1] + (m, m)
        )

    def potential(self, q, u):
        return self._potential(q, u)[0][..., 0]

    def vector_field(self, y, u, u_dot):
        """(q̇, ṗ): q̇ = A (p − G12 u̇), ṗ = −∂H_u/∂q, from the symbolic derivatives."""
        return self._field(y, u, u_dot)[0]

    def jump_field(self, y, u, delta_u):
        """(dq/ds, dp/ds) of a jump along u(s) = u + s Δu at s (u is u(s)): −K Δu and ∂/∂q [pᵀ K Δu]."""
        return self._jump(y, u, delta_u)[0]


def _symbols(name, symbols):
    symbols = list(symbols)
    if not symbols or not all(isinstance(s, sp.Symbol) for s in symbols):
        raise ValueError(f"{name}={symbols!r} must be a non-empty list of sympy Symbols")
    if len(set(symbols)) != len(symbols):
        raise ValueError(f"{name}={symbols!r} repeats a symbol")
    return symbols


NOT_FINITE = (sp.S.ComplexInfinity, sp.S.Infinity, sp.S.NegativeInfinity, sp.S.NaN)


def _expression(name, value):
    """value as a real, finite sympy expression (a number, a string sympy parses, an expression), else TypeError
    (nothing sympy reads as an expression) or ValueError (zoo, ±oo, nan or I in it), naming it: T and V are real
    functions, finite on the configuration space."""
    expected = f"{name}={value!r} must be a sympy expression (or a number) in q, u and their velocities"
    try:
        expression = sp.sympify(value, strict=not isinstance(value, str))
    except (sp.SympifyError, TypeError, ValueError, SyntaxError) as error:
        raise TypeError(expected) from error
    if not isinstance(expression, sp.Expr) or expression.is_Matrix:
        raise TypeError(expected)
    if expression.has(*NOT_FINITE):
        raise ValueError(f"{name}={expression} holds zoo, oo or nan: it must be finite")
    if expression.has(sp.I):
        raise ValueError(f"{name}={expression} holds the imaginary unit I: it must be real")
    return expression


def _velocities(symbols):
    """The velocity Symbol of each coordinate: the coordinate's name + "_dot", with the coordinate's assumptions."""
    return [sp.Symbol(s.name + "_dot", **s.assumptions0) for s in symbols]


def _check_symbols(name, expression, allowed, q, u):
    """The expression over the allowed Symbols (matched by name, whatever their assumptions), else ValueError."""
    by_name = {s.name: s for s in allowed}
    unknown = sorted(str(s) for s in expression.free_symbols if s.name not in by_name)
    if unknown:
        raise ValueError(
            f"{name}={expression} uses the symbol(s) {unknown}, which are not in q={q}, u={u} or their velocities "
            f"(valid: {sorted(by_name)}); give parameters as numbers"
        )
    return expression.xreplace({s: by_name[s.name] for s in expression.free_symbols})


def _lambdify(groups, outputs):
    """f(*arrays) → the outputs stacked on a last axis: each a flat list or Matrix of expressions, each argument
    an array (..., len(group)) whose entries are the group's symbols; broadcast over the leading axes."""
    flat = [list(output) for output in outputs]
    symbols = [sp.symbols(f"x{i}_0:{len(group)}") for i, group in enumerate(groups)]
    rename = {s: x for group, xs in zip(groups, symbols) for s, x in zip(group, xs)}
    entries = [[sp.sympify(e).xreplace(rename) for e in output] for output in flat]
    arguments, values = [x for xs in symbols for x in xs], [e for output in entries for e in output]
    f = sp.lambdify(arguments, values, "numpy", cse=True)
    scalar = [sp.lambdify(arguments, values, "math", cse=True)]  # one state: Python floats, no numpy overhead
    sizes = [len(output) for output in flat]
    bounds = list(zip(np.cumsum([0, *sizes[:-1]]), np.cumsum(sizes)))

    jax = []  # the JAX function, lambdified on the first traced call (connenv.jax): import connenv imports no jax

    def call(*arrays):
        if any(type(a) is not np.ndarray and not isinstance(a, float) and traced(namespace(a)) for a in arrays):
            return _traced_call(jax, arguments, values, bounds, arrays)
        if scalar[0] is not None and all(np.ndim(a) == 1 for a in arrays):
            try:
                out = np.array(scalar[0](*(x for a in arrays for x in np.asarray(a, float).tolist())), float)
                return [out] if len(bounds) == 1 else [out[start:end] for start, end in bounds]
            except (NameError, TypeError, ValueError, OverflowError, ZeroDivisionError):
                scalar[0] = None  # a function math lacks, or a domain error: numpy's, which answers nan or inf
        arrays = [floats(a) for a in arrays]  # complex on a Jacobian's rows
        shape = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
        columns = [a[..., j] for a in arrays for j in range(a.shape[-1])]
        out = [np.broadcast_to(v, shape) for v in f(*columns)]
        return [np.stack(out[start:end], axis=-1) for start, end in bounds]

    return call


def _traced_call(jax, arguments, values, bounds, arrays):
    """call on JAX arrays: the expressions lambdified to JAX (once), broadcast and stacked as numpy's are."""
    if not jax:
        jax.append(sp.lambdify(arguments, values, "jax", cse=True))
    ops = next(namespace(a) for a in arrays if type(a) is not np.ndarray and traced(namespace(a)))
    arrays = [floats(a) if type(a) is not np.ndarray and traced(namespace(a)) else np.asarray(a, float) for a in arrays]
    shape = np.broadcast_shapes(*(np.shape(a)[:-1] for a in arrays))
    columns = [a[..., j] for a in arrays for j in range(np.shape(a)[-1])]
    out = [ops.broadcast_to(ops.real_part(v) * 1.0, shape) for v in jax[0](*columns)]
    return [ops.stack(out[start:end], -1) for start, end in bounds]
