r"""Curvature and holonomy of a mechanical connection, for any env or system that has one.

A mechanical connection A(s) (Lawton; Marsden, Montgomery & Ratiu 1990) turns shape changes ṡ into the group
velocity ξ = −A(s) ṡ, which moves g by ġ = g ξ^ (body frame) or ġ = ξ^ g (space frame): `connenv.core.lie`. Its
*curvature* is the 2-form on the shape space, with A_i = A(s) e_i the column of the i-th shape coordinate,

    F_ij = ∂_i A_j − ∂_j A_i − σ [A_i, A_j],    σ = +1 in the body frame, −1 in the space frame,

[·,·] the matrix commutator of the group's algebra (``Group.bracket``: the cross product on SO(3); zero on SO(2)
and ℝ²). It is Hatton & Choset's curvature of the local connection, their "total Lie bracket" DA = dA + Σ[A_i, A_j]
(IJRR 2011) for ξ = −A ṡ in the body frame, written out with the commutator so that its sign is unambiguous: the
second-order Magnus expansion of the flow around a small loop that encloses the oriented area a_ij (a = ½∮ s_i ds_j
− s_j ds_i, positive counterclockwise in the (s_i, s_j) plane) gives the net motion

    g_start⁻¹ g_end ≈ exp(−Σ_{i<j} F_ij a_ij)    (body; g_end g_start⁻¹ in the space frame),

dA the *nonconservative* part (Stokes' theorem turns the loop integral −∮A ds into the area integral of dA) and the
bracket the *noncommutative* one (the group's motions in different directions do not commute). The first-order
prediction of a loop's holonomy is −∬F over a surface the loop bounds (`loop_holonomy`); its error is third order in
the loop's size, and fourth where the loop is based at the centre of the area it encloses (the third-order term goes
with the area's first moment about the base point).

Derivatives of A are by complex step where the connection carries complex shapes (every connection of connenv's
systems does: ``connenv.core.backend``): Im A(s + ih e_i)/h = ∂_i A(s), exact to rounding, as the models'
Jacobians (``connenv.core.model``). A connection that does not (it raises on complex input, drops the imaginary
part, or disagrees with a difference quotient at a probe shape) is differentiated by central differences with
Richardson extrapolation, whose error estimate `curvature` returns.

*Minimum-perturbation coordinates* (Hatton & Choset, IJRR 2011, "Geometric motion planning: the local connection,
Stokes' theorem, and the importance of coordinate choice"): a swimmer's body frame is a choice; moving it by a
shape-dependent β(s) ∈ SE(2) (the new frame g' = g β(s)) changes the connection to

    A'_i = Ad_{β⁻¹} A_i − β⁻¹ ∂_i β,

and the curvature covariantly, F' = Ad_{β⁻¹} F, so the holonomy is conjugated and the exact motion the same up to
that rigid change of frame, but the area integral of F' predicts it better where A' is small: the frame that moves
least with the shape (`minimum_perturbation`: β minimizing ∫|A'|² over the shape box). The command prints the
prediction error of circular gaits in both frames:

    python -m connenv.geometry --prediction-error ID    # an SE(2) swimmer: SnakeSwimmer, KozlovShell

and ``python -m connenv.geometry ID [--write FILE.png]`` draws an env's curvature map over its shape space
(``python -m agents.curvature_map ID``: with its analytic controller's gait, as on the env pages).
"""

from __future__ import annotations

import argparse
import functools
import itertools
import math
import sys
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.interpolate import RectBivariateSpline
from scipy.sparse import coo_matrix, diags, hstack, vstack
from scipy.sparse.linalg import lsqr
from scipy.spatial.transform import Rotation

from connenv import cli
from connenv.core.backend import floats
from connenv.core.lie import GROUPS, Connection, ConstantConnection, Magnus
from connenv.core.segments import run_segments
from connenv.core.steppers import ConnectionSystem, conforms
from connenv.core.validation import real_array
from connenv.systems.rolling_ball import RollingBall

PROG = "python -m connenv.geometry"
COMPLEX_STEP = 1e-20  # Im A(s + ih)/h: far below rounding of any shape, far above the smallest float
RICHARDSON_STEP = 1e-3  # central differences at h and h/2 (times max(1, |s_i|)): the fallback's
PROBE_TOLERANCE = 1e-6  # relative: a complex step that disagrees more with the fallback at a probe shape is refused
TRIANGLE_NODES = 8  # Gauss–Legendre nodes per direction on each triangle of the cone (collapsed square)
GRID = 33  # nodes per shape direction of the minimum-perturbation problem (odd: the box's centre is a node)
AMPLITUDES = (0.1, 0.3, 0.6)  # circular gaits' radii, as fractions of the shape box's half-widths
SAMPLES = 400  # points of a gait's loop
DIRECTIONS = {"SO2": ("θ",), "SE2": ("x", "y", "θ"), "SO3": ("ω₁", "ω₂", "ω₃"), "R2": ("x", "y")}
DIRECTION_UNITS = {"SO2": ("rad",), "SE2": ("m", "m", "rad"), "SO3": ("rad",) * 3, "R2": ("m", "m")}
FIGURE = (4.5, 4.7)  # inches per panel of the curvature map (and its legend below), at DPI
DPI = 100
GRID_RANGE = (3, 1025)  # minimum_perturbation's nodes per direction: a centre and a difference need 3, memory the top


