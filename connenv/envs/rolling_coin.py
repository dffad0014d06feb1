"""RollingCoin-v0: park a vertical coin, which rolls without slipping, through its connection."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR
from connenv.core.backend import vector as entries_vector
from connenv.core.params import Args, Bound, integrator, options, scale, step
from connenv.core.state import Fields, Options, angle, number, vector
from connenv.core.validation import ANGLE_BOUND, MAGNITUDE_BOUND
from connenv.envs.connection import DT_MAX, ConnectionEnv, ConnectionState  # DT_MAX: its dt range
from connenv.envs.spec import Measure, Spec
from connenv.rendering.rolling_coin import CoinRenderer
from connenv.systems import rolling_coin

TIME_COST = 0.01  # reward paid per step until success
SUCCESS_BONUS = 1.0  # reward on the step that parks
TARGET_DISTANCE = (1.0, 3.0)  # m: the target's distance from the start is drawn uniformly in this range
OFFSET_BOUND = 10.0  # m: the observed offsets are clipped here
TARGET_BOUND = Bound(lambda env, values: np.array([MAGNITUDE_BOUND, MAGNITUDE_BOUND, ANGLE_BOUND]), "(1e3, 1e3, 2π)")


@dataclass
class CoinState(ConnectionState):
    """ConnectionState with g = (x, y), s = (θ, φ), and the target (x*, y*, θ*)."""

    components: ClassVar[dict] = {"g": ("x", "y"), "s": ("theta", "phi"),
                                  "target": ("target_x", "target_y", "target_theta")}

    target: np.ndarray


class RollingCoinEnv(ConnectionEnv):
    r"""
    ## Description

    An upright coin of radius R rolls on the plane without slipping (`connenv.systems.rolling_coin`). The controller
    steers its heading θ (from the y axis) and rolls it by φ; its contact point (x, y) follows through the mechanical
    connection of rolling, ẋ = R sin θ φ̇, ẏ = R cos θ φ̇: `ConnectionEnv` on the group ℝ² with the shape (θ, φ). Steering
    alone never moves the coin and rolling moves it along its heading, so parking it beside its start takes a manoeuvre.

    ## Action Space

    `Box(-1, 1, (2,), float32)`: (θ̇, φ̇) = (a₀ · max_steer_rate, a₁ · max_roll_rate), constant over the step.

    ## Observation Space

    `Box(4,) float32`, with d = (x* − x, y* − y), the heading f = (sin θ, cos θ) and r = (cos θ, −sin θ) to its right:

    | Num | Observation | Min | Max | Unit |
    |-----|-------------|-----|-----|------|
    | 0 | d · f, the target's distance ahead, clipped | -10 | 10 | m |
    | 1 | d · r, the target's distance to the right, clipped | -10 | 10 | m |
    | 2 | sin(θ* − θ) | -1 | 1 | |
    | 3 | cos(θ* − θ) | -1 | 1 | |

    ## Rewards

    `c − c′ − 0.01 + 1 · (parked after the step)`, with the cost c = |d| + R |θ* − θ| (m: the heading error wrapped into
    [−π, π], weighed by the radius) before the step and c′ after it.

    ## Starting State

    The coin at the origin, θ = φ = 0, t = 0; the target in a uniform direction at a distance uniform in [1, 3] m, its
    heading θ* uniform in [−π, π). `reset(options={"state": {...}, "target": (x*, y*, θ*)})` sets any of these exactly:

    ## Episode End

    Terminated when parked (`info["is_success"]`): |d| ≤ `position_tolerance` and |θ* − θ| ≤ `heading_tolerance`
    (wrapped); φ is free. Truncated after 200 steps (20 s) by the registration's time limit; the reference planner
    (`agents.controllers.rolling_coin.CoinPlanner`) needs at most π/2 + 3/(R · 2) + π s, 78 steps.

    ## Arguments

    The default step is exact in closed form (the chord of the arc rolled at constant rates), for any rates and dt.
    Every `info` has `"state"` (the Starting State's keys and `t`), `"target"` (x*, y*, θ*), `"distance"` (|d|, m),
    `"heading_error"` (θ* − θ wrapped, rad) and `"is_success"`.
    """

    renderer = CoinRenderer
    metadata = {**ConnectionEnv.metadata, "measures": ("distance", "heading_error")}

    ARGS = Args(
        scale("radius", 0.5, "m", high=MAGNITUDE_BOUND),
        scale("max_steer_rate", 1.0, "rad/s", high=MAGNITUDE_BOUND),
        scale("max_roll_rate", 2.0, "rad/s", high=MAGNITUDE_BOUND),
        step(0.1, DT_MAX),
        scale("position_tolerance", 0.05, "m", physical=False),
        scale("heading_tolerance", 0.05, "rad", high=math.pi, open_high=True, physical=False),
        integrator(None, "exact", "magnus", "euler", "rk4", "dop853", "rk45", "lsoda", "radau", default_text='"exact"'),
        options(names="atol (magnus) / substeps / rtol, atol"),
    )

    STATE = Fields(
        number("x", "m", bound=MAGNITUDE_BOUND),
        number("y", "m", bound=MAGNITUDE_BOUND),
        angle("theta", "the heading"),
        number("phi", "rad", "the roll angle", bound=MAGNITUDE_BOUND),
    )
    OPTIONS = Options(vector("target", 3, "m, m, rad", "(x*, y*, θ*)", bound=TARGET_BOUND))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        self.radius, self.rates = a.radius, entries_vector(a.max_steer_rate, a.max_roll_rate)
        self.position_tolerance, self.heading_tolerance = a.position_tolerance, a.heading_tolerance
        super().__init__(
            "R2", functools.partial(rolling_coin.connection, radius=self.radius), shape_low=[-math.inf, -math.inf],
            shape_high=[math.inf, math.inf], dt=a.dt, render_mode=render_mode, vectorized=True, integrator=a.integrator,
            exact_segment=functools.partial(rolling_coin.exact_segment, radius=self.radius), **stepper_options,
        )
        self.state = CoinState(np.zeros(2), np.zeros(2), 0.0, np.array([0.0, 1.0, 0.0]))

    def _observation_space(self):
        high = np.array([OFFSET_BOUND, OFFSET_BOUND, 1.0, 1.0], np.float32)
        return spaces.Box(-high, high, dtype=np.float32)

    def start(self, options, ops=SCALAR):
        """The coin at the origin, the target drawn from np_random; traced (``connenv.jax``, ops its namespace), the
        same draws from its key."""
        rng = self.np_random
        distance, direction = rng.uniform(*TARGET_DISTANCE), rng.uniform(-math.pi, math.pi)
        heading = rng.uniform(-math.pi, math.pi)
        target = entries_vector(distance * ops.sin(direction), distance * ops.cos(direction), heading)
        values = self.reset_values(options, {"target": target})
        g = entries_vector(values["x"], values["y"])
        return CoinState(g, entries_vector(values["theta"], values["phi"]), 0.0, values["target"])

    def command(self, a):
        """(θ̇, φ̇) of action a (one (2,) or a batch (N, 2))."""
        return a * self.rates

    @staticmethod
    def coordinates(state, ops=SCALAR):
        """x, y, θ, φ, x*, y*, θ*: Python floats for one state, arrays over the rows of a batch."""
        if ops is SCALAR:
            return (*state.g.tolist(), *state.s.tolist(), *state.target.tolist())
        return (*state.g.T, *state.s.T, *state.target.T)

    def errors(self, state, ops=SCALAR):
        """d (the target's offset, x and y), the heading f's components (sin θ, cos θ), and θ* − θ wrapped."""
        x, y, theta, _, x_target, y_target, theta_target = self.coordinates(state, ops)
        turn = theta_target - theta
        return x_target - x, y_target - y, ops.sin(theta), ops.cos(theta), ops.atan2(ops.sin(turn), ops.cos(turn))

    def cost(self, distance, heading_error):
        return distance + self.radius * abs(heading_error)

    def observe(self, state, ops=SCALAR):
        dx, dy, sin, cos, heading = self.errors(state, ops)
        ahead = ops.clip(dx * sin + dy * cos, -OFFSET_BOUND, OFFSET_BOUND)
        right = ops.clip(dx * cos - dy * sin, -OFFSET_BOUND, OFFSET_BOUND)
        return ops.pack([ahead, right, ops.sin(heading), ops.cos(heading)])

    def success(self, distance, heading_error):
        return (distance <= self.position_tolerance) & (abs(heading_error) <= self.heading_tolerance)

    def reward(self, before, after, info, ops=SCALAR):
        dx, dy, _, _, heading = self.errors(before, ops)
        progress = self.cost(ops.hypot(dx, dy), heading) - self.cost(info["distance"], info["heading_error"])
        return progress - TIME_COST + SUCCESS_BONUS * ops.real(info["is_success"])

    def describe(self, state, ops=SCALAR):
        dx, dy, _, _, heading = self.errors(state, ops)
        x, y, theta, phi = self.coordinates(state, ops)[:4]
        distance = ops.hypot(dx, dy)
        return {
            "state": {"x": ops.real(x), "y": ops.real(y), "theta": ops.real(theta), "phi": ops.real(phi), "t": state.t},
            "target": state.target.copy(), "distance": ops.real(distance), "heading_error": ops.real(heading),
            "is_success": ops.flag(self.success(distance, heading)),
        }


SPECS = (
    Spec(
        "connenv/RollingCoin-v0", RollingCoinEnv, max_episode_steps=200, dt_max=DT_MAX,
        physics="RollingCoin.md", measure=Measure("time to park", "s", "time_to_success"),
        controllers=("turn_roll_turn",), variants=({}, {"integrator": "magnus"}),
        golden=(("coin", {"max_episode_steps": 60, "position_tolerance": 0.5}, None),),
        bench="coin",
        jax=({},),
    ),
)
