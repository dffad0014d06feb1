"""pygame drawing of connenv.envs.connection's env: the group element's frame and the shape against its bounds, or a
user's ``draw(state, canvas)``."""

from __future__ import annotations

import math

import numpy as np

from connenv.rendering import Canvas, Renderer


class ConnectionRenderer(Renderer):
    """The body frame (x axis red, y axis green; SO3's projected on the screen's plane, z blue, with the unit
    circle), centred on g's position for SE2 and R2, and s as bars against its bounds; the time. With a user's
    ``draw(state, canvas)``, that picture instead, on a Canvas spanning [-2, 2]²."""

    def __init__(self, env):
        self.canvas = Canvas(env, 2.0)
        self.group, self.low, self.high, self.user_draw = env.group.name, env.low, env.high, env.draw

    def draw(self, env):
        state = env.state_dict(env.state)
        if self.user_draw is not None:
            self.user_draw(state, self.canvas)
            return self.canvas.show()
        canvas, low, high = self.canvas, self.low, self.high
        pg, screen = canvas.pygame, canvas.screen
        screen.fill((255, 255, 255))
        g = state["g"]
        if self.group == "R2":
            canvas.center_x, canvas.center_y = g
            origin, axes = g, np.eye(2)
        elif self.group == "SE2":
            canvas.center_x, canvas.center_y = g[:2, 2]
            origin, axes = g[:2, 2], g[:2, :2]
        else:
            origin, axes = np.zeros(2), g[:2, :]
        if self.group == "SO3":
            pg.draw.circle(screen, (200, 200, 200), canvas.px(0.0, 0.0), int(canvas.scale), canvas.pt(1))
        for column, colour in zip(axes.T, ((204, 60, 60), (60, 160, 60), (60, 60, 204))):
            pg.draw.line(screen, colour, canvas.px(*origin), canvas.px(*(origin + column)), canvas.pt(2))
        pg.draw.circle(screen, (0, 0, 0), canvas.px(*origin), canvas.pt(2.5))
        size, bar, pt = screen.get_width(), canvas.pt(50), canvas.pt
        for i, value in enumerate(state["s"]):  # a bar per shape coordinate: its place within the bounds
            finite = math.isfinite(low[i]) and math.isfinite(high[i])
            fraction = (value - low[i]) / (high[i] - low[i]) if finite else 0.5 + math.atan(value) / math.pi
            x, width, height = pt(5) + pt(9) * i, pt(6), int(bar * fraction)
            pg.draw.rect(screen, (220, 220, 230), (x, size - pt(5) - bar, width, bar))
            pg.draw.rect(screen, (70, 110, 160), (x, size - pt(5) - height, width, height))
        return canvas.caption(f"t = {state['t']:5.2f}   s = {np.round(state['s'], 2)}")