# -- the connection of an env or a system ------------------------------------------------------------------------


@dataclass(frozen=True)
class LocalConnection:
    """A connection as this module reads it: ``connection`` (a `connenv.core.lie.Connection`: group, frame, A(s)),
    the ``system`` and ``stepper`` that step its group element (the env's own where there is an env), the shape box
    ``low``, ``high`` (±inf where unbounded; None without an env) and the ``field`` of the env's state that holds
    the shape."""

    connection: Connection
    system: object
    stepper: object
    low: np.ndarray | None
    high: np.ndarray | None
    field: str = "s"

    @property
    def group(self):
        return GROUPS[self.connection.group]


def local_connection(target, group: str | None = None, frame: str = "body") -> LocalConnection:
    """The connection of ``target``: an env id, an env (wrapped or not), a system with ``group``, ``frame`` and
    ``connection(s)`` (a `connenv.core.lie.Connection`, a swimmer's reduced model), or a callable A(s) of one
    shape with ``group`` (and ``frame``). An env without a connection (an active-constraint env) is a ValueError
    that says so."""
    if isinstance(target, LocalConnection):
        return target
    if isinstance(target, str):
        target = _make(target)
    env = getattr(target, "unwrapped", target)
    if hasattr(env, "reduced_system"):  # a swimmer: its connection is its zero-momentum (reduced) model's
        bound = np.asarray(env.shape_bounds, float)
        field = "s" if hasattr(env.state, "s") else "u"
        return LocalConnection(
            _as_connection(env.reduced_system), env.reduced_system, env.stepper, -bound, bound, field
        )
    system = getattr(env, "system", None)
    if isinstance(system, RollingBall):  # ω = e_z × v/ρ = −A v, Ṙ = ω̂ R: a constant connection, space frame
        A = np.array([[0.0, 1.0], [-1.0, 0.0], [0.0, 0.0]]) / system.radius
        unbounded = np.full(2, np.inf)
        return LocalConnection(ConstantConnection("SO3", "space", A=A), system, env.stepper, -unbounded, unbounded,
                               "position")  # fmt: skip
    if system is not None and conforms(system, ConnectionSystem):  # a ConnectionEnv
        return LocalConnection(_as_connection(system), system, env.stepper, env.low, env.high)
    if conforms(env, ConnectionSystem):
        return _standalone(_as_connection(env), env)
    if callable(target):
        if group not in GROUPS:
            raise ValueError(f"group={group!r}: a callable connection needs its group, one of {list(GROUPS)}")
        connection = Connection(group, frame, target)
        return _standalone(connection, connection)
    name = getattr(getattr(target, "spec", None), "id", None) or getattr(env, "name", type(env).__name__)
    raise ValueError(f"{name} has no mechanical connection (its shape does not fix its group velocity by "
                     "ξ = −A(s) ṡ): no curvature to draw")  # fmt: skip


def _make(env_id: str):
    """The env of an id, made with its spec's kwargs (an id that needs some has an example)."""
    import gymnasium as gym

    from connenv.envs.spec import spec

    if env_id not in gym.registry:
        raise ValueError(f"unknown env {env_id!r}")
    return gym.make(env_id, **spec(env_id).make_kwargs())


def _as_connection(system) -> Connection:
    """A `Connection` of a system that has group, frame and connection(s) (batched unless it says otherwise)."""
    if isinstance(system, Connection):
        return system
    return Connection(system.group, system.frame, system.connection, getattr(system, "vectorized", True))


def _standalone(connection, system) -> LocalConnection:
    """A connection without an env: stepped by the default Lie-group step, its shape box unknown."""
    return LocalConnection(connection, system, Magnus(), None, None)


def evaluate(connection: Connection, s) -> np.ndarray:
    """A(s), (N, dim 𝔤, k), at shapes s (N, k): complex shapes stay complex."""
    s = floats(s)
    if connection.vectorized:
        return floats(connection.connection(s))
    return np.stack([floats(connection.connection(row)) for row in s])


# -- curvature ---------------------------------------------------------------------------------------------------


