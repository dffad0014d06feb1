"""BeadOnBar-v0 and -v1: bring a bead on a turning bar to rest at a target, by tilting and spinning the bar."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, namespace, traced
from connenv.core.backend import vector as entries_vector
from connenv.core.params import Args, integrator, options, scale, step
from connenv.core.segments import check_drift
from connenv.core.state import Fields, Options, angle, number
from connenv.core.validation import MAGNITUDE_BOUND
from connenv.envs.active_constraint import (  # DT_MAX: the builder's, this env's too
    DT_MAX,
    ActiveConstraintEnv,
    ActiveConstraintState,
)
from connenv.envs.spec import Measure, Spec
from connenv.rendering.bead_on_bar import BeadRenderer

OMEGA_MAX = 500.0  # rad/s: the largest omega_max; at the longest dt the bead's growth, cosh(omega_max dt), stays finite
START_REACH = 0.8  # |r₀| ≤ 0.8 L, and so |r*| (g > 0)
MIN_DISTANCE = 0.2  # |r* − r₀| ≥ 0.2 L
OUTWARD_START = (0.1, 0.6)  # g = 0: |r₀| / L, away from the pivot, where a bead at rest cannot be moved
OUTWARD_DISTANCE = (0.2, 0.3)  # g = 0: |r*| − |r₀|, in L
POSITION_TOLERANCE = 0.02  # |r − r*| ≤ 0.02 L
SPEED_TOLERANCE = 0.05  # |ṙ| ≤ 0.05 L/s
SPEED_WEIGHT = 0.1  # s: the potential's weight of |ṙ| against |r − r*|
SHAPING = 10.0  # the reward's factor of the potential's change
TIME_COST = 0.01  # reward paid per step while the bead is outside the success tolerances
SPEED_CAP = 10.0  # L/s: |ṙ| beyond it costs no more, and is observed as this
OBSERVATION_HIGH = np.array([2.0, 3.0, SPEED_CAP, 1.0, 1.0, 1.0])  # past the bar's end only at the final step
ENERGY_ERROR_BOUND = 1e-2  # |the stepper's energy error| / (1 + |E|) past which it has diverged: StepperError


@dataclass
class BeadState(ActiveConstraintState):
    """ActiveConstraintEnv's state (y = (r, p), u = (θ,), t, the energy error) and the task's: the target r*, whether
    the bead is within the target's tolerances, and for how long (s)."""

    components: ClassVar[dict] = {"y": ("r", "p"), "u": ("theta",)}

    target: float
    inside: bool
    hold: float


