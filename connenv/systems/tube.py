"""A tube that bends but cannot twist: its tip frame is parallel transported along the trace of its tangent.

The tip's frame R ∈ SO(3) maps tip to space coordinates; its columns are the normal N, the binormal B and the unit
tangent T. A tube can bend (the frame turns about N and B) but not twist (about T), so its angular velocity in the
tip's own frame has no third component:

    Ṙ = R ω̂,    ω = (κ₁, κ₂, 0),

with κ = (κ₁, κ₂) the bending rates. The tangent then moves by Ṫ = R (ω × e₃) = κ₂ N − κ₁ B, and N by
Ṅ = R (ω × e₁) = −κ₂ T: N changes only along T, which is what parallel transport of N along the curve T(t) on the
unit sphere means (Lawton, slides 4–5). A tube bent in one plane (κ constant) turns about the fixed axis R ω and T
runs along a great circle. Holding κ over a step of length τ the update is one exponential, exact (Rodrigues):

    R ← R exp(τ ω̂).

**Holonomy.** When T comes back to where it started, R = R₀ Rz(ψ): the tip has turned about its own axis by the
angle ψ (the *twist*), which is the area enclosed by the loop T(t) on the unit sphere, counted positive for a loop
run counterclockwise seen from outside, mod 2π (the curvature of the sphere is 1). Along a circle of colatitude c
about an axis that is 2π(1 − cos c), the turn of a Foucault pendulum's plane in a day at colatitude c; along a
spherical polygon it is the spherical excess, Σ interior angles − (n − 2)π (Girard).

**Twist of an open path.** With Q = R₀ᵀR the frame in start coordinates and τ = Q e₃ the tangent there, carry the
frame back to the start along the great circle from τ to e₃ (the rotation G about τ × e₃ by the angle between
them; rotating along a great circle is parallel transport along it); then G Q = Rz(ψ). So ψ is the holonomy of
the path closed by that geodesic, continuous in Q wherever T ≠ −T₀, and on a closed path it is the twist above.
In closed form (the rotation from τ to e₃ is I + v̂ + v̂²/(1 + τ_z) with v = τ × e₃), with N = Q e₁:

    X = (1 + τ_z)(τ_z N_x − τ_x N_z) + τ_y (τ_y N_x − τ_x N_y),
    Y = (1 + τ_z)(τ_z N_y − τ_y N_z) − τ_x (τ_y N_x − τ_x N_y),        ψ = atan2(Y, X),

the angle of G N in the (e₁, e₂) plane, scaled by 1 + τ_z > 0. At T = −T₀ no geodesic is singled out and ψ = 0.
The same ψ is the twist of the swing–twist decomposition of Q about e₃, 2 atan2(q_z, q_w) in quaternions.

**Development.** The accumulated bend s = ∫ κ dt is the trace of T rolled out on the plane (the development of the
curve): the tube is a connection over s, ξ = −A ṡ with the constant A = −[[1, 0], [0, 1], [0, 0]], in the body
frame. It is the rolling ball's (``connenv.systems.rolling_ball``) read backwards: Rᵀ obeys
d(Rᵀ)/dt = (−ω)^ Rᵀ, the ball's equation ω = e_z × v/ρ with ρ = 1 and v = (−κ₂, κ₁): the sphere rolled on the
plane along s, its contact point tracing T in the tip's frame.

**Discrete loops.** n equal bends of length a, the bending direction turned by the exterior angle δ = π − α
between them, trace a regular spherical n-gon of side a and interior angle α, closed when
cos(a/2) sin(α/2) = cos(π/n), of area n α − (n − 2)π. The shortest closed curve enclosing an area A on the unit
sphere is a circle, of length √(A (4π − A)) (the isoperimetric inequality on the sphere).

A constant-curvature bend whose plane turns at the rate Ω, κ(t) = k (cos Ωt, sin Ωt), traces a circle: with
R = P Rz(Ωt)ᵀ, Ṗ = P (k e₁ + Ω e₃)^, so

    R(t) = R₀ exp(t (k e₁ + Ω e₃)^) Rz(−Ωt),

and T circles the axis R₀ (k, 0, Ω)/√(k² + Ω²), at colatitude c with cos c = Ω/√(k² + Ω²), once in
2π/√(k² + Ω²); after that turn R = R₀ Rz(−2π cos c): the twist is 2π(1 − cos c) mod 2π.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from connenv.core.backend import floats

BEND_CONNECTION = -np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
"""A of the tube as a connection over the accumulated bend s: ξ = −A ṡ = (ṡ₁, ṡ₂, 0), in the tip's frame."""


def hat(omega):
    """ω̂ (…, 3, 3): ω̂ v = ω × v."""
    w = floats(omega)
    zero = np.zeros_like(w[..., 0])
    rows = [[zero, -w[..., 2], w[..., 1]], [w[..., 2], zero, -w[..., 0]], [-w[..., 1], w[..., 0], zero]]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def rodrigues(omega):
    """exp(ω̂) (…, 3, 3), closed form: I + sin θ/θ ω̂ + (1 − cos θ)/θ² ω̂², θ = √(ω·ω) (analytic on the complex rows
    of a Jacobian, where the norm would be the modulus; θ = 0 decided by the real part)."""
    w = floats(omega)
    angle = np.sqrt(np.sum(w * w, axis=-1))[..., None, None]
    zero = np.real(angle) == 0.0
    safe = np.where(zero, 1.0, angle)
    a = np.where(zero, 1.0, np.sin(safe) / safe)
    b = np.where(zero, 0.5, 0.5 * (np.sin(0.5 * safe) / (0.5 * safe)) ** 2)
    W = hat(w)
    return np.eye(3) + a * W + b * (W @ W)