class Curvature(NamedTuple):
    """``F`` (N, dim 𝔤, k, k), antisymmetric in its last two axes: F[n, :, i, j] is F_ij at shape n (see the
    module); ``error``, an estimate of F's error per entry (0 where the derivatives are by complex step, exact to
    rounding); ``method``, "complex step" or "richardson"."""

    F: np.ndarray
    error: np.ndarray
    method: str


def curvature(connection, s, group: str | None = None, frame: str = "body") -> Curvature:
    """The curvature F_ij = ∂_i A_j − ∂_j A_i − σ[A_i, A_j] (σ = +1 body, −1 space; see the module) at shapes s
    (N, k) or (k,), in the frame of the connection (the env's): ``connection`` as `local_connection` takes it. For
    a 2-D shape space F[:, :, 0, 1] is one number per group direction; a small counterclockwise loop of area a
    moves g by about exp(−a F₁₂)."""
    local = local_connection(connection, group, frame)
    s = shapes("s", s, local, ndims=(1, 2))
    A = evaluate(local.connection, s)
    if A.ndim != 3 or A.shape[-1] != s.shape[1]:
        raise ValueError(f"s={s.tolist()} has {s.shape[1]} shape coordinates, and the connection A(s) has "
                         f"{np.shape(A)[-1]} columns: give one coordinate per column")
    D, error, method = derivatives(local.connection, s, A)
    dA = np.swapaxes(D, -1, -2) - D  # [n, d, i, j] = ∂_i A_j − ∂_j A_i (D[n, d, j, i] = ∂_i A_j)
    sign = 1.0 if local.connection.frame == "body" else -1.0
    F = dA - sign * brackets(local.group, A)
    return Curvature(F, np.swapaxes(error, -1, -2) + error, method)


def shapes(name: str, value, local: LocalConnection, ndims=(1, 2)) -> np.ndarray:
    """Shapes as float64 rows (N ≥ 1, k): real, finite, of ``ndims`` dimensions, k the connection's number of shape
    coordinates where its env says it (the shape box), else ValueError naming ``name``, the value and what is
    expected. (A standalone connection's k is checked against A's columns, where it is evaluated.)"""
    k = None if local.low is None else len(local.low)
    expected = f"finite real shapes, {'(k,) or ' if 1 in ndims else ''}(N ≥ 1, k)" + ("" if k is None else
                                                                                   f" with k = {k}")
    array = real_array(name, value, expected)
    if array.ndim not in ndims or array.size == 0 or (k is not None and array.shape[-1] != k):
        raise ValueError(f"{name}={value!r} has shape {array.shape}: expected {expected}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}={value!r} is not finite: expected {expected}")
    return np.atleast_2d(array)


def brackets(group, A) -> np.ndarray:
    """[A_i, A_j] (N, dim 𝔤, k, k) of the columns of A (N, dim 𝔤, k); zero on the abelian groups."""
    N, dim, k = A.shape
    out = np.zeros((N, dim, k, k), A.dtype)
    if group.abelian:
        return out
    for i in range(k):
        for j in range(i + 1, k):
            pair = group.bracket(tuple(A[:, :, i].T), tuple(A[:, :, j].T))
            out[:, :, i, j] = np.stack(np.broadcast_arrays(*pair), -1)
            out[:, :, j, i] = -out[:, :, i, j]
    return out


def derivatives(connection: Connection, s, A):
    """(D, error, method): D[n, d, j, i] = ∂_i A_dj at the shapes s (N, k), by complex step where the connection
    carries complex shapes (checked at the first shape against Richardson's), else by Richardson's."""
    D = _complex_step(connection, s, A)
    if D is not None:
        reference, error = _richardson(connection, s[:1])
        scale = np.max(np.abs(reference)) + np.max(np.abs(A[:1]))
        if np.all(np.abs(D[:1] - reference) <= PROBE_TOLERANCE * scale + 100 * error):
            return D, np.zeros_like(D), "complex step"
    D, error = _richardson(connection, s)
    return D, error, "richardson"


def _complex_step(connection, s, A):
    """Im A(s + ih e_i)/h as D (N, dim, k, k), or None where the connection does not carry complex shapes: it
    raises, warns of a discarded imaginary part, returns reals or non-finite numbers, or moves the real part."""
    N, k = s.shape
    shifted = (s[:, None, :] + 1j * COMPLEX_STEP * np.eye(k)).reshape(N * k, k)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", np.exceptions.ComplexWarning)
            moved = evaluate(connection, shifted)
    except (TypeError, ValueError, ArithmeticError, np.exceptions.ComplexWarning):
        return None
    if not np.iscomplexobj(moved) or moved.shape != (N * k, *A.shape[1:]) or not np.all(np.isfinite(moved)):
        return None
    moved = moved.reshape(N, k, *A.shape[1:])
    if not np.allclose(moved.real, A[:, None], rtol=1e-12, atol=1e-300):
        return None
    return np.moveaxis(moved.imag / COMPLEX_STEP, 1, -1)  # [n, i, d, j] → [n, d, j, i]


