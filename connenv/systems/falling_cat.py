r"""The falling cat of Kane & Scher (1969): two halves that bend but do not twist, at zero angular momentum.

**Bodies.** The cat is two identical axisymmetric rigid bodies, the front half A and the rear half B, joined at a
point. Each has mass m, an inertia J about its own axis (axial) and I about any axis through its centre of mass
perpendicular to it (transverse); its centre of mass lies at the distance ℓ from the joint along its axis.

**Cat frame and shape.** The cat's attitude is the *cat frame* g ∈ SO(3) (body → space), with e₁ the mean spine
(head forward), e₃ dorsal (the back: up when the cat is feet down) and e₂ = e₃ × e₁. The shape is the *bend
vector* s = (x, y) = β (cos γ, sin γ): the bend angle β between the halves' axes, and the direction γ of the bend
about the spine (γ = 0 bends toward e₂, sideways; γ = π/2 arches the back). With d = (0, cos γ, sin γ) the bend
direction and n = e₁ × d = (0, −sin γ, cos γ) the bend axis, the halves' attitudes relative to the cat frame are

    Q_A = exp(+β/2 n̂),    Q_B = exp(−β/2 n̂),    Q_Aᵀ Q_B = exp(−β n̂):

the relative rotation is about n, perpendicular to both halves' axes a = Q_A e₁ = cos(β/2) e₁ + sin(β/2) d and
b = Q_B e₁ = cos(β/2) e₁ − sin(β/2) d, so the halves bend and never twist about their own axes. The rotation
vectors ±(β/2) n = ±(0, −y, x)/2 are linear in s. The front half's attitude in space is R = g Q_A.

**Momentum.** In free fall gravity moves only the centre of mass (every particle falls alike), so it does not
enter the rotation: take the system's centre of mass as origin. It lies midway between the halves' centres, so
these are at ±ℓ cos(β/2) e₁: on the spine line, moving along it as β changes, so their relative motion carries no
angular momentum. With Ω the cat frame's angular velocity (in the cat frame), w_i the angular velocity of Q_i
(ŵ_i = Q̇_i Q_iᵀ) and 𝕀_i = Q_i diag(J, I, I) Q_iᵀ, the angular momentum in the cat frame is

    L = I_loc(s) Ω + 𝕀_A w_A + 𝕀_B w_B,    I_loc = 𝕀_A + 𝕀_B + 2 m ℓ² cos²(β/2) (1 − e₁ e₁ᵀ)

(I_loc the locked inertia: the cat frozen in its shape). The cat falls from rest, L = 0, so Ω = −A(s) ṡ with
A(s) ṡ = I_loc⁻¹ (𝕀_A w_A + 𝕀_B w_B): a mechanical connection on SO(3), in the body frame.

**The connection in closed form.** For exp(θ n̂) with unit n, w = θ̇ n + sin θ ṅ + (1 − cos θ) n × ṅ. Write
c = cos(β/2), σ = sin(β/2).

- A radial bend (γ fixed) turns the halves about n by ±β̇/2; n ⊥ a, b, so 𝕀_A n = 𝕀_B n = I n, and the two
  terms cancel: bending straight out turns nothing.
- A sweep (β fixed, ṅ = −γ̇ d) gives 𝕀_A w_A + 𝕀_B w_B = 2 γ̇ [I σ² − J c (1 − c)] e₁, along the spine, and
  I_loc e₁ = 2 (I σ² + J c²) e₁.

So the connection has one row, about the spine: Ω = −f(β) γ̇ e₁ with

    f(β) = [I σ² − J c (1 − c)] / (I σ² + J c²),    and γ̇ = (x ẏ − y ẋ)/β²:
    A(s) = f(β)/β² · [[−y, x], [0, 0], [0, 0]].

The cat turns only about its spine, g = g₀ Rx(φ), and the *roll* φ is an abelian holonomy: φ = −∮ f(β) dγ. Its
curvature is dA = (f′(β)/β) dx ∧ dy, so a small loop of area a around s rolls the cat by −(f′(β)/β) a (Stokes).
The mass and ℓ enter only the locked inertia across the spine, never the roll. f/β² is an even analytic function
of β, → (2I − J)/(8J) as β → 0, so the connection is smooth at the straight cat.

**Kane and Scher's motion.** Bend to β₀, sweep γ once around, unbend: the radial legs turn nothing, the sweep rolls
the cat by −2π f(β₀) (γ increasing), i.e. by 2π J c/(I σ² + J c²) mod 2π. A roll of 2π q needs f(β₀) = q, a
quadratic in c: (1 − q)(I − J) c² + J c − (1 − q) I = 0, and for q = 1/2 (a half turn)

    c₀ = [√(I² − IJ + J²) − J]/(I − J),    β₀ = 2 arccos c₀ ≈ 2 √(J/I) for slender halves (J ≪ I).

**Exact step.** Along a segment s(τ) = s₀ + τ v of constant velocity, dγ = (s₀ × v) dτ / β(τ)², so

    Δφ = −(s₀ × v) ∫₀^τ f(β)/β² dτ′,

an integral of an analytic function of β² = |s₀ + τ′ v|², a quadratic in τ′. Its nearest complex singularity is
where I σ² + J c² = 0, at β² = −(2 artanh √(J/I))²; Gauss–Legendre quadrature on pieces no longer than a quarter
of that distance converges to rounding (``pieces_for``; the tests compare it with adaptive quadrature).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from connenv.core.backend import ARRAYS, floats, is_complex, namespace, traced

GAUSS_NODES = 8  # Gauss–Legendre nodes per piece of a segment
PIECE_FRACTION = 0.25  # a piece's length at most this fraction of the distance to the integrand's singularity
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(GAUSS_NODES)


def _np(x):
    """numpy, or for traced rows (``connenv.jax``) their namespace, which answers the numpy names used here (sqrt,
    sin, cos, sinc, hypot, where, stack, zeros_like, minimum): one source for numpy's rows and JAX's."""
    if type(x) is np.ndarray or isinstance(x, (float, np.generic)):
        return np
    ops = namespace(x)
    return ops if traced(ops) else np


def matvec(M, v, transposed=False):
    """M v (Mᵀ v: transposed) over the rows (…, 3, k) (…, k): numpy's einsum, a matmul on traced rows (einsum takes
    no JAX array)."""
    if (type(M) is np.ndarray and type(v) is np.ndarray) or (_np(M) is np and _np(v) is np):
        return np.einsum("...ji,...j->...i" if transposed else "...ij,...j->...i", M, v)
    return ((np.swapaxes(M, -1, -2) if transposed else M) @ v[..., None])[..., 0]


def roll_fraction(beta, transverse_inertia: float, axial_inertia: float):
    """f(β) = [I σ² − J c (1 − c)] / (I σ² + J c²): the roll per radian of sweep (the cat rolls by −f dγ)."""
    half = 0.5 * floats(beta)
    c, s2 = np.cos(half), np.sin(half) ** 2
    return (transverse_inertia * s2 - axial_inertia * c * (1 - c)) / (transverse_inertia * s2 + axial_inertia * c * c)


def roll_density(beta_squared, transverse_inertia: float, axial_inertia: float):
    """f(β)/β² as a function of β² ≥ 0, without cancellation at β = 0: sin(β/2)/β and (1 − c)/β² = 2 sin²(β/4)/β²
    through np.sinc."""
    xp = _np(beta_squared)
    if xp is np:
        beta = np.sqrt(floats(beta_squared))
    else:  # traced rows: β's tangent 0 at β² = 0 (√'s is infinite there; β² is stationary at s = 0, as is f/β²'s)
        positive = beta_squared > 0.0
        beta = xp.where(positive, xp.sqrt(xp.where(positive, beta_squared, 1.0)), 0.0)
    c = xp.cos(0.5 * beta)
    half_sinc = 0.5 * xp.sinc(beta / (2 * math.pi))  # sin(β/2)/β
    quarter_sinc = 0.25 * xp.sinc(beta / (4 * math.pi))  # sin(β/4)/β
    numerator = transverse_inertia * half_sinc**2 - 2 * axial_inertia * c * quarter_sinc**2
    return numerator / (transverse_inertia * (beta * half_sinc) ** 2 + axial_inertia * c * c)


def connection(s, transverse_inertia: float, axial_inertia: float):
    """A(s) (…, 3, 2) at bend vectors s (…, 2): f(β)/β² · (−y, x) in the spine's row, zero in the others."""
    s = floats(s)
    density = roll_density(np.sum(s * s, axis=-1), transverse_inertia, axial_inertia)
    xp = _np(s)
    if xp is not np:  # traced rows (connenv.jax): stacked, as their arrays take no assignment
        zero = xp.zeros_like(density)
        first = xp.stack([-density * s[..., 1], density * s[..., 0]], -1)
        return xp.stack([first, xp.stack([zero, zero], -1), xp.stack([zero, zero], -1)], -2)
    A = np.zeros((*s.shape[:-1], 3, 2), density.dtype)
    A[..., 0, 0], A[..., 0, 1] = -density * s[..., 1], density * s[..., 0]
    return A


