"""Skier-v0: pump along a trail by raising and lowering the barycentre, and escape the valley."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, vector
from connenv.core.integrators import make_stepper
from connenv.core.params import Args, Bound, given, integrator, options, scale, step
from connenv.core.segments import check_drift, control_path, held_energy, run_segments
from connenv.core.state import Fields, number
from connenv.core.validation import check_number
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.rendering.skier import SkierRenderer
from connenv.systems.skier import Skier, barycentre_height, reach
from connenv.systems.trails import make_trail

DT_MAX = 10.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
PROGRESS_FLOOR = 1e-4  # floor of the progress in the reward's logarithm
TIME_COST = 0.01  # reward paid per step until success
ENERGY_ERROR_BOUND = 0.1  # |the stepper's energy error| / (m g Δz) past which it has diverged: StepperError
SPEED_BOUND = 3.0  # |observed speed| is clipped here
START_OFFSETS = (0.5, 2.0)  # m from the trail's lowest point, either side
RK8_MIN_LEVER = 0.5  # the default is the projected RK8 where min(1 − κ h_max) ≥ this, else DOP853 (see SkierEnv)
MAX_SUBSTEP = 0.05  # s: the projected RK8's substeps are ceil(dt / MAX_SUBSTEP), dt in the time of G_REFERENCE
G_REFERENCE = 9.81  # m/s²: the g at which DT_MAX and MAX_SUBSTEP were measured (and the default)
ENERGY_TOLERANCE = 1e-8  # its energy error per step, in m g Δz, past which it doubles its substeps
DOP853_TOLERANCES = {"rtol": 1e-8, "atol": 1e-10}
CLIMB_MIN = 1e-9  # the least Δz, relative to |z|: the energy check's bound, 0.1 m g Δz, stays far above E's rounding


def trail_end(name):
    """An end of the trail's domain, "lo" or "hi"."""
    return lambda env, values: getattr(env.trail, name)


def speed_bound(env, values):
    """|ẋ| given at reset, at the state's x and h: |σẋ| ≤ 3 v*, the observed speed."""
    sigma = env.system.geometry(values["x"], values["h"])[2]
    return SPEED_BOUND * env.speed_scale / sigma


def momentum_bound(env, values):
    """|p| given at reset: m w² times the bound of |ẋ|, w = 1 − κh."""
    w = env.system.geometry(values["x"], values["h"])[5]
    return env.system.mass * w * w * speed_bound(env, values)


@dataclass
class SkierState(State):
    """y = (x, p); the height h; the time t; side, the sign of x − target_x at reset (0 on a trail with two rims), from
    which the one goal is reached; the energy E at (y, h), which the reward compares; the stepper's energy error (E's
    change on held segments since reset); ẋ, f′, σ and κ at (x, h), read by the observation and info."""

    components: ClassVar[dict] = {"y": ("x", "p")}
    phase: ClassVar[tuple] = ("x", "p", "h")

    y: np.ndarray
    h: float
    t: float
    side: float
    energy: float
    energy_error: float
    x_dot: float
    f1: float
    sigma: float
    kappa: float


