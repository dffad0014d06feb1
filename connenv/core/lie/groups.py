"""Lie groups of motions in coordinates: exponentials, products and brackets.

| group | g as a matrix | coordinates of g (the state) | algebra coordinates ξ | bracket |
|---|---|---|---|---|
| "SO2" | 2×2 rotation | θ | ω | 0 |
| "SE2" | 3×3 homogeneous | (x, y, θ) | (v₁, v₂, ω) | (ω' v₂ − ω v₂', ω v₁' − ω' v₁, 0) |
| "SO3" | 3×3 rotation | its 9 entries, row by row | (ω₁, ω₂, ω₃), ω̂ v = ω × v | ω × ω' |
| "R2" | the vector itself | (x, y) | (v₁, v₂) | 0 |

A group's operations take *components*: tuples of Python floats for one state or of arrays over the rows of a
batch, with the same arithmetic through the operations ``ops_of(component)`` picks (math's or numpy's), so that
row i of a batch follows the single state's path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from connenv.core.backend import ARRAYS, floats, namespace, traced


class _Floats:
    sin, cos, sqrt, atan2 = math.sin, math.cos, math.sqrt, math.atan2

    @staticmethod
    def sinc(x):
        """sin x / x, 1 at 0."""
        return math.sin(x) / x if x != 0.0 else 1.0

    @staticmethod
    def sinc_half_squared(x):
        """(1 − cos x)/x² = ½ (sin(x/2)/(x/2))², ½ at 0; without the cancellation of 1 − cos x."""
        return 0.5 * _Floats.sinc(0.5 * x) ** 2


class _Arrays:
    sin, cos, sqrt, atan2 = np.sin, np.cos, np.sqrt, ARRAYS.atan2  # atan2 safe on complex rows

    @staticmethod
    def sinc(x):
        safe = np.where(x == 0.0, 1.0, x)
        return np.where(x == 0.0, 1.0, np.sin(safe) / safe)

    @staticmethod
    def sinc_half_squared(x):
        half = np.where(x == 0.0, 1.0, 0.5 * x)
        return np.where(x == 0.0, 0.5, 0.5 * (np.sin(half) / half) ** 2)




class _Traced:
    """_Arrays' operations in a tracing namespace (``connenv.jax``'s): the same where-guarded sinc, written on ops."""

    def __init__(self, ops):
        self.ops, self.sin, self.cos, self.sqrt, self.atan2 = ops, ops.sin, ops.cos, ops.sqrt, ops.atan2

    def sinc(self, x):
        safe = self.ops.where(x == 0.0, 1.0, x)
        return self.ops.where(x == 0.0, 1.0, self.ops.sin(safe) / safe)

    def sinc_half_squared(self, x):
        half = self.ops.where(x == 0.0, 1.0, 0.5 * x)
        return self.ops.where(x == 0.0, 0.5, 0.5 * (self.ops.sin(half) / half) ** 2)


def ops_of(component):
    """The operations (sin, cos, sqrt, atan2, sinc, sinc_half_squared) for a component: math's on a Python float,
    numpy's on an array, a tracing namespace's on its arrays (JAX's)."""
    if isinstance(component, float):
        return _Floats
    if type(component) is np.ndarray or not traced(namespace(component)):
        return _Arrays
    return _Traced(namespace(component))


@dataclass(frozen=True)
class Group:
    """A matrix Lie group in coordinates (see the module): ``size`` coordinates of g, ``dim`` of its algebra."""

    name: str
    size: int
    dim: int
    abelian: bool

    def identity(self):
        return {"SO2": (0.0,), "SE2": (0.0, 0.0, 0.0), "R2": (0.0, 0.0)}.get(self.name, tuple(np.eye(3).ravel()))

    def exp(self, xi):
        """The coordinates of exp(ξ^), closed form."""
        if self.name in ("SO2", "R2"):
            return tuple(xi)
        if self.name == "SE2":
            v1, v2, w = xi
            ops = ops_of(w)
            a, b = ops.sinc(w), w * ops.sinc_half_squared(w)  # sin ω/ω and (1 − cos ω)/ω
            return a * v1 - b * v2, b * v1 + a * v2, w
        w1, w2, w3 = xi  # SO3: Rodrigues, R = I + a ω̂ + b ω̂²
        ops = ops_of(w1)
        angle = ops.sqrt(w1 * w1 + w2 * w2 + w3 * w3)
        a, b = ops.sinc(angle), ops.sinc_half_squared(angle)
        return (
            1.0 - b * (w2 * w2 + w3 * w3), b * w1 * w2 - a * w3, b * w1 * w3 + a * w2,
            b * w1 * w2 + a * w3, 1.0 - b * (w1 * w1 + w3 * w3), b * w2 * w3 - a * w1,
            b * w1 * w3 - a * w2, b * w2 * w3 + a * w1, 1.0 - b * (w1 * w1 + w2 * w2),
        )  # fmt: skip

    def product(self, g, h):
        """The coordinates of g h."""
        if self.name in ("SO2", "R2"):
            return tuple(a + b for a, b in zip(g, h))
        if self.name == "SE2":
            x, y, theta = g
            ops = ops_of(theta)
            c, s = ops.cos(theta), ops.sin(theta)
            return x + c * h[0] - s * h[1], y + s * h[0] + c * h[1], theta + h[2]
        return tuple(sum(g[3 * i + k] * h[3 * k + j] for k in range(3)) for i in range(3) for j in range(3))

    def bracket(self, xi, eta):
        """[ξ, η] in algebra coordinates: the commutator [ξ^, η^] of the matrices."""
        if self.name == "SE2":
            (v1, v2, w), (u1, u2, z) = xi, eta
            return z * v2 - w * u2, w * u1 - z * v1, 0.0
        (a1, a2, a3), (b1, b2, b3) = xi, eta  # SO3: the cross product
        return a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1

    def matrix(self, g):
        """g as a matrix (a vector for R2), from its coordinates (..., size)."""
        g = floats(g)
        if self.name == "R2":
            return g.copy()
        if self.name == "SO3":
            return g.reshape(*g.shape[:-1], 3, 3)
        xp = np if type(g) is np.ndarray or not traced(namespace(g)) else namespace(g)  # JAX's rows (connenv.jax)
        c, s = xp.cos(g[..., -1]), xp.sin(g[..., -1])
        if self.name == "SO2":
            return xp.stack([xp.stack([c, -s], -1), xp.stack([s, c], -1)], -2)
        zero = xp.zeros_like(c)
        one = np.ones_like(c) if xp is np else zero + 1.0
        rows = [[c, -s, g[..., 0]], [s, c, g[..., 1]], [zero, zero, one]]
        return xp.stack([xp.stack(row, -1) for row in rows], -2)

    def coordinates(self, matrix):
        """The coordinates of g given as a matrix (a vector for R2); the inverse of ``matrix`` on the group."""
        m = floats(matrix)
        if self.name == "R2":
            return m.copy()
        if self.name == "SO3":
            return m.reshape(*m.shape[:-2], 9)
        angle = ARRAYS.atan2(m[..., 1, 0], m[..., 0, 0])[..., None]
        return angle if self.name == "SO2" else np.concatenate([m[..., :2, 2], angle], -1)

    def off_group(self, matrix):
        """How far a matrix is from the group (0 on it): max of ‖RᵀR − I‖ (Frobenius), |det R − 1| and, for SE2,
        the last row's distance from (0, 0, 1). Coordinates of SO2, SE2 and R2 are on their group by construction.
        A check: of the real parts on complex rows."""
        m = np.real(floats(matrix))
        if self.name == "R2":
            return np.zeros(m.shape[:-1])
        k = 3 if self.name == "SO3" else 2
        R = m[..., :k, :k]
        off = np.maximum(
            np.linalg.norm(np.swapaxes(R, -1, -2) @ R - np.eye(k), axis=(-2, -1)), np.abs(np.linalg.det(R) - 1.0)
        )
        if self.name == "SE2":
            off = np.maximum(off, np.max(np.abs(m[..., 2, :] - [0.0, 0.0, 1.0]), axis=-1))
        return off


GROUPS = {
    "SO2": Group("SO2", 1, 1, True),
    "SE2": Group("SE2", 3, 3, False),
    "SO3": Group("SO3", 9, 3, False),
    "R2": Group("R2", 2, 2, True),
}
FRAMES = ("body", "space")