def curvature(beta, transverse_inertia: float, axial_inertia: float):
    """F(β) = f′(β)/β, the curvature dA = F dx ∧ dy: a small loop of area a (counterclockwise) at s rolls the cat
    by −F a."""
    beta = floats(beta)
    I, J = transverse_inertia, axial_inertia  # noqa: E741  (the literature's I)
    c, s = np.cos(0.5 * beta), np.sin(0.5 * beta)
    numerator, denominator = I * s * s - J * c * (1 - c), I * s * s + J * c * c
    sinc = 0.5 * np.sinc(beta / (2 * math.pi))  # s/β, finite at β = 0
    return sinc * ((I * c - 0.5 * J * (2 * c - 1)) * denominator - numerator * (I - J) * c) / denominator**2


def bend_for_roll(roll: float, transverse_inertia: float, axial_inertia: float) -> float:
    """β₀ at which one full sweep of γ rolls the cat by |roll| ∈ [0, 2π) (f(β₀) = |roll|/2π): the root c ∈ (0, 1] of
    (1 − q)(I − J) c² + J c − (1 − q) I = 0, q = |roll|/2π (I > J)."""
    q, I, J = abs(roll) / (2 * math.pi), transverse_inertia, axial_inertia  # noqa: E741
    c = (math.sqrt(J * J + 4 * (1 - q) ** 2 * (I - J) * I) - J) / (2 * (1 - q) * (I - J))
    return 2 * math.acos(min(c, 1.0))


