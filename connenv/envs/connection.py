"""Connection-v0: any system moved by a mechanical connection, from the connection alone."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from connenv import examples
from connenv.core.backend import SCALAR, concat, namespace, traced
from connenv.core.integrators import make_stepper
from connenv.core.lie import FRAMES, GROUPS, ConstantConnection, ExactConnection, connection_system
from connenv.core.segments import bounded_segments, bounded_segments_batch, run_segments
from connenv.core.state import Fields, given, vector, within
from connenv.core.steppers import StepperError, check_observable
from connenv.core.validation import (
    MAGNITUDE_BOUND,
    check_bounds,
    check_dt,
    check_number,
    check_stepper_options,
    real_array,
)
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Spec
from connenv.envs.user_task import BuilderTask
from connenv.rendering.connection import ConnectionRenderer

DT_MAX = 100.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
ON_GROUP = 1e-9  # how far a given g may be from its group (reset options, a task's reset)
GROUP_BOUND = 1e-9  # how far a stepped g may drift from its group before the step raises StepperError


@dataclass
class ConnectionState(State):
    """g as its group's coordinates (``connenv.core.lie``: θ for SO2, (x, y, θ) for SE2, the 9 entries of R for SO3,
    (x, y) for R2), the shape s and the time t."""

    g: np.ndarray
    s: np.ndarray
    t: float


class ConnectionEnv(BuilderTask, TaskEnv):
    r"""
    ## Description

    A system whose shape s ∈ ℝᵏ the controller moves and whose position g in a Lie group follows through a *mechanical
    connection* A(s) (Lawton; Marsden, Montgomery & Ratiu 1990): with ξ the group velocity,

        ξ = −A(s) ṡ,    ġ = g ξ^ (frame="body"),    ġ = ξ^ g (frame="space").

    A falling cat, a swimmer at zero momentum, a satellite with rotors, a rolling ball: a closed loop of shapes moves g
    by the connection's holonomy however fast it is run (docs/physics/connections.md). `group` is one of

    | group | g (in `info["state"]["g"]`) | ξ |
    |---|---|---|
    | "SO2" | 2×2 rotation | ω |
    | "SE2" | 3×3 homogeneous [[R, (x, y)], [0, 0, 1]] | (v₁, v₂, ω) |
    | "SO3" | 3×3 rotation | (ω₁, ω₂, ω₃), ω̂ v = ω × v |
    | "R2" | the vector (x, y) | (v₁, v₂) |

    and `connection(s)` returns A(s), shape (dim 𝔤, k), for a shape s of shape (k,); one that is the same at every shape
    (the rolling ball's, the beanie's, a tube's) may be given as that array A.

    ## Action Space

    `Box(-1, 1, (k,), float32)`: the shape velocity ṡ = action · max_shape_speed, constant over the step, a coordinate
    stopping at a finite bound; infinite bounds are allowed (a coordinate that winds, as a rotor's angle).

    ## Observation Space

    Default: g flattened (SO2: 4 entries, SE2, SO3: 9, R2: 2) and s, `Box(-inf, inf, (n + k,), float32)`; a step taking
    an entry past float32's range (±3.4e38) raises `connenv.core.StepperError`. A `task`'s `observation(state)`, if it
    has one, as float32 (finite, of one shape) in its `observation_space` (else an unbounded Box).

    ## Rewards

    Default 0; with a `task`, `task.reward(state, next_state)` on the states as in `info["state"]` (finite).

    ## Starting State

    g = identity, s at the midpoint of its bounds where both are finite, else the finite bound or 0, t = 0, or either
    from `task.reset(np_random)`'s dict. `reset(options={"state": {...}})` sets either exactly:

    ## Episode End

    Never terminates by default; with a `task`, when `task.terminated(state)`. `info["is_success"]` is
    `task.is_success(state)` if the task has it, else False. The registration truncates after 1000 steps
    (`gym.make("connenv/Connection-v0", max_episode_steps=...)` changes it).

    ## Arguments

    | kwarg | default | range |
    |---|---|---|
    | group | (required) | "SO2", "SE2", "SO3", "R2" |
    | connection | (required) | callable s -> A(s), finite, of shape (dim 𝔤, k); or a constant array A of that shape |
    | shape_low, shape_high | (required) | arrays of shape (k,), low < high, within ±1e3; ±inf allowed |
    | dt | 0.1 | [1e-12, 100] s |
    | frame | "body" | "body", "space" |
    | max_shape_speed | 1.0 | (0, 1e3] |
    | task | None | an object with reset, reward, terminated and optionally observation, is_success (above) |
    | draw | None | callable draw(state, canvas) rendering a frame on a `connenv.rendering.Canvas` |
    | vectorized | False | True if connection(s) maps shapes (N, k) to (N, dim 𝔤, k): the steps call it once per batch |
    | exact_segment | None | callable (g, s, ṡ, τ) -> g after a segment at constant ṡ, in closed form (below) |
    | integrator | below | "exact", "magnus", "euler", "rk4", "dop853", "rk45", "lsoda", "radau" |
    | atol (magnus: 1e-10) / substeps, rtol, atol | | the stepper's |

    The default step is "exact" for a constant A or with an `exact_segment`, else "magnus" (`connenv.core.lie.Magnus`),
    which keeps g on its group to rounding by closed-form exponentials, substeps per segment chosen for an error ≤ atol,
    one (the exact flow) where A is constant along the path. A system that knows its flow gives it as
    `exact_segment(g, s, ṡ, τ)`, g's coordinates after a segment of length τ at constant ṡ from s, for one state or rows
    (τ a float or one per row), stepped by `connenv.core.lie.ExactConnection`; a row of NaN goes to the generic
    integrator, an infinite one raises StepperError. Diverged: g over 1e-9 off its group, or a segment needing over 4096
    substeps (a pole of A on the path). A callable connection and an exact_segment are tried at construction (at two
    shapes within the bounds; the segment over dt at rest and at top speed), the segment's answer again at every step:
    one that raises or returns no finite real numbers of the right shape is a ValueError or TypeError naming it.

    Every `info` has `"state"`: `{"g": ..., "s": array (k,), "t": float}`, and `"is_success"`. A `task`'s methods take
    such state dicts, row by row in the vector env; `connenv.envs.user_task` checks them (at construction: without
    reset, reward and terminated, a TypeError) and every answer, naming the method.
    """

    renderer = ConnectionRenderer

    JAX_NEEDS = (
        "the connection must be written with the namespace of its argument (connenv.core.backend.namespace(s), "
        "JAX's on a JAX array; numpy's functions only on constants, as connenv.examples' connections), and so must an "
        "exact_segment; a task's methods take Python numbers and do not trace (task=None)"
    )
    """What ``connenv.jax.make`` needs of the user's functions to trace this builder (its TypeError otherwise)."""

    STATE = Fields(
        given("g", "g_shape", "check_g", "on its group to 1e-9, every entry within ±1e3", "a vector for R2"),
        vector("s", "k", about="the shape",
               **within("low", "high", MAGNITUDE_BOUND, ("shape_low", "shape_high"))),
    )

    def __init__(self, group: str, connection, shape_low, shape_high, dt: float = 0.1, frame: str = "body",
                 max_shape_speed: float = 1.0, task=None, render_mode: str | None = None, draw=None,
                 vectorized: bool = False, integrator: str | None = None, exact_segment=None, **stepper_options):
        super().__init__(render_mode, check_dt(dt, DT_MAX))
        if group not in GROUPS:
            raise ValueError(f"group={group!r} is not one of {list(GROUPS)}")
        if frame not in FRAMES:
            raise ValueError(f"frame={frame!r} is not one of {list(FRAMES)}")
        self.group = GROUPS[group]
        self.low, self.high = check_bounds("shape_low", shape_low, "shape_high", shape_high)
        self.max_shape_speed = check_number("max_shape_speed", max_shape_speed, 0.0, MAGNITUDE_BOUND, open_low=True)
        if not isinstance(vectorized, (bool, np.bool_)):
            raise TypeError(f"vectorized={vectorized!r} must be True or False")
        self.adopt(task, draw, ("g", "s"))
        self.system = connection_system(group, frame, connection, bool(vectorized), exact_segment,
                                        self.sample_shapes(), self.dt, self.max_shape_speed)  # fmt: skip
        check_stepper_options(self.name, stepper_options, type(self))
        if integrator is None:
            integrator = "exact" if isinstance(self.system, (ConstantConnection, ExactConnection)) else "magnus"
        self.stepper = make_stepper(integrator, self.system, **stepper_options)
        self.state = ConnectionState(np.array(self.group.identity()), self.start_shape(), 0.0)
        self.action_space = spaces.Box(-1.0, 1.0, self.low.shape, np.float32)
        self.observation_space = self._observation_space()

    def start_shape(self):
        """The default s: the midpoint of finite bounds, else the finite bound, else 0."""
        low, high = np.isfinite(self.low), np.isfinite(self.high)
        middle = 0.5 * (np.where(low, self.low, 0.0) + np.where(high, self.high, 0.0))
        return np.where(low & high, middle, np.where(low, self.low, np.where(high, self.high, 0.0)))

    def sample_shapes(self):
        """The shapes the connection is tried at: the start, and a quarter up the bounds (start ± 0.5 if infinite)."""
        low = np.where(np.isfinite(self.low), self.low, self.start_shape() - 0.5)
        high = np.where(np.isfinite(self.high), self.high, self.start_shape() + 0.5)
        return np.stack([self.start_shape(), 0.75 * low + 0.25 * high])

    @property
    def components(self) -> dict:
        """The state's names for the model: g's coordinates (x, y, theta for SE2, R's entries for SO3), s₁…s_k."""
        names = {"SO2": ("theta",), "SE2": ("x", "y", "theta"), "R2": ("x", "y"),
                 "SO3": tuple(f"R{i}{j}" for i in range(1, 4) for j in range(1, 4))}[self.group.name]
        return {"g": names, "s": tuple(f"s{i}" for i in range(1, self.low.size + 1))}

    def parameters(self):
        own = {"group": self.group.name, "frame": self.system.frame, "max_shape_speed": self.max_shape_speed}
        return {**own, **super().parameters()}

    def start(self, options, ops=SCALAR):  # the default start is no draw: the same on JAX's reset (connenv.jax)
        values = self.start_values(options, {"g": np.array(self.group.identity()), "s": self.start_shape()})
        return ConnectionState(values["g"], values["s"], 0.0)

    def command(self, a):
        """ṡ of action a."""
        return a * self.max_shape_speed

    def advance(self, state, s_dot, stepper, ops=SCALAR):
        """The state after a step at the shape velocity ṡ, stopped where s meets a bound, by this stepper: one state, or
        rows, each with its own segments."""
        cut = bounded_segments if ops is SCALAR else bounded_segments_batch
        segments, s, _ = cut(state.s, s_dot, self.low, self.high, self.dt)
        g, _ = run_segments(stepper, self.system, state.g, segments)
        self.check_group(g)
        if self.observes_state:
            self.check_observable(g, s)
        return state.replace(g=g, s=s, t=state.t + self.dt)

    @staticmethod
    def check_observable(g, s):
        """StepperError, keeping the state, where g's coordinates or s (one state or rows) left float32's range, the
        observation's (SE2's and R2's position, s; an angle that large has lost all precision)."""
        check_observable("g", g)
        check_observable("s", s)

    def check_group(self, g):
        """StepperError if g (any row) left its group by more than GROUP_BOUND (SO3's matrices; the others cannot)."""
        if self.group.name != "SO3":
            return
        ops = namespace(g)
        if traced(ops):  # traced rows (connenv.jax): ‖RᵀR − I‖ as a failure reported as data
            R = self.group.matrix(g)
            gram = np.swapaxes(R, -1, -2) @ R - np.eye(3)
            off = ops.sqrt((gram * gram).sum(axis=(-2, -1)))
            ops.fail(~(off <= GROUP_BOUND), f"{self.stepper} left SO(3): ‖RᵀR − I‖ > {GROUP_BOUND}")
            return
        off = np.max(self.group.off_group(self.group.matrix(g)))
        if not off <= GROUP_BOUND:
            raise StepperError(f"{self.stepper} left SO(3): ‖RᵀR − I‖ = {off:.3g} > {GROUP_BOUND}")

    @property
    def g_shape(self) -> tuple:
        """The shape of g as the reset state takes it: a vector for R2, a matrix for the others."""
        return (2,) if self.group.name == "R2" else (2, 2) if self.group.name == "SO2" else (3, 3)

    @property
    def k(self) -> int:
        """The number of shape coordinates."""
        return self.low.size

    def check_g(self, value):
        """g given at reset: on its group to ON_GROUP, every entry within ±MAGNITUDE_BOUND; as its coordinates."""
        shape = self.g_shape
        expected = f"finite real numbers of shape {shape} for group {self.group.name}"
        g = real_array("state g", value, expected)
        if g.shape != shape or not np.all(np.isfinite(g)):
            raise ValueError(f"state g={value!r} must be {expected}")
        if np.any(np.abs(g) > MAGNITUDE_BOUND):
            raise ValueError(f"state g={value!r} has an entry beyond ±{MAGNITUDE_BOUND}")
        off = float(self.group.off_group(g))
        if not off <= ON_GROUP:
            raise ValueError(f"state g={value!r} is {off:.3g} off {self.group.name}; it must be on it to {ON_GROUP}")
        return self.group.coordinates(g)

    def state_dict(self, state, ops=SCALAR):
        """The state as `info["state"]`: g as a matrix (a vector for R2), s, t."""
        s = state.s if traced(ops) else np.array(state.s)  # JAX's rows (connenv.jax): no numpy
        return {"g": self.group.matrix(state.g), "s": s, "t": state.t}

    def raw_observation(self, state):
        """g's matrix entries (R2: the vector) and s, as float32."""
        g = self.group.matrix(state.g)
        return concat([g.reshape(*np.shape(state.s)[:-1], -1), state.s], axis=-1).astype(np.float32)


SPECS = (
    Spec(
        "connenv/Connection-v0", ConnectionEnv, max_episode_steps=1000, dt_max=DT_MAX,
        physics="connections.md", example=examples.beanie,
        variants=(examples.beanie, examples.rolling_ball),  # a flat and a curved connection
        fast_start={"state": {"s": [1000.0]}},
        bench="connection", jax=(examples.beanie_rk4,),
    ),
)
