"""SnakeSwimmer-v0: swim a chain of three elliptic links through a perfect fluid to a target by bending its joints."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from connenv.core.backend import SCALAR
from connenv.core.lie import fixed_rule
from connenv.core.params import Args, Bound, integrator, interval, options, scale, step
from connenv.core.segments import straight_path
from connenv.core.state import number
from connenv.core.validation import MAGNITUDE_BOUND, decimal
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Spec
from connenv.envs.swimmer import INTEGRATORS, SWIMMER, PlanarSwimmer, swimmer_state
from connenv.rendering.snake_swimmer import SnakeSwimmerRenderer
from connenv.systems.snake_swimmer import JOINT_LIMIT, ReducedSnakeSwimmer, SnakeSwimmer

DT_MAX = 0.25  # s: the longest dt; longer steps (joint moves up to the whole range) make the Lie-group rule's choice
# at construction take seconds
DEFAULT_INTEGRATOR = "magnus"
ASPECT_MAX = 100.0  # the largest aspect ratio a/b of a link (see SnakeSwimmerEnv)
SIZE_MIN = 1e-6  # the least a (m) and link_density: the link mass link_density · πab stays positive, so rho may be 0


def thinnest(args):
    """The least b of the arguments: a/ASPECT_MAX, as the table writes it."""
    return decimal(args["a"] / ASPECT_MAX)


@dataclass
class SnakeState(State):
    """The middle link's pose (x, y, θ), body momentum (0 in the reduced model), joint angles s = (α, β), target (x, y),
    time t; full: whether it steps the full model, whose spatial momentum stays at momentum0, its value at reset."""

    components: ClassVar[dict] = {"pose": ("x", "y", "theta"), "momentum": ("P1", "P2", "Pi"), "s": ("alpha", "beta"),
                                  "target": ("target_x", "target_y")}

    pose: np.ndarray
    momentum: np.ndarray
    s: np.ndarray
    target: np.ndarray
    t: float
    full: bool
    momentum0: np.ndarray


class SnakeSwimmerEnv(PlanarSwimmer, TaskEnv):
    r"""
    ## Description

    Three identical rigid elliptic links, semi-axes a along the link and b across it, hinged tip to tip, float in an
    unbounded planar ideal fluid at rest at infinity (Kanso, Marsden, Rowley & Melli-Huber 2005), each link's fluid that
    of the link alone, without drag; the controller assigns the joint angles s = (α, β) (an *active constraint*,
    Bressan; docs/physics/SnakeSwimmer.md). With g = (x, y, θ) the middle link's pose and μ = (P₁, P₂, Π) the body
    momentum of chain and fluid: from rest μ stays 0 and the motion is geometric (a mechanical connection), integrated
    on (x, y, θ) alone, a closed loop of (α, β) swimming the chain alike at any speed; a nonzero initial momentum
    switches the episode to the full (Kirchhoff) model on (x, y, θ, μ), conserving the spatial momentum. Goal: the
    middle link's centre within `success_radius` of a target. A body length: 6a, the straight chain's.

    ## Action Space

    `Box([-1, -1], [1, 1], float32)`: the commanded joint angles (α*, β*) = action · 2π/3 (rear, front), toward which
    they move straight, the one with further to go at `max_joint_speed`, holding on arrival or stopping at dt.

    ## Observation Space

    `Box(9,) float32` (𝕀_loc(0): the straight chain's locked inertia), target and momentum (0 if reduced) clipped:

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | target in the middle link's frame, along its axis, in body lengths | -3 | 3 |
    | 1 | target in the middle link's frame, across it, in body lengths | -3 | 3 |
    | 2 | cos θ | -1 | 1 |
    | 3 | sin θ | -1 | 1 |
    | 4 | α / (2π/3) | -1 | 1 |
    | 5 | β / (2π/3) | -1 | 1 |
    | 6 | P₁ / 𝕀_loc(0)₁₁, m/s | -10 | 10 |
    | 7 | P₂ / 𝕀_loc(0)₂₂, m/s | -10 | 10 |
    | 8 | Π / 𝕀_loc(0)₃₃, rad/s | -10 | 10 |

    ## Rewards

    With d the distance from the middle link's centre to the target before the step and d′ after it, progress in units
    of the success radius and a cost of time:

        reward = (d − d′) / success_radius − 0.01    (summed to success: (d₀ − d_T) / success_radius − 0.01 · steps)

    ## Starting State

    At rest, straight (μ = 0, α = β = 0) at the origin, θ = 0, t = 0; the target a uniform [1, 2] body lengths away in a
    uniform direction (np_random). `reset(options={"state": {...}, "target": (x, y)})` sets any of these exactly:

    ## Episode End

    Terminated when the middle link's centre is within `success_radius` of the target at the end of a step
    (`info["is_success"]`); truncated after 1000 steps (50 s at the default dt) by the registration's time limit.

    ## Arguments

    By default the reduced model takes the Lie-group step on SE(2) (`connenv.core.lie`), its quadrature rule the
    cheapest meeting atol on every joint motion at top speed (chosen at construction, which thinner links than a/b =
    100 would make slow), the full model (no connection) by DOP853. Diverged: the full model's spatial momentum moved
    over 0.1 of its norm since reset. Every `info` has `"state"` (`x`, `y`, `theta`, `alpha`, `beta`, `momentum` (μ),
    `t`, in SI), `"spatial_momentum"` ((R(θ)P, Π + x P_y − y P_x), conserved), `"target"` (x, y), `"distance"` (m),
    `"model"` ("reduced" or "full") and `"is_success"`. The evaluation table averages the final `"distance"`.
    """

    renderer = SnakeSwimmerRenderer
    state_class = SnakeState
    TARGET_DISTANCES = (1.0, 2.0)  # body lengths
    TOLERANCES: ClassVar[dict] = {"rtol": 1e-10, "atol": 1e-12}

    metadata: ClassVar[dict] = {**TaskEnv.metadata, "measures": ("distance",)}

    JAX_STATIC = ("a", "b", "link_density", "rho", "max_joint_speed")
    # they set the Lie-group step's fixed rule (snake_rule: its pieces)

    ARGS = Args(
        interval("a", 0.5, "m", SIZE_MIN, MAGNITUDE_BOUND, "the links' semi-axis along the link"),
        interval("b", 0.05, "m", Bound(thinnest, "a/100"), "a", "across the link", open_high=True),
        interval("link_density", 1.0, "kg/m²", SIZE_MIN, MAGNITUDE_BOUND, "a link's mass is link_density · πab"),
        interval("rho", 1.0, "kg/m²", 0.0, MAGNITUDE_BOUND, "fluid density"),
        scale("max_joint_speed", 3.0, "rad/s", high=MAGNITUDE_BOUND),
        step(0.05, DT_MAX),
        scale("success_radius", None, "m", optional=True, typical=Bound(lambda args: 0.6 * args["a"], "0.6a"),
              high=Bound(lambda args: 6.0 * args["a"], "6a"), open_high=True, physical=False,
              default_text="None: 0.1 body length, 0.6a"),
        integrator(DEFAULT_INTEGRATOR, *INTEGRATORS),
        options("rtol 1e-10, atol 1e-12"),
    )

    STATE = swimmer_state(
        number("alpha", "rad", "the rear joint", bound=JOINT_LIMIT),
        number("beta", "rad", "the front joint", bound=JOINT_LIMIT),
    )

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        params = {key: getattr(a, key) for key in ("a", "b", "link_density", "rho")}
        reduced = ReducedSnakeSwimmer(**params)
        self.body_length, self.max_joint_speed, self.joint_limit = 6.0 * a.a, a.max_joint_speed, JOINT_LIMIT
        self.success_radius = 0.1 * self.body_length if a.success_radius is None else a.success_radius
        self.target_unit, self.shape_bounds = self.body_length, (JOINT_LIMIT, JOINT_LIMIT)
        self.build(SnakeSwimmer(**params), reduced, a.integrator, stepper_options,
                   lambda atol: snake_rule(reduced, self.max_joint_speed, self.dt, atol))  # fmt: skip

    def parameters(self):
        return {**super().parameters(), "model": "full" if self.state.full else "reduced"}

    def advance(self, s, s_cmd, stepper, ops=SCALAR):
        """The joints follow their `straight_path`, the full model drifting while they hold: one state, or rows."""
        s_dot, ramp, s_end = straight_path(s.s, s_cmd, self.dt, self.max_joint_speed)
        moving = (s.s, s_dot, ramp)  # held joints do not move the chain at zero momentum
        full = [moving, (s_end, np.zeros(s_dot.shape), self.dt - ramp)]
        pose, momentum = self.swim(s, full, [moving], stepper, ops)
        return SnakeState(pose, momentum, s_end, s.target, s.t + self.dt, s.full, s.momentum0)

    def command(self, a):
        """The commanded joint angles (α*, β*) of action a."""
        return a * JOINT_LIMIT

    def shape(self, s):
        return s.s

    def start_shape(self, values):
        return np.array([values["alpha"], values["beta"]])

    def shape_info(self, s, ops=SCALAR):
        alpha, beta = ops.components(s.s)
        return {"alpha": alpha, "beta": beta}


@functools.cache
def snake_rule(system, max_speed, dt, atol):
    """The reduced model's Lie-group rule (pieces, points; `connenv.core.lie.fixed_rule`), judged on the motions at top
    speed in the eight directions from a 3 × 3 grid of joint angles, each for dt or until a joint meets its limit."""
    grid = np.linspace(-JOINT_LIMIT, JOINT_LIMIT, 3)
    segments = []
    for start in (np.array([p, q]) for p in grid for q in grid):
        for direction in (np.array([i, j], float) for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j):
            room = min((JOINT_LIMIT - d * x) / max_speed for x, d in zip(start, direction) if d)
            if room > 0.0:
                segments.append((start, direction * max_speed, min(dt, room)))
    return fixed_rule(system, segments, atol)


SPECS = (
    Spec(
        "connenv/SnakeSwimmer-v0", SnakeSwimmerEnv, max_episode_steps=1000, dt_max=DT_MAX,
        physics="SnakeSwimmer.md", **SWIMMER,
        golden=(
            ("snake", {"max_episode_steps": 60, "success_radius": 2.9}, None),
            ("snake_full", {"max_episode_steps": 60}, {"state": {"momentum": (0.3, -0.2, 0.1)}}),
        ),
        bench="snake",
        jax=({},),
    ),
)
