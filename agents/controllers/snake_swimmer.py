"""Reference controller of SnakeSwimmer-v0: the gait planner (agents.gaits) on the snake's gaits.

The joints take several steps to each vertex at their top speed; every gait
starts and ends straight, (α, β) = 0, where a reset puts the chain. A loop that is its own image under
(α, β) ↦ (−α, −β) (the chain mirrored across its middle link's axis, which mirrors the motion and turns it by −θ)
turns by nothing and translates: the squares and diamonds about the straight shape. Of the loops in one quadrant,
the S-shaped ones (Q2, Q4: α and β of opposite signs), their own images under (α, β) ↦ (−β, −α) (the chain
reversed end to end), do not turn either; the C-shaped ones (Q1, Q3: α and β of the same sign) turn.

"""

from __future__ import annotations

import numpy as np

from agents.gaits import GaitPlanner, trace

BASE = (0.0, 0.0)  # action units: straight, where a reset puts the chain
SCALES = (1.0, 0.5, 0.25, 0.125)  # the loops' sizes, as fractions of the joints' range 2π/3


def loops(scale: float) -> dict:
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
        f"{name}{suffix}@{s:g}": (*points, BASE)
        for name, shape in shapes.items()
        for suffix, points in (("", shape), ("r", shape[::-1]))
    }


def gaits(env, scales=SCALES):
    """The gait planner of the snake (see the module), its loops measured from the straight shape at rest."""
    start = env.state.replace(pose=np.zeros(3), momentum=np.zeros(3), s=np.zeros(2), full=False)

    def shape(state):
        return state.s / env.joint_limit

    gaits = [trace(env, name, path, start, shape) for s in scales for name, path in loops(s).items()]
    return GaitPlanner(env, gaits, BASE, env.body_length)


CLONES = {"connenv/SnakeSwimmer-v0": {"rounds": 0}}
"""agents.imitate's diagnosis (agents.imitate.Budget's fields where not its defaults). No DAgger: the gait planner,
planned afresh inside a plan, returns the snake to its base shape, so it cannot label a state it did not plan for."""
