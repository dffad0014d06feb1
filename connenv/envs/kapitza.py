"""KapitzaPendulum-v0 and KapitzaSwingUp-v0: hold a pendulum inverted, or swing it up, by moving its pivot."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, namespace, traced
from connenv.core.backend import vector as entries_vector
from connenv.core.integrators import make_stepper
from connenv.core.params import Args, Bound, choice, integrator, interval, options, scale, step
from connenv.core.segments import bounded_segments, bounded_segments_batch, check_drift, run_segments
from connenv.core.state import Fields, angle, number, vector
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.rendering.kapitza import KapitzaRenderer
from connenv.systems.kapitza import KapitzaPendulum

DT_MAX = 10.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
PIVOTS = {"vertical": (1,), "horizontal": (0,), "planar": (0, 1)}  # actuated axes of u = (u₁, u₂)
SPEED_BOUND = 5.0  # |observed θ̇| in units of 2√(g/l) is clipped here
HOLD_START = 0.2  # rad: KapitzaPendulum-v0 starts within this of inverted, at rest
HANG_START = (0.05, 0.1)  # rad: KapitzaSwingUp-v0 starts this far from hanging, either side, at rest
ENERGY_ERROR_BOUND = 0.1  # |the stepper's energy error| / (m g l) past which it has diverged: StepperError
DAMPING_MAX = 1e3  # the largest damping, in units of m l² √(g/l) (about one period's decay)


def damping_max(args):
    """The largest damping of a pendulum's arguments, N·m·s."""
    return DAMPING_MAX * args["mass"] * args["length"] ** 2 * math.sqrt(args["g"] / args["length"])


def speed_bound(env, values):
    """|θ̇| the observation holds, rad/s."""
    return SPEED_BOUND * env.theta_dot_scale


def momentum_bound(sign):
    """An end of p = m l² θ̇ + m l u̇·n: at θ̇ = ±the observed bound, at the state's θ and u̇."""
    def value(env, values):
        theta_dot = sign * speed_bound(env, values)
        return float(env.system.momentum(np.float64(values["theta"]), theta_dot, values["u_dot"]))

    return Bound(value, f"p({'−' if sign < 0 else ''}10√(g/l))")


def pivot_bound(name):
    """±the env's bound ``name`` along the actuated axes, 0 along the others."""
    def value(env, values):
        return np.array([getattr(env, name) if i in env.axes else 0.0 for i in range(2)])

    return Bound(value, f"{name} along the actuated axes, 0 along the others")


def pivot_note(env):
    return f" (pivot={env.pivot!r})"

LIFT_FLOOR = 1e-4  # floor of the swing-up's lift in the reward's logarithm: amplitude ≈ 0.02 rad
TIME_COST = 0.2  # the swing-up's reward paid per simulated second until success


@dataclass
class KapitzaState(State):
    """y = (θ, p); the pivot's position u and velocity u̇ (2 each, u̇ at the end of the step); the time t; the energy E in
    the frame of that u̇; the stepper's energy error (E's change on each segment of constant u̇, summed since reset)."""

    components: ClassVar[dict] = {"y": ("theta", "p"), "u": ("u1", "u2"), "u_dot": ("u1_dot", "u2_dot")}

    y: np.ndarray
    u: np.ndarray
    u_dot: np.ndarray
    t: float
    energy: float
    energy_error: float


@dataclass
class HoldState(KapitzaState):
    """KapitzaPendulum-v0's state: the largest deviation from inverted this episode."""

    max_deviation: float


@dataclass
class SwingUpState(KapitzaState):
    """KapitzaSwingUp-v0's state: the steps held within tolerance of inverted without a break; the lift ℓ."""

    upright_steps: int
    lift: float


