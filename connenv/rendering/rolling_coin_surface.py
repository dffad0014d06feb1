"""pygame drawing of the coin rolling on a surface: the coin from above on the surface's contour map, with its track."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import SIZE, Canvas, Renderer

CONTOURS = 16  # bands of the contour map over the arena's height range
LOW, HIGH = np.array([70.0, 120.0, 190.0]), np.array([235.0, 225.0, 200.0])  # colours of the lowest and highest band


class CoinSurfaceRenderer(Renderer):
    """The arena's contour map (height bands, lighter uphill, with their edges as contour lines), the target with
    its tolerance circle, the coin's track, and the coin seen from above: a bar of its diameter along the heading,
    with a dot at the contact point; the time, speed and distance in the corner."""

    def __init__(self, env):
        self.canvas = Canvas(env, env.arena)
        self.radius = env.system.radius
        self.background = self.pixels(self.contour_map(env.surface, env.arena))

    @staticmethod
    def point(env):
        return env.state.y[:2].copy()

    @staticmethod
    def contour_map(surface, arena):
        """(SIZE, SIZE, 3) uint8 image, rows from the top (y = arena) down: height bands and contour lines."""
        side = (np.arange(SIZE) + 0.5) / SIZE * 2 * arena - arena
        x, y = np.meshgrid(side, side[::-1])
        z = surface.height(x, y)[0]
        band = np.floor((z - z.min()) / max(np.ptp(z), 1e-12) * CONTOURS).clip(0, CONTOURS - 1)
        image = LOW + (HIGH - LOW) * (band / (CONTOURS - 1))[..., None]
        edge = np.zeros(band.shape, bool)
        edge[1:, :] |= band[1:, :] != band[:-1, :]
        edge[:, 1:] |= band[:, 1:] != band[:, :-1]
        image[edge] *= 0.7
        return image.astype(np.uint8)

    def pixels(self, image):
        return self.canvas.pygame.surfarray.make_surface(np.ascontiguousarray(np.transpose(image, (1, 0, 2))))

    def draw(self, env):
        s, track, tolerance = env.state, np.array(env.trace), env.tolerance
        y, theta, target, t = s.y, s.theta, s.target, s.t
        c, pg = self.canvas, self.canvas.pygame
        c.screen.blit(self.background, (0, 0))
        c.target(target, tolerance)
        if len(track) > 1:
            pg.draw.lines(c.screen, (60, 60, 60), False, [c.px(*p) for p in track], c.pt(1))
        heading = self.radius * np.array([math.sin(theta), math.cos(theta)])
        contact = np.asarray(y[:2])
        pg.draw.line(c.screen, (150, 40, 40), c.px(*(contact - heading)), c.px(*(contact + heading)), c.pt(2.5))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*contact), c.pt(2))
        distance = math.hypot(target[0] - y[0], target[1] - y[1])
        text = f"t = {t:5.2f} s   v = {self.radius * y[3]:5.2f} m/s   distance = {distance:5.2f} m"
        return c.caption(text)
