r"""The free rigid body: Euler's equations, their exact solution in Jacobi elliptic functions, and the attitude.

**Model.** A rigid body turns freely about its centre of mass. In its principal axes the inertia is
I = diag(I₁, I₂, I₃), I₁ < I₂ < I₃ (a real body also has I₃ ≤ I₁ + I₂). M is the angular momentum in body
coordinates, ω = I⁻¹M the angular velocity, R ∈ SO(3) the attitude (body → space coordinates). With no torque,

    Ṁ = M × ω                 (Euler's equations),        Ṙ = R ω̂       (the reconstruction),

and the spatial momentum m = R M is constant: d(RM)/dt = R (ω × M + M × ω) = 0. Euler's equations keep the energy
E = ½ Σ M_i²/I_i and |M|, so M runs along the intersection of the sphere |M| and the ellipsoid 2E, a closed curve
about the axis of the largest or of the smallest inertia (both stable); the curves M² = 2 E I₂ through the middle
axis (unstable) are the separatrices. The state of the steppers is y = (M, R row by row), 12 numbers on the last
axis; every function broadcasts over leading axes.

**Elliptic solution** (Landau & Lifshitz, Mechanics §37). Write D_i = M² − 2E I_i = Σ_j M_j² (I_j − I_i)/I_j (no
cancellation between the terms of M² and 2E); D₁ ≥ 0 ≥ D₃. M circulates about the axis r = 3 when D₂ > 0 (above
the separatrix: M² > 2 E I₂) and about r = 1 when D₂ < 0; p is the other extreme axis and q = 2. Then

    M_p = A_p cn u,    M_q = s A_q sn u,    M_r = s A_r dn u,      u = u₀ + ω_p t,  s = sign M_r,

    A_p² = −I_p D_r/(I_r − I_p),   A_q² = −I_q D_r/(I_r − I_q),   A_r² = I_r D_p/(I_r − I_p),
    ω_p² = (I_r − I_q) D_p/(I₁ I₂ I₃),   k² = (I_q − I_p)(−D_r)/((I_r − I_q) D_p),
    k'² = 1 − k² = (I_r − I_p) D_q/((I_r − I_q) D_p),

with the parameter m = k² of scipy.special.ellipj. Substituting shows each line of Euler's equations (e.g.
Ṁ_p = −A_p ω_p sn dn equals (1/I_r − 1/I_q) M_q M_r); the sign s is the same on both branches because swapping the
axes 1 and 3 reverses the orientation of the cross product and, with it, time. The phase u₀ = F(φ₀ | m), the
incomplete integral at the amplitude φ₀ = atan2(sn u₀, cn u₀) of the initial M. Near the separatrix k'² → 0 is
computed from D_q directly and K(k) = ellipkm1(k'²), without the cancellation of 1 − k². cn and sn have the period
4K(k), so M(t) is periodic with T = 4 K(k)/ω_p, which grows as ln(1/k'²) toward the separatrix. On the separatrix
itself (D₂ = 0) M is asymptotic to the middle axis and the flow returns NaN where the formula does (at the middle
axis): the `Exact` stepper then hands those states to DOP853.

**Attitude.** Ṙ = R ω̂ with ω(t) = I⁻¹M(t) known in closed form is linear in R: a Lie-group step keeps R on SO(3).
`exact_flow` cuts a step into pieces of at most ``max_turn`` radians of turn (|ω|² ≤ 2E/I₁) and takes each by the
sixth-order Magnus method with ω at three Gauss nodes (connenv.core.lie), one Rodrigues exponential per piece: M is
exact and R accurate to the Magnus error, for any step length.

**Phase** (Montgomery 1991; Ishlinskii's holonomy theorem). Over one period T, R(T)ᵀ m/|M| = M(T)/|M| = M(0)/|M|,
so R(T) R(0)ᵀ turns about the spatial momentum m, by

    Δθ = 2 E T/|M| − Λ     (mod 2π).

Λ is the solid angle enclosed by the body-frame curve n(t) = M(t)/|M|, counted positive when n runs counterclockwise
about the axis a it circles, Λ = ∮ a·(n × dn)/(1 + a·n) = ∮ (1 − cos θ) dφ in spherical angles (θ, φ) about a.
Derivation: choose space axes with m = |M| e_z and write R = R_z(ψ) B(n), B(n) the rotation about a × e_z that
takes n to e_z (regular for n ≠ −a after a rotation of axes). The spatial angular velocity is R ω, and its e_z
component is ω·n = 2E/|M|; B contributes (1 − cos θ) φ̇ to it. So ψ̇ = 2E/|M| − (1 − cos θ) φ̇: the *dynamic
phase* 2ET/|M| is what the energy adds, the *geometric phase* −Λ is the area of the loop, as for the rolling ball,
the tube and Elroy's beanie. A change of axis a changes Λ by a multiple of 4π.

**Other steppers** (for the work–precision chart, connenv.bench.rigid_body):

- `Splitting`: H = Σ_i M_i²/(2I_i) split into three free rotations about the body axes, each exact (M_i constant,
  M turned by −ω_i τ e_i, R by +ω_i τ e_i); Strang's composition 1 2 3 2 1 (McLachlan 1993; Touma & Wisdom 1994) is
  second order, symplectic, and keeps |M|, R ∈ SO(3) and m = RM to rounding, while E oscillates.
- RK4 on (M, R) and scipy's DOP853, by ``connenv.core.steppers`` on `vector_field`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipj, ellipkinc, ellipkm1

from connenv.core.integrators import SUBSTEPS_MAX
from connenv.core.integrators import make_stepper as make_core_stepper
from connenv.core.lie import GAUSS6, GROUPS, magnus_omega
from connenv.core.steppers import Exact, Scipy, StepperError, check_finite
from connenv.core.validation import check_number, check_rotation, check_vector

SO3 = GROUPS["SO3"]
NO_CONTROL = np.zeros(0)  # the rigid body has no assigned coordinates: u and u̇ of the stepper interface
MAX_PIECES = 100_000  # Magnus pieces per step: past it the step is too long for the turn bound (StepperError)
INTEGRATORS = ("exact", "splitting", "rk4", "dop853")


def check_inertia(inertia) -> tuple:
    """The principal inertias (I₁, I₂, I₃) as floats: positive, strictly increasing (the elliptic solution needs
    three distinct axes; sort yours), and I₃ ≤ I₁ + I₂ (the triangle inequality of every real body)."""
    I1, I2, I3 = check_vector("inertia", inertia, 3, 0.0).tolist()
    if not 0.0 < I1 < I2 < I3:
        raise ValueError(f"inertia={tuple(inertia)!r} must be positive and strictly increasing, I₁ < I₂ < I₃")
    if I3 > I1 + I2:
        raise ValueError(f"inertia={tuple(inertia)!r}: I₃={I3} is out of range: must be in (I₂, I₁ + I₂={I1 + I2}]")
    return I1, I2, I3


def check_momentum(M) -> np.ndarray:
    """The body angular momentum M (3,): finite and not zero (a body at rest has no orbit)."""
    M = check_vector("M", M, 3)
    if not np.any(M):
        raise ValueError(f"M={M.tolist()!r} is out of range: must be a nonzero vector (|M| > 0)")
    return M


def state(M, R=np.eye(3)) -> np.ndarray:
    """y = (M, R row by row), after checking both."""
    return np.concatenate([check_momentum(M), check_rotation("R", R).ravel()])


def energy(M, inertia):
    """E = ½ Σ M_i²/I_i."""
    M = np.asarray(M, float)
    return 0.5 * np.sum(M * M / np.asarray(inertia), axis=-1)


def euler(M, inertia):
    """Ṁ = M × ω, ω = I⁻¹M: Euler's equations."""
    M = np.asarray(M, float)
    return np.cross(M, M / np.asarray(inertia))