def singularity_distance(transverse_inertia: float, axial_inertia: float) -> float:
    """|β| of the nearest complex zero of I σ² + J c²: 2 artanh √(J/I) (J < I)."""
    return 2 * math.atanh(math.sqrt(axial_inertia / transverse_inertia))


def pieces_for(max_length: float, transverse_inertia: float, axial_inertia: float) -> int:
    """How many Gauss–Legendre pieces a segment of at most that length (rad of bend) needs."""
    reach = PIECE_FRACTION * singularity_distance(transverse_inertia, axial_inertia)
    return max(1, math.ceil(max_length / reach))


@functools.lru_cache(maxsize=None)
def _rule(pieces: int):
    """The nodes (fractions of the segment) and weights of Gauss–Legendre on `pieces` equal pieces of [0, 1]."""
    fractions = (np.arange(pieces)[:, None] + 0.5 * (_NODES + 1.0)[None, :]).ravel() / pieces
    return fractions, np.tile(_WEIGHTS, pieces) / (2 * pieces)


def segment_roll(s, s_dot, tau, transverse_inertia: float, axial_inertia: float, pieces: int = 1):
    """Δφ = −(s₀ × v) ∫₀^τ f/β² dτ′ over segments s₀ + τ′ v (s, s_dot (…, 2), tau a float or (…)): Gauss–Legendre
    with GAUSS_NODES nodes on each of `pieces` equal pieces."""
    s, v, tau = floats(s), floats(s_dot), floats(tau)
    fractions, weights = _rule(pieces)
    points = s[..., None, :] + (tau[..., None] * fractions)[..., None] * v[..., None, :]
    density = roll_density(np.sum(points * points, axis=-1), transverse_inertia, axial_inertia)
    cross = s[..., 0] * v[..., 1] - s[..., 1] * v[..., 0]
    return -cross * tau * (density @ weights)


def exact_segment(g, s, s_dot, tau, transverse_inertia: float, axial_inertia: float, pieces: int = 1):
    """The cat frame's 9 coordinates (row by row, …, 9) after a segment at constant ṡ: g Rx(Δφ)."""
    phi = segment_roll(s, s_dot, tau, transverse_inertia, axial_inertia, pieces)
    xp = _np(phi)
    c, n = xp.cos(phi)[..., None], xp.sin(phi)[..., None]
    g = floats(g).reshape(*np.shape(phi), 3, 3)
    columns = [g[..., 0], c * g[..., 1] + n * g[..., 2], c * g[..., 2] - n * g[..., 1]]
    return xp.stack(columns, -1).reshape(*np.shape(phi), 9)


def roll(g):
    """The roll about the spine (rad, (−π, π]): atan2(Z · g e₂, Z · g e₃), 0 feet down (g (…, 3, 3))."""
    return ARRAYS.atan2(g[..., 2, 1], g[..., 2, 2])


# -- the two bodies ------------------------------------------------------------