class BeadOnBarEnv(ActiveConstraintEnv):
    r"""
    ## Description

    A bead (mass m) slides frictionless on a straight bar of half-length L turning about a fixed pivot O in a vertical
    plane. The controller assigns the bar's angle θ from the horizontal (an *active constraint*, Bressan); the bead at
    signed distance r from O obeys ṙ = p/m, ṗ = m r θ̇² − m g sin θ: tilting slides it down, spinning flings it out. It
    is `ActiveConstraintEnv` on T = ½ m (ṙ² + r² θ̇²), V = m g r sin θ (`connenv.systems.bead_on_bar`), of the *general*
    class: θ may not jump, the control is its rate (docs/physics/BeadOnBar.md). Task: bring it to rest at a target. With
    g = 0 (Bressan's horizontal bar) it only moves outward, ṙ ≥ 0: the target lies farther out, reached slowly.

    ## Action Space

    `Box(-1, 1, (1,), float32)`: θ̇ = a · omega_max, constant over the step. θ winds freely.

    ## Observation Space

    `Box(6,) float32`, clipped to bounds that leave room beyond the bar (on it, |r/L| ≤ 1 and |(r* − r)/L| ≤ 2):

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | r / L | -2 | 2 |
    | 1 | (r* − r) / L | -3 | 3 |
    | 2 | ṙ / L, in 1/s | -10 | 10 |
    | 3 | sin θ | -1 | 1 |
    | 4 | cos θ | -1 | 1 |
    | 5 | hold / hold_time: the part of the hold done (0 with g = 0, which has no hold) | 0 | 1 |

    ## Rewards

    With the potential Φ = −(|r − r*| + 0.1 s · min(|ṙ|, 10 L/s)) / L, Φ before the step and Φ′ after it,

        reward = 10 (Φ′ − Φ) − 0.01 · [outside the tolerances]

    Potential-based shaping (Ng, Harada & Russell 1999) pays each step toward rest at the target and sums to
    10 (Φ_end − Φ₀) whatever the path; the time cost pays for speed. In the bar the rest of a 500-step episode costs
    under 35 from any state (Φ ≥ −3); leaving it (|r| > L) pays −exit_penalty instead (default 40) and ends the episode.

    ## Starting State

    At rest, θ = 0, t = 0. With g > 0: r₀ and r* uniform on [−0.8, 0.8] L, r* at least 0.2 L from r₀. With g = 0: |r₀|
    uniform on [0.1, 0.6] L either side of the pivot, r* on the same side, 0.2–0.3 L farther out.
    `reset(options={"state": {...}, "target": r*})` sets any of these exactly, others drawn as above:

    ## Episode End

    Terminated on success (`info["is_success"]`) or on leaving the bar (`info["left_bar"]`). Success: |r − r*| ≤ 0.02 L
    and |ṙ| ≤ 0.05 L/s, held for hold_time (every step from entry to hold_time later) with g > 0, without a hold with
    g = 0, where ṙ cannot decrease. Truncated after 500 steps (10 s) by the registration's time limit.

    ## Arguments

    The default step is the flow's closed form at constant θ̇, exact to rounding down to θ̇ = 0. Diverged: an energy error
    (of E = p²/(2m) + m g r sin θ, conserved at constant θ) past 1e-2 (1 + |E|). `info` has `"state"` (`r`, `r_dot`,
    `p`, `theta`, `t` in SI), `"target"` (r*, m), `"hold"` (s inside the tolerances), `"left_bar"` and `"is_success"`.

    ## Version History

    - v1 (connenv 0.4.0): registered with omega_max = 1 rad/s instead of 2π, all else v0's; the analytic tilt law (rate
      clipped to omega_max) loses no time by it. At 2π rad/s random actions spin the bar so fast the centrifugal force
      m r θ̇² (up to 4 m g at the bar's end) flings the bead off in a second: exploration met the exit penalty and agents
      learned to hold the bar still short of the target. At 1 rad/s it is ≤ m L (1/s)², 0.1 m g on the default bar.
    - v0: the first version, in connenv 0.1.0.
    """

    renderer = BeadRenderer

    JAX_STATIC = ("mass", "g")
    # the sympy-derived system holds them as constants

    ARGS = Args(
        scale("half_length", 1.0, "m", "L"),
        scale("g", 9.81, "m/s²", low=0.0),
        scale("mass", 1.0, "kg"),
        scale("omega_max", 2.0 * math.pi, "rad/s", high=OMEGA_MAX, default_text="2π (v1: 1)"),
        step(0.02, DT_MAX),
        scale("hold_time", 0.5, "s", low=0.0, physical=False),
        scale("exit_penalty", 40.0, low=0.0, physical=False),
        integrator(None, "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau",
                   default_text='"exact"'),
        options(),
    )

    STATE = Fields(
        number("r", "m", "the bead's position on the bar", bound="half_length"),
        number("r_dot", "m/s", bound=MAGNITUDE_BOUND),
        angle("theta", "the bar's angle"),
    )
    OPTIONS = Options(number("target", "m", "r*", bound="half_length"))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        self.half_length, self.omega_max, self.hold_time, self.exit_penalty = (
            a.half_length, a.omega_max, a.hold_time, a.exit_penalty)
        from connenv.systems.bead_on_bar import bead_on_bar  # sympy's: loaded by a make, not by import connenv

        super().__init__(
            bead_on_bar(a.mass, a.g), -math.inf, math.inf, dt=a.dt, max_control_speed=self.omega_max,
            integrator=a.integrator, render_mode=render_mode, **stepper_options,
        )  # fmt: skip
        self.mass, self.g = a.mass, a.g
        self.hold_needed = self.hold_time if a.g > 0.0 else 0.0
        low = -OBSERVATION_HIGH * (np.arange(6) < 5)
        self.observation_space = spaces.Box(low.astype(np.float32), OBSERVATION_HIGH.astype(np.float32))
        self.state = self.track(self.state, 0.0, None)

    def start(self, options, ops=SCALAR):
        """At rest, the bead and target drawn from np_random; traced (``connenv.jax``, ops its namespace), the same
        draws from its key."""
        r, target = self.draw_start(ops)
        values = self.reset_values(options, {"r": r, "target": target})
        y = entries_vector(values["r"], self.mass * values["r_dot"])
        s = self.at(y, entries_vector(values["theta"]), 0.0, 0.0)
        return self.track(s, ops.real(values["target"]), None)

    def draw_start(self, ops=SCALAR):
        """(r₀, r*) drawn from np_random as the docstring's Starting State says."""
        L, rng = self.half_length, self.np_random
        if self.g > 0.0:
            r = rng.uniform(-START_REACH, START_REACH)
            below = ops.maximum(r - MIN_DISTANCE + START_REACH, 0.0)  # the length of [−0.8, r₀ − 0.2]
            above = ops.maximum(START_REACH - r - MIN_DISTANCE, 0.0)  # of [r₀ + 0.2, 0.8]
            z = rng.uniform(0.0, below + above)
            target = ops.where(z < below, -START_REACH + z, r + MIN_DISTANCE + (z - below))
            return L * r, L * target
        side = rng.choice([-1.0, 1.0])
        r = rng.uniform(*OUTWARD_START)
        return L * side * r, L * side * (r + rng.uniform(*OUTWARD_DISTANCE))

    def advance(self, s, command, stepper, ops=SCALAR):
        return self.track(super().advance(s, command, stepper, ops), s.target, s, ops)

    def track(self, s, target, before, ops=SCALAR):
        """The BeadState of s with target r*: whether inside the tolerances, and the hold grown by dt if inside before
        the step too (before=None: at reset)."""
        r, p = s.y.T
        L = self.half_length
        r, p = r.real, p.real  # a flag: of the real parts on a Jacobian's rows
        inside = (abs(r - target) <= POSITION_TOLERANCE * L) & (abs(p / self.mass) <= SPEED_TOLERANCE * L)
        hold = 0.0 if before is None else ops.where(before.inside & inside, before.hold + self.dt, 0.0)
        return BeadState(s.y, s.u, s.t, s.energy_error, target, inside, hold)

    def segments(self, u, command, ops=SCALAR):
        """One segment at the commanded rate: θ has no bounds to stop at (the builder's cut, without the search)."""
        return None, [(u, command, self.dt)], u + command * self.dt

    def held_energy(self, y, u, u_dot):
        """E = p²/(2m) + m g r sin θ where θ is held, 0 where it turns (the builder's, in closed form)."""
        if type(u_dot) is not np.ndarray and traced(ops := namespace(u_dot)):  # JAX's rows (connenv.jax)
            return ops.where(u_dot[..., 0] == 0.0, self.system.energy(y, u[..., 0]), 0.0)
        if np.ndim(y) == 1:  # one state: Python floats
            return 0.0 if u_dot[0] != 0.0 else float(self.system.energy(y, u[0]))
        return np.where(u_dot[..., 0].real == 0.0, self.system.energy(y, u[..., 0]), 0.0)

    def check_energy_error(self, energy_error, y, u):
        if isinstance(energy_error, float) and energy_error == 0.0:  # one state, nothing to bound (the bar turned)
            return
        energy_error, energy = energy_error.real, self.system.energy(y, u[..., 0]).real
        absolute = np.abs if type(energy_error) is np.ndarray or isinstance(energy_error, float) else abs  # JAX's: abs
        check_drift(self.stepper, "energy error", absolute(energy_error) / (1.0 + absolute(energy)), ENERGY_ERROR_BOUND)

    def observe(self, s, ops=SCALAR):
        r, p = s.y.T
        theta, L = s.u.T[0], self.half_length
        hold = ops.clip(s.hold / self.hold_needed, 0.0, 1.0) if self.hold_needed > 0.0 else 0.0 * s.hold
        high = OBSERVATION_HIGH
        return ops.pack([
            ops.clip(r / L, -high[0], high[0]),
            ops.clip((s.target - r) / L, -high[1], high[1]),
            ops.clip(p / (self.mass * L), -high[2], high[2]),
            ops.sin(theta),
            ops.cos(theta),
            hold,
        ])

    def describe(self, s, ops=SCALAR):
        r, p = s.y.T
        state = {"r": r, "r_dot": p / self.mass, "p": p, "theta": s.u.T[0], "t": s.t}
        return {
            "state": state, "target": s.target, "hold": s.hold, "left_bar": ops.flag(abs(r) > self.half_length),
            "is_success": ops.flag(s.inside & (s.hold >= self.hold_needed - 1e-9 * self.dt)),
        }

    def potential(self, s, ops=SCALAR):
        r, p = s.y.T
        L = self.half_length
        return -(abs(r - s.target) / L + SPEED_WEIGHT * ops.clip(abs(p / self.mass) / L, 0.0, SPEED_CAP))

    def reward(self, before, after, info, ops=SCALAR):
        shaping = SHAPING * (self.potential(after, ops) - self.potential(before, ops))
        return ops.real(
            ops.where(info["left_bar"], -self.exit_penalty, shaping - ops.where(after.inside, 0.0, TIME_COST))
        )

    def terminated(self, state, info, ops=SCALAR):
        return info["is_success"] | info["left_bar"]


BEAD = {"dt_max": DT_MAX, "physics": "BeadOnBar.md", "max_episode_steps": 500,
        "measure": Measure("time to target", "s", "time_to_success"), "controllers": ("tilt",),
        "variants": ({}, {"g": 0.0}),
        "fast_start": {"state": {"r_dot": 1000.0}}}
SPECS = (
    Spec("connenv/BeadOnBar-v0", BeadOnBarEnv, **BEAD,
         golden=(("bead", {"max_episode_steps": 60}, None),), bench="bead", jax=({},)),
    Spec("connenv/BeadOnBar-v1", BeadOnBarEnv, kwargs={"omega_max": 1.0}, **BEAD, jax=({},)),  # see Version History
)
