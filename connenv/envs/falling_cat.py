"""FallingCat-v0: a cat dropped upside down at rest lands on its feet by bending alone (Kane & Scher 1969)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from connenv.core import backend
from connenv.core.backend import SCALAR, concat, traced
from connenv.core.params import Args, Bound, integrator, interval, options, scale, step
from connenv.core.segments import run_segments
from connenv.core.state import Fields, rotation, vector
from connenv.core.validation import MAGNITUDE_BOUND, decimal
from connenv.envs.connection import DT_MAX, ConnectionEnv, ConnectionState
from connenv.envs.spec import Measure, Spec
from connenv.rendering.falling_cat import CatRenderer
from connenv.systems import falling_cat

ROLL_OFFSET = 0.2  # rad: the start's roll is π + δ, δ uniform in [−ROLL_OFFSET, ROLL_OFFSET]
SUCCESS_BONUS = 1.0  # reward on the step the cat is in its landing pose
LANDING_SLACK = 1e-9  # s: t ≥ fall_time − LANDING_SLACK is the landing (the sum of dt's rounds)
AXIAL_RATIO_MIN = 1e-6  # the least J/I: the exact step's pieces grow as 1/√(J/I) (see FallingCatEnv)
VERTICAL = 1e-6  # a given spine within this of vertical (1 − |spine · Z|) has no roll about it: ValueError


def axial_min(args):
    """The least axial inertia J of the arguments: AXIAL_RATIO_MIN · I, as the table writes it."""
    return decimal(AXIAL_RATIO_MIN * args["transverse_inertia"])


@dataclass
class CatState(ConnectionState):
    """ConnectionState (g: the cat frame's 9 entries, s: the bend vector, t) with the bend velocity ṡ at the step's end
    (0 where the bend stopped at max_bend) and the heading frame H (9 entries), fixed at reset."""

    s_dot: np.ndarray
    heading: np.ndarray


class FallingCatEnv(ConnectionEnv):
    r"""
    ## Description

    Kane and Scher's falling cat (`connenv.systems.falling_cat`): two identical axisymmetric halves that bend at the
    joint but never twist about their own axes. Dropped at rest (zero angular momentum), its attitude g (the cat frame:
    e₁ the mean spine, e₃ the back) follows the bend vector s = β (cos γ, sin γ) through the mechanical connection
    Ω = −f(β) γ̇ e₁ (docs/physics/FallingCat.md): bending straight out turns nothing, sweeping it around the spine rolls
    the cat by 2π f(β₀) per sweep at β₀. `ConnectionEnv` on SO(3), body frame; gravity moves only the centre of mass.

    ## Action Space

    `Box(-1, 1, (2,), float32)`: ṡ = a · max_bend_speed, constant over the step, stopping at β = max_bend.

    ## Observation Space

    `Box(-1, 1, (12,), float32)`, H the heading frame (columns: start spine, horizontal across it, vertical ⊥ to it):

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–8 | E = Hᵀ g, row by row: the cat frame in H (E = I feet down, spine at its start) | -1 | 1 |
    | 9–10 | s / max_bend | -1 | 1 |
    | 11 | time left to landing / fall_time | 0 | 1 |

    ## Rewards

    `e − e′ + 1 · (is_success)`, with the landing error e = |roll| + spine error + β (rad) before the step and e′ after
    it; the roll is atan2(Z · g e₂, Z · g e₃) (0 feet down), the spine error the angle between g e₁ and its start.
    Bending out costs β, paid back when the cat straightens; the sweep pays the roll it takes away.

    ## Starting State

    Straight (s = 0) at rest, t = 0, upside down: g = Rz(ψ) Rx(π + δ), the spine horizontal, ψ and δ uniform in [0, 2π)
    and [−0.2, 0.2] (the roll does not depend on the heading ψ). `reset(options={"state": {...}})` sets either exactly:

    ## Episode End

    Terminated on success, |roll|, spine error and β each ≤ `tolerance` (`info["is_success"]`), or at the landing,
    t = fall_time: the cat meets the ground, a termination, not a truncation. The registration's time limit,
    fall_time/dt = 60 steps, is the landing at the defaults; with another fall_time or dt pass `max_episode_steps`.

    ## Arguments

    m and ℓ never enter the roll, only the locked inertia across the spine (in the angular momentum and the rendering).
    The defaults are a slender cat (J/I = 0.03): its half turn needs β₀ ≈ 0.35 rad and fits in the fall at the bend
    speed. The default step is the roll in closed form up to a Gauss–Legendre quadrature exact to rounding, whose pieces
    grow as J/I falls: hence J/I ≥ 1e-6. Diverged: R more than 1e-9 off SO(3). Every `info` has `"state"` (the Starting
    State's keys and `t`), `"angular_momentum"` (in space, about the centre of mass: 0 to rounding), `"roll"`,
    `"spine_error"`, `"bend_angle"` (β) and `"is_success"`.
    """

    renderer = CatRenderer
    metadata = {**ConnectionEnv.metadata, "measures": ("roll_error",)}

    JAX_STATIC = ("transverse_inertia", "axial_inertia", "max_bend", "max_bend_speed")
    # they set the count of the roll's Gauss–Legendre pieces (pieces_for), the step's structure

    ARGS = Args(
        scale("transverse_inertia", 0.01, "kg m²", "I: a half's inertia across its axis about its centre of mass",
              high=MAGNITUDE_BOUND),
        interval("axial_inertia", 0.0003, "kg m²", Bound(axial_min, "1e-6 I"), "transverse_inertia",
                 "J: about its own axis", open_high=True),
        scale("mass", 1.5, "kg", "m: each half", high=MAGNITUDE_BOUND),
        scale("cm_distance", 0.12, "m", "ℓ: joint to a half's centre of mass", high=MAGNITUDE_BOUND),
        scale("max_bend", 1.2, "rad", high=3.0),
        scale("max_bend_speed", 6.0, "rad/s", high=MAGNITUDE_BOUND),
        scale("fall_time", 0.6, "s", high=100.0, physical=False),
        step(0.01, DT_MAX),
        scale("tolerance", 0.05, "rad", high=math.pi, open_high=True, physical=False),
        integrator(None, "exact", "magnus", "euler", "rk4", "dop853", "rk45", "lsoda", "radau", default_text='"exact"'),
        options(names="atol (magnus) / substeps / rtol, atol"),
    )

    STATE = Fields(
        rotation("R", "the front half's attitude g Q_A(s), whose cat frame's spine is not vertical"),
        vector("bend", 2, "rad", "s, with β = |s| ≤ max_bend too", bound="max_bend"),
    )

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        self.mass, self.cm_distance, self.max_bend, self.fall_time = a.mass, a.cm_distance, a.max_bend, a.fall_time
        self.tolerance, self.inertias = a.tolerance, {"transverse_inertia": a.transverse_inertia,
                                                      "axial_inertia": a.axial_inertia}  # fmt: skip
        longest = min(math.sqrt(2) * a.max_bend_speed * a.dt, 2 * self.max_bend)  # a segment's longest bend
        pieces = falling_cat.pieces_for(longest, a.transverse_inertia, a.axial_inertia)
        super().__init__(
            "SO3", functools.partial(falling_cat.connection, **self.inertias), shape_low=[-self.max_bend] * 2,
            shape_high=[self.max_bend] * 2, dt=a.dt, frame="body", max_shape_speed=a.max_bend_speed,
            render_mode=render_mode, vectorized=True, integrator=a.integrator,
            exact_segment=functools.partial(falling_cat.exact_segment, **self.inertias, pieces=pieces),
            **stepper_options,
        )
        eye = np.eye(3).ravel()
        self.state = CatState(eye.copy(), np.zeros(2), 0.0, np.zeros(2), eye.copy())

    def _observation_space(self):
        return spaces.Box(-1.0, 1.0, (12,), np.float32)

    def start(self, options, ops=SCALAR):
        """Straight, at rest, upside down at a random heading and roll offset (see Starting State); traced
        (``connenv.jax``, ops its namespace), the same draws from its key, the arrays built by ``backend.vector``."""
        state, given = self.reset_values(options), options.get("state", {})
        s = state["bend"]
        if math.hypot(*s) > self.max_bend:
            raise ValueError(f"state bend={s.tolist()} has β = {math.hypot(*s):.6g} > max_bend={self.max_bend}")
        heading = self.np_random.uniform(0.0, 2 * math.pi)
        roll = math.pi + self.np_random.uniform(-ROLL_OFFSET, ROLL_OFFSET)
        if "R" in given:
            g = state["R"] @ falling_cat.halves(s)[0].T
        else:
            c, n, cr, sr = ops.cos(heading), ops.sin(heading), ops.cos(roll), ops.sin(roll)
            turn = backend.vector(c, -n, 0.0, n, c, 0.0, 0.0, 0.0, 1.0).reshape(3, 3)  # Rz(ψ)
            g = turn @ backend.vector(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr).reshape(3, 3)  # Rz(ψ) Rx(π + δ)
        spine = g[:, 0]
        if not traced(ops) and not 1.0 - abs(spine[2]) > VERTICAL:  # traced: a drawn start's spine is horizontal
            raise ValueError(f"state R={given['R']!r} puts the spine vertical, {spine.tolist()}: no roll about it")
        up = backend.vector(0.0, 0.0, 1.0) - spine[2] * spine
        if traced(ops):
            up = up / ops.sqrt(np.sum(up * up))
            H = ops.stack([spine, falling_cat.cross(up, spine), up], -1)
        else:
            up /= np.linalg.norm(up)
            H = np.stack([spine, np.cross(up, spine), up], -1)
        return CatState(g.ravel(), s, 0.0, np.zeros(2), H.ravel())

    def advance(self, state, s_dot, stepper, ops=SCALAR):
        """The state after bending at ṡ for dt, stopped at max_bend (one state, or rows with ops=BATCH)."""
        tau, s, v = falling_cat.disc_segment(state.s, s_dot, self.max_bend, self.dt)
        g = state.g
        if ops is not SCALAR or tau > 0.0:
            g = run_segments(stepper, self.system, g, [(state.s, s_dot, tau)])[0]
            self.check_group(g)
        return state.replace(g=g, s=s, s_dot=v, t=state.t + self.dt)

    def frames(self, state):
        """g and H as (…, 3, 3)."""
        lead = np.shape(state.g)[:-1]
        return state.g.reshape(*lead, 3, 3), state.heading.reshape(*lead, 3, 3)

    def errors(self, state, ops=SCALAR):
        """The roll (rad, 0 feet down), the spine error (rad) and β."""
        g, H = self.frames(state)
        if ops is SCALAR:
            (a1, _, _, a2, _, _, a3, _, _), (b1, _, _, b2, _, _, b3, _, _) = state.g.tolist(), state.heading.tolist()
            across = math.hypot(a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1)
            spine_error = math.atan2(across, a1 * b1 + a2 * b2 + a3 * b3)
            return math.atan2(state.g[7], state.g[8]), spine_error, math.hypot(*state.s.tolist())
        spine, start = g[..., :, 0], H[..., :, 0]
        across = falling_cat.cross(spine, start)  # np.cross's products and differences
        square = np.sum(across * across, -1)  # np.linalg.norm's arithmetic on real rows
        # the spine on its start (across = 0, as the cat turns only about its spine): √'s derivative at 0 is infinite,
        # times the tangent's 0 a NaN under JAX; √ of a square kept from 0 by where, the norm 0 there (derivative 0)
        aligned = ops.real_part(square) == 0.0
        norm = ops.where(aligned, 0.0, ops.sqrt(ops.where(aligned, 1.0, square)))
        spine_error = ops.atan2(norm, np.sum(spine * start, -1))
        return ops.atan2(g[..., 2, 1], g[..., 2, 2]), spine_error, ops.hypot(state.s[..., 0], state.s[..., 1])

    def landing_error(self, state, ops=SCALAR):
        roll, spine_error, beta = self.errors(state, ops)
        return abs(roll) + spine_error + beta

    def observe(self, state, ops=SCALAR):
        g, H = self.frames(state)
        E = (np.swapaxes(H, -1, -2) @ g).reshape(*np.shape(state.s)[:-1], 9)
        t = state.t if traced(ops) else np.asarray(state.t)
        left = ops.clip((self.fall_time - t) / self.fall_time, 0.0, 1.0)
        parts = [E, state.s / self.max_bend, (left if traced(ops) else np.asarray(left))[..., None]]
        return concat(parts, -1).astype(np.float32)

    def describe(self, state, ops=SCALAR):
        g, _ = self.frames(state)
        roll, spine_error, beta = self.errors(state, ops)
        omega = -falling_cat.matvec(falling_cat.connection(state.s, **self.inertias), state.s_dot)
        front = falling_cat.front_half(state.s)
        momentum = falling_cat.angular_momentum(g, state.s, state.s_dot, omega, **self.inertias, mass=self.mass,
                                                cm_distance=self.cm_distance, front=front)  # fmt: skip
        success = (abs(roll) <= self.tolerance) & (spine_error <= self.tolerance) & (beta <= self.tolerance)
        return {
            "state": {"R": g @ front[0], "bend": state.s * 1.0 if traced(ops) else np.array(state.s), "t": state.t}, "angular_momentum": momentum,
            "roll": roll, "roll_error": abs(roll), "spine_error": spine_error, "bend_angle": beta,
            "is_success": ops.flag(success),
        }

    def reward(self, before, after, info, ops=SCALAR):
        error = info["roll_error"] + info["spine_error"] + info["bend_angle"]
        return self.landing_error(before, ops) - error + SUCCESS_BONUS * ops.real(info["is_success"])

    def terminated(self, state, info, ops=SCALAR):
        landed = (state.t if traced(ops) else np.asarray(state.t)) >= self.fall_time - LANDING_SLACK
        return ops.flag(info["is_success"] | landed)


SPECS = (
    Spec(
        "connenv/FallingCat-v0", FallingCatEnv, max_episode_steps=60, dt_max=DT_MAX,
        physics="FallingCat.md", measure=Measure("roll error at landing", "rad", "roll_error"),
        controllers=("kane_scher",),
        golden=(("cat", {"max_episode_steps": 60, "fall_time": 0.4, "max_bend": 0.5}, None),),
        bench="cat", jax=({},),
    ),
)