def _richardson(connection, s):
    """Central differences at h and h/2 extrapolated, (4 D(h/2) − D(h))/3, and the estimate |D(h/2) − D(h)|/3 of
    D(h/2)'s error, which bounds the extrapolation's where the expansion in h holds; D[n, d, j, i] = ∂_i A_dj."""
    N, k = s.shape
    h = RICHARDSON_STEP * np.maximum(1.0, np.abs(s))  # (N, k)

    def central(h):
        offsets = h[:, :, None] * np.eye(k)  # [n, i, :] = h_i e_i
        plus = evaluate(connection, (s[:, None, :] + offsets).reshape(N * k, k))
        minus = evaluate(connection, (s[:, None, :] - offsets).reshape(N * k, k))
        quotient = (plus - minus).reshape(N, k, *plus.shape[1:]) / (2 * h[:, :, None, None])
        return np.moveaxis(np.real(quotient), 1, -1)

    coarse, fine = central(h), central(h / 2)
    return (4 * fine - coarse) / 3, np.abs(fine - coarse) / 3


# -- holonomy ----------------------------------------------------------------------------------------------------


class Holonomy(NamedTuple):
    """``net``: the exact net motion g_start⁻¹ g_end (body; g_end g_start⁻¹ in the space frame) in coordinates
    comparable with the algebra's: (x, y, θ) on SE(2), the rotation vector on SO(3), θ on SO(2), (x, y) on ℝ²;
    ``predicted``: the first-order prediction −∬F over the cone from the apex (algebra coordinates); ``g``: the
    coordinates of g_end from the identity, as the system's state holds them."""

    net: np.ndarray
    predicted: np.ndarray
    g: np.ndarray


def loop_holonomy(target, loop, *, period=None, apex=None, frame_change=None, group: str | None = None,
                  frame: str = "body") -> Holonomy:  # fmt: skip
    """The net group motion of a closed shape loop (M, k), the last point the first (modulo ``period``, a coordinate
    that winds: the beanie's ψ, 2π), integrated by the env's own stepper over the loop's chords from the identity,
    beside the first-order prediction, −∬F over the cone from ``apex`` (default: the loop's centroid) over the loop:
    for a 2-D shape space its interior (Green's theorem; the triangles from any apex add up to it, signed), for
    k > 2 that spanning surface. ``frame_change``: a `MinimumPerturbation`, whose frame both are given in."""
    local = local_connection(target, group, frame)
    if period is not None:
        period = float(real_array("period", period, "a positive finite real number"))
        if not (math.isfinite(period) and period > 0):
            raise ValueError(f"period={period!r}: expected a positive finite real number")
    loop = _closed(shapes("loop", loop, local, ndims=(2,)), period)
    segments = [(p, q - p, 1.0) for p, q in itertools.pairwise(loop)]  # the flow is geometric: any speed will do
    y = np.asarray(run_segments(local.stepper, local.system, np.array(local.group.identity()), segments)[0], float)
    net = _net(local.group.name, y)
    if frame_change is not None:
        net = frame_change.conjugated(net, loop[0])
    return Holonomy(net, -enclosed(local, loop, apex, frame_change), y)


def _closed(loop, period):
    """The loop (M, k) checked: at least 3 points, closed (modulo period)."""
    if loop.ndim != 2 or len(loop) < 3:
        raise ValueError(f"loop of shape {loop.shape}: expected (M ≥ 3, k) shapes")
    gap = loop[-1] - loop[0]
    if period is not None:
        gap = gap - period * np.round(gap / period)
    if not np.all(np.abs(gap) <= 1e-12 * (1.0 + np.max(np.abs(loop)))):
        raise ValueError(f"loop is not closed: it ends {gap.tolist()} from where it started")
    return loop


def _net(group: str, y) -> np.ndarray:
    """g's coordinates as a net motion comparable with the algebra's: SO(3)'s rotation vector, the others' own."""
    return Rotation.from_matrix(y.reshape(3, 3)).as_rotvec() if group == "SO3" else y.copy()


