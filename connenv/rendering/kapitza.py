"""pygame drawing of Kapitza's pendulum."""

from __future__ import annotations

import math

from connenv.rendering import Canvas, Renderer


class KapitzaRenderer(Renderer):
    """The pivot's travel as a bar, the pivot, rod and bob, the goal (the bob inverted over the pivot) as a ring; the
    time in the corner."""

    def __init__(self, env):
        self.length, self.a_max = env.system.length, env.a_max
        self.canvas = Canvas(env, 1.3 * (self.length + self.a_max))

    def draw(self, env):
        theta, u, t = env.state.y[0], env.state.u, env.state.t
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        a = self.a_max
        pg.draw.rect(c.screen, (225, 225, 235), pg.Rect(*c.px(-a, a), 2 * a * c.scale + 1, 2 * a * c.scale + 1))
        pivot = c.px(u[0], u[1])
        bob = c.px(u[0] + self.length * math.sin(theta), u[1] - self.length * math.cos(theta))
        pg.draw.line(c.screen, (60, 60, 60), pivot, bob, c.pt(1.5))
        pg.draw.circle(c.screen, (204, 77, 77), bob, c.pt(6))
        goal = c.px(u[0], u[1] + self.length)
        pg.draw.circle(c.screen, (40, 140, 40), goal, c.pt(8), c.pt(1))  # over the bob: it rings it when held
        pg.draw.circle(c.screen, (0, 0, 0), pivot, c.pt(2.5))
        return c.caption(f"t = {t:5.2f} s")
