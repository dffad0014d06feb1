"""Kane and Scher's motion for FallingCat-v0: bend, sweep the bend once around the spine, unbend.

Bending straight out or back (γ fixed) does not turn the cat; one sweep of the bend direction γ at the bend β₀ rolls
it by −2π f(β₀) per turn counterclockwise (`connenv.systems.falling_cat`). The plan, made at the start of an
episode from the observed roll r (the cat frame's E = Hᵀ g: r = atan2(E₃₂, E₃₃)):

1. straighten, if the cat starts bent (radially: no roll);
2. bend out along γ = 0 at full speed to β₀;
3. run the circle of radius β₀ as n equal chords, one per step, counterclockwise if r > 0 (the roll decreases)
   and clockwise if r < 0, n the fewest with a chord no longer than one step's bend;
4. bend back to straight along γ = 0.

β₀ is the root (brentq) of the *discrete* loop's roll, Σ over the chords of the env's own closed-form roll per
segment, equal to −r: the chords cut inside the circle, so β₀ is a little above the circle's value
(`falling_cat.bend_for_roll`, which brackets it). Every step is the env's exact step, so the cat lands with the
roll the root leaves, to rounding.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from agents.planning import RowPlanner
from connenv.systems import falling_cat

DONE = 1e-9  # rad: a roll below it needs no loop


class KaneScher(RowPlanner):
    """FallingCat-v0's controller: predict(obs) → (ṡ/max_bend_speed, state)."""

    def __init__(self, env):
        env = env.unwrapped
        self.dt, self.speed, self.max_bend = env.dt, env.max_shape_speed, env.max_bend
        self.inertias = env.inertias
        self.pieces = env.system.exact_segment.keywords["pieces"]
        self.plans = {}  # row of the (batched) observation -> the remaining bend velocities (k, 2)

    def act(self, i, obs):
        if obs[11] == 1.0 or i not in self.plans:  # the start of an episode
            E, s = obs[:9].reshape(3, 3), obs[9:11] * self.max_bend
            self.plans[i] = self.plan(math.atan2(E[2, 1], E[2, 2]), s)
        plan = self.plans[i]
        if not len(plan):
            return np.zeros(2)
        self.plans[i] = plan[1:]
        return plan[0] / self.speed

    def radial(self, start, end):
        """Bend velocities (k, 2) along the straight line from start to end, at full speed but the last step."""
        step = self.speed * self.dt
        length = float(np.linalg.norm(end - start))
        if length == 0.0:
            return np.zeros((0, 2))
        full = math.floor(length / step)
        moves = [step] * full + ([length - full * step] if length > full * step else [])
        return np.array(moves)[:, None] * (end - start) / length / self.dt

    def chords(self, beta, n, sense):
        """The circle of radius β as n chord velocities (n, 2), from γ = 0, counterclockwise for sense = +1."""
        angles = sense * 2 * math.pi * np.arange(n + 1) / n
        points = beta * np.stack([np.cos(angles), np.sin(angles)], -1)
        return points[:-1], np.diff(points, axis=0) / self.dt

    def loop_roll(self, beta, n, sense):
        """The roll of the circle's n chords at β, stepped by the env's closed form."""
        starts, velocities = self.chords(beta, n, sense)
        return float(np.sum(falling_cat.segment_roll(starts, velocities, self.dt, **self.inertias,
                                                     pieces=self.pieces)))  # fmt: skip

    def bend(self, roll):
        """β₀ and n for which the discrete loop rolls the cat by −roll."""
        step, sense = self.speed * self.dt, math.copysign(1.0, roll)
        guess = falling_cat.bend_for_roll(roll, **self.inertias)
        n = max(3, math.ceil(2 * math.pi * guess / step))
        while True:
            high = min(2 * guess, self.max_bend)
            beta = brentq(lambda b: self.loop_roll(b, n, sense) + roll, 0.5 * guess, high, xtol=1e-14, rtol=1e-15)
            if 2 * beta * math.sin(math.pi / n) <= step:
                return beta, n
            n += 1

    def plan(self, roll, s):
        """The bend velocities (k, 2) from the bend s at the roll r to straight at roll 0."""
        origin = np.zeros(2)
        straighten = self.radial(s, origin)
        if abs(roll) <= DONE:
            return straighten
        beta, n = self.bend(roll)
        out = np.array([beta, 0.0])
        _, loop = self.chords(beta, n, math.copysign(1.0, roll))
        return np.concatenate([straighten, self.radial(origin, out), loop, self.radial(out, origin)])


def kane_scher(env):
    return KaneScher(env)