@dataclass(frozen=True)
class Orbit:
    """The elliptic solution through an initial M (see the module): ``r3`` whether M circulates about axis 3 (else
    about axis 1), amplitudes A_p, A_q, A_r, the sign s, ω_p, m = k², k'² and u₀; floats for one state, arrays over
    the rows of a batch."""

    r3: object
    amplitude: tuple
    sign: object
    rate: object
    m: object
    m1: object
    u0: object

    @property
    def period(self):
        """T = 4 K(k)/ω_p: the period of M(t) (infinite on the separatrix)."""
        return 4.0 * ellipkm1(self.m1) / self.rate

    def momentum(self, t):
        """M(t), (…, 3) over the orbit's rows (t broadcasts against them)."""
        sn, cn, dn, _ = ellipj(self.u0 + self.rate * np.asarray(t, float), self.m)
        A_p, A_q, A_r = self.amplitude
        outer, middle, axis = A_p * cn, self.sign * A_q * sn, self.sign * A_r * dn
        if isinstance(self.r3, bool):
            return np.stack([outer, middle, axis] if self.r3 else [axis, middle, outer], -1)
        return np.stack([np.where(self.r3, outer, axis), middle, np.where(self.r3, axis, outer)], -1)


class _Floats:
    sqrt, atan2 = staticmethod(math.sqrt), staticmethod(math.atan2)

    @staticmethod
    def where(condition, a, b):
        return a if condition else b

    @staticmethod
    def positive(x):
        return max(x, 0.0)

    @staticmethod
    def unit(x):
        return min(max(x, 0.0), 1.0)


