"""Bressan's equations for a Lagrangian system steered by active constraints.

Coordinates split into free ones q (n of them) and assigned ones u (m of them),
which the controller sets directly through frictionless constraints. A system
is described by its kinetic-energy metric in blocks and its potential:

    T = ½ q̇ᵀ G11 q̇ + q̇ᵀ G12 u̇ + ½ u̇ᵀ G22 u̇,    V = V(q, u)

With p = G11 q̇ + G12 u̇ the momenta conjugate to q, and Bressan's matrices
A = G11⁻¹, K = A G12, B = G22 − G12ᵀ A G12, the free motion obeys Hamilton's
equations of

    H_u(q, p, t) = ½ pᵀ A p − pᵀ K u̇ − ½ u̇ᵀ B u̇ + V(q, u)

for the given control path u(t), u̇(t); the constraint force is never needed.
How u̇ enters classifies the system (`JumpClass`).

Any object with integer attributes ``n``, ``m`` and methods
``metric(q, u) -> (G11, G12, G22)`` and ``potential(q, u) -> V`` is a system
here. Arrays carry the coordinate on the last axis (matrices on the last two)
and broadcast over any leading batch axes. `check_metric` tries a system's metric
and potential at sample points; `MetricField` steps a system given by them alone,
on the numerical vector field; `JumpFlow` is a fit system's jump as a flow.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.differentiate import derivative

from connenv.core.backend import floats, namespace, traced
from connenv.core.batched import batched
from connenv.core.steppers import MAX_EVALUATIONS, Scipy
from connenv.core.validation import check_returned, probe

NUMERICAL_EVALUATIONS = 1_000  # per segment, of a vector field that is a numerical gradient (MetricField, JumpFlow
# without jump_field): each evaluation is a scipy.differentiate gradient, dozens of calls of the metric, so that a
# step that cannot succeed fails within seconds, as one on a closed-form field does within MAX_EVALUATIONS


class ActiveConstraintSystem(Protocol):
    n: int
    m: int

    def metric(self, q: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def potential(self, q: np.ndarray, u: np.ndarray) -> np.ndarray: ...


class JumpClass(enum.Enum):
    """Bressan's classification by how the control velocity u̇ enters the (q, p) equations."""

    STRONGLY_FIT = "strongly fit for jumps"  # K = 0, ∂B/∂q = 0: u̇ drops out, any measurable u
    FIT = "fit for jumps"  # ∂B/∂q = 0: affine in u̇, u of bounded variation
    GENERAL = "general"  # quadratic in u̇: u in W^{1,2}, vibrations act as forces


def bressan_matrices(system: ActiveConstraintSystem, q, u):
    """A = G11⁻¹, K = A G12, B = G22 − G21 A G12, at (q, u)."""
    G11, G12, G22 = system.metric(floats(q), floats(u))
    A = np.linalg.inv(G11)
    K = A @ G12
    B = G22 - np.swapaxes(G12, -1, -2) @ K
    return A, K, B


def hamiltonian(system: ActiveConstraintSystem, q, p, u, u_dot):
    """H_u = ½ (p − G12 u̇)ᵀ A (p − G12 u̇) − ½ u̇ᵀ G22 u̇ + V."""
    G11, G12, G22 = system.metric(q, u)
    w = p - _matvec(G12, u_dot)
    ops = namespace(w)
    solve = ops.solve if traced(ops) else np.linalg.solve  # JAX's rows (connenv.jax): its solve
    kinetic = 0.5 * np.sum(w * solve(G11, w[..., None])[..., 0], axis=-1)
    return kinetic - 0.5 * np.sum(u_dot * _matvec(G22, u_dot), axis=-1) + system.potential(q, u)


def vector_field(system: ActiveConstraintSystem, y, u, u_dot):
    """(q̇, ṗ) for y = (q, p) under the control (u, u̇): q̇ = A (p − G12 u̇), ṗ = −∂H_u/∂q.

    The q-derivative of H_u is taken by scipy.differentiate (adaptive central
    differences with Richardson extrapolation): accurate to about 1e-10, but
    tens of H_u evaluations per call. It is the reference that hand-derived
    vector fields are tested against, not a hot path.
    """
    y, u, u_dot = (np.asarray(a, float) for a in (y, u, u_dot))
    n = system.n
    q, p = y[..., :n], y[..., n:]
    G11, G12, _ = system.metric(q, u)
    q_dot = np.linalg.solve(G11, (p - _matvec(G12, u_dot))[..., None])[..., 0]
    p_dot = -_gradient(lambda qs, *args: hamiltonian(system, qs, *args), q, p, u, u_dot)
    return np.concatenate([q_dot, p_dot], axis=-1)


