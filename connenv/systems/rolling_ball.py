"""A ball rolling on a plane without slipping and without turning (spinning about the vertical).

A kinematic model is all this scene needs: the controller assigns the velocity v = (vx, vy) of the centre, so
there is no inertia to integrate (Lawton, slides 7–10; Lioe 2004). R ∈ SO(3) is the attitude (body → space
coordinates) and ρ the radius. Rolling without slipping and without turning fixes the angular velocity:

    ω = e_z × v / ρ = (−vy, vx, 0)/ρ,    Ṙ = ω̂ R,    (ẋ, ẏ) = v

With v held over a step of length τ the update R ← exp(τ ω̂) R is exact (Rodrigues, by scipy's Rotation). In the
stepper interface the centre (x, y) is the assigned coordinate u, v = u̇, and the state y is R flattened row by row
(9 numbers on the last axis), so the generic steppers integrate the matrix ODE Ṙ = ω̂R too.

Reorientation is the holonomy of the rolling distribution: a straight roll by d turns the ball about the horizontal
axis e_z × d by |d|/ρ, and a closed material path turns it about the vertical by the spherical area it encloses
(Lioe 2004). Rolling at unit speed along a circle of curvature k from the heading α, with ω₀ = e_z × (cos α, sin α)/ρ,

    R(s) = Rz(k s) · exp(s (ω₀ − k e_z)^) · R(0)                                   (the arc)

and the shortest rolling path to a given attitude, position free, is such an arc (Lioe 2004): the sub-Riemannian
geodesics of the distribution. Rolled in n straight steps of length ℓ whose heading turns by δ between steps, the
same computation gives exactly

    R_n = Rz(n δ) · (Rz(−δ) · exp(ℓ ω₀^))^n · R(0)                                (the discrete arc)

Everywhere below a rotation E "to roll" acts in space, R → E R; E = R* Rᵀ reaches the attitude R*.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, root
from scipy.spatial.transform import Rotation

from connenv.core.backend import concat, floats, is_complex, namespace, traced
from connenv.core.lie.groups import GROUPS
from connenv.core.steppers import StepperError
from connenv.core.validation import ndim

E_Z = np.array([0.0, 0.0, 1.0])
ARC_BRANCHES = 3
"""Branches m of the rotation vector searched by optimal_arc: 2(β + mπ) n̂ for m = −4 … 3 (see there)."""
ARC_GRID = 2048  # points of the scan for sign changes, per branch
CLOSURE = 1e-9  # largest rotation (rad) a solution may miss its target by before it is discarded
DRIFT_LIMIT = 1e-6  # ‖RᵀR − I‖ past which a stepper has left SO(3): StepperError
PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # the distinct entries of a symmetric 3×3 matrix


def rz(angle) -> Rotation:
    return Rotation.from_rotvec(np.multiply.outer(angle, E_Z))


@dataclass(frozen=True)
class Arc:
    """A circular arc rolled at unit speed: initial heading α (rad), curvature k (1/m), length s (m)."""

    heading: float
    curvature: float
    length: float


@dataclass(frozen=True)
class DiscreteArc:
    """n straight steps of length ℓ, the first at heading α, each turning by δ from the last."""

    heading: float
    turn: float
    step_length: float
    steps: int

    def displacements(self) -> np.ndarray:
        """(n, 2): the straight steps in order."""
        headings = self.heading + self.turn * np.arange(self.steps)
        return self.step_length * np.stack([np.cos(headings), np.sin(headings)], axis=-1)


@dataclass(frozen=True)
class RollingBall:
    radius: float = 1.0

    def spin(self, v):
        """e_z × v / ρ: the angular velocity of rolling at v, and the rotation vector of a straight roll by v."""
        if not isinstance(v, (np.ndarray, list, tuple)) and traced(namespace(v)):  # JAX's rows (connenv.jax)
            ops = namespace(v)
            return ops.stack([-v[..., 1], v[..., 0], ops.zeros_like(v[..., 0])], axis=-1) / self.radius
        v = floats(v)
        if v.ndim == 1:  # one velocity: Python floats (np.stack costs more than a whole step of the ball)
            vx, vy = v.tolist()
            return np.array([-vy / self.radius, vx / self.radius, 0.0])
        return np.stack([-v[..., 1], v[..., 0], np.zeros_like(v[..., 0])], axis=-1) / self.radius

    def vector_field(self, y, u, u_dot):
        """Ṙ = ω̂ R, flattened; u (the centre) does not enter."""
        w = self.spin(u_dot)
        R = np.reshape(y, (*np.shape(y)[:-1], 3, 3))  # np.reshape and np.shape ask a JAX array its own
        ops = namespace(w)
        if traced(ops):  # JAX's rows: ω̂ built by stacking (its arrays take no assignment)
            zero = ops.zeros_like(w[..., 0])
            hat = ops.stack([zero, zero, w[..., 1], zero, zero, -w[..., 0], -w[..., 1], w[..., 0], zero], axis=-1)
            hat = hat.reshape(*w.shape[:-1], 3, 3)
        else:
            hat = np.zeros((*w.shape[:-1], 3, 3), w.dtype)
            hat[..., 0, 2], hat[..., 1, 2], hat[..., 2, 0], hat[..., 2, 1] = w[..., 1], -w[..., 0], -w[..., 1], w[..., 0]
        return (hat @ R).reshape(np.shape(y))

    def exact_segment(self, y, u, u_dot, tau):
        """R ← exp(τ ω̂) R, exact for v held over the segment: scipy's Rotation over a batch; for one state,
        Rodrigues' formula on Python floats (scipy's Rotation costs more than a whole Pendulum-v1 step on one), and on
        the complex rows of a Jacobian and on JAX's rows (``connenv.jax``), which scipy's Rotation does not take:
        there Rodrigues' formula in the rows' namespace (`_exp`), equal to scipy's to rounding, not to the bit."""
        if type(y) is np.ndarray and y.ndim == 1 and ndim(tau) == 0:
            return np.array(_rodrigues_times(self.spin(u_dot).tolist(), float(tau), y.tolist()))
        R, rotvec = np.reshape(y, (*np.shape(y)[:-1], 3, 3)), tau * self.spin(u_dot)
        plain = type(rotvec) is np.ndarray and not is_complex(rotvec)  # numpy's real rows: scipy's, as ever
        step = Rotation.from_rotvec(rotvec).as_matrix() if plain else _exp(rotvec)
        return (step @ R).reshape(np.shape(y))

    def roll(self, displacements) -> Rotation:
        """The rotation of rolling the straight legs `displacements` (k, 2) one after the other."""
        rotation = Rotation.identity()
        for d in np.atleast_2d(displacements):
            rotation = Rotation.from_rotvec(self.spin(d)) * rotation
        return rotation

    # -- arcs --------------------------------------------------------------

    def arc_rotation(self, arc: Arc, s=None) -> Rotation:
        """R(s) R(0)ᵀ = Rz(k s) exp(s (ω₀ − k e_z)^) along the arc, at s (default: its end)."""
        s = arc.length if s is None else s
        w = self.spin([math.cos(arc.heading), math.sin(arc.heading)]) - arc.curvature * E_Z
        return rz(arc.curvature * s) * Rotation.from_rotvec(np.multiply.outer(s, w))

    def arc_position(self, arc: Arc, s=None):
        """Displacement of the centre along the arc at s (default: its end)."""
        s = arc.length if s is None else np.asarray(s, float)
        a, k = arc.heading, arc.curvature
        if k == 0.0:
            return np.stack([s * math.cos(a), s * math.sin(a)], axis=-1)
        return np.stack([(np.sin(a + k * s) - math.sin(a)) / k, (math.cos(a) - np.cos(a + k * s)) / k], axis=-1)

    def optimal_arc(self, rotation: Rotation) -> Arc:
        """The shortest arc that rolls the ball by `rotation`; its length is the sub-Riemannian distance.

        With φ = k s the total turn of the heading, the arc is Rz(φ) exp(r̂) with r = s (ω₀ − k e_z), so
        Rz(−φ) E must have a rotation vector r with r_z = −φ; then s = ρ |r_xy| and α = atan2(−r_x, r_y). The
        rotation vectors of a rotation with unit quaternion (cos β, sin β n̂) are 2(β + mπ) n̂, m ∈ ℤ: for each
        branch the root condition is one equation in φ. Its roots are bracketed on a grid and refined by brentq;
        each is checked by rolling it, and the shortest is kept. A vertical rotation Rz(γ) has no such root: it
        is reached by a whole turn of the second factor, |r| = 2π, so s = ρ √(4π² − φ²) with φ = γ + 2πj.
        """
        if rotation.magnitude() == 0.0:
            return Arc(0.0, 0.0, 0.0)
        candidates = [self._arc_from_root(rotation, m, phi) for m, phi in self._arc_roots(rotation)]
        candidates += self._whole_turns(rotation)
        for arc in sorted((arc for arc in candidates if arc is not None), key=lambda arc: arc.length):
            if self.misses(arc, rotation) <= CLOSURE:
                return arc
        raise ArithmeticError(f"no arc found that rolls the ball by {rotation.as_rotvec()}")

    def misses(self, arc: Arc, rotation: Rotation) -> float:
        """Angle (rad) between the arc's rotation and `rotation`."""
        return float((self.arc_rotation(arc) * rotation.inv()).magnitude())

    def _branch_vectors(self, rotation: Rotation, phi, m):
        """r_m(φ) = 2(β + mπ) n̂ for the quaternion of Rz(−φ) E, continued smoothly in φ."""
        bx, by, bz, bw = rotation.as_quat()
        c, s = np.cos(phi / 2), -np.sin(phi / 2)
        vec = np.stack([c * bx - s * by, c * by + s * bx, c * bz + s * bw], axis=-1)
        w = c * bw - s * bz
        norm = np.linalg.norm(vec, axis=-1)
        beta = np.arctan2(norm, w)
        return (2 * (beta + m * math.pi) / np.where(norm > 0, norm, 1.0))[..., None] * vec

    def _arc_roots(self, rotation: Rotation):
        """(m, φ) with r_m(φ)_z + φ = 0, for m = −B−1 … B and |φ| ≤ 2π(B + 1), where |r_m| allows a root."""
        bound = 2 * math.pi * (ARC_BRANCHES + 1)
        grid = np.linspace(-bound, bound, ARC_GRID)
        for m in range(-ARC_BRANCHES - 1, ARC_BRANCHES + 1):
            f = self._branch_vectors(rotation, grid, m)[:, 2] + grid
            for i in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0):
                g = lambda phi, m=m: self._branch_vectors(rotation, phi, m)[2] + phi  # noqa: E731
                yield m, brentq(g, grid[i], grid[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)

    def _arc_from_root(self, rotation: Rotation, m: int, phi: float) -> Arc | None:
        r = self._branch_vectors(rotation, phi, m)
        length = self.radius * math.hypot(r[0], r[1])
        return None if length == 0.0 else Arc(math.atan2(-r[0], r[1]), phi / length, length)

    def _whole_turns(self, rotation: Rotation) -> list[Arc]:
        """Arcs to a vertical rotation Rz(γ): a whole turn of exp(s(ω₀ − k e_z)^), φ = γ + 2πj, |φ| < 2π."""
        if np.linalg.norm(rotation.apply(E_Z) - E_Z) > CLOSURE:
            return []
        gamma = rotation.as_rotvec() @ E_Z
        arcs = []
        for phi in (gamma, gamma - math.copysign(2 * math.pi, gamma)):
            length = self.radius * math.sqrt(max(4 * math.pi**2 - phi**2, 0.0))
            if length > 0.0:
                arcs.append(Arc(0.0, phi / length, length))
        return arcs

    def discrete_arc_rotation(self, arc: DiscreteArc) -> Rotation:
        """Rz(n δ) (Rz(−δ) exp(ℓ ω₀^))^n: the rotation of rolling the steps of `arc`."""
        first = Rotation.from_rotvec(
            self.spin(arc.step_length * np.array([math.cos(arc.heading), math.sin(arc.heading)]))
        )
        return rz(arc.steps * arc.turn) * (rz(-arc.turn) * first) ** arc.steps

    def discrete_arc(self, rotation: Rotation, steps: int, guess: Arc) -> DiscreteArc | None:
        """The n-step discrete arc that rolls the ball exactly by `rotation`, near the arc `guess`, or None.

        Newton's method (scipy's hybrid root finder) on the three unknowns (α, δ, ℓ), from the chords of the arc:
        α + kℓ/2, kℓ, ℓ = s/n. The discrete arc converges to the arc as n grows.
        """
        step = guess.length / steps
        x0 = [guess.heading + guess.curvature * step / 2, guess.curvature * step, step]

        def residual(x):
            return (self.discrete_arc_rotation(DiscreteArc(x[0], x[1], x[2], steps)) * rotation.inv()).as_rotvec()

        solution = root(residual, x0, method="hybr", options={"xtol": 1e-15})
        heading, turn, length = solution.x
        arc = DiscreteArc(heading, turn, abs(length), steps) if length >= 0 else None
        if arc is None or np.linalg.norm(residual(solution.x)) > CLOSURE:
            return None
        return arc

    # -- holonomy ------------------------------------------------------------

    def tilt_and_yaw(self, rotation: Rotation) -> tuple[np.ndarray, float]:
        """(t, γ) with rotation = exp(t̂) Rz(γ): t horizontal, |t| ≤ π, taking e_z where the rotation takes it."""
        up = rotation.apply(E_Z)
        axis = np.cross(E_Z, up)
        sin, cos = np.linalg.norm(axis), up[2]
        if sin > 0.0:
            tilt = math.atan2(sin, cos) * axis / sin
        else:
            tilt = np.array([math.pi, 0.0, 0.0]) if cos < 0 else np.zeros(3)
        yaw = Rotation.from_rotvec(-tilt) * rotation
        return tilt, float(yaw.as_rotvec() @ E_Z)

    def turn_legs(self, yaw: float, shift) -> np.ndarray:
        """Lawton's turn (slide 8), placed so that it ends displaced by `shift`, |shift| = ρ|yaw|:
        roll ρπ/2 along e, ρ·yaw along −e⊥, ρπ/2 along −e. The ball turns by `yaw` about the vertical: the legs
        trace on the sphere a lune between two meridians, of area `yaw`. With e = (1, 0) it is the seed's maneuver."""
        if yaw == 0.0:
            return np.zeros((0, 2))
        normal = -np.asarray(shift, float) / (self.radius * yaw)  # e⊥
        e = np.array([normal[1], -normal[0]])
        quarter = self.radius * math.pi / 2 * e
        return np.stack([quarter, -self.radius * yaw * normal, -quarter])

    def holonomy_legs(self, rotation: Rotation, position=None) -> np.ndarray:
        """Straight legs (k, 2) that roll the ball by `rotation`: turns about the vertical by holonomy, then one
        straight tilt. With `position` the legs also bring the centre from there back to the origin.

        rotation = exp(t̂) Rz(γ). The tilt is a straight roll by ρ t × e_z. Position free, one turn of γ does the rest.
        To close at the origin, two turns of γ₁ + γ₂ = γ must carry the centre by D = −position − ρ t × e_z, their
        shifts ρ|γᵢ| long in directions of our choosing: γᵢ = γ/2 if |D| ≤ ρ|γ| (an isosceles triangle), else
        γ₁,₂ = (γ ± |D|/ρ)/2, of opposite signs and both shifts along D.
        """
        tilt, yaw = self.tilt_and_yaw(rotation)
        tilt_leg = self.radius * np.cross(tilt, E_Z)[:2]
        if position is None:
            turns = [(yaw, [0.0, -self.radius * yaw])]
        else:
            target = -np.asarray(position, float) - tilt_leg
            turns = self._two_turns(yaw, target)
        legs = [self.turn_legs(g, shift) for g, shift in turns]
        return np.concatenate([*legs, tilt_leg[None] if tilt.any() else np.zeros((0, 2))])

    def _two_turns(self, yaw: float, target):
        reach = np.linalg.norm(target) / self.radius
        direction = target / (reach * self.radius) if reach > 0 else np.array([1.0, 0.0])
        if reach > abs(yaw):
            yaws = ((yaw + reach) / 2, (yaw - reach) / 2)
            return [(g, self.radius * abs(g) * direction) for g in yaws]
        half = self.radius * yaw / 2
        across = math.sqrt(max(half**2 - (reach * self.radius / 2) ** 2, 0.0))
        side = np.array([-direction[1], direction[0]]) * across
        middle = target / 2
        return [(yaw / 2, middle + side), (yaw / 2, middle - side)]


def split_legs(legs, step_length: float) -> np.ndarray:
    """Steps (k, 2) that roll each straight leg in full steps of step_length, and one partial step for the rest."""
    steps = []
    for leg in np.atleast_2d(legs):
        length = float(np.linalg.norm(leg))
        whole = math.floor(length / step_length)
        direction = leg / length if length > 0 else leg
        steps += [step_length * direction] * whole
        if length - whole * step_length > 1e-15:
            steps.append((length - whole * step_length) * direction)
    return np.array(steps).reshape(-1, 2)


def attitude_error(R, R_target):
    """R R*ᵀ: the rotation from the target to R in space; it rolls as R does (Ṗ = ω̂ P)."""
    return R @ np.swapaxes(R_target, -1, -2)


def rotation_angle(P):
    """The angle of rotation matrices P (..., 3, 3), accurate near 0 and π: atan2(|vee(P − Pᵀ)|/2, (tr P − 1)/2)."""
    if type(P) is np.ndarray and P.ndim == 2:  # one matrix: Python floats
        (a, b, c), (d, e, f), (g, h, i) = P.tolist()
        return math.atan2(0.5 * math.sqrt((h - f) ** 2 + (c - g) ** 2 + (d - b) ** 2), 0.5 * (a + e + i - 1.0))
    ops = namespace(P)
    skew = ops.stack([P[..., 2, 1] - P[..., 1, 2], P[..., 0, 2] - P[..., 2, 0], P[..., 1, 0] - P[..., 0, 1]], -1)
    trace = P[..., 0, 0] + P[..., 1, 1] + P[..., 2, 2]  # np.trace's sum, in its order
    return ops.atan2(0.5 * norm(skew), 0.5 * (trace - 1.0))


def norm(x, keepdims=False):
    """√(x·x) over the last axis: np.linalg.norm's arithmetic on real rows; on the complex rows of a Jacobian, the
    analytic continuation (the norm's would be the modulus, dropping the derivative's sign)."""
    return namespace(x).sqrt((x * x).sum(axis=-1, keepdims=keepdims))


def _exp(rotvec):
    """The rotation matrices exp(r̂) (..., 3, 3) of rotation vectors r (..., 3) by Rodrigues' formula
    (`connenv.core.lie.groups`), analytic in r, in the namespace of r's rows (numpy's complex ones, JAX's)."""
    entries = GROUPS["SO3"].exp(tuple(rotvec[..., i] for i in range(3)))
    ops = namespace(rotvec)
    entries = entries if traced(ops) else np.broadcast_arrays(*entries)
    return ops.stack(entries, -1).reshape(*np.shape(rotvec)[:-1], 3, 3)


def quaternion_matrix(q):
    """The rotation matrices (..., 3, 3) of quaternions q (..., 4) = (x, y, z, w), normalized here, in q's
    namespace: a uniform rotation from a normal draw of q, as scipy's Rotation.random draws it."""
    ops = namespace(q)
    q = q / norm(q, keepdims=True)
    x, y, z, w = (q[..., i] for i in range(4))
    entries = (
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    )  # fmt: skip
    return ops.stack(entries, -1).reshape(*q.shape[:-1], 3, 3)


def six_d(R):
    """The continuous 6-D form of rotations (Zhou et al. 2019): the first two columns, (..., 6)."""
    return concat([R[..., :, 0], R[..., :, 1]], axis=-1)


def _rodrigues_times(w, tau, R):
    """exp(τ ŵ) R, flattened, for a horizontal w (w_z = 0) and R flattened (9 floats): with θ = τ|w| and k = w/|w|,
    exp(θ k̂) = I + sin θ k̂ + 2 sin²(θ/2) (k kᵀ − I)."""
    theta = tau * math.hypot(w[0], w[1])
    if theta == 0.0:
        return R
    kx, ky = tau * w[0] / theta, tau * w[1] / theta
    s, c = math.sin(theta), 2.0 * math.sin(0.5 * theta) ** 2
    step = (
        (1.0 + c * (kx * kx - 1.0), c * kx * ky, s * ky),
        (c * kx * ky, 1.0 + c * (ky * ky - 1.0), -s * kx),
        (-s * ky, s * kx, 1.0 - c),
    )
    columns = R[0::3], R[1::3], R[2::3]
    return [dot3(row, column) for row in step for column in columns]


def dot3(a, b) -> float:
    """Σ a_k b_k of two 3-vectors of Python floats, from 0.0 left to right: sum()'s order, so the same bits, without
    its generator's cost."""
    return 0.0 + a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def six_d_angle(achieved, desired) -> float:
    """The angle between the rotations of two 6-D forms (sequences of 6 floats): rotation_angle(attitude_error(
    from_six_d(achieved), from_six_d(desired))) on Python floats, for one pair, without numpy's per-call cost."""
    A, D = list(zip(*_frame(achieved))), list(zip(*_frame(desired)))  # rows
    P = [[dot3(a, d) for d in D] for a in A]  # A Dᵀ
    skew = (P[2][1] - P[1][2], P[0][2] - P[2][0], P[1][0] - P[0][1])
    return math.atan2(0.5 * math.sqrt(dot3(skew, skew)), 0.5 * (P[0][0] + P[1][1] + P[2][2] - 1.0))


def _frame(x):
    """from_six_d's Gram–Schmidt on one 6-D form: the three columns."""
    a0, a1, a2, b0, b1, b2 = np.asarray(x, float).tolist()
    norm = math.sqrt(dot3((a0, a1, a2), (a0, a1, a2)))
    c1 = (a0 / norm, a1 / norm, a2 / norm)
    dot = dot3(c1, (b0, b1, b2))
    b = (b0 - dot * c1[0], b1 - dot * c1[1], b2 - dot * c1[2])
    norm = math.sqrt(dot3(b, b))
    c2 = (b[0] / norm, b[1] / norm, b[2] / norm)
    return c1, c2, [c1[1] * c2[2] - c1[2] * c2[1], c1[2] * c2[0] - c1[0] * c2[2], c1[0] * c2[1] - c1[1] * c2[0]]


def from_six_d(x):
    """Rotation matrices from the 6-D form, by Gram–Schmidt (exact for the columns of a rotation)."""
    x = floats(x)
    a, b = x[..., :3], x[..., 3:]
    c1 = a / norm(a, keepdims=True)
    b = b - (c1 * b).sum(axis=-1, keepdims=True) * c1  # np.sum's reduction, in x's namespace
    c2 = b / norm(b, keepdims=True)
    return namespace(x).stack([c1, c2, cross(c1, c2)], axis=-1)


def cross(u, v):
    """u × v over the last axis (3), np.cross's arithmetic (each component a product minus a product), in u's
    namespace."""
    u0, u1, u2 = (u[..., i] for i in range(3))
    v0, v1, v2 = (v[..., i] for i in range(3))
    return namespace(u).stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], -1)


