"""The guide's own system with a task to train on (docs/guides/own-system.md): a body with a rotor,
T = ½ I θ̇² + ½ J (θ̇ + u̇)², whose rotor angle u the controller drives at a bounded speed, and whose body angle θ
is to be turned to TARGET.

    python train.py --env connenv/ActiveConstraint-v0 --env-kwargs examples.my_robot:env_kwargs --algo ppo

At rest θ + J u/(I + J) is conserved, so the body turns only while the rotor does, by −J/(I + J) of the rotor's
turn: from θ near 0 and u = 0 the rotor must stop at u = (θ − TARGET)(I + J)/J, within [−π, π].
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from connenv.core.lagrangian import LagrangianSystem

I, J = 2.0, 0.5  # the body's and the rotor's moments of inertia
TARGET, TOLERANCE = 0.5, 0.01  # rad: the body angle to reach, and how close counts as reached
ROTOR_SPEED = math.pi / 2  # rad/s: the rotor's top speed; a rotor that jumped would reach the answer in one step


def rotor_body() -> LagrangianSystem:
    """The body (angle θ, free) with a rotor (angle u, assigned), no potential."""
    theta, theta_dot, u, u_dot = sp.symbols("theta theta_dot u u_dot")
    kinetic = I * theta_dot**2 / 2 + J * (theta_dot + u_dot) ** 2 / 2
    return LagrangianSystem(kinetic, 0, [theta], [u])


class TurnTo:
    """Start at rest, θ uniform in [−0.1, 0.1] rad, u = 0; reward −|θ − TARGET| each step, so that the sooner and the
    closer the better; success, which ends the episode, when |θ − TARGET| < TOLERANCE."""

    def reset(self, np_random):
        return {"q": np_random.uniform(-0.1, 0.1, 1), "u": np.zeros(1)}

    def reward(self, state, next_state):
        return -abs(next_state["q"][0] - TARGET)

    def is_success(self, state):
        return abs(state["q"][0] - TARGET) < TOLERANCE

    def terminated(self, state):
        return self.is_success(state)


def env_kwargs() -> dict:
    """The make kwargs of connenv/ActiveConstraint-v0: the action commands u in [−π, π], which the rotor turns
    toward at ROTOR_SPEED; episodes of at most 200 steps (10 s)."""
    return {
        "system": rotor_body(),
        "u_low": -math.pi,
        "u_high": math.pi,
        "max_control_speed": ROTOR_SPEED,
        "task": TurnTo(),
        "max_episode_steps": 200,
    }