def enclosed(target, loop, apex=None, frame_change=None) -> np.ndarray:
    """∬F (dim 𝔤) over the cone from apex over the closed loop (M, k): Σ_m ∫ over the triangle (apex, p_m,
    p_{m+1}) of F(a_m, b_m), a_m = p_m − apex, b_m = p_{m+1} − apex, on the collapsed square
    σ(u, v) = apex + u a + u v (b − a), whose area element is u (a ∧ b) du dv; Gauss–Legendre in u and v."""
    local = local_connection(target)
    loop = shapes("loop", loop, local, ndims=(2,))
    if len(loop) < 2:
        raise ValueError(f"loop of shape {loop.shape}: expected (M ≥ 2, k) shapes")
    apex = np.mean(loop[:-1], axis=0) if apex is None else shapes("apex", apex, local, ndims=(1,))[0]
    if apex.shape != loop.shape[1:]:
        raise ValueError(f"apex={apex.tolist()}: expected one shape of the loop's {loop.shape[1]} coordinates")
    a, b = loop[:-1] - apex, loop[1:] - apex  # (M, k)
    x, w = np.polynomial.legendre.leggauss(TRIANGLE_NODES)
    u, weights = 0.5 * (x + 1.0), 0.5 * w
    U, V = u[None, :, None, None], u[None, None, :, None]
    points = (apex + U * (a[:, None, None, :] + V * (b - a)[:, None, None, :])).reshape(-1, loop.shape[1])
    F = curvature(local, points).F  # (M · n², dim, k, k)
    if frame_change is not None:
        F = np.moveaxis(frame_change.adjoint_inverse(points, np.moveaxis(F, 1, -1)), -1, 1)
    F = F.reshape(len(a), len(u), len(u), *F.shape[1:])
    pairing = np.einsum("muvdij,mi,mj->muvd", F, a, b)
    return np.einsum("muvd,u,v->d", pairing, weights * u, weights)


# -- minimum-perturbation coordinates ------------------------------------------------------------------------------


@dataclass(frozen=True)
class MinimumPerturbation:
    """A change of body frame on SE(2), g' = g β(s) (see the module): β = (x, y, θ) on the grid ``axes`` of the
    shape box, ``beta`` (n₁, n₂, 3), between the nodes by bicubic splines (scipy's RectBivariateSpline)."""

    axes: tuple
    beta: np.ndarray

    @functools.cached_property
    def splines(self):
        return [RectBivariateSpline(*self.axes, self.beta[..., c]) for c in range(3)]

    def at(self, s, derivative=(0, 0)) -> np.ndarray:
        """β(s) (N, 3) at shapes s (N, 2), or its derivative ∂^derivative β."""
        s = np.asarray(s, float)
        return np.stack([spline.ev(s[:, 0], s[:, 1], *derivative) for spline in self.splines], -1)

    def transformed(self, s, A) -> np.ndarray:
        """A' = Ad_{β⁻¹} A − β⁻¹ ∂β (N, 3, 2), the connection in the new frame, from A (N, 3, 2) at shapes s (N, 2);
        β⁻¹ ∂_i β = (R(−β_θ) ∂_i β_p, ∂_i β_θ)."""
        theta, out = self.at(s)[:, 2], np.moveaxis(self.adjoint_inverse(s, np.moveaxis(A, 1, -1)), -1, 1)
        c, n = np.cos(theta), np.sin(theta)
        for i, derivative in enumerate(((1, 0), (0, 1))):
            x, y, turn = self.at(s, derivative).T
            out[:, :, i] -= np.stack([c * x + n * y, c * y - n * x, turn], -1)
        return out

    def adjoint_inverse(self, s, xi) -> np.ndarray:
        """Ad_{β(s)⁻¹} ξ = (R(−β_θ)(v + ω J β_p), ω), J p = (−p_y, p_x): ξ (N, …, 3) at shapes s (N, 2), the
        algebra's coordinates in the new frame (the curvature's too: F' = Ad_{β⁻¹} F)."""
        beta = self.at(s).reshape(len(s), *(1,) * (np.ndim(xi) - 2), 3)
        (px, py, theta), (v1, v2, w) = np.moveaxis(beta, -1, 0), np.moveaxis(xi, -1, 0)
        u1, u2 = v1 - w * py, v2 + w * px
        c, n = np.cos(theta), np.sin(theta)
        return np.stack([c * u1 + n * u2, c * u2 - n * u1, w], -1)

    def conjugated(self, net, s0) -> np.ndarray:
        """A net motion h (x, y, θ) of a loop based at s0 in the new frame: β(s0)⁻¹ h β(s0)."""
        group, beta = GROUPS["SE2"], tuple(self.at(np.asarray(s0, float)[None])[0].tolist())
        x, y, theta = beta
        c, n = math.cos(theta), math.sin(theta)
        inverse = (-(c * x + n * y), n * x - c * y, -theta)
        return np.array(group.product(group.product(inverse, tuple(np.asarray(net).tolist())), beta))


