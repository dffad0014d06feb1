"""Reference controller of RollingCoinSurface-v0: steer the direction of motion at a waypoint, then the target.

The coin moves only along its heading, at the speed gravity gives it, and turning it costs no energy: steering is
choosing where the velocity points. The law (pure pursuit, read off the observation):

- aim point: the target; on the hill surface, a waypoint beside the hill, W = c ± (3 w, 0) (c the hill's
  centre, w its width, on the target's side), while the straight line to the target is blocked (`blocked`): it
  rises within MARGIN of the coin's level E/(m g), the height where the coin would stop and roll back;
- direction of motion: the heading θ when the coin rolls forward (R φ̇ > 0), θ + π when it rolls backward; at
  rest, the end of its line that points downhill, where gravity will start it;
- steering: θ̇ = clip(e / dt, ±max_steer_rate), e the angle from the direction of motion to the aim point
  (wrapped into (−π, π]; at rest into (−π/2, π/2], the line having two ends): the error is removed in one step
  where the rate allows.

Off the hill, every target the reset draws lies below the start on a straight line whose height stays below the
start's (a plane, a convex bowl), so aiming straight at it reaches it.
"""

from __future__ import annotations

import math

import numpy as np

REST_SPEED = 1e-9  # |R φ̇| / v* below which the coin counts as at rest
CLEARANCE = 3.0  # the waypoint's distance from the hill's centre, in hill widths
MARGIN = 0.1  # m below the coin's level that the line to the target must stay, else it aims beside the hill
LINE_SAMPLES = 41  # points of the line to the target where its height is read


class SteerToTarget:
    """The law of the module, for one observation or a batch, with the env's parameters."""

    def __init__(self, env):
        self.arena, self.distance = env.arena, env.target_distance
        self.slope_bound, self.dt, self.max_rate = env.slope_bound, env.dt, env.max_steer_rate
        self.surface, self.speed_scale, self.g = env.surface, env.speed_scale, env.system.g
        hill = getattr(env.surface, "center", None)
        self.hill = None if hill is None else (np.array(hill), CLEARANCE * env.surface.width)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, float)
        x, y = obs[..., 0] * self.arena, obs[..., 1] * self.arena
        target_x, target_y = x + obs[..., 2] * self.distance, y + obs[..., 3] * self.distance
        theta = np.arctan2(obs[..., 4], obs[..., 5])
        speed, z_x, z_y = obs[..., 6], obs[..., 7], obs[..., 8]
        aim_x, aim_y = target_x, target_y
        if self.hill is not None:
            (cx, cy), clearance = self.hill
            blocked = self.blocked(x, y, obs[..., 6] * self.speed_scale, target_x, target_y)
            aim_x = np.where(blocked, cx + np.where(target_x >= cx, clearance, -clearance), target_x)
            aim_y = np.where(blocked, cy, target_y)
        wanted = np.arctan2(aim_x - x, aim_y - y)
        at_rest = np.abs(speed) < REST_SPEED
        backward = np.where(at_rest, z_x * np.sin(theta) + z_y * np.cos(theta) > 0.0, speed < 0.0)
        error = wrap(wanted - theta - np.where(backward, math.pi, 0.0))
        error = np.where(at_rest, wrap(2.0 * error) / 2.0, error)
        action = np.clip(error / (self.dt * self.max_rate), -1.0, 1.0)
        return action.astype(np.float32)[..., None], state


    def blocked(self, x, y, v, target_x, target_y):
        """Whether the straight line to the target rises within MARGIN of the coin's level E/(m g), the height
        where it would stop."""
        level = self.surface.height(x, y)[0] + 0.75 * v * v / self.g
        s = np.linspace(0.0, 1.0, LINE_SAMPLES)[:, None] if np.ndim(x) else np.linspace(0.0, 1.0, LINE_SAMPLES)
        z = self.surface.height(x + s * (target_x - x), y + s * (target_y - y))[0]
        return np.max(z, axis=0) > level - MARGIN


def wrap(angle):
    """angle into (−π, π]."""
    return math.pi - np.mod(math.pi - angle, 2.0 * math.pi)


def steer(env):
    return SteerToTarget(env)
