"""pygame drawing of Elroy's beanie."""

from __future__ import annotations

import math

from connenv.rendering import SIZE, Canvas, Renderer


class BeanieRenderer(Renderer):
    """The body (a disk with a radius drawn at θ), the beanie on it (a smaller disk with its propeller at θ + ψ),
    the target θ* as a dashed line, and the beanie's winding ψ/2π counted beside; a bar shows the hold."""

    def __init__(self, env):
        self.canvas = Canvas(env, 1.5)

    def draw(self, env):
        s = env.state
        theta, psi, target, momentum, t, held = float(s.g[0]), float(s.s[0]), s.target, s.momentum, s.t, s.held
        held = held / env.hold_time
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))

        def ray(angle, length):
            return c.px(length * math.cos(angle), length * math.sin(angle))

        pg.draw.circle(c.screen, (225, 225, 235), c.px(0.0, 0.0), int(1.0 * c.scale))
        pg.draw.circle(c.screen, (60, 60, 60), c.px(0.0, 0.0), int(1.0 * c.scale), c.pt(1))
        for k in range(12):  # dashes toward the target, past the body's rim
            pg.draw.line(c.screen, (90, 170, 90), ray(target, 0.1 * k), ray(target, 0.1 * k + 0.05), c.pt(1.5))
        pg.draw.line(c.screen, (60, 60, 120), c.px(0.0, 0.0), ray(theta, 1.0), c.pt(2.5))  # the body's mark
        pg.draw.circle(c.screen, (250, 230, 120), c.px(0.0, 0.0), int(0.4 * c.scale))
        pg.draw.circle(c.screen, (150, 120, 40), c.px(0.0, 0.0), int(0.4 * c.scale), c.pt(1))
        for blade in (0.0, math.pi):  # the beanie's propeller, at θ + ψ in space
            pg.draw.line(c.screen, (204, 77, 77), c.px(0.0, 0.0), ray(theta + psi + blade, 0.38), c.pt(2))
        left, top, length, height = c.pt(5), SIZE - c.pt(15), c.pt(100), c.pt(7)
        pg.draw.rect(c.screen, (220, 220, 230), (left, top, length, height))
        pg.draw.rect(c.screen, (90, 170, 90), (left, top, min(int(held * length), length), height))
        lines = [f"t = {t:5.2f} s   θ* − θ = {math.remainder(target - theta, 2 * math.pi):+6.3f} rad",
                 f"beanie turns ψ/2π = {psi / (2 * math.pi):+7.2f}   μ = {momentum:+5.2f}"]  # fmt: skip
        return c.caption(*lines)