class KapitzaPendulumEnv(TaskEnv):
    r"""
    ## Description

    A pendulum (rod length l, bob mass m) whose pivot position u = (u₁, u₂) the controller moves, an *active constraint*
    (Bressan); θ is the rod's angle from the downward vertical, p = m l² θ̇ + m l u̇·n its momentum, n = (cos θ, sin θ). u̇
    enters quadratically (Bressan's *general* class), so fast pivot vibration acts as a force: vibrated vertically with
    amplitude a ≪ l and frequency ω, the pendulum is stable inverted when a²ω² > 2 g l (Kapitza 1951;
    docs/physics/kapitza.md). Goal: hold it inverted, |θ − π| ≤ `tolerance`, all episode.

    ## Action Space

    `Box(-1, 1, (k,), float32)`: the pivot's velocity v_max · a, constant over the step, along the actuated axes: u̇₂
    (vertical pivot) or u̇₁ (horizontal), k = 1; (u̇₁, u̇₂) (planar), k = 2. An axis at its end stop |uᵢ| = a_max rests
    there for the rest of the step. Only u̇ enters the equations, so it may jump: p is continuous, θ̇ jumps by −Δu̇·n/l.

    ## Observation Space

    `Box(3 + 2k,) float32`. No clock: (u, u̇) is the vibration's phase, where `agents.controllers.kapitza` reads it.

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | cos θ | -1 | 1 |
    | 1 | sin θ | -1 | 1 |
    | 2 | θ̇ / (2√(g/l)), 1 at the bottom for a pendulum that just reaches the top; clipped (spinning fast) | -5 | 5 |
    | 3 (3, 4) | pivot position along the actuated axes, uᵢ / a_max | -1 | 1 |
    | 4 (5, 6) | pivot velocity along the actuated axes at the end of the step, u̇ᵢ / v_max | -1 | 1 |

    ## Rewards

    With δ = |θ − π| (θ wrapped to (−π, π]) after the step, on every step:

        reward = 1 − (δ/tolerance)²

    in [0, 1] while held, negative on the falling step, never below 1 − (π/tolerance)²: −108.7 at the default tolerance.

    ## Starting State

    θ₀ = π + uniform(−0.2, 0.2) rad (np_random), at rest, pivot at rest at the centre, t = 0.
    `reset(options={"state": {...}})` sets any of these exactly:

    ## Episode End

    Terminated when the pendulum falls, δ > tolerance (`info["is_success"]` turns False). Truncated after 2000 steps
    (10 s at the default dt) by the registration's time limit, having held it inverted throughout.

    ## Arguments

    Damping m l² √(g/l) damps a swing in about a period; a thousand times that would spend the step's work on the decay.
    The default step is exact: at constant u̇ the rod swings in the pivot's frame as a plain pendulum, in closed form, or
    by RK4 at a fine step near its separatrix (the held-inverted pendulum; docs/physics/kapitza.md); with damping,
    DOP853. Diverged: without damping, an energy error (pivot's frame) past 0.1 m g l. Every `info` has `"state"`
    (`theta`, `theta_dot`, `p`, `u` (2), `u_dot` (2), `t`, in SI), `"energy"` (E = ½ m l² θ̇² − m g l cos θ, J, in the
    pivot's frame, conserved at constant u̇), `"deviation"` (δ, rad), `"max_deviation"` (δ's largest so far) and
    `"is_success"`.
    """

    renderer = KapitzaRenderer

    metadata: ClassVar[dict] = {**TaskEnv.metadata, "measures": ("max_deviation",)}

    JAX_STATIC = ("damping",)  # it chooses the step: the closed form without it, the numerical fallback with it

    ARGS = Args(
        choice("pivot", "vertical", PIVOTS),
        scale("length", 1.0, "m", "l"),
        scale("mass", 1.0, "kg"),
        scale("g", 9.81, "m/s²"),
        scale("v_max", 10.0, "m/s"),
        scale("a_max", 0.1, "m", high="length", open_high=True),
        step(0.005, DT_MAX),
        scale("tolerance", 0.3, "rad", high=math.pi, open_high=True, physical=False),
        interval("damping", 0.0, "N·m·s", 0.0, Bound(damping_max, "1e3 m l² √(g/l)"),
                 "torque −c θ̇ at the pivot, for tests of the averaged motion"),
        integrator("exact", "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau"),
        options(),
    )

    STATE = Fields(
        angle("theta"),
        vector("u", 2, "m", "the pivot's position (horizontal, vertical)", bound=pivot_bound("a_max"),
               note=pivot_note),
        vector("u_dot", 2, "m/s", "its velocity", bound=pivot_bound("v_max"), note=pivot_note),
        number("theta_dot", "rad/s", "the observed bound", bound=Bound(speed_bound, "10√(g/l)")),
        number("p", "kg m²/s", "m l² θ̇ + m l u̇·n", low=momentum_bound(-1.0), high=momentum_bound(1.0),
               range_text="that of θ̇ within its bound"),
        either=(("theta_dot", "p"),),
    )

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.pivot, self.axes = a.pivot, list(PIVOTS[a.pivot])
        self.actuated = slice(self.axes[0], self.axes[-1] + 1)  # the axes as a slice of u (they are contiguous)
        self.system = KapitzaPendulum(length=a.length, mass=a.mass, g=a.g, damping=a.damping)
        self.v_max, self.a_max, self.tolerance = a.v_max, a.a_max, a.tolerance
        self.stepper = make_stepper(a.integrator, self.system, **stepper_options)

        self.theta_dot_scale = 2.0 * namespace(a.length).sqrt(self.system.g / a.length)
        k = len(self.axes)
        self.action_space = spaces.Box(-1.0, 1.0, (k,), np.float32)
        high = np.array([1.0, 1.0, SPEED_BOUND] + [1.0] * 2 * k, np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        y, u, u_dot = np.array([math.pi, 0.0]), np.zeros(2), np.zeros(2)
        self.state = self.at(y, u, u_dot, 0.0, self.system.energy(y, u_dot), 0.0)

    def parameters(self):
        return {"pivot": self.pivot, **super().parameters()}

    def start_angle(self):
        return math.pi + self.np_random.uniform(-HOLD_START, HOLD_START)

    def start(self, options, ops=SCALAR):
        state = self.reset_values(options, {"theta": self.start_angle()})
        theta, u, u_dot = state["theta"], state["u"], state["u_dot"]
        p = state["p"] if "p" in state else ops.real(self.system.momentum(theta, state["theta_dot"], u_dot))
        y = entries_vector(theta, p)
        return self.at(y, u, u_dot, 0.0, self.system.energy(y, u_dot), 0.0, ops=ops)

    def advance(self, s, u_dot_cmd, stepper, ops=SCALAR):
        """The state after a step at the commanded u̇, each axis (each row's, with ops=BATCH) held at its end stops."""
        if ops is SCALAR:
            segments, u, u_dot = bounded_segments(s.u, u_dot_cmd, -self.a_max, self.a_max, self.dt)
        else:  # the actuated axes' stops alone end segments (a pivot on one axis: two segments, not three)
            segments, u, u_dot = bounded_segments_batch(s.u, u_dot_cmd, -self.a_max, self.a_max, self.dt, self.axes)
        y, change = run_segments(stepper, self.system, s.y, segments, self.frame_energy)
        self.check_energy_error(s.energy_error + change)
        return self.at(y, u, u_dot, s.t + self.dt, self.system.energy(y, u_dot), s.energy_error + change, s, ops)

    def frame_energy(self, y, u, u_dot):
        """E in the frame of the pivot's velocity u̇, conserved on each segment (the energy check's quantity)."""
        return self.system.energy(y, u_dot)

    def check_energy_error(self, energy_error):
        """StepperError if |the stepper's energy error| (of any row of a batch) passes its bound, without damping."""
        if self.system.damping == 0.0:
            bound = ENERGY_ERROR_BOUND * self.system.mass * self.system.g * self.system.length
            check_drift(self.stepper, "energy error", energy_error, bound, " J")

    def at(self, y, u, u_dot, t, energy, energy_error, before=None, ops=SCALAR):
        """The state at (y, u, u̇, t) with energy E, its record continued from the state before (or started)."""
        deviation = self.deviation(y, ops)
        record = deviation if before is None else ops.maximum(before.max_deviation, deviation)
        return HoldState(y, u, u_dot, t, energy, energy_error, record)

    def command(self, a):
        """The commanded pivot velocity u̇ (2) of action a: v_max · a along the actuated axes."""
        if traced(ops := namespace(a)):  # JAX's rows: immutable, built whole
            zero = ops.zeros_like(a[..., 0])
            axes = [a[..., self.axes.index(i)] * self.v_max if i in self.axes else zero for i in range(2)]
            return ops.stack(axes, axis=-1)
        u_dot = np.zeros(a.shape[:-1] + (2,), complex if a.dtype.kind == "c" else float)  # complex: a Jacobian's rows
        u_dot[..., self.actuated] = a * self.v_max
        return u_dot

    def deviation(self, y, ops=SCALAR):
        """|θ − π| with θ wrapped to (−π, π]: 0 inverted, π hanging."""
        theta = ops.components(y)[0]
        return math.pi - ops.abs(ops.atan2(ops.sin(theta), ops.cos(theta)))

    def theta_dot(self, s, ops=SCALAR):
        """θ̇ = (p − m l u̇·n)/(m l²) of the state."""
        return ops.real(self.system.theta_dot(s.y, s.u_dot))

    def observe(self, s, ops=SCALAR):
        theta, u, u_dot = ops.components(s.y)[0], ops.components(s.u), ops.components(s.u_dot)
        speed = ops.clip(self.theta_dot(s, ops) / self.theta_dot_scale, -SPEED_BOUND, SPEED_BOUND)
        pivot = [u[i] / self.a_max for i in self.axes] + [u_dot[i] / self.v_max for i in self.axes]
        return ops.pack([ops.cos(theta), ops.sin(theta), speed, *pivot])

    def describe_pendulum(self, s, ops=SCALAR):
        """The info both tasks give: the state, the energy and the deviation from inverted."""
        theta, p = ops.components(s.y)
        state = {
            "theta": theta, "theta_dot": self.theta_dot(s, ops), "p": p, "u": ops.vector(s.u),
            "u_dot": ops.vector(s.u_dot), "t": s.t,
        }
        return {"state": state, "energy": ops.real(s.energy), "deviation": self.deviation(s.y, ops)}

    def describe(self, s, ops=SCALAR):
        info = self.describe_pendulum(s, ops)
        info["max_deviation"] = s.max_deviation
        info["is_success"] = ops.flag(info["deviation"] <= self.tolerance)
        return info

    def reward(self, before, after, info, ops=SCALAR):
        return 1.0 - (info["deviation"] / self.tolerance) ** 2

    def terminated(self, s, info, ops=SCALAR):
        return info["deviation"] > self.tolerance


class KapitzaSwingUpEnv(KapitzaPendulumEnv):
    r"""
    ## Description

    KapitzaPendulum-v0's pendulum, to swing up and hold inverted by moving the pivot: vertical motion pumps energy in by
    parametric resonance near twice the natural frequency √(g/l); fast vertical vibration holds it up (Kapitza).

    ## Action Space, Observation Space

    As KapitzaPendulum-v0.

    ## Rewards

    With the lift ℓ = (E/(m g l) + 1)/2, E the energy in the pivot's frame (ℓ = 0 at rest hanging, 1 at rest inverted,
    (1 − cos A)/2 for a swing of amplitude A), capped at 1 and floored at 1e-4, ℓ before the step and ℓ′ after it:

        reward = ln(ℓ′/ℓ) − 0.2 dt

    Pumping multiplies ℓ by a factor per cycle, which the logarithm pays alike at every amplitude (potential-based
    shaping, Ng et al. 1999); the constant pays for time. Summed to success: ln(ℓ_T/ℓ₀) − 0.2 t.

    ## Arguments

    ## Starting State

    θ₀ uniform on ±[0.05, 0.1] rad from hanging (np_random; at rest hanging, vertical motion cannot pump it), at rest,
    pivot at rest at the centre, t = 0. Reset options as KapitzaPendulum-v0.

    ## Episode End

    Terminated on success (`info["is_success"]`): held within `tolerance` of inverted for the last `hold_time` seconds
    (rounded up to whole steps). Truncated after 6000 steps (30 s at the default dt). `info` has KapitzaPendulum-v0's
    keys, with `"upright_time"` (s held within `tolerance` without a break) in place of `"max_deviation"`.

    ## Open Challenge

    No agent of the reference results learns this task: PPO and SAC pump the pendulum up but seldom catch and hold it. A
    DAgger clone of the analytic controller into the same network does, so observation and action suffice: what is
    missing is learning the catch, which the reward pays only through the time it saves once ℓ is capped. Clones and
    training curves: under Reference results below; attempts that did not help (a reward paying the hold, a curriculum
    of starts released from every angle): the reference-results guide, "What changed, and what is still open". At the
    field's budget (JAX PPO, 10⁸ steps per seed), with wide starts, and with exact gradients (SHAC): the open
    challenges' page of the baselines (docs/baselines/challenges.md).
    """

    metadata: ClassVar[dict] = {**TaskEnv.metadata, "measures": ()}

    ARGS = KapitzaPendulumEnv.ARGS + (scale("hold_time", 2.0, "s", physical=False),)

    def __init__(self, render_mode: str | None = None, **kwargs):
        super().__init__(render_mode, **kwargs)
        self.hold_steps = math.ceil(self.args.hold_time / self.dt - 1e-9)  # hold_time in whole steps

    def start_angle(self):
        return self.np_random.uniform(*HANG_START) * self.np_random.choice([-1.0, 1.0])

    def at(self, y, u, u_dot, t, energy, energy_error, before=None, ops=SCALAR):
        """The state at (y, u, u̇, t) with energy E and its lift, the upright count continued from before (or 0)."""
        upright = 0 if before is None else (before.upright_steps + 1) * (self.deviation(y, ops) <= self.tolerance)
        return SwingUpState(y, u, u_dot, t, energy, energy_error, upright, self.lift(energy, ops))

    def lift(self, energy, ops=SCALAR):
        system = self.system
        lift = 0.5 * (ops.real(energy) / (system.mass * system.g * system.length) + 1.0)
        return ops.clip(lift, LIFT_FLOOR, 1.0)

    def describe(self, s, ops=SCALAR):
        info = self.describe_pendulum(s, ops)
        info["upright_time"] = s.upright_steps * self.dt
        info["is_success"] = ops.flag(s.upright_steps >= self.hold_steps)
        return info

    def reward(self, before, after, info, ops=SCALAR):
        return ops.log(after.lift / before.lift) - TIME_COST * self.dt

    def terminated(self, s, info, ops=SCALAR):
        return info["is_success"]


PENDULUM = {"dt_max": DT_MAX, "physics": "kapitza.md",
            "fast_start": {"state": {"theta": math.pi}}}  # on the separatrix: the exact step's RK4 branch
SPECS = (
    Spec(
        "connenv/KapitzaPendulum-v0", KapitzaPendulumEnv, max_episode_steps=2000,
        **PENDULUM, measure=Measure("max deviation", "rad", "max_deviation"), controllers=("kapitza", "damped"),
        variants=({}, {"pivot": "planar"}),
        golden=(
            ("kapitza", {"max_episode_steps": 100, "pivot": "planar"}, None),
            ("kapitza_fall", {"max_episode_steps": 100, "pivot": "horizontal"}, None),
        ),
        bench="kapitza", single_target=1.5, vector_target=0.1,
        jax=({},),  # {"pivot": "planar"} agrees as well (5e-13), but its three exact segments compile in minutes
    ),
    Spec(
        "connenv/KapitzaSwingUp-v0", KapitzaSwingUpEnv, max_episode_steps=6000, **PENDULUM,
        measure=Measure("time to target", "s", "time_to_success"), controllers=("swingup",),
        golden=(("swingup", {"max_episode_steps": 100, "hold_time": 0.05, "tolerance": 3.07}, None),),
        single_target=1.5, vector_target=0.1,
        jax=({},),
    ),
)
