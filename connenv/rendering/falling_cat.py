"""pygame drawing of the falling cat."""

from __future__ import annotations

import math

from connenv.rendering import Canvas, Renderer
from connenv.systems import falling_cat


class CatRenderer(Renderer):
    """The cat seen from the side (its start spine to the right, up is up): the two halves as thick bars from the
    joint, with legs along each half's −e₃ (feet); beside it, a dial seen along the spine with the back's
    direction (feet down: the back up, the goal ticked at the dial's top); the time, the roll and the bend."""

    def __init__(self, env):
        self.length = env.cm_distance
        self.canvas = Canvas(env, 3.2 * env.cm_distance, center_x=0.8 * env.cm_distance)

    def draw(self, env):
        """E: the cat frame in the heading frame; Q_A, Q_B: the halves in the cat frame."""
        (g, H), (Q_A, Q_B), bend, t = env.frames(env.state), falling_cat.halves(env.state.s), env.state.s, env.state.t
        E, roll = H.T @ g, env.errors(env.state)[0]
        c, pg, ell = self.canvas, self.canvas.pygame, self.length
        c.screen.fill((255, 255, 255))
        front, rear = E @ Q_A, E @ Q_B
        joint = -0.5 * ell * (front[:, 0] - rear[:, 0])  # the centre of mass at the origin

        def side(point):  # the heading frame's (spine, up) plane
            return c.px(point[0], point[2])

        for Q, sign, colour in ((front, 1.0, (204, 120, 60)), (rear, -1.0, (150, 90, 50))):
            tip = joint + sign * 2 * ell * Q[:, 0]
            pg.draw.line(c.screen, colour, side(joint), side(tip), c.pt(6))
            hip = joint + sign * 1.5 * ell * Q[:, 0]
            pg.draw.line(c.screen, (60, 60, 60), side(hip), side(hip - 0.8 * ell * Q[:, 2]), c.pt(2))  # a leg
        pg.draw.circle(c.screen, (0, 0, 0), side(joint), c.pt(2.5))
        dial, radius = c.px(2.3 * ell, 2.0 * ell), int(0.6 * ell * c.scale)
        pg.draw.circle(c.screen, (170, 170, 170), dial, radius, c.pt(1))
        top = dial[1] - radius
        pg.draw.line(c.screen, (40, 140, 40), (dial[0], top - c.pt(4)), (dial[0], top + c.pt(4)), c.pt(1.5))
        back = (dial[0] + int(radius * math.sin(roll)), dial[1] - int(radius * math.cos(roll)))
        pg.draw.line(c.screen, (60, 60, 204), dial, back, c.pt(2))
        lines = [f"t = {t:5.2f} s   roll = {roll:+6.3f} rad",
                 f"bend β = {math.hypot(*bend):4.2f} rad  γ = {math.atan2(bend[1], bend[0]):+5.2f} rad"]  # fmt: skip
        return c.caption(*lines)