def classify(system: ActiveConstraintSystem, q_samples, u_samples, rtol: float = 1e-7) -> JumpClass:
    """Classify a system from K and ∂B/∂q evaluated at sample points (q, u).

    K counts as zero where |K| ≤ rtol·(1 + |A||G12|) and ∂B/∂q where
    |∂B/∂q| ≤ rtol·(1 + |B|): relative to the matrices they are built from.
    """
    q = np.atleast_2d(np.asarray(q_samples, float))
    u = np.atleast_2d(np.asarray(u_samples, float))
    q, u = np.repeat(q, len(u), axis=0), np.tile(u, (len(q), 1))  # every q with every u
    A, K, B = bressan_matrices(system, q, u)
    _, G12, _ = system.metric(q, u)
    k_zero = np.max(np.abs(K)) <= rtol * (1.0 + np.max(np.abs(A)) * np.max(np.abs(G12)))
    dB_dq = np.stack(
        [
            _gradient(lambda qs, uu: bressan_matrices(system, qs, uu)[2][..., a, b], q, u)
            for a in range(system.m)
            for b in range(system.m)
        ]
    )
    b_flat = np.max(np.abs(dB_dq)) <= rtol * (1.0 + np.max(np.abs(B)))
    if not b_flat:
        return JumpClass.GENERAL
    return JumpClass.STRONGLY_FIT if k_zero else JumpClass.FIT


@dataclass(frozen=True)
class MetricField:
    """A system given by its metric and potential alone, with the numerical vector field `vector_field`, and
    the adaptive stepper's budget of evaluations per segment for it (connenv.core.steppers.evaluation_budget)."""

    system: object
    max_evaluations = NUMERICAL_EVALUATIONS

    @property
    def n(self):
        return self.system.n

    def vector_field(self, y, u, u_dot):
        return vector_field(self.system, y, u, u_dot)


JUMP_STEPPER = Scipy("DOP853", rtol=1e-13, atol=1e-13)
"""The stepper of a `JumpFlow` over s ∈ [0, 1]: tolerances at rounding, since the jump is a map, not a step to
be refined."""
JUMP_ROWS = batched(JUMP_STEPPER)
"""JUMP_STEPPER over rows, each row stepped as the single state (`connenv.core.batched`)."""


@dataclass(frozen=True)
class JumpFlow:
    """The jump equations of a fit system as a vector field in s: along u(s) = u + s Δu, dq/ds = −K Δu,
    dp/ds = ∂/∂q [pᵀ K] Δu; the system's own ``jump_field`` if it has one (exact), else K from the metric and
    ∂/∂q by scipy.differentiate. A stepper over the segment (u, Δu, 1) is then the jump."""

    system: object

    @property
    def max_evaluations(self):
        """The stepper's budget per jump: a numerical field's, unless the system gives its jump_field."""
        return MAX_EVALUATIONS if hasattr(self.system, "jump_field") else NUMERICAL_EVALUATIONS

    def vector_field(self, y, u, delta_u):
        if hasattr(self.system, "jump_field"):
            return self.system.jump_field(y, u, delta_u)
        n, delta_u = self.system.n, floats(delta_u)
        q, p = y[..., :n], y[..., n:]
        K_delta = _matvec(bressan_matrices(self.system, q, u)[1], delta_u)
        flux = _gradient(self._momentum_flux, q, p, u, delta_u)
        return np.concatenate([-K_delta, flux], axis=-1)

    def _momentum_flux(self, q, p, u, delta_u):
        """pᵀ K(q, u) Δu."""
        return np.sum(p * _matvec(bressan_matrices(self.system, q, u)[1], delta_u), axis=-1)


SYSTEM = (
    "integer attributes n, m and methods metric(q, u) -> (G11, G12, G22) and potential(q, u) -> V, "
    "broadcasting over leading axes; or use ActiveConstraintEnv.from_lagrangian(kinetic, potential, q, u)"
)


def check_system(system):
    """ValueError unless system has integer attributes n, m ≥ 1 and callable metric and potential."""
    if system is None or not all(hasattr(system, key) for key in ("n", "m", "metric", "potential")):
        raise ValueError(f"system={system!r} must have {SYSTEM}")
    for name in ("n", "m"):
        value = getattr(system, name)
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"system.{name}={value!r} must be an integer ≥ 1")
    for name in ("metric", "potential", "vector_field", "jump_field"):
        if hasattr(system, name) and not callable(getattr(system, name)):
            raise ValueError(
                f"system.{name}={getattr(system, name)!r} is not callable; system must have {SYSTEM} (and may have "
                "methods vector_field(y, u, u_dot) and jump_field(y, u, delta_u))"
            )


def check_fields(system, q, u):
    """The system's own vector_field and jump_field, tried at construction at rest, at one state y = (q, 0) and over the
    batch of samples (each q with each u): real finite arrays of y's shape, else TypeError or ValueError naming it."""
    q, u = np.repeat(q, len(u), axis=0), np.tile(u, (len(q), 1))
    y = np.concatenate([q, np.zeros_like(q)], axis=-1)
    for method in ("vector_field", "jump_field"):
        if not hasattr(system, method):
            continue
        for point in (0, slice(None)):  # one state, then the batch
            where = "y = (q, p = 0)" if point == 0 else f"a batch of {len(y)} states y = (q, p = 0)"
            name = f"system.{method}(y, u, {'u_dot' if method == 'vector_field' else 'delta_u'}) at {where}"
            value = probe(name, getattr(system, method), y[point], u[point], np.zeros_like(u[point]))
            check_returned(name, value, y[point].shape, f"real finite arrays of y's shape {y[point].shape}")


