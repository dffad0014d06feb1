"""pygame drawing of Kozlov's shell: the shell, its inner mass, the target and the wake."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer

OUTLINE_POINTS = 64


class KozlovShellRenderer(Renderer):
    """The ellipse with its body x axis, the inner mass, the target with its success circle, and the path of the
    centre (the wake) drawn over the shell; the view is centred between the start and the target."""

    def __init__(self, env):
        a, b = env.full_system.a, env.full_system.b
        self.canvas = Canvas(env, 0.5 * env.reach + a + 0.3)
        angles = np.linspace(0.0, 2.0 * math.pi, OUTLINE_POINTS, endpoint=False)
        self.outline = np.stack([a * np.cos(angles), b * np.sin(angles)], axis=-1)  # body frame
        self.a = a

    @staticmethod
    def point(env):
        return tuple(env.state.pose[:2])

    def draw(self, env):
        s, path, success_radius = env.state, env.trace, env.success_radius
        pose, u, target, t = s.pose, s.u, s.target, s.t
        c, pg = self.canvas, self.canvas.pygame
        c.center_x, c.center_y = 0.5 * (path[0][0] + target[0]), 0.5 * (path[0][1] + target[1])
        c.screen.fill((255, 255, 255))
        x, y, theta = pose
        rotation = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])

        def to_space(points):
            return np.asarray(points) @ rotation.T + (x, y)

        outline = [c.px(*p) for p in to_space(self.outline)]
        pg.draw.polygon(c.screen, (225, 232, 245), outline)
        pg.draw.polygon(c.screen, (70, 110, 160), outline, c.pt(1.5))
        nose = to_space([(0.0, 0.0), (self.a, 0.0)])
        pg.draw.line(c.screen, (70, 110, 160), c.px(*nose[0]), c.px(*nose[1]), c.pt(1))
        c.target(target, success_radius)
        if len(path) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in path], c.pt(1))
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*to_space([u])[0]), c.pt(3.5))
        distance = math.hypot(target[0] - x, target[1] - y)
        return c.caption(f"t = {t:5.2f} s   distance = {distance:4.2f} m")
