"""A geometric gait planner for KozlovShell-v0, built on the holonomy of the mechanical connection.

At zero momentum the shell moves by ξ = −I(u)⁻¹ C(u) u̇: the net motion g ∈ SE(2) after a closed loop of u is the
connection's holonomy, and it does not depend on how fast the loop is run. So a gait is a closed polygon of
commanded mass positions, one vertex per step, and its net motion per cycle is measured once, from the env's own
model and stepper. A loop turns the shell; a figure-eight, a loop followed by its mirror image run the other way,
translates it without net turn (the two turns cancel exactly, by the mirror symmetry of the ellipse).

Every gait starts and ends with the mass at the box corner BASE. There the planner chooses the next gait greedily,
looking one gait further: the gait g minimizing its steps + min over the next gait h of (h's steps + the steps still
needed after both), estimated from the target's predicted position in the body frame as (turn toward the best
translating direction) + (distance / its speed). Only g is run; at BASE again it chooses anew.

At the defaults the figure-eight X through the box's corners moves the shell 0.040 m per cycle of 4 steps, 0.13 rad
off body −y (0.010 m per step); the loop O turns it by 1.04 rad in 4 steps, the triangles by 0.52 rad in 3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BASE = (1.0, -1.0)  # action units: the corner u = (u1_max, −u2_max) where every gait starts and ends
SCALES = (1.0, 0.5, 0.25, 0.125)  # sizes of the gaits, as fractions of the box
U_TOLERANCE = 1e-4  # action units: the mass is where the planner sent it
NO_TURN = 1e-6  # rad: a gait turning less per cycle translates only (the figure-eights turn by the stepper error)


@dataclass(frozen=True)
class Gait:
    """A closed polygon of commanded actions ending at BASE, and its measured net motion (x, y, θ) per cycle,
    in the body frame of its start."""

    name: str
    waypoints: tuple
    holonomy: tuple

    @property
    def steps(self) -> int:
        return len(self.waypoints)


def loops(scale: float) -> dict:
    """Polygons through the corners of the box shrunk by `scale` about its centre, from BASE (entered and left
    along the diagonal when scale < 1): the figure-eight X (right lobe counter-clockwise, left lobe clockwise:
    the shell moves along body y), the loop O around the box and the triangles T, U, V, which turn it; each also
    run backwards (suffix r), which inverts its net motion. The other figure-eight, top and bottom lobes, swims
    along body x at half X's speed; it is left out, since a greedy planner would crawl along it rather than turn."""
    s = scale
    shapes = {
        "X": [(s, s), (-s, -s), (-s, s)],
        "O": [(s, s), (-s, s), (-s, -s)],
        "T": [(s, s), (-s, -s)],
        "U": [(-s, s), (-s, -s)],
        "V": [(s, s), (-s, s)],
    }
    entry = [] if s == 1.0 else [(s, -s)]
    return {
        f"{name}{suffix}@{s:g}": (*entry, *points, *entry, BASE)
        for name, shape in shapes.items()
        for suffix, points in (("", shape), ("r", shape[::-1]))
    }


def measure(env, waypoints) -> tuple:
    """The net motion (x, y, θ) of one cycle from BASE, at zero momentum, with the env's reduced model and
    stepper: the connection's holonomy."""
    y, u = np.zeros(3), np.array(BASE) * env.u_max
    for action in waypoints:
        u_cmd = np.array(action) * env.u_max
        y = env.stepper(env.reduced_system, y, u, (u_cmd - u) / env.dt, env.dt)
        u = u_cmd
    return tuple(float(v) for v in y)


def gait_library(env, scales=SCALES) -> list[Gait]:
    """Every loop at every scale, with its measured holonomy."""
    return [Gait(name, path, measure(env, path)) for s in scales for name, path in loops(s).items()]


def targets_after(holonomies, target):
    """The body-frame target after one cycle of each gait, R(−θ)(t − p): shape (..., gaits, 2) for target (..., 2)."""
    x, y, theta = holonomies.T
    c, s = np.cos(theta), np.sin(theta)
    dx, dy = target[..., 0:1] - x, target[..., 1:2] - y
    return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)


class GaitPlanner:
    """Swim to the target with gaits from the library, chosen greedily at BASE (see the module docstring).

    It reads the KozlovShell-v0 observation: the target in the body frame (obs[0:2]) and the mass position
    (obs[4:6]). A new episode, or any other interruption, shows as the mass not being where the planner sent it
    (the reset puts it at the centre, which no gait visits): the planner then drops its plan and returns the mass
    to BASE first. Observations may be batched; each row keeps its own plan.
    """

    def __init__(self, env):
        self.gaits = gait_library(env)
        self.holonomies = np.array([g.holonomy for g in self.gaits])
        self.steps = np.array([g.steps for g in self.gaits])
        self.goal = 0.8 * env.success_radius  # a margin for the float32 observation
        translating = np.abs(self.holonomies[:, 2]) < NO_TURN
        self.turn_rate = np.max(np.abs(self.holonomies[:, 2]) / self.steps)  # rad per step
        moves = self.holonomies[translating, :2]
        self.directions = moves / np.linalg.norm(moves, axis=-1, keepdims=True)
        self.speeds = np.linalg.norm(moves, axis=-1) / self.steps[translating]  # m per step
        self.plans = []  # per observation row: [pending waypoints, last command]

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float64)
        rows = np.atleast_2d(obs)
        while len(self.plans) < len(rows):
            self.plans.append([[], None])
        actions = np.array([self._act(row, plan) for row, plan in zip(rows, self.plans)], np.float32)
        return (actions if obs.ndim == 2 else actions[0]), state

    def _act(self, obs, plan):
        pending, last = plan
        u = obs[4:6]
        if last is None or np.max(np.abs(u - last)) > U_TOLERANCE:
            pending.clear()  # a new episode, or the mass was moved: start over from BASE
        if not pending:
            at_base = np.max(np.abs(u - BASE)) <= U_TOLERANCE
            pending.extend(self.choose(obs[:2]).waypoints if at_base else [BASE])
        plan[1] = np.array(pending.pop(0))
        return plan[1]

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
