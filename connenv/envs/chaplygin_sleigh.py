"""ChaplyginSleigh-v0: a sled on a knife edge, propelled and steered only by a mass moving across it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import ARRAYS, SCALAR, is_traced, namespace, traced
from connenv.core.backend import vector as entries_vector
from connenv.core.integrators import make_stepper
from connenv.core.mechanics import JUMP_ROWS, JUMP_STEPPER, JumpClass, JumpFlow
from connenv.core.params import Args, Bound, integrator, interval, options, scale, step
from connenv.core.segments import bounded_segments, bounded_segments_batch, check_drift, run_segments
from connenv.core.state import Fields, Options, angle, number, vector
from connenv.core.validation import MAGNITUDE_BOUND
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.rendering.chaplygin_sleigh import SleighRenderer
from connenv.systems.chaplygin_sleigh import ChaplyginSleigh

DT_MAX = 1.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
TRAVEL_MAX = 2.0  # m: the longest travel of the mass in one step, max_mass_speed · dt (the default speed at DT_MAX)
DEFAULT_INTEGRATOR = "rk4"
DEFAULT_SUBSTEPS = 2  # RK4 × 2, chosen on the work–precision chart (python -m connenv.bench precision --env sleigh)
ENERGY_ERROR_BOUND = 1e-2  # |the stepper's energy error| / (1 + E) past which it has diverged: StepperError
TARGET_DISTANCE = (1.0, 2.0)  # m from the start, any direction
SPEED_BOUND = 10.0  # |v| (m/s) given at reset
RATE_BOUND = 20.0  # |ω| (rad/s) given at reset
OBSERVED = (10.0, 10.0, 5.0, 10.0, 1.0, 1.0, 1.0, 1.0)  # bounds of the observation (clipped), in its order
PROGRESS_GAIN = 10.0  # reward per metre of approach
TIME_COST = 0.01  # reward paid per step until success


def mass_speed(env, values):
    """|u̇| given at reset: max_mass_speed, 0 without it (u jumps)."""
    return 0.0 if env.max_mass_speed is None else env.max_mass_speed


def along_speed(env, values):
    """|u̇₁| given at reset: the mass's speed, 0 with box=0 (the rail alone)."""
    return mass_speed(env, values) if env.box > 0.0 else 0.0



@dataclass
class SleighState(State):
    """y = (x, y, φ, p₁, p₂) (P, heading, Bressan's momenta: `connenv.systems.chaplygin_sleigh`); the mass offset u and
    u̇ at the step's end (along, across); the target; t; the energy error (T's change where u is held, since reset)."""

    components: ClassVar[dict] = {"y": ("x", "y", "phi", "p1", "p2"), "u": ("u1", "u2"), "u_dot": ("u1_dot", "u2_dot"),
                                  "target": ("target_x", "target_y")}
    phase: ClassVar[tuple] = ("phi", "p2", "u1", "u2")

    y: np.ndarray
    u: np.ndarray
    u_dot: np.ndarray
    target: np.ndarray
    t: float
    energy_error: float


