"""pygame drawing of the snake swimmer: the three elliptic links, the target and the wake."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer

OUTLINE_POINTS = 48
WAKE_COLOURS = ((200, 130, 130), (130, 130, 130), (110, 150, 200))  # rear, middle, front


class SnakeSwimmerRenderer(Renderer):
    """Each link an ellipse (the middle one darker, the front one's axis marked), the target with its success
    circle, and the wake: the path of every link's centre since reset; the view is centred between the start and
    the target."""

    def __init__(self, env):
        a, b = env.full_system.a, env.full_system.b
        self.canvas = Canvas(env, 0.5 * env.reach + 4.0 * a)
        angles = np.linspace(0.0, 2.0 * math.pi, OUTLINE_POINTS, endpoint=False)
        self.outline = np.stack([a * np.cos(angles), b * np.sin(angles)], axis=-1)  # a link's frame
        self.a = a

    @staticmethod
    def point(env):
        """The links' (x, y, φ): rear, middle and front."""
        return env.full_system.link_poses(env.state.pose, env.state.s)

    def draw(self, env):
        links, wake = env.trace[-1], [links[:, :2] for links in env.trace]  # the wake: the centres, step by step
        target, success_radius, t = env.state.target, env.success_radius, env.state.t
        c, pg = self.canvas, self.canvas.pygame
        start = wake[0][1]
        c.center_x, c.center_y = 0.5 * (start[0] + target[0]), 0.5 * (start[1] + target[1])
        c.screen.fill((255, 255, 255))
        c.target(target, success_radius)
        if len(wake) > 1:
            for i, colour in enumerate(WAKE_COLOURS):
                pg.draw.lines(c.screen, colour, False, [c.px(*centres[i]) for centres in wake], c.pt(1))
        for i, (x, y, phi) in enumerate(links):
            rotation = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
            outline = [c.px(*p) for p in self.outline @ rotation.T + (x, y)]
            pg.draw.polygon(c.screen, (150, 175, 215) if i == 1 else (215, 225, 242), outline)
            pg.draw.polygon(c.screen, (70, 110, 160), outline, c.pt(1))
        x, y, phi = links[2]
        nose = (x + self.a * math.cos(phi), y + self.a * math.sin(phi))
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*nose), c.pt(3))
        middle = links[1]
        distance = math.hypot(target[0] - middle[0], target[1] - middle[1])
        return c.caption(f"t = {t:5.2f} s   distance = {distance:4.2f} m")
