r"""Elroy's beanie: a flat connection with a conserved momentum (Marsden, Montgomery & Ratiu 1990; Lawton).

Two coaxial planar bodies turn about one axis: the body (inertia I₁, angle θ) and the beanie on it (inertia I₂,
angle θ + ψ relative to space); a motor assigns ψ, the beanie's angle relative to the body. With no external
torque the angular momentum is conserved:

    μ = I₁ θ̇ + I₂ (θ̇ + ψ̇) = (I₁ + I₂) θ̇ + I₂ ψ̇,

so the group SO(2) (θ) follows the shape ψ by

    dθ = −A dψ + μ/(I₁ + I₂) dt,    A = I₂/(I₁ + I₂),

the mechanical connection A plus the locked inertia's velocity 𝕀⁻¹μ with 𝕀 = I₁ + I₂. A is constant, so the
connection is flat: a loop of ψ turns the body by the *geometric phase* −2π A · w, w the loop's winding number
(how often the beanie went round), whatever the speed profile, and the *dynamic phase* μ T/(I₁ + I₂) adds over
the loop's duration T. At constant ψ̇ over a segment of length τ the step is exact:

    θ ← θ − A ψ̇ τ + μ τ/(I₁ + I₂)   (`exact_segment` for the first term, `dynamic_phase` for the second).

The body holds still (θ̇ = 0) when the beanie spins at ψ̇ = μ/I₂.
"""

from __future__ import annotations

import numpy as np

from connenv.core.backend import floats, is_traced, namespace


def coupling(body_inertia: float, beanie_inertia: float) -> float:
    """A = I₂/(I₁ + I₂)."""
    return beanie_inertia / (body_inertia + beanie_inertia)


def connection(s, body_inertia: float, beanie_inertia: float):
    """A (shape (..., 1, 1)) at shapes s of shape (..., 1): the same at every ψ."""
    A, shape = coupling(body_inertia, beanie_inertia), (*np.shape(s)[:-1], 1, 1)
    return namespace(A).full(shape, A) if is_traced(A) else np.full(shape, A)  # traced: connenv.jax's parameters


def exact_segment(g, s, s_dot, tau, body_inertia: float, beanie_inertia: float):
    """θ after a segment of length tau at constant ψ̇, at zero momentum (the geometric part): g (..., 1); complex
    on the rows of a complex-step Jacobian."""
    tau = floats(tau)
    turn = coupling(body_inertia, beanie_inertia) * floats(s_dot) * tau[..., None]
    return floats(g) - turn


def dynamic_phase(momentum, tau, body_inertia: float, beanie_inertia: float):
    """μ τ/(I₁ + I₂): the body's turn over a time tau from the momentum alone."""
    return momentum * tau / (body_inertia + beanie_inertia)
