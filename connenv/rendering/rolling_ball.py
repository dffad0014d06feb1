"""pygame drawing of the rolling ball."""

from __future__ import annotations

import numpy as np

from connenv.rendering import Canvas, Renderer


class RollingBallRenderer(Renderer):
    """Top view following the ball: the path it has rolled, the ball with its body axes (solid where they point
    up, hollow where down) and, in the corner, the target attitude's axes for comparison."""

    COLORS = ((204, 77, 77), (77, 160, 77), (77, 110, 204))  # body x, y, z

    def __init__(self, env):
        self.radius = env.system.radius
        self.canvas = Canvas(env, 4.0 * self.radius)

    @staticmethod
    def point(env):
        return env.state.position

    def axes(self, R, center, size):
        """Each body axis as a line from the centre to its tip, seen from above, and a marker at the tip."""
        c, pg = self.canvas, self.canvas.pygame
        for i in np.argsort(R[2]):  # the axes pointing down first, so that the upper ones are drawn on top
            tip = center + size * R[:2, i]
            pg.draw.line(c.screen, self.COLORS[i], c.px(*center), c.px(*tip), c.pt(1.5))
            pg.draw.circle(c.screen, self.COLORS[i], c.px(*tip), c.pt(3), 0 if R[2, i] >= 0 else c.pt(1))

    def draw(self, env):
        s, path = env.state, np.array(env.trace)
        R, R_target, t, angle_error = s.R, s.R_target, s.t, s.angle_error
        c, pg = self.canvas, self.canvas.pygame
        c.center_x, c.center_y = path[-1]
        c.screen.fill((255, 255, 255))
        if len(path) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in path], c.pt(1))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(0.0, 0.0), c.pt(2))  # the origin
        pg.draw.circle(c.screen, (235, 235, 245), c.px(*path[-1]), int(self.radius * c.scale))
        pg.draw.circle(c.screen, (60, 60, 60), c.px(*path[-1]), int(self.radius * c.scale), c.pt(1))
        self.axes(R, path[-1], self.radius)
        inset = path[-1] + np.array([2.9, -2.9]) * self.radius
        pg.draw.circle(c.screen, (60, 60, 60), c.px(*inset), int(0.8 * self.radius * c.scale), c.pt(1))
        self.axes(R_target, inset, 0.8 * self.radius)
        text = f"t = {t:5.2f} s   angle error = {angle_error:5.3f} rad   (target: lower right)"
        return c.caption(text)
