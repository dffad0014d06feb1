r"""The vertical rolling coin as a mechanical connection (Lawton; Hand & Finch §2, rolling coin).

A coin of radius R stands upright on the plane and rolls without slipping. Its contact point is (x, y), its
heading θ is measured from the y axis (the coin rolls along (sin θ, cos θ)), and φ is the angle it has rolled.
Rolling without slipping is the pair of constraints

    ω₁ = dx − R sin θ dφ = 0,    ω₂ = dy − R cos θ dφ = 0,

so the position g = (x, y) ∈ ℝ² follows the shape s = (θ, φ) through the connection A(s) with ξ = −A(s) ṡ:

    A(θ, φ) = [[0, −R sin θ],
               [0, −R cos θ]],    ẋ = R sin θ φ̇,   ẏ = R cos θ φ̇.

The group is abelian, so the body and space frames agree. The curvature is dA = (−R cos θ, R sin θ) dθ ∧ dφ:
steering alone (dφ = 0) never moves the coin, rolling alone moves it along its heading, and a loop in the shape
plane moves it by Δg = −∮A = −∬dA over the loop's inside (Stokes): (R cos θ, −R sin θ) times the area for a
counterclockwise loop in the (θ, φ) plane.

**Exact step.** With θ̇ = Ω and φ̇ = ν constant over a segment of length τ, θ(t) = θ + Ω t and

    Δx = R ν ∫₀^τ sin(θ + Ω t) dt = R ν τ sinc(Ω τ/2) sin(θ + Ω τ/2),
    Δy = R ν ∫₀^τ cos(θ + Ω t) dt = R ν τ sinc(Ω τ/2) cos(θ + Ω τ/2),

sinc x = sin x / x (1 at 0): the chord of the arc of radius R ν/Ω the coin rolls, in a form without the
cancellation of (cos θ − cos(θ + Ω τ))/Ω near Ω = 0 (`exact_segment`).

**Rectangle.** Roll by Δφ at θ₀, steer to θ₀ + Δθ, roll back by −Δφ, steer back: the coin moves by

    R Δφ (sin θ₀ − sin(θ₀ + Δθ),  cos θ₀ − cos(θ₀ + Δθ)),

exactly, for any size (`rectangle_displacement`): the integral of the curvature over the rectangle.
"""

from __future__ import annotations

import math

import numpy as np

from connenv.core.backend import floats, namespace, traced


def connection(s, radius: float):
    """A(θ, φ) of shape (..., 2, 2) for shapes s of shape (..., 2)."""
    theta = floats(s)[..., 0]
    if type(theta) is not np.ndarray and traced(ops := namespace(theta)):  # JAX's rows: A built whole (connenv.jax)
        zero = ops.zeros_like(theta)
        return ops.stack([zero, -radius * ops.sin(theta), zero, -radius * ops.cos(theta)], -1).reshape(*theta.shape, 2, 2)
    A = np.zeros((*theta.shape, 2, 2), theta.dtype)
    A[..., 0, 1] = -radius * np.sin(theta)
    A[..., 1, 1] = -radius * np.cos(theta)
    return A


def exact_segment(g, s, s_dot, tau, radius: float):
    """(x, y) after a segment of length tau at constant (θ̇, φ̇) from the shape s = (θ, φ): one state (arrays (2,),
    a float tau) or a batch of rows (arrays (N, 2), tau a float or one per row; complex on a Jacobian's, the sinc's
    branch at 0 taken by the real parts; JAX's rows too, ``connenv.jax``: the same arithmetic in their namespace)."""
    g = floats(g)
    if g.ndim == 1 and type(g) is np.ndarray:
        theta, (omega, nu), tau = float(s[0]), map(float, s_dot), float(tau)
        half = 0.5 * omega * tau
        chord = radius * nu * tau * (math.sin(half) / half if half != 0.0 else 1.0)
        mid = theta + half
        return np.array([g[0] + chord * math.sin(mid), g[1] + chord * math.cos(mid)])
    s, s_dot = floats(s), floats(s_dot)
    ops = namespace(g)  # numpy's rows (ARRAYS: numpy's own functions), or JAX's
    half = 0.5 * s_dot[..., 0] * tau
    zero = ops.real_part(half) == 0.0
    safe = ops.where(zero, 1.0, half)
    chord = radius * s_dot[..., 1] * tau * ops.where(zero, 1.0, ops.sin(safe) / safe)
    mid = s[..., 0] + half
    return ops.stack([g[..., 0] + chord * ops.sin(mid), g[..., 1] + chord * ops.cos(mid)], axis=-1)


def rectangle_displacement(theta0: float, delta_theta: float, delta_phi: float, radius: float):
    """The closed form of the rectangle loop's displacement (see the module)."""
    return radius * delta_phi * np.array(
        [math.sin(theta0) - math.sin(theta0 + delta_theta), math.cos(theta0) - math.cos(theta0 + delta_theta)]
    )