def bent(R, bend):
    """R after a bend by the vector bend = (b₁, b₂) (rad) in the tip's frame: R exp((b₁, b₂, 0)^)."""
    b = floats(bend)
    return floats(R) @ rodrigues(np.concatenate([b, np.zeros_like(b[..., :1])], -1))


def twist(Q, atan2=np.arctan2):
    """ψ of the frame Q = R₀ᵀR (…, 3, 3), rad in (−π, π]: the turn about T₀ once carried back along the geodesic
    (see the module). Arithmetic and one atan2 (given: math.atan2 for one frame of floats)."""
    Nx, Ny, Nz = Q[..., 0, 0], Q[..., 1, 0], Q[..., 2, 0]
    tx, ty, tz = Q[..., 0, 2], Q[..., 1, 2], Q[..., 2, 2]
    w, cross = 1.0 + tz, ty * Nx - tx * Ny
    return atan2(w * (tz * Ny - ty * Nz) - tx * cross, w * (tz * Nx - tx * Nz) + ty * cross)


def tangent_angle(Q, atan2=np.arctan2, hypot=np.hypot):
    """The angle between T and T₀ (rad), Q = R₀ᵀR."""
    return atan2(hypot(Q[..., 0, 2], Q[..., 1, 2]), Q[..., 2, 2])


def wrap(angle):
    """angle mod 2π in [−π, π)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def bend_toward(R, v):
    """The bend (b₁, b₂) that carries T = R e₃ along the great circle to the unit vector v (not −T)."""
    d = np.asarray(R, float).T @ np.asarray(v, float)  # v in the tip's frame
    sideways = math.hypot(d[0], d[1])
    if sideways == 0.0:
        return np.zeros(2)
    angle = math.atan2(sideways, d[2])
    return angle * np.array([-d[1], d[0]]) / sideways  # Ṫ = κ₂ N − κ₁ B points along (d₀, d₁)


def heading_bend(heading, length):
    """The bend of that length that moves T along the direction at angle `heading` from N toward B."""
    return length * np.array([-math.sin(heading), math.cos(heading)])


def polygon_area(vertices):
    """The area on the unit sphere enclosed by the spherical polygon through the unit vectors (n, 3), run
    counterclockwise seen from outside: the sum of the signed solid angles of the triangles (v₀, vᵢ, vᵢ₊₁), each
    2 atan2(a·(b × c), 1 + a·b + b·c + c·a) (Van Oosterom & Strackee 1983)."""
    v = np.asarray(vertices, float)
    a, b, c = v[0], v[1:-1], v[2:]
    numerator = np.einsum("j,ij->i", a, np.cross(b, c))
    denominator = 1.0 + b @ a + np.einsum("ij,ij->i", b, c) + c @ a
    return float(np.sum(2.0 * np.arctan2(numerator, denominator)))


def circle_length(area):
    """The length of the shortest closed curve enclosing that area on the unit sphere: a circle, √(A (4π − A))."""
    return math.sqrt(area * (4 * math.pi - area))


@dataclass(frozen=True)
class RegularLoop:
    """A regular spherical polygon run counterclockwise: `sides` sides of length `side` (rad), turning left by the
    exterior angle `turn` at each vertex; it encloses `area`."""

    sides: int
    side: float
    turn: float
    area: float

    @property
    def length(self):
        return self.sides * self.side


def regular_loop(area: float, sides: int) -> RegularLoop:
    """The regular spherical n-gon of that area, 0 < area < 2π: interior angle α = (A + (n − 2)π)/n, side a from
    cos(a/2) sin(α/2) = cos(π/n)."""
    if not 0.0 < area < 2 * math.pi or sides < 3:
        raise ValueError(f"a regular loop needs 0 < area < 2π and sides ≥ 3; got area={area!r}, sides={sides!r}")
    interior = (area + (sides - 2) * math.pi) / sides
    side = 2.0 * math.acos(min(1.0, math.cos(math.pi / sides) / math.sin(interior / 2)))
    return RegularLoop(sides, side, math.pi - interior, area)


def cap_loop(area: float, max_side: float) -> RegularLoop:
    """The regular loop of that area with the fewest sides no longer than max_side: the discrete circle."""
    sides = max(3, math.ceil(circle_length(area) / max_side))
    while regular_loop(area, sides).side > max_side:
        sides += 1
    return regular_loop(area, sides)


def circle_frame(R0, curvature: float, rate: float, t):
    """R(t) of the bend κ(t) = k (cos Ωt, sin Ωt) from R₀: R₀ exp(t (k e₁ + Ω e₃)^) Rz(−Ωt) (see the module)."""
    t = np.asarray(t, float)[..., None]
    spin = rodrigues(t * np.array([curvature, 0.0, rate]))
    return np.asarray(R0, float) @ spin @ rodrigues(-t * np.array([0.0, 0.0, rate]))


def circle_rate(colatitude: float, curvature: float = 1.0) -> float:
    """Ω for which the bend k (cos Ωt, sin Ωt) traces the circle of that colatitude: Ω = k cot c."""
    return curvature / math.tan(colatitude)

