"""pygame drawing of the skier on its trail."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer


class SkierRenderer(Renderer):
    """The trail, and the skier as a stick figure: legs bent at the knee as h drops, torso and head along the normal."""

    def __init__(self, env):
        self.trail, self.h_max = trail, h_max = env.trail, env.h_max
        xs = np.linspace(trail.lo, trail.hi, 300)
        ys = trail.profile(xs)[0]
        half = 0.55 * max(trail.hi - trail.lo, ys.max() - ys.min() + 2.5 * h_max)
        self.canvas = Canvas(env, half, 0.5 * (ys.max() + ys.min()) + h_max, 0.5 * (trail.lo + trail.hi))
        self.points = [self.canvas.px(x, y) for x, y in zip(xs, ys)]

    def draw(self, env):
        x, h, t = env.state.y[0], env.state.h, env.state.t
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        pg.draw.lines(c.screen, (70, 110, 160), False, self.points, c.pt(2))
        f, f1, _, _ = self.trail.derivatives(x)
        sigma = math.sqrt(1.0 + f1 * f1)
        tangent, normal = np.array([1.0, f1]) / sigma, np.array([-f1, 1.0]) / sigma
        foot = np.array([x, f])
        hip = foot + h * normal  # the barycentre
        bend = math.sqrt(max((0.5 * self.h_max) ** 2 - (0.5 * h) ** 2, 0.0))  # knee out, legs of length h_max
        knee = foot + 0.5 * h * normal + bend * tangent
        neck = hip + 0.45 * self.h_max * normal
        for a, b in ((foot, knee), (knee, hip), (hip, neck)):
            pg.draw.line(c.screen, (40, 40, 40), c.px(*a), c.px(*b), c.pt(2))
        ski = c.px(*(foot - 0.4 * tangent)), c.px(*(foot + 0.4 * tangent))
        pg.draw.line(c.screen, (40, 40, 40), *ski, c.pt(1.5))
        head = neck + 0.15 * self.h_max * normal
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*head), max(int(0.15 * self.h_max * c.scale), c.pt(1.5)))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*hip), c.pt(2))
        return c.caption(f"t = {t:5.2f} s   h = {h:4.2f} m")
