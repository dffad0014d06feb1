"""pygame drawing of the rolling coin from above."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer


class CoinRenderer(Renderer):
    """Top view: the track of the contact point, the coin as a segment along its heading (its edge seen from
    above) with a tick at the rolled angle φ, and the target pose as a hollow outline."""

    def __init__(self, env):
        self.radius = env.radius
        self.canvas = Canvas(env, 4.0)

    @staticmethod
    def point(env):
        return env.state.g.copy()

    def coin(self, position, theta, colour, width):
        c, pg = self.canvas, self.canvas.pygame
        heading = self.radius * np.array([math.sin(theta), math.cos(theta)])
        pg.draw.line(c.screen, colour, c.px(*(position - heading)), c.px(*(position + heading)), width)
        pg.draw.circle(c.screen, colour, c.px(*(position + heading)), c.pt(2.5))  # the front

    def draw(self, env):
        s, track = env.state, np.array(env.trace)
        (theta, phi), target, t = s.s, s.target, s.t
        c, pg = self.canvas, self.canvas.pygame
        c.center_x, c.center_y = 0.5 * (track[-1] + target[:2])
        c.screen.fill((255, 255, 255))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(0.0, 0.0), c.pt(1.5))  # the origin
        c.target(target[:2], 0.05)
        self.coin(target[:2], target[2], (90, 160, 90), c.pt(1.5))
        if len(track) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in track], c.pt(1))
        self.coin(track[-1], theta, (60, 60, 120), c.pt(3))
        tick = track[-1] + self.radius * math.cos(phi) * np.array([math.sin(theta), math.cos(theta)])
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*tick), c.pt(2))  # a point of the rim: where φ has turned it
        text = f"t = {t:5.2f} s   distance = {np.hypot(*(target[:2] - track[-1])):5.3f} m"
        return c.caption(text)
