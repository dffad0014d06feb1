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
and broadcast over any leading batch axes.
"""

from __future__ import annotations

import enum
from typing import Protocol

import numpy as np
from scipy.differentiate import derivative


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
    G11, G12, G22 = system.metric(np.asarray(q, float), np.asarray(u, float))
    A = np.linalg.inv(G11)
    K = A @ G12
    B = G22 - np.swapaxes(G12, -1, -2) @ K
    return A, K, B


def hamiltonian(system: ActiveConstraintSystem, q, p, u, u_dot):
    """H_u = ½ (p − G12 u̇)ᵀ A (p − G12 u̇) − ½ u̇ᵀ G22 u̇ + V."""
    G11, G12, G22 = system.metric(q, u)
    w = p - _matvec(G12, u_dot)
    kinetic = 0.5 * np.sum(w * np.linalg.solve(G11, w[..., None])[..., 0], axis=-1)
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
