"""pygame drawing for Lawton's connection envs: the rolling coin from above, Elroy's beanie."""

from __future__ import annotations

import math

import numpy as np

from connenv.envs.rendering import Canvas


class CoinRenderer:
    """Top view: the track of the contact point, the coin as a segment along its heading (its edge seen from
    above) with a tick at the rolled angle φ, and the target pose as a hollow outline."""

    def __init__(self, radius: float, render_mode: str, fps: int):
        self.radius = radius
        self.canvas = Canvas(4.0, 0.0, render_mode, fps)

    def coin(self, position, theta, colour, width):
        c, pg = self.canvas, self.canvas.pygame
        heading = self.radius * np.array([math.sin(theta), math.cos(theta)])
        pg.draw.line(c.screen, colour, c.px(*(position - heading)), c.px(*(position + heading)), width)
        pg.draw.circle(c.screen, colour, c.px(*(position + heading)), 5)  # the front

    def draw(self, track, theta, phi, target, t):
        c, pg = self.canvas, self.canvas.pygame
        c.center_x, c.center_y = 0.5 * (track[-1] + target[:2])
        c.screen.fill((255, 255, 255))
        pg.draw.circle(c.screen, (0, 0, 0), c.px(0.0, 0.0), 3)  # the origin
        pg.draw.circle(c.screen, (160, 200, 160), c.px(*target[:2]), max(int(0.05 * c.scale), 2))
        self.coin(target[:2], target[2], (120, 180, 120), 2)
        if len(track) > 1:
            pg.draw.lines(c.screen, (150, 150, 150), False, [c.px(*p) for p in track], 2)
        self.coin(track[-1], theta, (60, 60, 120), 6)
        tick = track[-1] + self.radius * math.cos(phi) * np.array([math.sin(theta), math.cos(theta)])
        pg.draw.circle(c.screen, (204, 77, 77), c.px(*tick), 4)  # a point of the rim: where φ has turned it
        text = f"t = {t:5.2f} s   distance = {np.hypot(*(target[:2] - track[-1])):5.3f} m"
        c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10))
        return c.show()

    def close(self):
        self.canvas.close()


class BeanieRenderer:
    """The body (a disk with a radius drawn at θ), the beanie on it (a smaller disk with its propeller at θ + ψ),
    the target θ* as a dashed line, and the beanie's winding ψ/2π counted beside; a bar shows the hold."""

    def __init__(self, render_mode: str, fps: int):
        self.canvas = Canvas(1.5, 0.0, render_mode, fps)

    def draw(self, theta, psi, target, momentum, t, held):
        c, pg = self.canvas, self.canvas.pygame
        c.screen.fill((255, 255, 255))

        def ray(angle, length):
            return c.px(length * math.cos(angle), length * math.sin(angle))

        pg.draw.circle(c.screen, (225, 225, 235), c.px(0.0, 0.0), int(1.0 * c.scale))
        pg.draw.circle(c.screen, (60, 60, 60), c.px(0.0, 0.0), int(1.0 * c.scale), 2)
        for k in range(12):  # dashes toward the target, past the body's rim
            pg.draw.line(c.screen, (90, 170, 90), ray(target, 0.1 * k), ray(target, 0.1 * k + 0.05), 3)
        pg.draw.line(c.screen, (60, 60, 120), c.px(0.0, 0.0), ray(theta, 1.0), 5)  # the body's mark
        pg.draw.circle(c.screen, (250, 230, 120), c.px(0.0, 0.0), int(0.4 * c.scale))
        pg.draw.circle(c.screen, (150, 120, 40), c.px(0.0, 0.0), int(0.4 * c.scale), 2)
        for blade in (0.0, math.pi):  # the beanie's propeller, at θ + ψ in space
            pg.draw.line(c.screen, (204, 77, 77), c.px(0.0, 0.0), ray(theta + psi + blade, 0.38), 4)
        width = int(held * 200)
        pg.draw.rect(c.screen, (220, 220, 230), (10, 470, 200, 14))
        pg.draw.rect(c.screen, (90, 170, 90), (10, 470, min(width, 200), 14))
        lines = [f"t = {t:5.2f} s   θ* − θ = {math.remainder(target - theta, 2 * math.pi):+6.3f} rad",
                 f"beanie turns ψ/2π = {psi / (2 * math.pi):+7.2f}   μ = {momentum:+5.2f}"]  # fmt: skip
        for k, text in enumerate(lines):
            c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10 + 20 * k))
        return c.show()

    def close(self):
        self.canvas.close()


class CatRenderer:
    """The cat seen from the side (its start spine to the right, up is up): the two halves as thick bars from the
    joint, with legs along each half's −e₃ (feet); beside it, a dial seen along the spine with the back's
    direction (feet down: the back up); the time, the roll and the bend."""

    def __init__(self, cm_distance: float, render_mode: str, fps: int):
        self.length = cm_distance
        self.canvas = Canvas(3.2 * cm_distance, 0.0, render_mode, fps, center_x=0.8 * cm_distance)

    def draw(self, E, Q_A, Q_B, bend, t, roll):
        """E: the cat frame in the heading frame; Q_A, Q_B: the halves in the cat frame."""
        c, pg, ell = self.canvas, self.canvas.pygame, self.length
        c.screen.fill((255, 255, 255))
        front, rear = E @ Q_A, E @ Q_B
        joint = -0.5 * ell * (front[:, 0] - rear[:, 0])  # the centre of mass at the origin

        def side(point):  # the heading frame's (spine, up) plane
            return c.px(point[0], point[2])

        for Q, sign, colour in ((front, 1.0, (204, 120, 60)), (rear, -1.0, (150, 90, 50))):
            tip = joint + sign * 2 * ell * Q[:, 0]
            pg.draw.line(c.screen, colour, side(joint), side(tip), 12)
            hip = joint + sign * 1.5 * ell * Q[:, 0]
            pg.draw.line(c.screen, (60, 60, 60), side(hip), side(hip - 0.8 * ell * Q[:, 2]), 4)  # a leg
        pg.draw.circle(c.screen, (0, 0, 0), side(joint), 5)
        dial, radius = c.px(2.3 * ell, 2.0 * ell), int(0.6 * ell * c.scale)
        pg.draw.circle(c.screen, (200, 200, 200), dial, radius, 2)
        back = (dial[0] + int(radius * math.sin(roll)), dial[1] - int(radius * math.cos(roll)))
        pg.draw.line(c.screen, (60, 60, 204), dial, back, 4)
        lines = [f"t = {t:5.2f} s   roll = {roll:+6.3f} rad",
                 f"bend β = {math.hypot(*bend):4.2f} rad  γ = {math.atan2(bend[1], bend[0]):+5.2f} rad"]  # fmt: skip
        for k, text in enumerate(lines):
            c.screen.blit(c.font.render(text, True, (0, 0, 0)), (10, 10 + 20 * k))
        return c.show()

    def close(self):
        self.canvas.close()