def minimum_perturbation(target, grid: int = GRID) -> MinimumPerturbation:
    """Hatton & Choset's minimum-perturbation body frame of an SE(2) connection in the body frame over its shape
    box (2-D, bounded): β minimizing ∫|A'|² (A' = Ad_{β⁻¹} A − β⁻¹ dβ), on a grid of ``grid`` × ``grid`` nodes with
    differences along its edges. The two parts separate: the rotation's, |A_θ − ∇β_θ|², is a Poisson problem with
    Neumann boundary conditions (the Helmholtz–Hodge split of A_θ: its gradient part removed), fixed by β_θ = 0 at
    the box's centre; the translation's, |A_p + A_θ J β_p − ∇β_p|², a linear least-squares problem (sparse, lsqr)."""
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or not (
            GRID_RANGE[0] <= grid <= GRID_RANGE[1]):
        raise ValueError(f"grid={grid!r}: expected a whole number of nodes per direction in [{GRID_RANGE[0]}, "
                         f"{GRID_RANGE[1]}]")
    local = local_connection(target)
    c = local.connection
    box = None if local.low is None else np.array([local.low, local.high])
    if (c.group, c.frame) != ("SE2", "body") or box is None or box.shape != (2, 2) or not np.all(np.isfinite(box)):
        raise ValueError(
            f"minimum-perturbation coordinates here are for SE(2) connections in the body frame over a "
            f"bounded 2-D shape box; got {c.group}, {c.frame}, a box {local.low} to {local.high}"
        )
    axes = tuple(np.linspace(lo, hi, grid) for lo, hi in zip(local.low, local.high))
    difference, mean, midpoints, direction = _edges(axes)
    column = evaluate(c, midpoints)[np.arange(len(direction)), :, direction]  # (E, 3): A at each edge, along it
    theta = _least_squares(difference, column[:, 2])
    theta -= theta[(grid * grid) // 2]
    turn = diags(column[:, 2]) @ mean
    coupled = vstack([hstack([difference, turn]), hstack([-turn, difference])])
    p = _least_squares(coupled, np.concatenate([column[:, 0], column[:, 1]]))
    beta = np.stack([p[: grid * grid], p[grid * grid :], theta], -1).reshape(grid, grid, 3)
    return MinimumPerturbation(axes, beta)


def _edges(axes):
    """The grid's edges: (difference (E, n²), the derivative along each edge; mean (E, n²), the mean of its ends;
    midpoints (E, 2); direction (E,), the shape coordinate it runs along)."""
    n0, n1 = len(axes[0]), len(axes[1])
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
    index = np.arange(n0 * n1).reshape(n0, n1)
    tail = np.concatenate([index[:-1, :].ravel(), index[:, :-1].ravel()])
    head = np.concatenate([index[1:, :].ravel(), index[:, 1:].ravel()])
    direction = np.repeat([0, 1], [(n0 - 1) * n1, n0 * (n1 - 1)])
    h = nodes[head, direction] - nodes[tail, direction]
    rows, shape = np.repeat(np.arange(len(h)), 2), (len(h), n0 * n1)
    ends = np.stack([tail, head], -1).ravel()
    difference = coo_matrix((np.stack([-1 / h, 1 / h], -1).ravel(), (rows, ends)), shape).tocsr()
    mean = coo_matrix((np.full(2 * len(h), 0.5), (rows, ends)), shape).tocsr()
    return difference, mean, 0.5 * (nodes[tail] + nodes[head]), direction


def _least_squares(matrix, rhs) -> np.ndarray:
    """The least-squares solution of smallest norm (scipy's lsqr, to rounding)."""
    return lsqr(matrix, rhs, atol=1e-14, btol=1e-14, iter_lim=100 * matrix.shape[1])[0]


# -- circular gaits: the prediction's error in both frames --------------------------------------------------------


class GaitError(NamedTuple):
    """A circular gait's radius (a fraction of the shape box's half-widths) and its holonomy in the env's frame
    (``default``) and in minimum-perturbation coordinates (``minimum``)."""

    amplitude: float
    default: Holonomy
    minimum: Holonomy


def gait_errors(target, amplitudes=AMPLITUDES, samples: int = SAMPLES, grid: int = GRID) -> list[GaitError]:
    """The circular gaits s(t) = c + r h (cos t, sin t), t from 0 to 2π (counterclockwise, based at c + r h e₁), c
    the shape box's centre and h its half-widths (circles in the env's action units), each r of ``amplitudes``:
    their exact holonomy and its first-order prediction in both frames."""
    local = local_connection(target)
    frame = minimum_perturbation(local, grid)
    centre, half = 0.5 * (local.high + local.low), 0.5 * (local.high - local.low)
    t = np.linspace(0.0, 2 * math.pi, samples + 1)
    rows = []
    for r in amplitudes:
        loop = centre + r * half * np.stack([np.cos(t), np.sin(t)], -1)
        loop[-1] = loop[0]
        rows.append(GaitError(r, loop_holonomy(local, loop), loop_holonomy(local, loop, frame_change=frame)))
    return rows


def print_gait_errors(env_id: str, file=None):
    """The table of `gait_errors` for an env: each gait's net turn θ, its net translation |p| and the prediction's
    error |Δp| in each frame (the frames' origins differ, and so do their translations), and the error of the turn
    (the same in both: θ's row is abelian, Ad leaves it, and its prediction is Stokes' theorem, exact)."""
    file = file or sys.stdout
    print(f"{env_id}: circular gaits c + r h (cos t, sin t), h the shape box's half-widths; Δ = net − (−∬F)", file=file)
    print(f"{'r':>5} {'net θ':>10} | {'net |p|: default':>16} {'min-pert':>10} | {'|Δp|: default':>13} "
          f"{'min-pert':>10} | {'|Δθ|':>8}", file=file)  # fmt: skip
    for row in gait_errors(env_id):
        default, minimum = row.default, row.minimum
        error = [np.abs(h.net - h.predicted) for h in (default, minimum)]
        print(f"{row.amplitude:5.2f} {default.net[2]:10.3e} | {math.hypot(*default.net[:2]):16.3e} "
              f"{math.hypot(*minimum.net[:2]):10.3e} | {math.hypot(*error[0][:2]):13.3e} "
              f"{math.hypot(*error[1][:2]):10.3e} | {error[0][2]:8.1e}", file=file)  # fmt: skip


# -- the curvature map -------------------------------------------------------------------------------------------


def window(local: LocalConnection, gait) -> tuple[np.ndarray, np.ndarray]:
    """The shape box drawn: the bounds where finite, else the gait's extent padded (±π without a gait)."""
    low, high = local.low.astype(float), local.high.astype(float)
    for i in np.flatnonzero(~(np.isfinite(low) & np.isfinite(high))):
        lo, hi = (gait[:, i].min(), gait[:, i].max()) if len(gait) else (-math.pi, math.pi)
        pad = max(0.15 * (hi - lo), 0.5)
        low[i], high[i] = lo - pad, hi + pad
    return low, high


def shape_axes(env, field: str) -> list[tuple[str, str]]:
    """(name, unit) of each shape coordinate of an env: the model's names of the state field's entries (its
    ``components``; a planar contact point ``position`` is (x, y)), and the unit its reset state declares for that
    name, or for the field, or for its only 2-vector ("" where none does)."""
    model = env.model
    entry = next(e for e in model.entries if e.name == field)
    names = entry.names(model.components)
    if field == "position" and names == ["position[0]", "position[1]"]:
        names = ["x", "y"]
    declared = env.STATE.fields if hasattr(env, "STATE") else {}
    vectors = [f for f in declared.values() if f.kind == "vector" and f.size == 2]
    units = []
    for name in names:
        by = declared.get(name) or declared.get(field) or (vectors[0] if len(vectors) == 1 else None)
        units.append(by.unit if by is not None else "")
    return list(zip(names, units))


def per_area(unit: str, shape_units: list[str]) -> str:
    """The unit of F (a group velocity's unit per shape unit²): m/rad², 1/rad, ..."""
    u0, u1 = shape_units
    if not (u0 and u1):
        return f"{unit} per shape unit²"
    area = f"{u0}²" if u0 == u1 else f"{u0}·{u1}"
    return f"1/{u0}" if unit == u0 == u1 else f"{unit}/{area}"


def direction_marks(panel, loop, count: int = 4, color="k"):
    """Arrowheads along a drawn path at count points evenly spaced in its length: the direction it runs."""
    steps = np.linalg.norm(np.diff(loop, axis=0), axis=1)
    length = np.concatenate([[0.0], np.cumsum(steps)])
    if length[-1] == 0.0:
        return
    for fraction in (np.arange(count) + 0.5) / count:
        i = min(int(np.searchsorted(length, fraction * length[-1])), len(loop) - 1)
        j = max(i - 1, 0)
        while j > 0 and np.allclose(loop[j], loop[i]):
            j -= 1
        if not np.allclose(loop[j], loop[i]):
            panel.annotate("", xy=loop[i], xytext=loop[j],
                           arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.5, "mutation_scale": 16})  # fmt: skip


