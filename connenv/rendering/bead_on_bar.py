"""pygame drawing of the bead on a turning bar: the bar through its pivot, the bead on it, and the target on the bar."""

from __future__ import annotations

import math

from connenv.rendering import Canvas, Renderer


class BeadRenderer(Renderer):
    """The bar at its angle with the pivot, the target as a ring on the bar (green while the bead is within the
    tolerances), the bead, and the time, r and r* in the corner."""

    def __init__(self, env):
        self.half_length = env.half_length
        self.canvas = Canvas(env, 1.25 * env.half_length)

    def draw(self, env):
        s = env.state
        r, theta, target, t, inside = float(s.y[0]), float(s.u[0]), float(s.target), s.t, bool(s.inside)
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        along = math.cos(theta), math.sin(theta)
        L = self.half_length
        ends = c.px(-L * along[0], -L * along[1]), c.px(L * along[0], L * along[1])
        pg.draw.line(c.screen, (60, 60, 60), *ends, c.pt(2.5))
        size = max(int(0.05 * L * c.scale), c.pt(2))
        ring = (77, 160, 77) if inside else (77, 110, 204)
        pg.draw.circle(c.screen, ring, c.px(target * along[0], target * along[1]), size + c.pt(2.5), c.pt(1.5))
        pg.draw.circle(c.screen, (204, 77, 77), c.px(r * along[0], r * along[1]), size)
        pg.draw.circle(c.screen, (0, 0, 0), c.px(0.0, 0.0), c.pt(2.5))
        text = f"t = {t:5.2f} s   r = {r:+5.3f} m   r* = {target:+5.3f} m"
        return c.caption(text)
