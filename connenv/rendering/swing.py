"""pygame drawing of the swing."""

from __future__ import annotations

import math

from connenv.rendering import SIZE, Canvas, Renderer


class SwingRenderer(Renderer):
    """Pivot, rod and bob; the reachable radii as a shaded band, labelled over the pivot; the time and radius in the
    corner."""

    def __init__(self, env):
        self.canvas = Canvas(env, 1.15 * env.r_max)

    def draw(self, env):
        theta, r, r_min, t = env.state.y[0], env.state.r, env.r_min, env.state.t
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        pivot = c.px(0.0, 0.0)
        r_max = SIZE / (2 * 1.15 * c.scale)
        pg.draw.circle(c.screen, (235, 235, 245), pivot, int(r_max * c.scale), 0)
        pg.draw.circle(c.screen, (255, 255, 255), pivot, int(r_min * c.scale), 0)
        label = c.font.render(f"reachable r: {r_min:.2f}–{r_max:.2f} m", True, (90, 90, 120))
        c.screen.blit(label, label.get_rect(center=c.px(0.0, 0.5 * (r_min + r_max))))
        bob = c.px(r * math.sin(theta), -r * math.cos(theta))
        pg.draw.line(c.screen, (60, 60, 60), pivot, bob, c.pt(1.5))
        pg.draw.circle(c.screen, (204, 77, 77), bob, c.pt(6))
        pg.draw.circle(c.screen, (0, 0, 0), pivot, c.pt(2.5))
        return c.caption(f"t = {t:5.2f} s   r = {r:4.2f} m")