class ChaplyginSleighEnv(TaskEnv):
    r"""
    ## Description

    A sled of mass M and inertia J (about its centre of mass C) glides on a knife edge at the point P of its axis, C a
    distance a ahead of P: P cannot slip sideways (the Chaplygin sleigh). Its only drive is a mass m in a box on it at
    the offset from C the controller assigns, u = (u₁ along the axis, u₂ across, left positive), an *active constraint*:
    shaking the mass across propels the sled (tail first), along and across together turns it. u̇ enters the equations
    quadratically (the thrust), so only the rail over the knife edge is fit for jumps (docs/physics/ChaplyginSleigh.md).

    ## Action Space

    `Box(-1, 1, (2,), float32)` by the class (`env.unwrapped.jump_class`); action 0 at u = 0 keeps the mass at C.

    | class | action a means | |
    |---|---|---|
    | general (the default) | u̇ = a · max_mass_speed through the step | the mass stops at the box's walls |
    | fit (box=0, offset=0) | u = a · (box, rail) commanded | reached at max_mass_speed; with None, a jump |

    ## Observation Space

    `Box(8,) float32`, each entry clipped to its bound:

    | Num | Observation | Bound |
    |-----|-------------|-------|
    | 0 | target − P along the sled's axis, m | ±10 |
    | 1 | target − P across it (left), m | ±10 |
    | 2 | v, forward velocity of P, m/s | ±5 |
    | 3 | ω, rad/s | ±10 |
    | 4 | u₂ / rail | ±1 |
    | 5 | u̇₂ / max_mass_speed (u̇₂ without max_mass_speed, always 0) | ±1 |
    | 6 | u₁ / max(box, rail) | ±1 |
    | 7 | u̇₁ / max_mass_speed | ±1 |

    ## Rewards

    `10 (d − d′) − 0.01`, d and d′ the distance from P to the target before and after the step: progress, summing to
    10 (d₀ − d_T) so that no loop pays, and a cost of time.

    ## Starting State

    At rest at the origin heading along x, the mass at C (u = u̇ = 0), t = 0; the target uniform at 1 to 2 m in any
    direction. `reset(options={"state": {...}, "target": (x, y)})` sets any of these exactly:

    ## Episode End

    Terminated on success (`info["is_success"]`): P within `tolerance` of the target at the end of a step. Truncated
    after 1000 steps (50 s at the default dt) by the registration's time limit.

    ## Arguments

    A step moves the mass at most 2 m (the default speed at the longest dt): the sled answers a faster shake faster, and
    the default's two RK4 substeps (cheaper than DOP853 for the task's accuracy) fall behind. Diverged: an energy error
    past 1e-2 (1 + T), T conserved where the mass is held. Every `info` has `"state"` (the Starting State's keys and
    `t`), `"target"`, `"distance"`, `"energy"` (T, J) and `"is_success"`.
    """

    renderer = SleighRenderer

    JAX_STATIC = ("sled_mass", "sled_inertia", "offset", "mass", "rail", "box")
    # the jump class, a numerical test of the equations at them, decides the control

    ARGS = Args(
        scale("sled_mass", 1.0, "kg"),
        scale("sled_inertia", 0.1, "kg m²", "about C"),
        scale("offset", 0.5, "m", "C ahead of P", low=0.0),
        scale("mass", 0.5, "kg"),
        interval("rail", 0.3, "m", 0.0, MAGNITUDE_BOUND, "|u₂| ≤ rail", open_low=True),
        interval("box", 0.3, "m", 0.0, MAGNITUDE_BOUND, "|u₁| ≤ box; 0: the rail alone"),
        scale("max_mass_speed", 2.0, "m/s", "with max_mass_speed · dt ≤ 2 m; None (fit class only): u jumps",
              optional=True),
        scale("tolerance", 0.1, "m", high=1.0, open_high=True, physical=False),
        step(0.05, DT_MAX),
        integrator(DEFAULT_INTEGRATOR, "euler", "rk4", "dop853", "rk45", "lsoda", "radau",
                   default_text='"rk4" (2 substeps)'),
        options(),
    )

    STATE = Fields(
        number("x", "m", bound=MAGNITUDE_BOUND),
        number("y", "m", bound=MAGNITUDE_BOUND),
        angle("phi", "the heading"),
        number("v", "m/s", "the speed along the heading", bound=SPEED_BOUND),
        number("omega", "rad/s", bound=RATE_BOUND),
        number("u", "m", "u₂, across", bound="rail"),
        number("u_dot", "m/s", bound=Bound(mass_speed, "max_mass_speed (0 without it)")),
        number("u_along", "m", "u₁", bound="box"),
        number("u_along_dot", "m/s", bound=Bound(along_speed, "max_mass_speed (0 with box=0)")),
    )
    OPTIONS = Options(vector("target", 2, "m", "(x, y)", bound=MAGNITUDE_BOUND))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.system = ChaplyginSleigh(a.sled_mass, a.sled_inertia, a.offset, a.mass)
        self.rail, self.box, self.tolerance = a.rail, a.box, a.tolerance
        self.u_high = np.array([self.box, self.rail])
        grid = np.meshgrid(np.linspace(-self.box, self.box, 5), np.linspace(-self.rail, self.rail, 7))
        directions = ((1.0, 0.0), (0.0, 1.0), (1.0, 1.0)) if self.box > 0.0 else ((0.0, 1.0),)  # admissible u̇
        self.jump_class = self.system.jump_class(np.stack(grid, -1).reshape(-1, 2), directions)
        self.control = "velocity" if self.jump_class is JumpClass.GENERAL else "position"
        if a.max_mass_speed is None and self.control == "velocity":
            raise ValueError(
                f"max_mass_speed=None would jump the mass, which this sleigh (offset={self.system.offset}, "
                f"box={self.box}, class {self.jump_class.value!r}: u̇ enters its equations quadratically) does not "
                "admit; give a speed > 0 (only the rail, box=0, over the knife edge, offset=0, is fit for jumps)"
            )
        if a.max_mass_speed is not None and not is_traced(a.max_mass_speed) and a.max_mass_speed * self.dt > TRAVEL_MAX:
            raise ValueError(
                f"max_mass_speed={a.max_mass_speed!r} is out of range with dt={self.dt!r}: the mass's travel in a "
                f"step, max_mass_speed · dt = {a.max_mass_speed * self.dt:.6g} m, must be at most {TRAVEL_MAX} m"
            )
        self.max_mass_speed = a.max_mass_speed
        if a.integrator == DEFAULT_INTEGRATOR:
            stepper_options = {"substeps": DEFAULT_SUBSTEPS, **stepper_options}
        self.stepper = make_stepper(a.integrator, self.system, **stepper_options)
        self.jump = JumpFlow(self.system)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        high = np.array(OBSERVED, np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        self.state = SleighState(np.zeros(5), np.zeros(2), np.zeros(2), np.array([1.0, 0.0]), 0.0, 0.0)

    def start(self, options, ops=SCALAR):
        """At rest at the origin, the target uniform in distance and bearing from np_random; traced (``connenv.jax``,
        ops its namespace), the same draws from its key."""
        distance = self.np_random.uniform(*TARGET_DISTANCE)
        bearing = self.np_random.uniform(-math.pi, math.pi)
        target = entries_vector(distance * ops.cos(bearing), distance * ops.sin(bearing))
        values = self.reset_values(options, {"target": target})
        u = entries_vector(values["u_along"], values["u"])
        u_dot = entries_vector(values["u_along_dot"], values["u_dot"])
        p = self.system.momenta(values["v"], values["omega"], u, u_dot)
        y = entries_vector(values["x"], values["y"], values["phi"], *p)
        return SleighState(y, u, u_dot, values["target"], 0.0, 0.0)

    def command(self, a):
        """u̇ (velocity control) or the commanded u (position control) of action a (one or a batch)."""
        return a * (self.max_mass_speed if self.control == "velocity" else self.u_high)

    def segments(self, u, command, ops=SCALAR):
        """(Δu of a jump or None, control segments, u and u̇ at the end) of a step from u: one state, or rows (each
        stopped at its own bounds) with ops=BATCH."""
        rows = ARRAYS if ops is SCALAR else ops  # one state's u is an array (2,) as well
        if self.control == "position" and self.max_mass_speed is None:
            zero = rows.zeros_like(command)
            return command - u, [(command, zero, self.dt if ops is SCALAR else rows.full(len(u), self.dt))], command, zero
        if self.control == "position":
            u_dot = rows.copysign(self.max_mass_speed, command - u)
            # the one-sided derivative at u = command (the complex step's, ARRAYS' own minimum and maximum)
            low, high = rows.minimum_one_sided(u, command), rows.maximum_one_sided(u, command)
        else:
            u_dot, low, high = command, -self.u_high, self.u_high
        bounded = bounded_segments if ops is SCALAR else bounded_segments_batch
        segments, u_end, u_dot_end = bounded(u, u_dot, low, high, self.dt)
        return None, segments, u_end, u_dot_end

    def advance(self, s, command, stepper, ops=SCALAR):
        """The state after a step, the mass jumping first if fit and max_mass_speed is None; rows with ops=BATCH."""
        delta, segments, u_end, u_dot_end = self.segments(s.u, command, ops)
        y = s.y
        if delta is not None and (np.any(delta.real != 0.0) if ops is SCALAR else ops.any(ops.real_part(delta) != 0.0)):
            jump = JUMP_STEPPER if ops is SCALAR else JUMP_ROWS
            y = jump(self.jump, y, s.u, delta, 1.0 if ops is SCALAR else np.ones(len(y)))
        y, change = run_segments(stepper, self.system, y, segments, self.held_energy)
        self.check_energy_error(s.energy_error + change, y, u_end)
        return SleighState(y, u_end, u_dot_end, s.target, s.t + self.dt, s.energy_error + change)

    def held_energy(self, y, u, u_dot):
        """T where the mass is held (u̇ = 0, of the real parts on a Jacobian's rows), 0 where it moves."""
        if type(u_dot) is not np.ndarray and traced(ops := namespace(u_dot)):  # JAX's rows (connenv.jax)
            return ops.where(ops.all(u_dot == 0.0, axis=-1), self.system.energy(y, u, 0.0 * u), 0.0)
        held = np.all(u_dot.real == 0.0, axis=-1)
        energy = self.system.energy(y, u, 0.0 * u)
        return np.where(held, energy, 0.0) if np.ndim(held) else (float(energy) if held else 0.0)

    def check_energy_error(self, energy_error, y, u):
        energy_error, energy = energy_error.real, self.system.energy(y, u, 0.0 * u).real
        magnitude = abs(energy_error) if traced(namespace(energy_error)) else np.abs(energy_error)
        check_drift(self.stepper, "energy error", magnitude / (1.0 + energy), ENERGY_ERROR_BOUND)

    def relative_target(self, s, ops=SCALAR):
        """target − P in the sled's frame (along its axis, across it) and the distance."""
        dx, dy = s.target[..., 0] - s.y[..., 0], s.target[..., 1] - s.y[..., 1]
        c, n = ops.cos(s.y[..., 2]), ops.sin(s.y[..., 2])
        return c * dx + n * dy, -n * dx + c * dy, ops.hypot(dx, dy)

    def reward(self, before, after, info, ops=SCALAR):
        return PROGRESS_GAIN * (self.relative_target(before, ops)[2] - info["distance"]) - TIME_COST

    def observe(self, s, ops=SCALAR):
        along, across, _ = self.relative_target(s, ops)
        v, omega = self.system.velocities(s.y, s.u, s.u_dot)
        speed = 1.0 if self.max_mass_speed is None else self.max_mass_speed
        parts = (along, across, v, omega, s.u[..., 1] / self.rail, s.u_dot[..., 1] / speed,
                 s.u[..., 0] / max(self.box, self.rail), s.u_dot[..., 0] / speed)
        return ops.pack([ops.clip(ops.real(x), -bound, bound) for x, bound in zip(parts, OBSERVED)])

    def describe(self, s, ops=SCALAR):
        v, omega = self.system.velocities(s.y, s.u, s.u_dot)
        distance = self.relative_target(s, ops)[2]
        state = {"x": s.y[..., 0], "y": s.y[..., 1], "phi": s.y[..., 2], "v": v, "omega": omega,
                 "u": s.u[..., 1], "u_dot": s.u_dot[..., 1], "u_along": s.u[..., 0], "u_along_dot": s.u_dot[..., 0],
                 "t": s.t}
        return {
            "state": {key: ops.real(value) for key, value in state.items()}, "target": s.target.copy(),
            "distance": ops.real(distance), "energy": ops.real(self.system.energy(s.y, s.u, s.u_dot)),
            "is_success": ops.flag(distance <= self.tolerance),
        }


SPECS = (
    Spec(
        "connenv/ChaplyginSleigh-v0", ChaplyginSleighEnv, max_episode_steps=1000,
        dt_max=DT_MAX, physics="ChaplyginSleigh.md", measure=Measure("time to target", "s", "time_to_success"),
        controllers=("planner", "tail_first"),
        variants=({}, {"offset": 0.0, "box": 0.0}),  # general: u̇ commanded; fit: u commanded
        golden=(
            ("sleigh", {"max_episode_steps": 60, "tolerance": 0.5}, None),
            ("sleigh_fit", {"max_episode_steps": 60, "offset": 0.0, "box": 0.0}, None),
        ),
        bench="sleigh",
        # the fit variant ({"offset": 0.0, "box": 0.0}) steps to the bit as well, but its jacfwd along u₁, pinned at
        # 0 by box=0, differs from the complex step's where u₁ sits on its command (a kink)
        jax=({},),
    ),
)