def cross(a, b):
    """a × b over the last axis (…, 3): numpy's np.cross costs more than the arithmetic on 3-vectors; two single
    vectors on Python floats (the same products and differences)."""
    if a.ndim == 1 and b.ndim == 1 and type(a) is np.ndarray and type(b) is np.ndarray:
        (a0, a1, a2), (b0, b1, b2) = a.tolist(), b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    return a[..., [1, 2, 0]] * b[..., [2, 0, 1]] - a[..., [2, 0, 1]] * b[..., [1, 2, 0]]


def front_half(s):
    """Q_A = exp(v̂) and the left Jacobian J(v), (Q̇_A Q_Aᵀ) = (J(v) v̇)^, at v = (0, −y, x)/2 (…, 3, 3); the rear
    half's are their transposes (v ↦ −v): Q_B = Q_Aᵀ, J(−v) = J(v)ᵀ. With θ = β/2 and V = v̂:
    Q = I + sin θ/θ V + (1 − cos θ)/θ² V², J = I + (1 − cos θ)/θ² V + (θ − sin θ)/θ³ V², by series below 1e-3."""
    s = floats(s)
    if s.ndim == 1:
        return _front_half_one(*(0.5 * s).tolist())
    x, y = 0.5 * s[..., 0], 0.5 * s[..., 1]
    xp = _np(s)
    ops = ARRAYS if xp is np else xp
    theta = ops.hypot(x, y)[..., None, None]
    small = ops.real_part(theta) < 1e-3
    safe = xp.where(small, 1.0, theta)
    sin_part = xp.where(small, 1 - theta**2 / 6, xp.sin(safe) / safe)
    cos_part = xp.where(small, 0.5 - theta**2 / 24, (1 - xp.cos(safe)) / safe**2)
    tail = xp.where(small, 1 / 6 - theta**2 / 120, (safe - xp.sin(safe)) / safe**3)
    zero = xp.zeros_like(x)
    V = xp.stack([xp.stack([zero, -x, -y], -1), xp.stack([x, zero, zero], -1), xp.stack([y, zero, zero], -1)], -2)
    V2 = V @ V
    eye = np.eye(3)
    return eye + sin_part * V + cos_part * V2, eye + cos_part * V + tail * V2


def _front_half_one(x, y):
    """front_half of one shape, in floats (v = (0, −y, x), the halved bend)."""
    theta = math.hypot(x, y)
    if theta < 1e-3:
        sin_part, cos_part, tail = 1 - theta**2 / 6, 0.5 - theta**2 / 24, 1 / 6 - theta**2 / 120
    else:
        sin_part, cos_part = math.sin(theta) / theta, (1 - math.cos(theta)) / theta**2
        tail = (theta - math.sin(theta)) / theta**3
    V = np.array([[0.0, -x, -y], [x, 0.0, 0.0], [y, 0.0, 0.0]])
    V2 = np.array([[-theta * theta, 0.0, 0.0], [0.0, -x * x, -x * y], [0.0, -x * y, -y * y]])
    return _EYE + sin_part * V + cos_part * V2, _EYE + cos_part * V + tail * V2


_EYE = np.eye(3)


def halves(s):
    """Q_A, Q_B (…, 3, 3): the front and rear halves' attitudes in the cat frame, exp(±(0, −y, x)^/2)."""
    Q = front_half(s)[0]
    return Q, np.swapaxes(Q, -1, -2)


def angular_momentum(g, s, s_dot, omega, transverse_inertia: float, axial_inertia: float, mass: float,
                     cm_distance: float, front=None):  # fmt: skip
    """The angular momentum in space about the centre of mass (…, 3), summed over the two bodies: their spins
    𝕀_i ω_i and their centres' m r_i × ṙ_i, from the cat frame g (…, 3, 3), its angular velocity Ω (…, 3, in the
    cat frame), the shape s and ṡ (front: `front_half(s)` if at hand)."""
    s_dot, omega = floats(s_dot), floats(omega)
    Q, jacobian = front_half(s) if front is None else front
    xp = _np(s_dot)
    if s_dot.ndim == 1 and xp is np:  # one shape velocity: np.stack of 0-d arrays costs more than the rest of the line
        v_dot = 0.5 * np.array([0.0, -s_dot[1], s_dot[0]])
    else:
        v_dot = 0.5 * xp.stack([xp.zeros_like(s_dot[..., 0]), -s_dot[..., 1], s_dot[..., 0]], -1)
    inertia = np.array([axial_inertia, transverse_inertia, transverse_inertia])
    total, centres = 0.0, []
    for Q_i, w_i, sign in ((Q, jacobian @ v_dot[..., None], 1.0), (np.swapaxes(Q, -1, -2),
                           -np.swapaxes(jacobian, -1, -2) @ v_dot[..., None], -1.0)):  # fmt: skip
        w_i = w_i[..., 0]  # Q̇_i Q_iᵀ = ŵ_i
        body = matvec(Q_i, omega + w_i, transposed=True)  # ω_i in the half's own axes
        total = total + matvec(Q_i, inertia * body)
        axis = Q_i[..., 0]
        centres.append((sign * cm_distance * axis, sign * cm_distance * cross(w_i, axis)))  # joint → centre
    (a, a_dot), (b, b_dot) = centres
    shift, shift_dot = 0.5 * (a + b), 0.5 * (a_dot + b_dot)  # the joint → the system's centre of mass
    for r, r_dot in ((a - shift, a_dot - shift_dot), (b - shift, b_dot - shift_dot)):
        total = total + mass * cross(r, cross(omega, r) + r_dot)
    return matvec(g, total)