def draw(env_id: str, path: str, points: int = 41, gait=None, gait_label: str = "gait"):
    """The curvature map of an env with a 2-D shape space, written to path (PNG): one panel per group direction that
    moves (where A or F is not zero), colour the curvature F₁₂ of that direction (its unit: the direction's per shape
    unit²), arrows the shape velocity −A_d (the row d of −A: along it g moves fastest in +d), and ``gait``, the shapes
    (T, 2) a policy ran through (``python -m agents.curvature_map ID`` records the analytic controller's), with
    arrowheads the way it runs and its start marked."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt
    from matplotlib.lines import Line2D

    local = local_connection(env_id)
    k = local.low.size
    if k != 2:
        flat = " (a 1-D shape space encloses no area: flat, its holonomy topological)" if k == 1 else ""
        raise ValueError(f"{env_id}'s shape space is {k}-D: the curvature map is for 2-D shape spaces{flat}")
    gait = np.zeros((0, 2)) if gait is None else np.asarray(gait, float).reshape(-1, 2)
    axes = [np.linspace(lo, hi, points) for lo, hi in zip(*window(local, gait))]
    shapes = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
    F = curvature(local, shapes).F[:, :, 0, 1]
    A = np.real(evaluate(local.connection, shapes))
    moving = [d for d in range(local.group.dim) if np.any(F[:, d] != 0.0) or np.any(A[:, d] != 0.0)]
    figure, panels = plt.subplots(
        1, len(moving), figsize=(FIGURE[0] * len(moving), FIGURE[1]), squeeze=False, layout="constrained"
    )
    (s0, u0), (s1, u1) = shape_axes(_make(env_id).unwrapped, local.field)
    names, units, every = DIRECTIONS[local.group.name], DIRECTION_UNITS[local.group.name], max(1, points // 12)
    handles = {}
    for panel, d in zip(panels[0], moving):
        scale = max(np.max(np.abs(F[:, d])), 1e-300)
        image = panel.pcolormesh(*axes, F[:, d].reshape(points, points).T, cmap="RdBu_r", vmin=-scale, vmax=scale,
                                 shading="auto")  # fmt: skip
        figure.colorbar(image, ax=panel, label=f"F₁₂ ({names[d]}) [{per_area(units[d], [u0, u1])}]")
        arrows = shapes.reshape(points, points, 2)[::every, ::every].reshape(-1, 2)
        field = -A.reshape(points, points, -1, 2)[::every, ::every, d].reshape(-1, 2)
        if np.any(field):
            panel.quiver(arrows[:, 0], arrows[:, 1], field[:, 0], field[:, 1], color="0.25", pivot="mid")
            handles["arrows"] = Line2D([], [], color="0.25", marker=r"$\rightarrow$", markersize=12, lw=0,
                                       label="arrows −A: the shape velocity that moves it fastest")
        if len(gait):
            (line,) = panel.plot(gait[:, 0], gait[:, 1], color="k", lw=1.5, label=gait_label)
            direction_marks(panel, gait)
            (start,) = panel.plot(*gait[0], "o", color="k", markerfacecolor="w", label="its start")
            handles["gait"], handles["start"] = line, start
        panel.set(title=f"{names[d]}: F and −A", xlabel=f"{s0} ({u0})" if u0 else s0,
                  ylabel=f"{s1} ({u1})" if u1 else s1, aspect="auto")  # fmt: skip
    if handles:
        wide = len(moving) > 2  # a narrower figure stacks the entries
        figure.legend(handles=list(handles.values()), loc="outside lower center", ncols=len(handles) if wide else 1,
                      frameon=False)  # fmt: skip
    figure.suptitle(f"{env_id}: curvature F of the connection ({local.connection.group}, "
                    f"{local.connection.frame} frame)\na small counterclockwise loop of ({s0}, {s1}) moves the body "
                    f"by −F × its area", fontsize="medium")  # fmt: skip
    figure.savefig(path, dpi=DPI)
    plt.close(figure)


# -- command line --------------------------------------------------------------------------------------------------


def map_path(env_id: str) -> str:
    """Where an env's curvature map goes by default: <Env>-curvature.png in the working directory."""
    return f"{env_id.rpartition('/')[2].rpartition('-')[0]}-curvature.png"


def main(argv: list[str] | None = None):
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("env_id", metavar="ID", help="a connenv id whose env has a mechanical connection")
    parser.add_argument("--write", type=cli.writable_file, metavar="FILE.png",
                        help="where the curvature map goes (default: <Env>-curvature.png here); "
                             "python -m agents.curvature_map ID draws it with the analytic controller's gait")  # fmt: skip
    parser.add_argument("--prediction-error", action="store_true",
                        help="print the first-order prediction's error for circular gaits in the env's frame and in "
                             "minimum-perturbation coordinates (SE(2) swimmers) instead of drawing")  # fmt: skip
    args = parser.parse_args(argv)
    if args.prediction_error:
        print_gait_errors(args.env_id)
        return None
    path = args.write or map_path(args.env_id)
    draw(args.env_id, path)
    print(path)
    return path


if __name__ == "__main__":
    cli.run(main, PROG)
