"""Reference controllers of TubeTwist-v0: a loop of T enclosing the area the twist still needs.

From the observation, the error E = Rz(ψ*)ᵀ R₀ᵀ R (row 2: T₀ in the tip's frame) and the twist error ψ − ψ*, the
plan is: bend T back to T₀ along the great circle (which leaves the twist ψ as defined unchanged), then run a
regular spherical polygon of area A = |ψ* − ψ| (wrapped into [−π, π)) from T₀, counterclockwise seen from
outside to add A, clockwise to take it away; along each side the bending direction is fixed in the tip's frame
(the frame is parallel transported), and at each vertex it turns by the exterior angle. Every bend is exact in
the exact model, so the loop closes and turns the tip by A to rounding.

- ``cap``: the polygon with the fewest sides of at most one step's bend each, max_bend_rate · dt: a discrete
  circle. The circle is the shortest closed curve of a given area on the sphere, √(A (4π − A)) long, so from the
  start (T = T₀) this loop is the shortest to within the polygon's excess over its circle.
- ``square``: a regular spherical quadrilateral of the same area, each side cut into steps of equal bends: longer,
  for comparison.

As agents.controllers.rolling_ball's planners, it follows its plan open loop and plans again when the observation is not the
one the plan predicted (a new episode, a disturbance) or the plan is spent.
"""

from __future__ import annotations

import math

import numpy as np

from agents.planning import RowPlanner
from connenv.systems.tube import bent, cap_loop, heading_bend, regular_loop

MATCH = 1e-5  # largest difference between the observed and the predicted error E of a plan
DONE = 1e-9  # rad: a twist or tangent error below it needs no loop


class LoopPlanner(RowPlanner):
    """TubeTwist-v0's controller: predict(obs) → (κ/max_bend_rate, state); sides=None for the cap loop."""

    def __init__(self, max_bend_rate: float, dt: float, sides: int | None = None):
        self.step_length, self.sides = max_bend_rate * dt, sides
        self.plans = {}  # row of the (batched) observation -> [remaining bends, predicted E]

    def act(self, i, obs):
        E, twist_error = obs[:9].reshape(3, 3), math.atan2(obs[10], obs[9])
        bends, expected = self.plans.get(i, (np.zeros((0, 2)), None))
        if not len(bends) or np.abs(E - expected).max() > MATCH:
            bends = self.plan(E, twist_error)
            if not len(bends):
                return np.zeros(2)
        self.plans[i] = (bends[1:], bent(E, bends[0]))
        return bends[0] / self.step_length

    def plan(self, E, twist_error):
        """The bends (k, 2), each at most one step's, that bring E to I: back along the geodesic, then the loop."""
        home = E[2]  # T₀ in the tip's frame
        sideways = math.hypot(home[0], home[1])
        angle = math.atan2(sideways, home[2])
        back = np.zeros((0, 2))
        if angle > DONE:
            steps = math.ceil(angle / self.step_length)
            back = np.tile(angle / steps * np.array([-home[1], home[0]]) / sideways, (steps, 1))
        area = -twist_error
        if abs(area) <= DONE:
            return back
        loop = cap_loop(abs(area), self.step_length) if self.sides is None else regular_loop(abs(area), self.sides)
        pieces = math.ceil(loop.side / self.step_length - 1e-12)
        turn = math.copysign(loop.turn, area)
        bends = [heading_bend(k * turn, loop.side / pieces) for k in range(loop.sides) for _ in range(pieces)]
        return np.concatenate([back, np.array(bends)])


def for_env(env, sides: int | None = None):
    """The planner for an env's max_bend_rate and dt."""
    env = env.unwrapped
    return LoopPlanner(env.max_shape_speed, env.dt, sides)


def cap(env):
    return for_env(env)


def square(env):
    return for_env(env, sides=4)