class _Arrays:
    sqrt, atan2, where = np.sqrt, np.arctan2, np.where

    @staticmethod
    def positive(x):
        return np.maximum(x, 0.0)

    @staticmethod
    def unit(x):
        return np.clip(x, 0.0, 1.0)


def orbit(M, inertia) -> Orbit:
    """The elliptic solution with M(0) = M (…, 3) for principal inertias I₁ < I₂ < I₃: Python floats for one
    state (M of shape (3,)), arrays over the rows of a batch."""
    M = np.asarray(M, float)
    ops = _Floats if M.ndim == 1 else _Arrays
    M1, M2, M3 = M.tolist() if M.ndim == 1 else np.moveaxis(M, -1, 0)
    I1, I2, I3 = inertia
    D1 = M2 * M2 * (1.0 - I1 / I2) + M3 * M3 * (1.0 - I1 / I3)  # D_i = M² − 2 E I_i, term by term
    D2 = M1 * M1 * (1.0 - I2 / I1) + M3 * M3 * (1.0 - I2 / I3)
    D3 = M1 * M1 * (1.0 - I3 / I1) + M2 * M2 * (1.0 - I3 / I2)
    r3 = D2 > 0.0
    Ip, Ir, Dp, Dr = ops.where(r3, I1, I3), ops.where(r3, I3, I1), ops.where(r3, D1, D3), ops.where(r3, D3, D1)
    M_p, M_r = ops.where(r3, M1, M3), ops.where(r3, M3, M1)
    with np.errstate(divide="ignore", invalid="ignore"):
        A_p = ops.sqrt(ops.positive(-Ip * Dr / (Ir - Ip)))
        A_q = ops.sqrt(ops.positive(-I2 * Dr / (Ir - I2)))
        A_r = ops.sqrt(ops.positive(Ir * Dp / (Ir - Ip)))
        rate = ops.sqrt(ops.positive((Ir - I2) * Dp / (I1 * I2 * I3)))
        m = ops.unit((I2 - Ip) * -Dr / ((Ir - I2) * Dp))
        m1 = ops.unit((Ir - Ip) * D2 / ((Ir - I2) * Dp))
    sign = ops.where(M_r < 0.0, -1.0, 1.0)
    amplitude = ops.atan2(sign * M2 * A_p, M_p * A_q)  # tan φ₀ = sn/cn = (s M_q/A_q)/(M_p/A_p)
    return Orbit(r3 if ops is _Arrays else bool(r3), (A_p, A_q, A_r), sign, rate, m, m1, ellipkinc(amplitude, m))


def attitude(R, velocity, tau, pieces: int):
    """R after ``pieces`` sixth-order Magnus steps of Ṙ = R ω̂ over a time tau, ω = velocity(t) (…, 3) at times t
    of shape (pieces · 3, …): one call for every Gauss node. R (…, 3, 3); one state goes through Python floats."""
    R = np.asarray(R, float)
    h = np.asarray(tau, float) / pieces
    times = (np.arange(pieces)[:, None] + np.array(GAUSS6)).reshape(-1, *([1] * (R.ndim - 2))) * h
    omega = velocity(times)  # (pieces · 3, …, 3)
    if R.ndim == 2:
        g, h, nodes = tuple(R.ravel().tolist()), float(h), omega.reshape(pieces, 3, 3).tolist()
    else:
        g = tuple(np.moveaxis(R.reshape(*R.shape[:-2], 9), -1, 0))
        nodes = np.moveaxis(omega.reshape(pieces, 3, *omega.shape[1:]), -1, 2)  # (pieces, node, component, …)
    for xi in nodes:
        g = SO3.product(g, SO3.exp(magnus_omega(SO3, "body", h, list(map(tuple, xi)))))
    return np.array(g).reshape(3, 3) if R.ndim == 2 else np.stack(g, -1).reshape(R.shape)


