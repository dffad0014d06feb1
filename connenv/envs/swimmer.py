"""What the planar swimmers in an ideal fluid, Kozlov's shell and the snake, share: a pose (x, y, θ) on SE(2), a body
momentum (P₁, P₂, Π) in the full (Kirchhoff) model, which conserves its spatial momentum, and a target to reach."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, components, traced
from connenv.core.backend import vector as entries_vector
from connenv.core.integrators import make_stepper
from connenv.core.lie import Magnus
from connenv.core.params import Bound
from connenv.core.segments import check_drift, run_segments
from connenv.core.state import Field, Fields, Options, angle, number, vector
from connenv.envs.spec import Measure
from connenv.systems import ideal_fluid

TIME_COST = 0.01  # reward paid per step until success
MOMENTUM_ERROR_BOUND = 0.1  # |spatial momentum − its value at reset| / |that value| past which a stepper diverged
TARGET_BOUND = 3.0  # the observed target, in units of target_unit, is clipped here
MOMENTUM_BOUND = 10.0  # the observed momentum, in velocity units, is clipped here
INTEGRATORS = ("magnus", "dop853", "euler", "semi_implicit_euler", "rk4", "rk45", "lsoda", "radau")  # a swimmer's
POSITION_BOUND = 100.0  # m: |x|, |y| of a swimmer and of its target given at reset
SWIMMER = {"measure": Measure("steps to target", "", "steps_to_target"), "controllers": ("gaits",),
           "starts": (None, {"state": {"momentum": (0.2, 0.0, -0.1)}})}  # with a momentum: the full (Kirchhoff) model
"""What the swimmers' specs share: the reference table's measure, the gait controller, a start in each model."""


def momentum_bound(env, values):
    """|P_k| given at reset: the momentum the observation holds, MOMENTUM_BOUND times the locked inertia's k-th."""
    return MOMENTUM_BOUND * env.momentum_scale


def swimmer_state(*shape: Field) -> Fields:
    """A swimmer's reset state (`connenv.core.state`): x, y, θ, its shape, its body momentum (≠ 0: the full model)."""
    return Fields(
        number("x", "m", bound=POSITION_BOUND),
        number("y", "m", bound=POSITION_BOUND),
        angle("theta"),
        *shape,
        vector("momentum", 3, "kg m/s, kg m²/s", "P₁, P₂, Π in the body frame; the observed bounds",
               bound=Bound(momentum_bound, "10 𝕀_loc(0)_kk")),
    )