def disc_segment(s, s_dot, max_bend: float, dt: float):
    """The bend's segment over a step of length dt at the velocity ṡ, stopped where β reaches max_bend (the disc's
    edge; it rests there for the rest of the step): its duration τ (a float, or one per row), and s and ṡ at the
    end of the step. τ is the positive root of |s + τ ṡ|² = max_bend², without cancellation."""
    s, v = floats(s), floats(s_dot)
    if s.ndim == 1:
        return _disc_segment_one(s, v, max_bend, dt)
    # numpy's own on real rows (no dispatch per call); ARRAYS' on a Jacobian's complex rows; the namespace of traced
    # rows (connenv.jax), whose maximum and minimum take ARRAYS' one-sided derivative at a tie (s on the disc's edge)
    xp = _np(v) if _np(s) is np else _np(s)
    if xp is not np:
        ops, minimum, maximum = xp, xp.minimum_one_sided, xp.maximum_one_sided
    else:
        ops = ARRAYS if is_complex(s) or is_complex(v) else np
        minimum, maximum = ops.minimum, ops.maximum
    real = ARRAYS.real_part if xp is np else xp.real_part
    a, b = np.sum(v * v, -1), 2 * np.sum(s * v, -1)
    c = minimum(np.sum(s * s, -1) - max_bend**2, 0.0)  # ≤ 0: s is in the disc
    end = s + v * dt
    inside = real(np.sum(end * end, -1)) <= max_bend**2
    # the rows that stay inside take no root and no quotient (their τ is dt), nor a row the quotient it does not take:
    # each kept from 0 by where (a where's branch not taken must stay finite: reverse mode multiplies its cotangent 0
    # by the branch's derivative, NaN where that is infinite)
    outward = real(b) >= 0
    root = xp.sqrt(xp.where(inside, 1.0, b * b - 4 * a * c))
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = xp.where(outward, -2 * c / xp.where(outward & ~inside, b + root, 1.0),
                         (root - b) / xp.where(outward | inside, 1.0, 2 * a))
    reach = xp.nan_to_num(reach)
    tau = xp.where(inside, dt, np.clip(reach, 0.0, dt) if ops is np else minimum(maximum(reach, 0.0), dt))
    edge = s + v * tau[..., None]
    edge = edge * minimum(1.0, max_bend / maximum(ops.hypot(edge[..., 0], edge[..., 1]), 1e-300))[..., None]
    s_end = xp.where(inside[..., None], end, edge)
    v_end = xp.where(inside[..., None], v, 0.0)
    return (float(tau) if np.ndim(tau) == 0 else tau), s_end, v_end


def _disc_segment_one(s, v, max_bend: float, dt: float):
    """disc_segment of one state, in floats."""
    (x, y), (vx, vy) = s.tolist(), v.tolist()
    end = s + v * dt
    if math.hypot(end[0], end[1]) <= max_bend:
        return dt, end, v
    a, b, c = vx * vx + vy * vy, 2 * (x * vx + y * vy), min(x * x + y * y - max_bend**2, 0.0)
    root = math.sqrt(b * b - 4 * a * c)
    reach = -2 * c / (b + root) if b >= 0 else (root - b) / (2 * a)
    tau = min(max(reach if math.isfinite(reach) else 0.0, 0.0), dt)
    edge = s + v * tau
    return tau, edge * min(1.0, max_bend / max(math.hypot(edge[0], edge[1]), 1e-300)), np.zeros(2)