@dataclass(frozen=True)
class RigidBody:
    """The free rigid body of principal inertias ``inertia`` (I₁ < I₂ < I₃, kg m²), for the steppers of
    connenv.core.steppers on y = (M, R) (see the module); ``max_turn`` (rad) bounds the turn of one Magnus piece of
    the exact flow's attitude."""

    inertia: tuple = (1.0, 2.0, 2.5)
    max_turn: float = 0.05

    def __post_init__(self):
        object.__setattr__(self, "inertia", check_inertia(self.inertia))
        object.__setattr__(self, "max_turn", check_number("max_turn", self.max_turn, 0.0, math.pi, open_low=True))

    def split(self, y):
        y = np.asarray(y, float)
        return y[..., :3], y[..., 3:].reshape(*y.shape[:-1], 3, 3)

    def vector_field(self, y, u=NO_CONTROL, u_dot=NO_CONTROL):
        """ẏ = (M × ω, R ω̂), ω = I⁻¹M."""
        M, R = self.split(y)
        omega = M / np.asarray(self.inertia)
        return np.concatenate([np.cross(M, omega), np.cross(R, omega[..., None, :]).reshape(*M.shape[:-1], 9)], -1)

    def exact_flow(self, y, u=NO_CONTROL, tau=0.0):
        """y after a time tau: M from the elliptic solution, R by the Magnus pieces (NaN where the elliptic
        formula is, at the middle axis on the separatrix)."""
        M, R = self.split(y)
        path = orbit(M, self.inertia)
        turn = float(np.max(np.sqrt(2.0 * energy(M, self.inertia) / self.inertia[0]) * np.abs(tau)))  # |ω|² ≤ 2E/I₁
        pieces = max(1, math.ceil(turn / self.max_turn)) if math.isfinite(turn) else 1
        if pieces > MAX_PIECES:
            raise StepperError(f"a step turning the body by {turn:.3g} rad needs > {MAX_PIECES} Magnus pieces")
        end, inverse = [], 1.0 / np.array(self.inertia)

        def velocity(t):  # ω at the Gauss nodes; M at the end of the step from the same call of ellipj
            last = np.reshape(tau, (1, *np.shape(t)[1:])) if np.ndim(tau) else np.full((1, *np.shape(t)[1:]), tau)
            M_t = path.momentum(np.concatenate([t, last]))
            end.append(M_t[-1])
            return M_t[:-1] * inverse

        R = attitude(R, velocity, tau, pieces)
        return np.concatenate([end[0], R.reshape(*R.shape[:-2], 9)], -1)

    def invariants(self, y):
        """(E, |M|, m = R M): the energy, the norm of M and the spatial momentum."""
        M, R = self.split(y)
        return energy(M, self.inertia), np.linalg.norm(M, axis=-1), np.einsum("...ij,...j->...i", R, M)


def _rotate(M, R, axis: int, angle):
    """The exact flow of H_i = M_i²/(2I_i) for the time that turns the body by ``angle`` = ω_i t about axis i:
    M ← Rot_i(−angle) M, R ← R Rot_i(angle)."""
    j, k = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(angle), np.sin(angle)
    M_j, M_k = M[..., j].copy(), M[..., k]
    M[..., j] = c * M_j + s * M_k
    M[..., k] = c * M_k - s * M_j
    col_j, col_k = R[..., :, j].copy(), R[..., :, k]
    R[..., :, j] = c[..., None] * col_j + s[..., None] * col_k
    R[..., :, k] = c[..., None] * col_k - s[..., None] * col_j


STRANG = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))  # (axis, fraction of the substep)


@dataclass(frozen=True)
class Splitting:
    """Strang splitting of the free rigid body into exact rotations about its axes (see the module), ``substeps``
    equal substeps per step, in the stepper interface (system, y, u, u̇, τ)."""

    substeps: int = 1

    def __call__(self, system, y, u, u_dot, tau):
        M, R = (a.copy() for a in system.split(y))
        h = np.asarray(tau, float) / self.substeps
        for _ in range(self.substeps):
            for axis, fraction in STRANG:
                _rotate(M, R, axis, fraction * h * M[..., axis] / system.inertia[axis])
        return check_finite(np.concatenate([M, R.reshape(*R.shape[:-2], 9)], -1), self)


def make_stepper(integrator: str = "exact", **options):
    """A stepper of the rigid body by name: "exact" (the default: elliptic M and Magnus R, DOP853 where the elliptic
    formula fails), "splitting" and "rk4" with ``substeps``, "dop853" with ``rtol`` and ``atol``."""
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator={integrator!r} is not one of {INTEGRATORS}")
    if integrator == "splitting":
        substeps = options.pop("substeps", 1)
        if options:
            raise ValueError(f"unknown option(s) {sorted(options)} for integrator='splitting'; it takes ['substeps']")
        integer = isinstance(substeps, (int, np.integer)) and not isinstance(substeps, bool)
        if not (integer and 1 <= substeps <= SUBSTEPS_MAX):
            raise ValueError(f"substeps={substeps!r} must be an integer in [1, {SUBSTEPS_MAX}]")
        return Splitting(int(substeps))
    return make_core_stepper(integrator, RigidBody(), **options)


def advance(system: RigidBody, y, tau, stepper=Exact(Scipy())):
    """y after a time tau by the stepper (default: the exact flow); StepperError if it leaves the finite numbers."""
    tau = check_number("tau", tau, 0.0)
    return stepper(system, np.asarray(y, float), NO_CONTROL, NO_CONTROL, tau)
