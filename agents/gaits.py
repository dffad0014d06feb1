"""A geometric gait planner for swimmers moved by a mechanical connection; agents.controllers.kozlov_shell and
snake_swimmer give it their gaits.

At zero momentum the body moves by ξ = −A(s) ṡ: the net motion g ∈ SE(2) after a closed loop of shapes s is the
connection's holonomy, and it does not depend on how fast the loop is run. So a gait is a closed polygon of
commanded shapes, and its net motion per cycle is measured once, from the env's own model and stepper (`trace`:
the env's step, toward each vertex until the shape gets there). Gaits that turn by nothing (by a symmetry of the
body) translate; the others turn.

Every gait starts and ends at the shape `base`. There the planner chooses the next gait greedily, looking one gait
further: the gait g minimizing its steps + min over the next gait h of (h's steps + the steps still needed after
both), estimated from the target's predicted position in the body frame as (turn toward the best translating
direction) + (distance / its speed). Only g is run; at `base` again it chooses anew.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

U_TOLERANCE = 1e-4  # action units: the shape is where the planner sent it
NO_TURN = 1e-6  # rad: a gait turning less per cycle translates only (the figure-eights turn by the stepper error)


@dataclass(frozen=True)
class Gait:
    """A closed polygon of commanded actions ending at the base shape, one per step (a vertex repeated until the
    shape gets there), the shape after each step (action units), and its measured net motion (x, y, θ) per cycle,
    in the body frame of its start."""

    name: str
    waypoints: tuple
    holonomy: tuple
    shapes: tuple

    @property
    def steps(self) -> int:
        return len(self.waypoints)


def trace(env, name, vertices, start, shape, tolerance=1e-12) -> Gait:
    """The gait of the polygon `vertices` (action units) from the state `start` (at rest at the origin), by the
    env's own step (its reduced model and stepper): each vertex commanded until shape(state), the shape in action
    units, is within tolerance of it; the net motion is the connection's holonomy."""
    state, actions, shapes = start, [], []
    for vertex in vertices:
        while not shapes or np.max(np.abs(np.subtract(shapes[-1], vertex))) > tolerance:
            state = env.advance(state, env.command(np.array(vertex, float)), env.stepper)
            actions.append(tuple(vertex))
            shapes.append(tuple(float(v) for v in shape(state)))
        shapes[-1] = tuple(vertex)
    return Gait(name, tuple(actions), tuple(float(v) for v in state.pose), tuple(shapes))


def targets_after(holonomies, target):
    """The body-frame target after one cycle of each gait, R(−θ)(t − p): shape (..., gaits, 2) for target (..., 2)."""
    x, y, theta = holonomies.T
    c, s = np.cos(theta), np.sin(theta)
    dx, dy = target[..., 0:1] - x, target[..., 1:2] - y
    return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)


class GaitPlanner:
    """Swim to the target with gaits from the library, chosen greedily at the base shape (see the module docstring).

    It reads a swimmer's observation (KozlovShell's, SnakeSwimmer's): the target in the body frame (obs[0:2], in
    units of target_scale metres) and the shape in action units (obs[4:6]). A new episode, or any other
    interruption, shows as the shape not being where the gait left it: the planner then drops its plan and returns
    to the base first. Observations may be batched; each row keeps its own plan.

    gaits: the library (each measured by `trace`); base: the shape every gait starts and ends at.
    """

    def __init__(self, env, gaits, base, target_scale: float = 1.0):
        self.gaits = gaits
        self.base, self.target_scale = np.array(base), target_scale
        self.holonomies = np.array([g.holonomy for g in self.gaits])
        self.steps = np.array([g.steps for g in self.gaits])
        self.goal = 0.8 * env.success_radius  # a margin for the float32 observation
        translating = np.abs(self.holonomies[:, 2]) < NO_TURN
        self.turn_rate = np.max(np.abs(self.holonomies[:, 2]) / self.steps)  # rad per step
        moves = self.holonomies[translating, :2]
        self.directions = moves / np.linalg.norm(moves, axis=-1, keepdims=True)
        self.speeds = np.linalg.norm(moves, axis=-1) / self.steps[translating]  # m per step
        self.plans = []  # per observation row: [pending (action, shape after it), the shape expected now or None]

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float64)
        rows = np.atleast_2d(obs)
        while len(self.plans) < len(rows):
            self.plans.append([[], None])
        actions = np.array([self._act(row, plan) for row, plan in zip(rows, self.plans)], np.float32)
        return (actions if obs.ndim == 2 else actions[0]), state

    def _act(self, obs, plan):
        pending, expected = plan
        shape = obs[4:6]
        if expected is not None and np.max(np.abs(shape - expected)) > U_TOLERANCE:
            pending.clear()  # a new episode, or the shape was moved: start over from the base
        if not pending:
            at_base = np.max(np.abs(shape - self.base)) <= U_TOLERANCE
            gait = self.choose(obs[:2] * self.target_scale) if at_base else None
            pending.extend(zip(gait.waypoints, gait.shapes) if at_base else [(tuple(self.base), None)])
        action, plan[1] = pending.pop(0)
        return np.array(action)

    def choose(self, target) -> Gait:
        """The gait g minimizing steps(g) + min_h [steps(h) + steps_to_go(after g, then h)], or the shortest
        gait that ends inside the goal."""
        first = targets_after(self.holonomies, np.asarray(target, float))  # (gaits, 2)
        second = targets_after(self.holonomies, first)  # (gaits, gaits, 2)
        ahead = np.min(self.steps + self.steps_to_go(second), axis=-1)
        cost = self.steps + np.where(np.linalg.norm(first, axis=-1) <= self.goal, 0.0, ahead)
        return self.gaits[int(np.argmin(cost))]

    def steps_to_go(self, target):
        """0 inside the goal; else the fastest (turn toward a translating gait's direction, then swim along it),
        for targets of shape (..., 2)."""
        distance = np.linalg.norm(target, axis=-1)
        cos = (target @ self.directions.T) / np.maximum(distance, 1e-300)[..., None]
        turn = np.arccos(np.clip(cos, -1.0, 1.0))
        estimate = np.min(turn / self.turn_rate + distance[..., None] / self.speeds, axis=-1)
        return np.where(distance <= self.goal, 0.0, estimate)