class SkierEnv(TaskEnv):
    r"""
    ## Description

    A skier on a narrow trail y = f(x) in a vertical plane pumps by raising and lowering the barycentre: its height h
    above the trail, along the normal, is the control, an *active constraint* (Bressan). x is the feet's horizontal
    position, σ = √(1 + f′²), κ = f″/σ³ the curvature, φ the slope angle and p = m (1 − κh)² σ² ẋ
    (docs/physics/skier.md); a jump of h leaves (x, p) unchanged. Standing up where the trail curves up and the skier is
    fast, and crouching at the turning points, pumps energy in as on a swing (on the circular `halfpipe`, exactly a
    swing of radius R − h). Goal: escape the valley, to a rim, or to `target_x` on a trail without rims.

    ## Action Space

    `Box(-1, 1, (1,), float32)`: the commanded height h = h_min + (a + 1)/2 · (h_max − h_min), jumped to at the start of
    the step or, with `max_height_speed`, approached at that speed.

    ## Observation Space

    `Box(6,) float32`, k* = max |κ| h_max on the trail; speed and position clipped, the position only once it has left
    the domain (after success).

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | (x − x_mid)/x_half, x_mid and x_half the centre and half-width of the trail's domain | -1 | 1 |
    | 1 | sin φ | -1 | 1 |
    | 2 | cos φ | 0 | 1 |
    | 3 | speed along the trail σẋ / v*, v* = √(2 g Δz), Δz the height to climb (below) | -3 | 3 |
    | 4 | (h − h_mid)/h_half over [h_min, h_max] | -1 | 1 |
    | 5 | κ h_max, the curvature at the feet in units of 1/h_max | -k* | k* |

    ## Rewards

    With z = E/(m g) the height the barycentre would reach at rest, z₀ its lowest value (at rest at the bottom,
    crouched) and z* the value that just reaches the goal crouched (H + h_min at a rim of the valley), the progress is
    ε = (z − z₀)/(z* − z₀), Δz = z* − z₀, and, ε before the step and ε′ after it,

        reward = ln(max(ε′, 1e-4) / max(ε, 1e-4)) − 0.01

    The logarithm pays the factor by which pumping multiplies ε; the constant, time. Summed: ln(ε_T/ε₀) − 0.01·steps.

    ## Starting State

    At rest with h = h_min, x₀ uniform on 0.5 ≤ |x₀ − x_b| ≤ 2.0 m (np_random), x_b the trail's lowest point (x = 0 on
    the valley), from where no held h escapes. `reset(options={"state": {...}})` sets any of these exactly:

    ## Episode End

    Terminated on success (`info["is_success"]`): at a step's end, x at or past a rim (|x| ≥ L/2 on the valley, the
    halfpipe's lips) or `target_x`. Truncated after 1000 steps (50 s by default) by the registration's time limit.

    ## Arguments

    A user trail's `trail_params` also give its expression's other symbols. Under g the skier moves as under 9.81 m/s²
    in time scaled by √(g/9.81), so dt's bound and the default's substeps apply to dt √(g/9.81). Where 1 − κ h_max ≥ 0.5
    on the whole trail (the valley, the halfpipe), the default is "rk8_energy": ⌈dt √(g/9.81)/0.05 s⌉ substeps of
    DOP853's formula, projected back onto the energy level where h is held (no phase error near the rims); a step whose
    energy error passes 1e-8 m g Δz is retaken at twice the substeps. Nearer the centre of curvature, DOP853 at rtol
    1e-8, atol 1e-10 (why: docs/guides/env-notes.md). Diverged: an energy error past 0.1 m g Δz. Past its domain a trail
    continues as its osculating parabola, so a step across a rim stays finite. Every `info` has `"state"` (`x`, `x_dot`,
    `p`, `h`, `t`, `s` the arc length from the trail's origin, `kappa`, in SI), `"energy"` (E = p²/(2 m (1 − κh)² σ²) +
    m g (f + h cos φ), J), `"progress"` (ε) and `"is_success"`.
    """

    renderer = SkierRenderer

    JAX_STATIC = ("h_min", "h_max", "g")
    # h_min and h_max set the trail's reach (its floor, goals and curvature bound, from a grid) and the observation
    # space; g sets the stepper's count of substeps

    ARGS = Args(
        scale("h_min", 0.5, "m", "below h_max"),
        scale("h_max", 1.0, "m", "with 1 − κ h_max > 0 on the whole trail", low="h_min"),
        scale("mass", 70.0, "kg"),
        scale("g", G_REFERENCE, "m/s²", "with dt √(g/9.81) ≤ 10 s"),
        step(0.05, DT_MAX),
        given("trail", "valley",
              '"valley", "halfpipe", a sympy expression in x (or its text), or callables (f, f′, f″, f‴)'),
        given("trail_params", None,
              "valley: H=3.0, L=12.0; halfpipe: radius=5.0, max_angle=1.4; others: domain=(lo, hi)"),
        given("target_x", None,
              "required for a trail without rims: a point of the domain above the bottom, Δz ≥ 1e-9 |z|"),
        scale("max_height_speed", None, "m/s", optional=True, typical=1.0, physical=False),
        integrator(None, "euler", "semi_implicit_euler", "rk4", "rk8", "rk8_energy", "gauss6", "dop853", "rk45",
                   "lsoda", "radau", default_text="below"),
        options("below"),
    )

    STATE = Fields(
        number("x", "m", low=Bound(trail_end("lo"), "lo"), high=Bound(trail_end("hi"), "hi"),
               range_text="the trail's domain"),
        number("h", "m", low="h_min", high="h_max"),
        number("x_dot", "m/s", "the observed speed", bound=Bound(speed_bound, "3 v*/σ"),
               range_text="|σẋ| ≤ 3 v*"),
        number("p", "kg m²/s", bound=Bound(momentum_bound, "m (1 − κh)² σ² · 3 v*/σ"),
               range_text="that of ẋ times m (1 − κh)² σ²"),
        either=(("x_dot", "p"),),
    )

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.h_min, self.h_max, self.max_height_speed = a.h_min, a.h_max, a.max_height_speed
        if a.trail_params is not None and not isinstance(a.trail_params, dict):
            raise ValueError(f"trail_params={a.trail_params!r} must be a dict or None")
        self.trail = make_trail(a.trail, a.trail_params)
        self.x_bottom, self.z_floor, self.kappa_bound, self.min_lever = reach(self.trail, self.h_min, self.h_max)
        self.system = Skier(self.trail, mass=a.mass, g=a.g)
        self.held_energy = functools.partial(held_energy, self.system.energy)  # E where h is held
        self.scaled_dt = self.dt * math.sqrt(self.system.g / G_REFERENCE)  # the step in the time of g = 9.81 m/s²
        if self.scaled_dt > DT_MAX:
            raise ValueError(
                f"g={a.g!r} with dt={a.dt!r} is out of range: the step in the time of 9.81 m/s², dt √(g/9.81) = "
                f"{self.scaled_dt:.6g} s, must be at most {DT_MAX} s"
            )
        self.goals = self._goals(a.target_x)
        self.z_goal = min(float(barycentre_height(self.trail, np.array(x), self.h_min)) for x in self.goals)
        least = CLIMB_MIN * max(abs(self.z_floor), abs(self.z_goal))
        if not self.z_goal - self.z_floor >= least:
            raise ValueError(
                f"target_x={a.target_x!r} is at the bottom of the trail: the height to climb to it, Δz = "
                f"{self.z_goal - self.z_floor:.3g} m, must be at least {CLIMB_MIN:g} of the barycentre's height, "
                f"{least:.3g} m (the energy check is relative to Δz)"
            )
        self.speed_scale = math.sqrt(2.0 * self.system.g * (self.z_goal - self.z_floor))
        integrator, stepper_options = self._default_stepper(a.integrator, stepper_options)
        self.stepper = make_stepper(integrator, self.system, **stepper_options)
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        high = np.array([1.0, 1.0, 1.0, SPEED_BOUND, 1.0, self.kappa_bound], np.float32)
        low = -high
        low[2] = 0.0
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self.state = self.at(np.array([self.x_bottom, 0.0]), self.h_min, 0.0, 0.0, 0.0)

    def _default_stepper(self, integrator, options):
        """(integrator, options): the given ones, with the defaults filled in (see the class docstring)."""
        if integrator is None:
            integrator = "rk8_energy" if self.min_lever >= RK8_MIN_LEVER else "dop853"
        if integrator == "rk8_energy":
            energy_scale = self.system.mass * self.system.g * (self.z_goal - self.z_floor)  # m g Δz
            substeps = math.ceil(self.scaled_dt / MAX_SUBSTEP)
            options = {"substeps": substeps, "atol": ENERGY_TOLERANCE * energy_scale, **options}
        elif integrator == "dop853":
            options = {**DOP853_TOLERANCES, **options}
        return integrator, options

    def parameters(self):
        lever = round(self.min_lever, 12)  # beside h_max, which sets it
        return {"h_min": self.h_min, "h_max": self.h_max, "min 1 − κ h_max": lever, **super().parameters()}

    # -- construction ----------------------------------------------------------

    def _goals(self, target_x):
        """The points to reach: the rims, or target_x."""
        if target_x is None:
            if not self.trail.rims:
                raise ValueError("this trail has no rims: give target_x, a point of its domain to reach")
            return (self.trail.lo, self.trail.hi)
        return (check_number("target_x", target_x, self.trail.lo, self.trail.hi),)

    def at(self, y, h, t, side, energy_error, ops=SCALAR):
        """The state at (y, h, t), with its energy."""
        energy, x_dot, f1, sigma, kappa = (ops.real(v) for v in self.system.kinematics(y, h))
        return SkierState(y, h, t, side, energy, energy_error, x_dot, f1, sigma, kappa)

    def start(self, options, ops=SCALAR):
        """At rest crouched, x₀ from np_random (see the class); traced (``connenv.jax``, ops its namespace), the same
        draws from its key."""
        offset = self.np_random.uniform(*START_OFFSETS) * self.np_random.choice([-1.0, 1.0])
        x0 = ops.clip(self.x_bottom + offset, self.trail.lo, self.trail.hi)
        state = self.reset_values(options, {"x": x0, "h": self.h_min})
        x, h = state["x"], state["h"]
        if "p" in state:
            p = state["p"]
        else:
            w = self.system.geometry(x, h)[5]
            p = self.system.mass * w * w * state["x_dot"]
        y = vector(x, p)
        side = ops.copysign(1.0, y[0] - self.goals[0]) if len(self.goals) == 1 else 0.0
        return self.at(y, h, 0.0, side, 0.0, ops)

    def advance(self, s, h_cmd, stepper, ops=SCALAR):
        """The state after a step toward the commanded height; rows with the vector env's stepper and ops=BATCH."""
        segments, h = control_path(s.h, h_cmd, self.dt, self.max_height_speed, ops)
        y, change = run_segments(stepper, self.system, s.y, segments, self.held_energy)
        self.check_energy_error(s.energy_error + change)
        return self.at(y, h, s.t + self.dt, s.side, s.energy_error + change, ops)

    def check_energy_error(self, energy_error):
        """StepperError if |the stepper's energy error| (of any row of a batch) passes its bound."""
        bound = ENERGY_ERROR_BOUND * self.system.mass * self.system.g * (self.z_goal - self.z_floor)
        check_drift(self.stepper, "energy error", energy_error, bound, " J")

    def command(self, a):
        return self.h_min + 0.5 * (a.T[0] + 1.0) * (self.h_max - self.h_min)

    def progress(self, energy):
        return (energy / (self.system.mass * self.system.g) - self.z_floor) / (self.z_goal - self.z_floor)

    def reward(self, before, after, info, ops=SCALAR):
        progress_before, progress_after = self.progress(before.energy), info["progress"]
        floor = PROGRESS_FLOOR
        return ops.log(ops.maximum(progress_after, floor) / ops.maximum(progress_before, floor)) - TIME_COST

    def success(self, s, ops=SCALAR):
        """At or beyond a rim (side 0), or at or past the one goal from the side the episode started on."""
        x = ops.components(s.y)[0]
        if len(self.goals) == 2:
            return (x <= self.goals[0]) | (x >= self.goals[1])
        return (x - self.goals[0]) * s.side <= 0.0

    def observe(self, s, ops=SCALAR):
        x, h, sigma = ops.components(s.y)[0], s.h, s.sigma
        mid, half = 0.5 * (self.trail.hi + self.trail.lo), 0.5 * (self.trail.hi - self.trail.lo)
        h_mid, h_half = 0.5 * (self.h_max + self.h_min), 0.5 * (self.h_max - self.h_min)
        speed = sigma * s.x_dot / self.speed_scale
        return ops.pack([
            ops.clip((x - mid) / half, -1.0, 1.0),
            s.f1 / sigma,
            1.0 / sigma,
            ops.clip(speed, -SPEED_BOUND, SPEED_BOUND),
            (h - h_mid) / h_half,
            ops.clip(s.kappa * self.h_max, -self.kappa_bound, self.kappa_bound),
        ])

    def describe(self, s, ops=SCALAR):
        x, p = ops.components(s.y)
        state = {
            "x": x, "x_dot": s.x_dot, "p": p, "h": s.h, "t": s.t, "s": ops.real(self.trail.arc_length(x)),
            "kappa": s.kappa,
        }
        return {
            "state": state, "energy": s.energy, "progress": self.progress(s.energy),
            "is_success": ops.flag(self.success(s, ops)),
        }


SPECS = (
    Spec(
        "connenv/Skier-v0", SkierEnv, max_episode_steps=1000, dt_max=DT_MAX, physics="skier.md",
        measure=Measure("time to target", "s", "time_to_success"), controllers=("pumping",),
        play="space", space_action=1.0,  # held: the skier rises (h_max)
        variants=(
            {}, {"trail": "halfpipe"}, {"trail": "0.25*x**2", "trail_params": {"domain": (-5.0, 5.0)}, "target_x": 4.0},
            {"integrator": "rk4", "substeps": 8},
        ),
        fast_start={"state": {"x": 0.0, "x_dot": 23.0}},
        golden=(
            ("skier", {"max_episode_steps": 80}, None),
            ("skier_ramp", {"max_episode_steps": 40, "max_height_speed": 3.0, "target_x": 0.3}, None),
        ),
        bench="skier", single_target=5.0, vector_target=0.15,
        jax=({},),
    ),
)