def check_so3(stepper, R):
    """StepperError if R (any row of a batch) is more than DRIFT_LIMIT off SO(3): the stepper has left it."""
    if R.ndim == 2:  # one attitude: ‖RᵀR − I‖ (Frobenius) on Python floats
        columns = R.T.tolist()
        gram = [dot3(u, v) - (u is v) for u in columns for v in columns]
        drift = math.sqrt(sum(map(operator.mul, gram, gram)))
    else:  # the six distinct entries of RᵀR − I elementwise over the rows: cheaper than a stacked matmul
        ops = namespace(R)
        c = [ops.real_part(R[..., :, k]) for k in range(3)]  # a check: of the real parts on complex rows
        dot = [c[i][..., 0] * c[j][..., 0] + c[i][..., 1] * c[j][..., 1] + c[i][..., 2] * c[j][..., 2] for i, j in PAIRS]
        square = sum((d - (i == j)) ** 2 * (1 if i == j else 2) for d, (i, j) in zip(dot, PAIRS))
        if traced(ops):  # JAX's rows: the failure as data (connenv.jax)
            ops.fail(~(ops.sqrt(square) <= DRIFT_LIMIT), f"{stepper} left SO(3): ‖RᵀR − I‖ > {DRIFT_LIMIT}")
            return
        drift = math.sqrt(float(np.max(square)))
    if not drift <= DRIFT_LIMIT:
        raise StepperError(f"{stepper} left SO(3): ‖RᵀR − I‖ = {drift:.3g} > {DRIFT_LIMIT}")