def check_metric(system, q, u):
    """ValueError (TypeError for what is no real numbers) unless the metric at every sample (each q with each u)
    has blocks of shapes (n, n), (n, m), (m, m) that make a finite, symmetric G, positive semidefinite with G11
    positive definite (the bead at the pivot of its bar has G22 = 0), and the potential is finite; a metric or
    potential that raises is a ValueError naming it."""
    n, m = system.n, system.m
    q, u = np.repeat(q, len(u), axis=0), np.tile(u, (len(q), 1))
    name = f"system.metric(q, u) at a batch of {len(q)} points"
    expected = f"(G11, G12, G22), real arrays of shapes (n, n), (n, m), (m, m) (n = {n}, m = {m}) over the batch"
    blocks = probe(name, system.metric, q, u)
    if not isinstance(blocks, (tuple, list)) or len(blocks) != 3:
        raise TypeError(f"{name} returned {blocks!r}; expected {expected}")
    blocks = [check_returned(f"{name}, block {b},", block, expected=expected) for b, block in zip(("G11", "G12", "G22"),
                                                                                                  blocks)]  # fmt: skip
    for block_name, block, shape in zip(("G11", "G12", "G22"), blocks, ((n, n), (n, m), (m, m))):
        if block.shape != (len(q), *shape):
            raise ValueError(
                f"metric block {block_name} has shape {block.shape[1:]} at a batch of {len(q)} points; expected "
                f"{shape} (n = {n}, m = {m}), broadcast over leading axes"
            )
    G11, G12, G22 = blocks
    G = np.block([[G11, G12], [np.swapaxes(G12, -1, -2), G22]])
    for block_name, block in (("G11", G11), ("G22", G22)):
        if not np.allclose(block, np.swapaxes(block, -1, -2), rtol=1e-12, atol=0):
            i = np.argmax(np.abs(block - np.swapaxes(block, -1, -2)).reshape(len(q), -1).max(-1))
            raise ValueError(
                f"metric block {block_name} = {block[i].tolist()} at q = {q[i]}, u = {u[i]} is not symmetric"
            )
    for block_name, matrix, floor in (("G11", G11, 0.0), ("G", G, -1e-12)):
        eigenvalues = np.linalg.eigvalsh(matrix)
        scale = np.max(np.abs(eigenvalues), axis=-1)
        if not np.all(eigenvalues[..., 0] > floor * scale):
            lowest = eigenvalues[..., 0]  # relative to the scale; a zero matrix (scale 0) is the worst
            i = np.argmin(np.divide(lowest, scale, out=np.full_like(lowest, -np.inf), where=scale > 0))
            kind = "positive definite (q̇ must cost kinetic energy)" if block_name == "G11" else "positive semidefinite"
            raise ValueError(
                f"the metric {'block G11' if block_name == 'G11' else 'G'} = {matrix[i].tolist()} at q = {q[i]}, "
                f"u = {u[i]} is not {kind}: eigenvalues {eigenvalues[i].tolist()}"
            )
    name = f"system.potential(q, u) at a batch of {len(q)} points"
    check_returned(name, probe(name, system.potential, q, u), (len(q),), f"V, {len(q)} finite real numbers")


def _matvec(M, v):
    return (M @ v[..., None])[..., 0]


def _gradient(f, q, *args):
    """∂f/∂q for a scalar f(q, *args), q of shape (..., n), by scipy.differentiate.derivative.

    derivative is elementwise: it adds trailing stencil axes and drops converged
    elements as it goes, and it does both to the arrays passed in its ``args``.
    So every other number f needs goes through ``args`` as a scalar column, and
    f_i stacks the columns back into vectors.
    """
    batch, n = q.shape[:-1], q.shape[-1]
    vectors = [q, *(np.broadcast_to(a, batch + a.shape[-1:]) for a in args)]
    sizes = [v.shape[-1] for v in vectors]
    columns = [v.reshape(-1, v.shape[-1])[:, j] for v in vectors for j in range(v.shape[-1])]
    gradient = []
    for i in range(n):

        def f_i(s, *cols, i=i):
            cols = [np.broadcast_to(c, s.shape) for c in cols]
            cols[i] = s
            split = np.cumsum(sizes)[:-1]
            qs, *rest = (np.stack(group, axis=-1) for group in np.split(np.array(cols), split))
            return f(qs, *rest)

        gradient.append(derivative(f_i, columns[i], args=tuple(columns), initial_step=0.1).df)
    return np.stack(gradient, axis=-1).reshape(q.shape)
