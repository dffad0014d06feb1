"""pygame drawing of the tube."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer


class TubeRenderer(Renderer):
    """The unit sphere of tangent directions seen from the side of B₀ above the start tangent T₀: the trace of the tip's
    tangent T (solid in front, faint behind), the tip frame at T (N red, B green, T blue from the centre), and at T₀
    the start normal (grey) and the target normal R₀ Rz(ψ*) e₁ (pink)."""

    TILT = 1.0  # rad: the view axis from T₀ toward B₀: loops turning toward B₀ face the viewer, not edge-on
    COLORS = ((204, 77, 77), (77, 160, 77), (77, 110, 204))  # N, B, T

    def __init__(self, env):
        self.canvas = Canvas(env, 1.5)

    @staticmethod
    def point(env):
        return env.state.g[2::3].copy()

    def draw(self, env):
        s, trace = env.state, np.array(env.trace)
        R, R0, t, twist, target = s.g.reshape(3, 3), s.R0.reshape(3, 3), s.t, env.describe(s)["twist"], s.target
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        cos, sin = math.cos(self.TILT), math.sin(self.TILT)
        view = np.array([[-1.0, 0.0, 0.0], [0.0, -cos, sin], [0.0, sin, cos]]) @ R0.T  # space → screen (x, y, depth)
        pg.draw.circle(c.screen, (235, 235, 245), c.px(0.0, 0.0), int(c.scale))
        pg.draw.circle(c.screen, (120, 120, 120), c.px(0.0, 0.0), int(c.scale), c.pt(1))
        ring = view @ R0 @ np.stack([np.cos(np.linspace(0, 2 * np.pi, 73)), np.sin(np.linspace(0, 2 * np.pi, 73)),
                                     np.zeros(73)])  # fmt: skip
        pg.draw.lines(c.screen, (200, 200, 210), True, [c.px(x, y) for x, y in ring[:2].T], c.pt(1))  # T₀'s equator
        points = trace @ view.T
        for a, b in zip(points[:-1], points[1:]):
            colour = (40, 40, 40) if a[2] + b[2] >= 0 else (190, 190, 190)
            pg.draw.line(c.screen, colour, c.px(*a[:2]), c.px(*b[:2]), c.pt(1))
        start, n0 = view @ R0[:, 2], view @ R0[:, 0]
        n_target = view @ R0 @ np.array([math.cos(target), math.sin(target), 0.0])
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*start[:2]), c.pt(2.5))
        for direction, colour in ((n0, (150, 150, 150)), (n_target, (230, 110, 150))):
            pg.draw.line(c.screen, colour, c.px(*start[:2]), c.px(*(start + 0.4 * direction)[:2]), c.pt(2))
        frame = view @ R
        tip = frame[:, 2]
        pg.draw.line(c.screen, self.COLORS[2], c.px(0.0, 0.0), c.px(*tip[:2]), c.pt(1.5))
        for i in (0, 1):
            pg.draw.line(c.screen, self.COLORS[i], c.px(*tip[:2]), c.px(*(tip + 0.3 * frame[:, i])[:2]), c.pt(2))
        pg.draw.circle(c.screen, self.COLORS[2], c.px(*tip[:2]), c.pt(3), 0 if tip[2] >= 0 else c.pt(1))
        text = f"t = {t:5.2f} s   twist = {twist:+5.3f} rad   target = {target:+5.3f} rad"
        return c.caption(text)
