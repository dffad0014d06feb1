"""Swing-v0: pump a swing to a target amplitude by standing and squatting."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import BATCH, SCALAR, namespace, vector
from connenv.core.integrators import make_stepper
from connenv.core.params import Args, Bound, integrator, interval, options, scale, step
from connenv.core.segments import check_drift, control_path, held_energy, run_segments
from connenv.core.state import Fields, angle, number
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.rendering.swing import SwingRenderer
from connenv.systems.swing import Swing

DT_MAX = 100.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
LIFT_FLOOR = 1e-4  # floor of h in the reward's logarithm: amplitude ≈ 0.014 rad
TIME_COST = 0.01  # reward paid per step until success
ENERGY_ERROR_BOUND = 0.1  # |the stepper's energy error| / (m g r_max) past which it has diverged: StepperError


def speed_bound(env, values):
    """|θ̇| given at reset, rad/s: the observed bound."""
    return env.obs_high[2] * env.theta_dot_scale


def momentum_bound(env, values):
    """|p| given at reset: m r² times the bound of |θ̇|, at the state's r."""
    return env.system.mass * values["r"] ** 2 * speed_bound(env, values)


@dataclass
class SwingState(State):
    """y = (θ, p); the radius r; the time t; the energy E and lift h at (y, r), which the reward compares; the stepper's
    energy error (E's change on held segments since reset)."""

    components: ClassVar[dict] = {"y": ("theta", "p")}
    phase: ClassVar[tuple] = ("theta", "p", "r")

    y: np.ndarray
    r: float
    t: float
    energy: float
    lift: float
    energy_error: float


