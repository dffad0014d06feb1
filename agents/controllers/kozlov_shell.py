"""Reference controller of KozlovShell-v0: the gait planner (agents.gaits) on the shell's gaits.

The mass reaches each vertex in one step; every gait starts at the box corner
BASE, which a reset (mass at the centre) never gives. A loop turns the shell; a figure-eight, a loop followed by its
mirror image run the other way, translates it without net turn (the two turns cancel exactly, by the mirror symmetry
of the ellipse). At the defaults the figure-eight X through the box's corners moves the shell 0.040 m per cycle of 4
steps, 0.13 rad off body −y (0.010 m per step); the loop O turns it by 1.04 rad in 4 steps, the triangles by 0.52 rad
in 3.
"""

from __future__ import annotations

import numpy as np

from agents.gaits import Gait, GaitPlanner, trace

BASE = (1.0, -1.0)  # action units: the corner u = (u1_max, −u2_max) where every shell gait starts and ends
SCALES = (1.0, 0.5, 0.25, 0.125)  # sizes of the gaits, as fractions of the box


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


def gait_library(env, scales=SCALES) -> list[Gait]:
    """The shell's loops at every scale, each measured from BASE."""
    start = env.state.replace(pose=np.zeros(3), momentum=np.zeros(3), u=np.array(BASE) * env.u_max, full=False)

    def shape(state):
        return state.u / env.u_max

    return [trace(env, name, path, start, shape) for s in scales for name, path in loops(s).items()]



def gaits(env):
    return GaitPlanner(env, gait_library(env), BASE)
