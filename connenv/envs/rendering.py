"""pygame drawing for the envs, as in Gymnasium's classic control (pygame is an optional dependency)."""

from __future__ import annotations

import math

import numpy as np
from gymnasium.error import DependencyNotInstalled

SIZE = 500


class Canvas:
    """A square pygame surface in world coordinates (metres, y up), shown or returned as an array."""

    def __init__(self, half_width: float, center_y: float, render_mode: str, fps: int, center_x: float = 0.0):
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
        self.font = pygame.font.Font(None, 22)

    def px(self, x, y):
        return int(SIZE / 2 + (x - self.center_x) * self.scale), int(SIZE / 2 - (y - self.center_y) * self.scale)

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


class SkierRenderer:
    """The trail, and the skier as a stick figure: legs bent at the knee as h drops, torso and head along the normal."""

    def __init__(self, trail, h_max: float, render_mode: str, fps: int):
        self.trail, self.h_max = trail, h_max
        xs = np.linspace(trail.lo, trail.hi, 300)
        ys = trail.profile(xs)[0]
        half = 0.55 * max(trail.hi - trail.lo, ys.max() - ys.min() + 2.5 * h_max)
        self.canvas = Canvas(half, 0.5 * (ys.max() + ys.min()) + h_max, render_mode, fps, 0.5 * (trail.lo + trail.hi))
        self.points = [self.canvas.px(x, y) for x, y in zip(xs, ys)]

    def draw(self, x: float, h: float, h_min: float, t: float):
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        pg.draw.lines(c.screen, (70, 110, 160), False, self.points, 4)
        f, f1, _, _ = self.trail.derivatives(x)
        sigma = math.sqrt(1.0 + f1 * f1)
        tangent, normal = np.array([1.0, f1]) / sigma, np.array([-f1, 1.0]) / sigma
        foot = np.array([x, f])
        hip = foot + h * normal  # the barycentre
        bend = math.sqrt(max((0.5 * self.h_max) ** 2 - (0.5 * h) ** 2, 0.0))  # knee out, legs of length h_max
        knee = foot + 0.5 * h * normal + bend * tangent
        neck = hip + 0.45 * self.h_max * normal
        for a, b in ((foot, knee), (knee, hip), (hip, neck)):
            pg.draw.line(c.screen, (40, 40, 40), c.px(*a), c.px(*b), 4)
        pg.draw.line(c.screen, (40, 40, 40), c.px(*(foot - 0.4 * tangent)), c.px(*(foot + 0.4 * tangent)), 3)  # ski
        head = neck + 0.15 * self.h_max * normal
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*head), max(int(0.15 * self.h_max * c.scale), 3))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*hip), 4)
        c.screen.blit(c.font.render(f"t = {t:5.2f} s   h = {h:4.2f} m", True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class RollingBallRenderer:
    """Top view following the ball: the path it has rolled, the ball with its body axes (solid where they point
    up, hollow where down) and, in the corner, the target attitude's axes for comparison."""

    COLORS = ((204, 77, 77), (77, 160, 77), (77, 110, 204))  # body x, y, z

    def __init__(self, radius: float, render_mode: str, fps: int):
        self.radius = radius
        self.canvas = Canvas(4.0 * radius, 0.0, render_mode, fps)

    def axes(self, R, center, size):
        """Each body axis as a line from the centre to its tip, seen from above, and a marker at the tip."""
        c, pg = self.canvas, self.canvas.pygame
        for i in np.argsort(R[2]):  # the axes pointing down first, so that the upper ones are drawn on top
            tip = center + size * R[:2, i]
            pg.draw.line(c.screen, self.COLORS[i], c.px(*center), c.px(*tip), 3)
            pg.draw.circle(c.screen, self.COLORS[i], c.px(*tip), 6, 0 if R[2, i] >= 0 else 2)

    def draw(self, R, R_target, path, t: float, angle_error: float):
        c, pg = self.canvas, self.canvas.pygame
        c.center_x, c.center_y = path[-1]
        c.screen.fill((255, 255, 255))
        if len(path) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in path], 2)
        pg.draw.circle(c.screen, (0, 0, 0), c.px(0.0, 0.0), 4)  # the origin
        pg.draw.circle(c.screen, (235, 235, 245), c.px(*path[-1]), int(self.radius * c.scale))
        pg.draw.circle(c.screen, (60, 60, 60), c.px(*path[-1]), int(self.radius * c.scale), 2)
        self.axes(R, path[-1], self.radius)
        inset = path[-1] + np.array([2.9, -2.9]) * self.radius
        pg.draw.circle(c.screen, (60, 60, 60), c.px(*inset), int(0.8 * self.radius * c.scale), 1)
        self.axes(R_target, inset, 0.8 * self.radius)
        text = f"t = {t:5.2f} s   angle error = {angle_error:5.3f} rad   (target: lower right)"
        c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class TubeRenderer:
    """The unit sphere of tangent directions seen from the side of B₀ above the start tangent T₀: the trace of the tip's
    tangent T (solid in front, faint behind), the tip frame at T (N red, B green, T blue from the centre), and at T₀
    the start normal (grey) and the target normal R₀ Rz(ψ*) e₁ (pink)."""

    TILT = 1.0  # rad: the view axis from T₀ toward B₀: loops turning toward B₀ face the viewer, not edge-on
    COLORS = ((204, 77, 77), (77, 160, 77), (77, 110, 204))  # N, B, T

    def __init__(self, render_mode: str, fps: int):
        self.canvas = Canvas(1.5, 0.0, render_mode, fps)

    def draw(self, R, R0, trace, t: float, twist: float, target: float):
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        cos, sin = math.cos(self.TILT), math.sin(self.TILT)
        view = np.array([[-1.0, 0.0, 0.0], [0.0, -cos, sin], [0.0, sin, cos]]) @ R0.T  # space → screen (x, y, depth)
        pg.draw.circle(c.screen, (235, 235, 245), c.px(0.0, 0.0), int(c.scale))
        pg.draw.circle(c.screen, (120, 120, 120), c.px(0.0, 0.0), int(c.scale), 1)
        ring = view @ R0 @ np.stack([np.cos(np.linspace(0, 2 * np.pi, 73)), np.sin(np.linspace(0, 2 * np.pi, 73)),
                                     np.zeros(73)])  # fmt: skip
        pg.draw.lines(c.screen, (200, 200, 210), True, [c.px(x, y) for x, y in ring[:2].T], 1)  # T₀'s equator
        points = trace @ view.T
        for a, b in zip(points[:-1], points[1:]):
            colour = (40, 40, 40) if a[2] + b[2] >= 0 else (190, 190, 190)
            pg.draw.line(c.screen, colour, c.px(*a[:2]), c.px(*b[:2]), 2)
        start, n0 = view @ R0[:, 2], view @ R0[:, 0]
        n_target = view @ R0 @ np.array([math.cos(target), math.sin(target), 0.0])
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*start[:2]), 5)
        for direction, colour in ((n0, (150, 150, 150)), (n_target, (240, 150, 170))):
            pg.draw.line(c.screen, colour, c.px(*start[:2]), c.px(*(start + 0.4 * direction)[:2]), 3)
        frame = view @ R
        tip = frame[:, 2]
        pg.draw.line(c.screen, self.COLORS[2], c.px(0.0, 0.0), c.px(*tip[:2]), 3)
        for i in (0, 1):
            pg.draw.line(c.screen, self.COLORS[i], c.px(*tip[:2]), c.px(*(tip + 0.3 * frame[:, i])[:2]), 4)
        pg.draw.circle(c.screen, self.COLORS[2], c.px(*tip[:2]), 6, 0 if tip[2] >= 0 else 2)
        text = f"t = {t:5.2f} s   twist = {twist:+5.3f} rad   target = {target:+5.3f} rad"
        c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class KapitzaRenderer:
    """The pivot's travel as a bar, the pivot, rod and bob; the time in the corner."""

    def __init__(self, length: float, a_max: float, render_mode: str, fps: int):
        self.length, self.a_max = length, a_max
        self.canvas = Canvas(1.3 * (length + a_max), 0.0, render_mode, fps)

    def draw(self, theta: float, u, t: float):
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))
        a = self.a_max
        pg.draw.rect(c.screen, (225, 225, 235), pg.Rect(*c.px(-a, a), 2 * a * c.scale + 1, 2 * a * c.scale + 1))
        pivot = c.px(u[0], u[1])
        bob = c.px(u[0] + self.length * math.sin(theta), u[1] - self.length * math.cos(theta))
        pg.draw.line(c.screen, (60, 60, 60), pivot, bob, 3)
        pg.draw.circle(c.screen, (204, 77, 77), bob, 12)
        pg.draw.circle(c.screen, (0, 0, 0), pivot, 5)
        c.screen.blit(c.font.render(f"t = {t:5.2f} s", True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class CoordinatePlot:
    """The coordinates against time: each q and u over the last WINDOW seconds (from the left edge, scrolling once
    the window is full), scaled to the range they have covered; or, with a user's ``draw(state, canvas)``, that picture on a Canvas spanning [-1, 1]² (metres
    by default: the callback may change ``canvas.scale``)."""

    WINDOW = 10.0  # s of history shown
    COLORS = ((204, 77, 77), (77, 110, 204), (77, 160, 77), (200, 140, 40), (140, 77, 180), (60, 60, 60))

    def __init__(self, n: int, m: int, render_mode: str, fps: int, draw=None):
        self.canvas = Canvas(1.0, 0.0, render_mode, fps)
        self.labels = [f"q{i}" for i in range(n)] + [f"u{i}" for i in range(m)]
        self.user_draw, self.history = draw, []

    def draw(self, state: dict):
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
        top, height = 40, SIZE - 60
        x = 10 + (trace[:, 0] - trace[0, 0]) / self.WINDOW * (SIZE - 20)
        for k, label in enumerate(self.labels):
            y = top + height * (0.5 - 0.45 * (trace[:, 1 + k] - mid) / half)
            color = self.COLORS[k % len(self.COLORS)]
            if len(trace) > 1:
                pg.draw.lines(c.screen, color, False, list(zip(x.astype(int), y.astype(int))), 2)
            c.screen.blit(c.font.render(f"{label} = {trace[-1, 1 + k]:+.3f}", True, color), (10 + 110 * k, SIZE - 18))
        text = f"t = {state['t']:5.2f} s   range [{low:.3g}, {high:.3g}]"
        c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class SleighRenderer:
    """Top view: the track of the knife edge, the sled (its outline, the knife edge at P, the mass's box or rail
    around C), the mass and the target disc."""

    def __init__(self, offset: float, rail: float, box: float, tolerance: float, render_mode: str, fps: int):
        self.offset, self.rail, self.box, self.tolerance = offset, rail, box, tolerance
        self.canvas = Canvas(3.0, 0.0, render_mode, fps)
        self.track = []

    def draw(self, pose, u, target, t: float):
        c, pg = self.canvas, self.canvas.pygame
        x, y, phi = pose
        if t == 0.0:
            self.track = []
        self.track.append((x, y))
        e1, e2 = np.array([math.cos(phi), math.sin(phi)]), np.array([-math.sin(phi), math.cos(phi)])
        P = np.array([x, y])
        C = P + self.offset * e1
        c.center_x, c.center_y = 0.5 * (P + target)  # the sled and the target in view
        c.scale = SIZE / (2.0 * max(2.5, 0.6 * float(np.hypot(*(P - target))) + 1.0))
        c.screen.fill((255, 255, 255))
        pg.draw.circle(c.screen, (200, 230, 200), c.px(*target), max(int(self.tolerance * c.scale), 3))
        pg.draw.circle(c.screen, (60, 140, 60), c.px(*target), 4)
        if len(self.track) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in self.track], 2)
        half = 1.2 * self.rail
        front = self.offset + 1.2 * max(self.box, 0.1)
        corners = [P - 0.1 * e1 + half * e2, P + front * e1 + half * e2, P + front * e1 - half * e2,
                   P - 0.1 * e1 - half * e2]
        pg.draw.polygon(c.screen, (225, 225, 240), [c.px(*p) for p in corners])
        pg.draw.polygon(c.screen, (60, 60, 90), [c.px(*p) for p in corners], 2)
        pg.draw.line(c.screen, (40, 40, 40), c.px(*(P - 0.15 * e1)), c.px(*(P + 0.15 * e1)), 5)  # the knife edge
        b, r = self.box, self.rail
        box = [C + b * e1 + r * e2, C + b * e1 - r * e2, C - b * e1 - r * e2, C - b * e1 + r * e2]
        pg.draw.lines(c.screen, (120, 120, 160), True, [c.px(*p) for p in box], 2)  # the mass's box (a rail if b = 0)
        pg.draw.circle(c.screen, (0, 0, 0), c.px(*C), 3)
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*(C + u[0] * e1 + u[1] * e2)), 8)
        c.screen.blit(c.font.render(f"t = {t:5.2f} s", True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()