class PlanarSwimmer:
    """Task code of a TaskEnv whose states (``state_class``) are (pose, momentum, shape, target, t, full, momentum0),
    and which has `success_radius`, observation scales `target_unit` and `shape_bounds`, and `shape(state)`,
    `start_shape(values)` (from the reset state's values), `shape_info(state, ops)`: the assigned coordinates, their
    `info["state"]` entries. ``TARGET_DISTANCES`` (in target units) bound the target's distance from the start, drawn
    uniform in a uniform direction; ``TOLERANCES`` are DOP853's in the full model, atol the Lie-group step's too."""

    state_class: type
    TARGET_DISTANCES: tuple[float, float]
    TOLERANCES: dict
    OPTIONS = Options(vector("target", 2, "m", "(x, y)", bound=POSITION_BOUND))

    def build(self, full_system, reduced_system, integrator, options, rule):
        """The two models; the stepper of the full one (TOLERANCES by default for "magnus" and "dop853"; the Lie-group
        step with the quadrature rule ``rule(atol) -> (pieces, points)`` fixed once for the reduced one); the momentum's
        observed scales (the locked inertia's diagonal at the straight shape), the spaces and the view's reach."""
        self.full_system, self.reduced_system = full_system, reduced_system
        if integrator in ("magnus", "dop853"):
            options = {**self.TOLERANCES, **options}
        self.stepper = make_stepper(integrator, full_system, **options)
        if isinstance(self.stepper, Magnus):
            pieces, points = rule(self.stepper.atol)
            self.stepper = dataclasses.replace(self.stepper, pieces=pieces, points=points)
        self.momentum_scale = np.diag(full_system.locked_inertia(np.zeros(2)))  # M + m + λ₁, M + m + λ₂, J + λ₃
        self.momentum_bounds = self.momentum_scale.tolist()  # as floats
        self.reach = self.TARGET_DISTANCES[1] * self.target_unit  # the farthest target, which the view takes in
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        high = np.array([TARGET_BOUND] * 2 + [1.0] * 4 + [MOMENTUM_BOUND] * 3, np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        self.state = self.state_class(*(np.zeros(n) for n in (3, 3, 2, 2)), 0.0, False, np.zeros(3))

    def start(self, options, ops=SCALAR):
        """At rest at the origin, or options['state']; the target drawn by np_random, or options['target']. The model
        follows the momentum: reduced at zero, full otherwise. Traced (``connenv.jax``, ops its namespace): the same
        draws from its key."""
        distance = self.np_random.uniform(*self.TARGET_DISTANCES) * self.target_unit
        angle = self.np_random.uniform(-math.pi, math.pi)
        values = self.reset_values(options, {"target": entries_vector(distance * ops.cos(angle),
                                                                      distance * ops.sin(angle))})
        pose, momentum = np.array([values["x"], values["y"], values["theta"]]), values["momentum"]
        full = bool(momentum.any())
        momentum, shape = momentum if full else np.zeros(3), self.start_shape(values)
        s = self.state_class(pose, momentum, shape, values["target"], 0.0, full, np.zeros(3))
        return s.replace(momentum0=np.array(self.spatial_momentum(s)))

    def swim(self, s, full_segments, reduced_segments, stepper, ops=SCALAR):
        """(pose, momentum) after a step: the full model across its control segments where s.full, its spatial momentum
        checked, the reduced one elsewhere (the momentum stays 0); zero-length segments skipped per row."""
        if ops is SCALAR:
            if s.full:
                y = np.concatenate([s.pose, s.momentum])
                y = run_segments(stepper, self.full_system, y, [c for c in full_segments if c[2] > 0.0])[0]
                self.check_momentum(y, s.momentum0)
                return y[:3], y[3:]
            pose = run_segments(stepper, self.reduced_system, s.pose, [c for c in reduced_segments if c[2] > 0.0])[0]
            return pose, s.momentum
        if traced(ops):
            return self._swim_traced(s, full_segments, reduced_segments, stepper, ops)
        full, rest = s.full, ~s.full
        if not full.any():
            return run_segments(stepper, self.reduced_system, s.pose, reduced_segments)[0], s.momentum
        y = np.concatenate([s.pose, s.momentum], axis=-1)
        y[full] = run_segments(stepper, self.full_system, y[full], _rows(full_segments, full))[0]
        self.check_momentum(y[full], s.momentum0[full])
        if rest.any():
            y[rest, :3] = run_segments(stepper, self.reduced_system, s.pose[rest], _rows(reduced_segments, rest))[0]
        return y[:, :3], y[:, 3:]

    def _swim_traced(self, s, full_segments, reduced_segments, stepper, ops):
        """swim on traced rows (connenv.jax): each row keeping its own model's step by ``where``, the full model's run
        where some row is full (``ops.branch``: rows stepped in one call skip it when none is, as the numpy rows do;
        under vmap every row runs both); the spatial momentum checked on the full rows (a failure as data)."""
        full = ops.flag(s.full)
        y = ops.concat([s.pose, s.momentum], axis=-1)
        y = ops.branch(full, lambda y: run_segments(stepper, self.full_system, y, full_segments)[0], lambda y: y, y)
        drift = self.full_system.spatial_momentum(y) - s.momentum0
        drift = ops.sqrt((drift * drift).sum(axis=-1))
        norm = ops.sqrt((s.momentum0 * s.momentum0).sum(axis=-1))
        check_drift(self.stepper, "the spatial momentum", ops.where(full, drift, 0.0), MOMENTUM_ERROR_BOUND,
                    norm=norm)
        pose = run_segments(stepper, self.reduced_system, s.pose, reduced_segments)[0]
        return ops.where(full[..., None], y[..., :3], pose), ops.where(full[..., None], y[..., 3:], s.momentum)

    def spatial_momentum(self, s, ops=SCALAR):
        """(R(θ) P, Π + x P_y − y P_x): a tuple of floats for one state, an array (N, 3) for a batch."""
        momentum = ideal_fluid.spatial_momentum(*components(s.pose), *components(s.momentum), ops)
        return momentum if ops is SCALAR else ops.stack(momentum, axis=-1)

    def check_momentum(self, y, momentum0):
        """StepperError where the spatial momentum moved over MOMENTUM_ERROR_BOUND of its norm (any row; real parts)."""
        drift = np.linalg.norm(np.real(self.full_system.spatial_momentum(y) - momentum0), axis=-1)
        norm = np.linalg.norm(np.real(momentum0), axis=-1)
        check_drift(self.stepper, "the spatial momentum", drift, MOMENTUM_ERROR_BOUND, norm=norm)

    def distance(self, s, ops=SCALAR):
        """From the body's point (x, y) to the target, m."""
        (x, y, _), (x_target, y_target) = components(s.pose), components(s.target)
        return ops.hypot(x_target - x, y_target - y)

    def reward(self, before, after, info, ops=SCALAR):
        return (self.distance(before, ops) - info["distance"]) / self.success_radius - TIME_COST

    def observe(self, s, ops=SCALAR):
        (x, y, theta), (x_target, y_target) = components(s.pose), components(s.target)
        c, sin = ops.cos(theta), ops.sin(theta)
        dx, dy = (x_target - x) / self.target_unit, (y_target - y) / self.target_unit
        body_target = [ops.clip(c * dx + sin * dy, -TARGET_BOUND, TARGET_BOUND)]
        body_target.append(ops.clip(-sin * dx + c * dy, -TARGET_BOUND, TARGET_BOUND))
        scaled_shape = [u / bound for u, bound in zip(components(self.shape(s)), self.shape_bounds)]
        momentum = zip(components(s.momentum), self.momentum_bounds)
        scaled_momentum = [ops.clip(p / scale, -MOMENTUM_BOUND, MOMENTUM_BOUND) for p, scale in momentum]
        return ops.pack([*body_target, c, sin, *scaled_shape, *scaled_momentum])

    def describe(self, s, ops=SCALAR):
        x, y, theta = ops.components(s.pose)
        distance = self.distance(s, ops)
        state = {"x": x, "y": y, "theta": theta, **self.shape_info(s, ops), "momentum": ops.vector(s.momentum),
                 "t": s.t}  # fmt: skip
        return {
            "state": state, "spatial_momentum": self.spatial_momentum(s, ops), "target": ops.vector(s.target),
            "distance": distance,
            "model": ops.flag(s.full) if traced(ops) else ops.where(s.full, "full", "reduced"),  # JAX's: whether full
            "is_success": ops.flag(distance <= self.success_radius),
        }


def _rows(segments, rows):
    """The control segments of the rows selected (a duration that is one float for all rows stays one)."""
    return [tuple(a if np.ndim(a) == 0 else a[rows] for a in segment) for segment in segments]
