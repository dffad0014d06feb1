"""pygame drawing for the envs, as in Gymnasium's classic control (pygame is an optional dependency): the Canvas
every renderer draws on, and one module per env module (connenv.rendering.swing draws connenv.envs.swing's envs),
which the env names as its renderer; pygame loads on the first render."""

from __future__ import annotations

import numpy as np
from gymnasium.error import DependencyNotInstalled

SIZE = 500
POINTS = 250  # a canvas is POINTS points wide: widths, radii and text are in points, so they scale with SIZE


class Canvas:
    """A square pygame surface in world coordinates (metres, y up), shown or returned as an array."""

    def __init__(self, env, half_width: float, center_y: float = 0.0, center_x: float = 0.0):
        """A canvas for env (its render_mode and fps), half_width metres each side of (center_x, center_y)."""
        render_mode, fps = env.render_mode, env.metadata["render_fps"]
        try:
            import pygame
        except ImportError as e:
            raise DependencyNotInstalled(
                'pygame is not installed, run `pip install "gymnasium[classic-control]"`'
            ) from e
        self.pygame, self.render_mode, self.fps = pygame, render_mode, fps
        self.scale = SIZE / (2 * half_width)
        self.center_x, self.center_y = center_x, center_y
        pygame.font.init()
        if render_mode == "human":
            pygame.display.init()
            self.screen = pygame.display.set_mode((SIZE, SIZE))
        else:
            self.screen = pygame.Surface((SIZE, SIZE))
        self.clock = pygame.time.Clock()
        self.font = pygame.font.Font(None, self.pt(13))

    @staticmethod
    def pt(points: float) -> int:
        """A length in points as whole pixels, at least one: lines stay visible in the docs' animations."""
        return max(1, round(points * SIZE / POINTS))

    def px(self, x, y):
        return int(SIZE / 2 + (x - self.center_x) * self.scale), int(SIZE / 2 - (y - self.center_y) * self.scale)

    def show(self):
        if self.render_mode == "human":
            self.pygame.event.pump()
            self.clock.tick(self.fps)
            self.pygame.display.flip()
            return None
        return np.transpose(np.array(self.pygame.surfarray.pixels3d(self.screen)), axes=(1, 0, 2))

    def caption(self, *lines: str):
        """The lines of text in the top left corner, on white to read over any background, and the frame shown
        (`show`)."""
        for k, text in enumerate(lines):
            label = self.font.render(text, True, (0, 0, 0), (255, 255, 255))
            self.screen.blit(label, (self.pt(5), self.pt(5) + self.font.get_linesize() * k))
        return self.show()

    def target(self, position, radius: float):
        """A target: its disc of `radius` metres (the tolerance), ringed and with its centre marked, and never smaller
        than a marker, so that it shows however far the view is zoomed out."""
        centre, pg = self.px(*position), self.pygame
        size = max(int(radius * self.scale), self.pt(6))
        pg.draw.circle(self.screen, (200, 230, 200), centre, size)
        pg.draw.circle(self.screen, (40, 140, 40), centre, size, self.pt(1))
        pg.draw.circle(self.screen, (40, 140, 40), centre, self.pt(1.5))

    def close(self):
        if self.render_mode == "human":
            self.pygame.display.quit()


class Renderer:
    """Base of the renderers: an env makes its renderer on its first render, ``renderer(env)``, which then draws the
    env's state, ``draw(env)``, on its ``canvas`` (closing closes it). A renderer that draws a track behind the body
    gives a static ``point(env)`` (called on the class, before any renderer exists): while rendering, the env keeps
    the point of each state since reset (``env.trace``)."""

    canvas: Canvas
    point = None

    def close(self):
        self.canvas.close()


class CoordinatePlot(Renderer):
    """The coordinates against time: each q and u over the last WINDOW seconds (from the left edge, scrolling once
    the window is full), scaled to the range they have covered, with a dot at its value now; or, with a user's
    ``draw(state, canvas)``, that picture on a Canvas spanning [-1, 1]² (metres by default: the callback may change
    ``canvas.scale``)."""

    WINDOW = 10.0  # s of history shown
    COLORS = ((204, 77, 77), (77, 110, 204), (77, 160, 77), (200, 140, 40), (140, 77, 180), (60, 60, 60))

    def __init__(self, env):
        self.canvas = Canvas(env, 1.0)
        self.labels = [f"q{i}" for i in range(env.n)] + [f"u{i}" for i in range(env.m)]
        self.user_draw, self.history = env.draw, []

    def draw(self, env):
        state = env.state_dict(env.state)
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        if self.user_draw is not None:
            self.user_draw(state, c)
            return c.show()
        if self.history and state["t"] < self.history[-1][0]:  # a reset
            self.history = []
        self.history.append((state["t"], *state["q"], *state["u"]))
        trace = np.array([row for row in self.history if row[0] >= state["t"] - self.WINDOW])
        self.history = [tuple(row) for row in trace]
        low, high = trace[:, 1:].min(), trace[:, 1:].max()
        half = max(0.5 * (high - low), 1e-9)
        mid = 0.5 * (high + low)
        margin, top = c.pt(5), c.pt(20)
        height = SIZE - top - c.pt(10) - c.font.get_linesize()
        x = margin + (trace[:, 0] - trace[0, 0]) / self.WINDOW * (SIZE - 2 * margin)
        for k, label in enumerate(self.labels):
            y = top + height * (0.5 - 0.45 * (trace[:, 1 + k] - mid) / half)
            color = self.COLORS[k % len(self.COLORS)]
            points = list(zip(x.astype(int), y.astype(int)))
            if len(points) > 1:
                pg.draw.lines(c.screen, color, False, points, c.pt(1))
            pg.draw.circle(c.screen, color, points[-1], c.pt(2.5))  # the value now, shown from the first frame
            text = c.font.render(f"{label} = {trace[-1, 1 + k]:+.3f}", True, color)
            c.screen.blit(text, (margin + c.pt(60) * k, SIZE - margin - c.font.get_linesize()))
        return c.caption(f"t = {state['t']:5.2f} s   range [{low:.3g}, {high:.3g}]")
