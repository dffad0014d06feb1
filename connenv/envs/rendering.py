"""pygame drawing for the envs, as in Gymnasium's classic control (pygame is an optional dependency)."""

from __future__ import annotations

import math

import numpy as np
from gymnasium.error import DependencyNotInstalled

SIZE = 500


class Canvas:
    """A square pygame surface in world coordinates (metres, y up), shown or returned as an array."""

    def __init__(self, half_width: float, center_y: float, render_mode: str, fps: int):
        try:
            import pygame
        except ImportError as e:
            raise DependencyNotInstalled('pygame is not installed, run `pip install "gymnasium[classic-control]"`') from e
        self.pygame, self.render_mode, self.fps = pygame, render_mode, fps
        self.scale = SIZE / (2 * half_width)
        self.center_y = center_y
        pygame.font.init()
        if render_mode == "human":
            pygame.display.init()
            self.screen = pygame.display.set_mode((SIZE, SIZE))
        else:
            self.screen = pygame.Surface((SIZE, SIZE))
        self.clock = pygame.time.Clock()
        self.font = pygame.font.Font(None, 22)

    def px(self, x, y):
        return int(SIZE / 2 + x * self.scale), int(SIZE / 2 - (y - self.center_y) * self.scale)

    def show(self):
        if self.render_mode == "human":
            self.pygame.event.pump()
            self.clock.tick(self.fps)
            self.pygame.display.flip()
            return None
        return np.transpose(np.array(self.pygame.surfarray.pixels3d(self.screen)), axes=(1, 0, 2))

    def close(self):
        if self.render_mode == "human":
            self.pygame.display.quit()


class SwingRenderer:
    """Pivot, rod and bob; the reachable radii as a shaded band; the time in the corner."""

    def __init__(self, r_max: float, render_mode: str, fps: int):
        self.canvas = Canvas(1.15 * r_max, 0.0, render_mode, fps)

    def draw(self, theta: float, r: float, r_min: float, t: float):
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        pivot = c.px(0.0, 0.0)
        r_max = SIZE / (2 * 1.15 * c.scale)
        pg.draw.circle(c.screen, (235, 235, 245), pivot, int(r_max * c.scale), 0)
        pg.draw.circle(c.screen, (255, 255, 255), pivot, int(r_min * c.scale), 0)
        bob = c.px(r * math.sin(theta), -r * math.cos(theta))
        pg.draw.line(c.screen, (60, 60, 60), pivot, bob, 3)
        pg.draw.circle(c.screen, (204, 77, 77), bob, 12)
        pg.draw.circle(c.screen, (0, 0, 0), pivot, 5)
        c.screen.blit(c.font.render(f"t = {t:5.2f} s   r = {r:4.2f} m", True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()
