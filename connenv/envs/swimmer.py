"""What the planar swimmers in an ideal fluid share, KozlovShell-v0 and SnakeSwimmer-v0: a pose (x, y, θ) on SE(2),
a body momentum (P₁, P₂, Π) in the full (Kirchhoff) model, whose spatial momentum is conserved, and the task of
reaching a target point."""

from __future__ import annotations

import numpy as np

from connenv.core.segments import check_drift
from connenv.envs.base import SCALAR

TIME_COST = 0.01  # reward paid per step until success
MOMENTUM_ERROR_BOUND = 0.1  # |spatial momentum − its value at reset| / |that value| past which a stepper diverged


def components(a):
    """The components along the last axis: floats of one state's array, columns of a batch's."""
    return a.tolist() if a.ndim == 1 else [a[..., i] for i in range(a.shape[-1])]


class PlanarSwimmer:
    """Task code of a TaskEnv whose states have ``pose``, ``momentum`` and ``target``, and which has
    ``full_system`` (with ``spatial_momentum``), ``stepper`` and ``success_radius``."""

    def spatial_momentum(self, s, ops=SCALAR):
        """(R(θ) P, Π + x P_y − y P_x), the arithmetic of the system's spatial_momentum: a tuple of floats for one
        state, an array (N, 3) for a batch."""
        (x, y, theta), (p1, p2, pi) = components(s.pose), components(s.momentum)
        c, sin = ops.cos(theta), ops.sin(theta)
        px, py = c * p1 - sin * p2, sin * p1 + c * p2
        momentum = px, py, pi + x * py - y * px
        return momentum if ops is SCALAR else np.stack(momentum, axis=-1)

    def check_momentum(self, y, momentum0):
        """StepperError if the full model's spatial momentum (of any row of a batch) has moved from its value at
        reset by more than MOMENTUM_ERROR_BOUND of its norm."""
        drift = np.linalg.norm(self.full_system.spatial_momentum(y) - momentum0, axis=-1)
        norm = np.linalg.norm(momentum0, axis=-1)
        check_drift(self.stepper, "the spatial momentum", drift, MOMENTUM_ERROR_BOUND, norm=norm)

    def distance(self, s, ops=SCALAR):
        """From the body's point (x, y) to the target, m."""
        (x, y, _), (x_target, y_target) = components(s.pose), components(s.target)
        return ops.hypot(x_target - x, y_target - y)

    def reward(self, before, after, info, ops=SCALAR):
        return (self.distance(before, ops) - info["distance"]) / self.success_radius - TIME_COST
