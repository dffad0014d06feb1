"""Worked examples of the two builders, each as make kwargs: what the guide "Your own system" shows, the benchmarks time and the
contract tests check the generic ids with.

- ``rotor()``: ActiveConstraintEnv on a body with a rotor, T = ½ I θ̇² + ½ J (θ̇ + u̇)², fit for jumps;
- ``swing()``: ActiveConstraintEnv on the swing from its Lagrangian, T = ½ m (ṙ² + r² θ̇²), V = −m g r cos θ,
  strongly fit, with the swing env's radii;
- ``bead()``: ActiveConstraintEnv on a bead on a rotating bar, T = ½ m (ṙ² + r² θ̇²), V = m g r sin θ, general
  (the bar's angle θ is steered by its rate);
- ``beanie()``: ConnectionEnv on Elroy's beanie, SO(2) with A = I₂/(I₁+I₂), flat;
- ``rolling_ball()``: ConnectionEnv on the ball rolled without turning, SO(3) in the space frame, shape the contact
  point, A = −(1/ρ) [[0, −1], [1, 0], [0, 0]] so that ω = e_z × v/ρ;
- ``swing_rk4()``, ``rotor_ramp_rk4()``, ``beanie_rk4()``: the swing, the rotor (turned at a bounded speed, not
  jumped) and the beanie stepped by RK4, the builders' examples that ``connenv.jax`` traces (their default steppers,
  DOP853 and Magnus, and a fit system's jumps do not trace).

Every value is picklable (module-level functions, partials, sympy systems), as vector envs and copies need.
"""

from __future__ import annotations

import functools

import numpy as np


def rotor(inertia: float = 1.0, rotor_inertia: float = 0.25) -> dict:
    """A body (angle θ, inertia I) turned by a rotor on it (angle u relative to the body, inertia J)."""
    import sympy as sp

    from connenv.core.lagrangian import LagrangianSystem

    theta, theta_dot, u, u_dot = sp.symbols("theta theta_dot u u_dot")
    kinetic = inertia * theta_dot**2 / 2 + rotor_inertia * (theta_dot + u_dot) ** 2 / 2
    return {"system": LagrangianSystem(kinetic, sp.Integer(0), [theta], [u]), "u_low": -np.pi, "u_high": np.pi}


def swing(mass: float = 1.0, g: float = 9.81, r_min: float = 1.6, r_max: float = 2.0) -> dict:
    """The swing with its radius r assigned (q = θ, u = r)."""
    import sympy as sp

    from connenv.core.lagrangian import LagrangianSystem

    r, r_dot, theta, theta_dot = sp.symbols("r r_dot theta theta_dot")
    kinetic = mass * (r_dot**2 + r**2 * theta_dot**2) / 2
    return {"system": LagrangianSystem(kinetic, -mass * g * r * sp.cos(theta), [theta], [r]),
            "u_low": r_min, "u_high": r_max}


def bead(mass: float = 1.0, g: float = 9.81, max_tilt: float = 1.0, max_tilt_speed: float = 1.0) -> dict:
    """The bead at distance r along a bar through the pivot (q = r), the bar's angle θ from the horizontal assigned
    (u = θ, within ±max_tilt, turned at most at max_tilt_speed)."""
    import sympy as sp

    from connenv.core.lagrangian import LagrangianSystem

    r, r_dot, theta, theta_dot = sp.symbols("r r_dot theta theta_dot")
    kinetic = mass * (r_dot**2 + r**2 * theta_dot**2) / 2
    system = LagrangianSystem(kinetic, mass * g * r * sp.sin(theta), [r], [theta])
    return {"system": system, "u_low": -max_tilt, "u_high": max_tilt, "max_control_speed": max_tilt_speed}


def beanie_connection(s, body_inertia: float, beanie_inertia: float):
    """A(ψ) = I₂/(I₁+I₂) (1×1): the body turns by −I₂/(I₁+I₂) dψ as the beanie turns by dψ relative to it."""
    return np.full((*np.shape(s)[:-1], 1, 1), beanie_inertia / (body_inertia + beanie_inertia))


def beanie(body_inertia: float = 3.0, beanie_inertia: float = 1.0) -> dict:
    """Elroy's beanie: group SO2 (the body's angle θ₁), shape ψ, the beanie's angle relative to the body."""
    connection = functools.partial(beanie_connection, body_inertia=body_inertia, beanie_inertia=beanie_inertia)
    return {"group": "SO2", "connection": connection, "shape_low": [-np.inf], "shape_high": [np.inf],
            "vectorized": True}


def rolling_ball_connection(s, radius: float):
    """A(s) = −(1/ρ) [[0, −1], [1, 0], [0, 0]] (3×2) at every contact point s: ξ = −A ṡ = e_z × ṡ/ρ."""
    A = np.array([[0.0, 1.0], [-1.0, 0.0], [0.0, 0.0]]) / radius
    return np.broadcast_to(A, (*np.shape(s)[:-1], 3, 2))


def rolling_ball(radius: float = 1.0, reach: float = 10.0) -> dict:
    """The rolling-ball env's ball as a connection: SO3, space frame, shape the contact point within ±reach."""
    connection = functools.partial(rolling_ball_connection, radius=radius)
    return {"group": "SO3", "frame": "space", "connection": connection, "shape_low": [-reach, -reach],
            "shape_high": [reach, reach], "vectorized": True}


def swing_rk4() -> dict:
    """swing() stepped by RK4: its vector field lambdified to JAX as well, the step traced by connenv.jax."""
    return {**swing(), "integrator": "rk4"}


def rotor_ramp_rk4() -> dict:
    """rotor() with u heading to its command at 2 rad/s (no jump), stepped by RK4: the body turns from rest."""
    return {**rotor(), "max_control_speed": 2.0, "integrator": "rk4"}


def beanie_rk4() -> dict:
    """beanie() stepped by RK4: its connection (numpy on constants only) traced by connenv.jax."""
    return {**beanie(), "integrator": "rk4"}

