"""A geometric gait planner for swimmers moved by a mechanical connection: KozlovShell-v0 and SnakeSwimmer-v0.

At zero momentum the body moves by ξ = −A(s) ṡ: the net motion g ∈ SE(2) after a closed loop of shapes s is the
connection's holonomy, and it does not depend on how fast the loop is run. So a gait is a closed polygon of
commanded shapes, and its net motion per cycle is measured once, from the env's own model and stepper (`trace`:
the env's step, toward each vertex until the shape gets there). Gaits that turn by nothing (by a symmetry of the
body) translate; the others turn.

Every gait starts and ends at the shape `base`. There the planner chooses the next gait greedily, looking one gait
further: the gait g minimizing its steps + min over the next gait h of (h's steps + the steps still needed after
both), estimated from the target's predicted position in the body frame as (turn toward the best translating
direction) + (distance / its speed). Only g is run; at `base` again it chooses anew.

KozlovShell-v0 (`GaitPlanner(env)`): the mass reaches each vertex in one step; every gait starts at the box corner
BASE, which a reset (mass at the centre) never gives. A loop turns the shell; a figure-eight, a loop followed by its
mirror image run the other way, translates it without net turn (the two turns cancel exactly, by the mirror symmetry
of the ellipse). At the defaults the figure-eight X through the box's corners moves the shell 0.040 m per cycle of 4
steps, 0.13 rad off body −y (0.010 m per step); the loop O turns it by 1.04 rad in 4 steps, the triangles by 0.52 rad
in 3.

SnakeSwimmer-v0 (`snake_planner(env)`): the joints take several steps to each vertex at their top speed; every gait
starts and ends straight, (α, β) = 0, where a reset puts the chain. A loop that is its own image under
(α, β) ↦ (−α, −β) (the chain mirrored across its middle link's axis, which mirrors the motion and turns it by −θ)
turns by nothing and translates: the squares and diamonds about the straight shape. Of the loops in one quadrant,
the S-shaped ones (Q2, Q4: α and β of opposite signs), their own images under (α, β) ↦ (−β, −α) (the chain
reversed end to end), do not turn either; the C-shaped ones (Q1, Q3: α and β of the same sign) turn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BASE = (1.0, -1.0)  # action units: the corner u = (u1_max, −u2_max) where every shell gait starts and ends
SCALES = (1.0, 0.5, 0.25, 0.125)  # sizes of the gaits, as fractions of the box
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


def trace(env, name, vertices, start, shape, tolerance=1e-12) -> Gait:
    """The gait of the polygon `vertices` (action units) from the state `start` (at rest at the origin), by the
    env's own step (its reduced model and stepper): each vertex commanded until shape(state), the shape in action
    units, is within tolerance of it; the net motion is the connection's holonomy."""
    state, actions, shapes = start, [], []
    for vertex in vertices:
        while not shapes or np.max(np.abs(np.subtract(shapes[-1], vertex))) > tolerance:
            state = env.advance(state, env.command(np.array(vertex, float)))
            actions.append(tuple(vertex))
            shapes.append(tuple(float(v) for v in shape(state)))
        shapes[-1] = tuple(vertex)
    return Gait(name, tuple(actions), tuple(float(v) for v in state.pose), tuple(shapes))


def gait_library(env, scales=SCALES) -> list[Gait]:
    """KozlovShell-v0's loops at every scale, each measured from BASE."""
    start = env.state.replace(pose=np.zeros(3), momentum=np.zeros(3), u=np.array(BASE) * env.u_max, full=False)

    def shape(state):
        return state.u / env.u_max

    return [trace(env, name, path, start, shape) for s in scales for name, path in loops(s).items()]


SNAKE_BASE = (0.0, 0.0)  # action units: straight, where a reset puts the chain
SNAKE_SCALES = (1.0, 0.5, 0.25, 0.125)  # the loops' sizes, as fractions of the joints' range 2π/3


def snake_loops(scale: float) -> dict:
    """Polygons of joint angles (action units) from the straight shape and back: the square S through (±s, ±s) and
    the diamond D through (±s, 0), (0, ±s), each its own mirror image (they translate), and the four quadrant
    squares Q1–Q4 (Q1 and Q3 turn; Q2 and Q4, their own images under (α, β) ↦ (−β, −α), translate); each also run
    backwards (suffix r)."""
    s = scale
    shapes = {
        "S": [(s, s), (-s, s), (-s, -s), (s, -s), (s, s)],
        "D": [(s, 0.0), (0.0, s), (-s, 0.0), (0.0, -s), (s, 0.0)],
        **{f"Q{k}": [(i * s, 0.0), (i * s, j * s), (0.0, j * s)] for k, (i, j) in
           enumerate([(1, 1), (-1, 1), (-1, -1), (1, -1)], 1)},
    }  # fmt: skip
    return {
        f"{name}{suffix}@{s:g}": (*points, SNAKE_BASE)
        for name, shape in shapes.items()
        for suffix, points in (("", shape), ("r", shape[::-1]))
    }


def snake_planner(env, scales=SNAKE_SCALES):
    """The gait planner of SnakeSwimmer-v0 (see the module), its loops measured from the straight shape at rest."""
    start = env.state.replace(pose=np.zeros(3), momentum=np.zeros(3), s=np.zeros(2), full=False)

    def shape(state):
        return state.s / env.joint_limit

    gaits = [trace(env, name, path, start, shape) for s in scales for name, path in snake_loops(s).items()]
    return GaitPlanner(env, gaits, SNAKE_BASE, env.body_length)


def targets_after(holonomies, target):
    """The body-frame target after one cycle of each gait, R(−θ)(t − p): shape (..., gaits, 2) for target (..., 2)."""
    x, y, theta = holonomies.T
    c, s = np.cos(theta), np.sin(theta)
    dx, dy = target[..., 0:1] - x, target[..., 1:2] - y
    return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)


class GaitPlanner:
    """Swim to the target with gaits from the library, chosen greedily at the base shape (see the module docstring).

    It reads the observation of KozlovShell-v0 or SnakeSwimmer-v0: the target in the body frame (obs[0:2], in
    units of target_scale metres) and the shape in action units (obs[4:6]). A new episode, or any other
    interruption, shows as the shape not being where the gait left it: the planner then drops its plan and returns
    to the base first. Observations may be batched; each row keeps its own plan.

    gaits: the library (default: KozlovShell-v0's, `gait_library`); base: the shape every gait starts and ends at.
    """

    def __init__(self, env, gaits=None, base=BASE, target_scale: float = 1.0):
        self.gaits = gait_library(env) if gaits is None else gaits
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