class SwingEnv(TaskEnv):
    r"""
    ## Description

    A child pumps a swing by standing and squatting: the controller assigns r, the pivot-to-barycentre distance, an
    *active constraint* (Bressan). A point mass m on a massless rod of length r, at angle θ from the downward vertical,
    with angular momentum p = m r² θ̇: ṗ = −m g r sin θ. It is strongly fit for jumps: a jump of r leaves (θ, p)
    unchanged. Shortening r near the bottom and lengthening it at the extremes multiplies h = 1 − cos A at amplitude A
    by ρ³ per half swing, ρ = r_max/r_min (Piccoli & Kulkarni 2005). Goal: reach `target_amplitude` fast.

    ## Action Space

    `Box(-1, 1, (1,), float32)`: the commanded radius r = r_min + (a + 1)/2 · (r_max − r_min), jumped to at the start of
    the step or, with `max_radial_speed`, approached at that speed.

    ## Observation Space

    `Box(4,) float32`. Below the top (h < 2) |θ̇| ≤ 2√(g/r_min), ρ² times that after a jump: the bound holds up to
    success (after it, it may saturate) and for every reset state.

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | cos θ | -1 | 1 |
    | 1 | sin θ | -1 | 1 |
    | 2 | θ̇ / (2 √(g/r_min)): 1 at the bottom for a swing that just reaches the top at r_min | -ρ² | ρ² |
    | 3 | (r − r_mid) / r_half, r_mid and r_half the centre and half-width of [r_min, r_max] | -1 | 1 |

    ## Rewards

    With h = (E + m g r)/(m g r), the energy above the bottom in units of m g r, h before the step and h′ after it:

        reward = ln(max(h′, 1e-4) / max(h, 1e-4)) − 0.01

    The logarithm pays the factor ρ³ alike at any amplitude; the constant, time. To success: ln(h*/h₀) − 0.01·steps.

    ## Starting State

    θ₀ uniform on ±[0.05, 0.1] rad (np_random; a swing at rest at the bottom cannot be pumped), θ̇₀ = 0, r = r_max,
    t = 0. `reset(options={"state": {...}})` sets any of these exactly:

    ## Episode End

    Terminated when the amplitude of E at the current r reaches `target_amplitude` (`info["is_success"]`). Truncated
    after 500 steps (25 s at the default dt) by the registration's time limit; the ideal pumping schedule needs 10.3 s.

    ## Arguments

    The default step is the pendulum's closed-form flow at constant r, without truncation error (docs/physics/swing.md).
    Diverged: an energy error past 0.1 m g r_max. Every `info` has `"state"` (`theta`, `theta_dot`, `p`, `r`, `t` in
    SI), `"energy"` (E = p²/(2 m r²) − m g r cos θ, J), `"lift"` (h), `"amplitude"` (rad) and `"is_success"`.
    """

    renderer = SwingRenderer

    JAX_STATIC = ("r_min", "r_max")  # they set the observation space

    ARGS = Args(
        scale("r_min", 1.6, "m"),
        scale("r_max", 2.0, "m", low="r_min"),
        scale("g", 9.81, "m/s²"),
        scale("mass", 1.0, "kg"),
        step(0.05, DT_MAX),
        interval("target_amplitude", math.pi / 2, "rad", 0.0, math.pi, "π means going over the top", open_low=True,
                 physical=False),
        scale("max_radial_speed", None, "m/s", optional=True, typical=1.0),
        integrator("exact", "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau"),
        options(),
    )

    STATE = Fields(
        angle("theta"),
        number("r", "m", low="r_min", high="r_max"),
        number("theta_dot", "rad/s", "the observed bound", bound=Bound(speed_bound, "2ρ² √(g/r_min)")),
        number("p", "kg m²/s", bound=Bound(momentum_bound, "m r² · 2ρ² √(g/r_min)"),
               range_text="that of θ̇ times m r²"),
        either=(("theta_dot", "p"),),
    )

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.r_min, self.r_max, self.target_amplitude = a.r_min, a.r_max, a.target_amplitude
        self.max_radial_speed, self.system = a.max_radial_speed, Swing(mass=a.mass, g=a.g)
        self.stepper = make_stepper(a.integrator, self.system, **stepper_options)
        self.held_energy = functools.partial(held_energy, self.system.energy)  # E where r is held

        self.theta_dot_scale = 2.0 * namespace(self.system.g).sqrt(self.system.g / self.r_min)
        self.target_lift = 1.0 - math.cos(self.target_amplitude)
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.obs_high = np.array([1.0, 1.0, (self.r_max / self.r_min) ** 2, 1.0])
        high = self.obs_high.astype(np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        self.state = self.at(np.zeros(2), self.r_max, 0.0, 0.0)

    def at(self, y, r, t, energy_error, ops=SCALAR):
        """The state at (y, r, t), with its energy and lift."""
        energy, weight = ops.real(self.system.energy(y, r)), self.system.mass * self.system.g * r
        return SwingState(y, r, t, energy, (energy + weight) / weight, energy_error)  # lift as Swing.lift

    def start(self, options, ops=SCALAR):
        theta = self.np_random.uniform(0.05, 0.1) * self.np_random.choice([-1.0, 1.0])
        state = self.reset_values(options, {"theta": theta, "r": self.r_max})
        r = state["r"]
        p = state["p"] if "p" in state else self.system.mass * r**2 * state["theta_dot"]
        return self.at(vector(state["theta"], p), r, 0.0, 0.0, ops)

    def advance(self, s, r_cmd, stepper, ops=SCALAR):
        """The state after a step toward the commanded radius; rows with the vector env's stepper and ops=BATCH."""
        segments, r = control_path(s.r, r_cmd, self.dt, self.max_radial_speed, ops)
        y, change = run_segments(stepper, self.system, s.y, segments, self.held_energy)
        self.check_energy_error(s.energy_error + change)
        return self.at(y, r, s.t + self.dt, s.energy_error + change, ops)

    def check_energy_error(self, energy_error):
        """StepperError if |the stepper's energy error| (of any row of a batch) passes its bound."""
        bound = ENERGY_ERROR_BOUND * self.system.mass * self.system.g * self.r_max
        check_drift(self.stepper, "energy error", energy_error, bound, " J")

    def command(self, a):
        """The commanded radius of action a (one, a float; or a batch)."""
        ops = SCALAR if a.ndim == 1 else BATCH
        return self.r_min + 0.5 * (ops.components(a)[0] + 1.0) * (self.r_max - self.r_min)

    def reward(self, before, after, info, ops=SCALAR):
        lift_before, lift_after = ops.maximum(before.lift, LIFT_FLOOR), ops.maximum(after.lift, LIFT_FLOOR)
        return ops.log(lift_after / lift_before) - TIME_COST

    def observe(self, s, ops=SCALAR):
        theta, p, r = (*(s.y.tolist() if ops is SCALAR else s.y.T), s.r)  # one state: Python floats
        r_mid, r_half = 0.5 * (self.r_max + self.r_min), 0.5 * (self.r_max - self.r_min)
        bound = self.obs_high[2]
        speed = ops.clip(p / (self.system.mass * r**2) / self.theta_dot_scale, -bound, bound)
        return ops.pack([ops.cos(theta), ops.sin(theta), speed, (r - r_mid) / r_half])

    def describe(self, s, ops=SCALAR):
        theta, p = ops.components(s.y)
        return {
            "state": {"theta": theta, "theta_dot": p / (self.system.mass * s.r**2), "p": p, "r": s.r, "t": s.t},
            "energy": s.energy, "lift": s.lift, "amplitude": ops.acos(ops.clip(1.0 - s.lift, -1.0, 1.0)),
            "is_success": ops.flag(s.lift >= self.target_lift),
        }


SPECS = (
    Spec(
        "connenv/Swing-v0", SwingEnv, max_episode_steps=500, dt_max=DT_MAX, physics="swing.md",
        measure=Measure("time to target", "s", "time_to_success"), controllers=("pumping",),
        play="space", space_action=-1.0,  # held: the child stands (r_min)
        variants=({}, {"integrator": "rk4", "substeps": 4}),
        fast_start={"state": {"theta": 3.0, "theta_dot": 7.7, "r": 1.6}},
        golden=(
            ("swing", {"max_episode_steps": 60, "target_amplitude": 0.3}, None),
            ("swing_ramp", {"max_episode_steps": 60, "max_radial_speed": 2.0}, None),
        ),
        bench="swing", single_target=1.5, vector_target=0.35,
        jax=({}, {"integrator": "rk4", "substeps": 4}),
    ),
)
