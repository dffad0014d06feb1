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

    def __init__(self, a: float, b: float, reach: float, render_mode: str, fps: int):
        self.canvas = Canvas(0.5 * reach + 4.0 * a, 0.0, render_mode, fps)
        angles = np.linspace(0.0, 2.0 * math.pi, OUTLINE_POINTS, endpoint=False)
        self.outline = np.stack([a * np.cos(angles), b * np.sin(angles)], axis=-1)  # a link's frame
        self.a = a

    def draw(self, links, target, wake, success_radius: float, t: float):
        """links: the (x, y, φ) of the rear, middle and front links; wake: their centres (3, 2) step by step."""
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
