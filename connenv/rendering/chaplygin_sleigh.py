"""pygame drawing of the Chaplygin sleigh."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import SIZE, Canvas, Renderer


class SleighRenderer(Renderer):
    """Top view: the track of the knife edge, the sled (its outline, the knife edge at P, the mass's box or rail
    around C), the mass and the target disc."""

    def __init__(self, env):
        self.offset, self.rail, self.box, self.tolerance = env.system.offset, env.rail, env.box, env.tolerance
        self.canvas = Canvas(env, 3.0)

    @staticmethod
    def point(env):
        return tuple(env.state.y[:2])

    def draw(self, env):
        c, pg, s = self.canvas, self.canvas.pygame, env.state
        (x, y, phi), u, target, t = s.y[:3], s.u, s.target, s.t
        e1, e2 = np.array([math.cos(phi), math.sin(phi)]), np.array([-math.sin(phi), math.cos(phi)])
        P = np.array([x, y])
        C = P + self.offset * e1
        c.center_x, c.center_y = 0.5 * (P + target)  # the sled and the target in view
        c.scale = SIZE / (2.0 * max(2.5, 0.6 * float(np.hypot(*(P - target))) + 1.0))
        c.screen.fill((255, 255, 255))
        c.target(target, self.tolerance)
        if len(env.trace) > 1:
            pg.draw.lines(c.screen, (110, 110, 110), False, [c.px(*p) for p in env.trace], c.pt(1))
        half = 1.2 * self.rail
        front = self.offset + 1.2 * max(self.box, 0.1)
        corners = [P - 0.1 * e1 + half * e2, P + front * e1 + half * e2, P + front * e1 - half * e2,
                   P - 0.1 * e1 - half * e2]
        pg.draw.polygon(c.screen, (225, 225, 240), [c.px(*p) for p in corners])
        pg.draw.polygon(c.screen, (60, 60, 90), [c.px(*p) for p in corners], c.pt(1))
        knife = c.px(*(P - 0.15 * e1)), c.px(*(P + 0.15 * e1))  # the knife edge
        pg.draw.line(c.screen, (40, 40, 40), *knife, c.pt(2.5))
        b, r = self.box, self.rail  # the mass's box (a rail if b = 0)
        box = [C + b * e1 + r * e2, C + b * e1 - r * e2, C - b * e1 - r * e2, C - b * e1 + r * e2]
        pg.draw.lines(c.screen, (120, 120, 160), True, [c.px(*p) for p in box], c.pt(1))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*C), c.pt(1.5))
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*(C + u[0] * e1 + u[1] * e2)), c.pt(4))
        return c.caption(f"t = {t:5.2f} s")
