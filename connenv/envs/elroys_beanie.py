"""ElroysBeanie-v0: turn a body by spinning the beanie on it, against the drift of its angular momentum."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, traced
from connenv.core.backend import vector as entries_vector
from connenv.core.params import Args, Bound, integrator, interval, options, scale, step
from connenv.core.state import Fields, Options, angle, number
from connenv.core.validation import MAGNITUDE_BOUND
from connenv.envs.connection import DT_MAX, ConnectionEnv, ConnectionState  # DT_MAX: its dt range
from connenv.envs.spec import Measure, Spec
from connenv.rendering.elroys_beanie import BeanieRenderer
from connenv.systems import elroys_beanie

MOMENTUM_RANGE = (0.25, 1.0)  # |μ| drawn at reset (kg m²/s), with a random sign
OFF_TARGET_COST = 0.05  # reward paid per step the body is off the target by 10 tolerances or more (graded below)
SUCCESS_BONUS = 1.0  # reward on the step that completes the hold
FINE_SCALE = 10.0  # the observed fine error is (θ* − θ)/(FINE_SCALE · tolerance), clipped to [−1, 1]
HOLD_SLACK = 1e-9  # s: a hold of hold_time − HOLD_SLACK counts (the sum of dt's rounds)


def least_speed(args):
    """The least max_beanie_speed, rad/s: 1.2 · 1/I₂ (1.2 times the speed that holds the largest drawn μ)."""
    return 1.2 * MOMENTUM_RANGE[1] / args["beanie_inertia"]


@dataclass
class BeanieState(ConnectionState):
    """ConnectionState with g = (θ,) the body's angle, s = (ψ,) the beanie's relative to it (both unwrapped); the
    angular momentum μ, the target θ* and the time held within the tolerance."""

    components: ClassVar[dict] = {"g": ("theta",), "s": ("psi",)}

    momentum: float
    target: float
    held: float


class ElroysBeanieEnv(ConnectionEnv):
    r"""
    ## Description

    Elroy's beanie (`connenv.systems.elroys_beanie`): a body of inertia I₁ and a beanie of inertia I₂ on it turn about
    one axis, a motor spinning the beanie at ψ̇ relative to the body. Their angular momentum μ = (I₁ + I₂) θ̇ + I₂ ψ̇ is
    conserved, so θ̇ = −I₂/(I₁ + I₂) ψ̇ + μ/(I₁ + I₂): the geometric phase of the flat connection A = I₂/(I₁ + I₂) on
    SO(2), −2π A per turn of the beanie whatever its speed profile, plus the dynamic phase μ t/(I₁ + I₂), both exact
    (`ConnectionEnv`). μ is drawn nonzero at reset, so the body drifts unless the beanie spins at μ/I₂.

    ## Action Space

    `Box(-1, 1, (1,), float32)`: ψ̇ = a · max_beanie_speed, constant over the step.

    ## Observation Space

    `Box(5,) float32`, with μ_max = 0.9 I₂ · max_beanie_speed the largest momentum a reset takes:

    | Num | Observation | Min | Max | Unit |
    |-----|-------------|-----|-----|------|
    | 0 | sin(θ* − θ) | -1 | 1 | |
    | 1 | cos(θ* − θ) | -1 | 1 | |
    | 2 | μ | -μ_max | μ_max | kg m²/s |
    | 3 | time held within the tolerance / hold_time, at most 1 | 0 | 1 | |
    | 4 | (θ* − θ)/(10 · tolerance), clipped: the error at the resolution the hold needs | -1 | 1 | |

    ## Rewards

    `|e| − |e′| − 0.05 · min(1, |e′|/(10 tolerance)) · (|e′| > tolerance) + 1 · (hold completed)`, e = θ* − θ wrapped
    into [−π, π] before the step, e′ after it. The cost off the target grows with the error up to ten tolerances (a near
    miss costs less than a far one) and is 0 inside the tolerance, where staying earns less than completing the hold.

    ## Starting State

    θ = 0, ψ = 0, t = 0; |μ| uniform in [0.25, 1] kg m²/s with a uniform sign (the body drifts at up to 0.8 rad/s;
    holding needs |ψ̇| = |μ|/I₂ ≤ 4 rad/s, within the 4π rad/s bound); θ* uniform in [−π, π).
    `reset(options={"state": {...}, "target": θ*})` sets any of these exactly:

    ## Episode End

    Terminated when the body has stayed within `tolerance` of θ* for `hold_time` (`info["is_success"]`). Truncated after
    200 steps (10 s) by the registration's time limit.

    ## Arguments

    Every `info` has `"state"` (`theta`, `psi` (both unwrapped), `momentum`, `t`), `"target"` (θ*), `"error"` (θ* − θ
    wrapped, rad), `"held"` (s) and `"is_success"`.
    """

    renderer = BeanieRenderer
    metadata = {**ConnectionEnv.metadata, "measures": ("error",)}

    JAX_STATIC = ("beanie_inertia", "max_beanie_speed")  # they set the observation space

    ARGS = Args(
        scale("body_inertia", 1.0, "kg m²", high=MAGNITUDE_BOUND),
        scale("beanie_inertia", 0.25, "kg m²", high=MAGNITUDE_BOUND),
        interval("max_beanie_speed", 4 * math.pi, "rad/s", Bound(least_speed, "1.2 · 1/I₂", "1.2 · 1/beanie_inertia"),
                 MAGNITUDE_BOUND, "the largest drawn μ can be held"),
        step(0.05, DT_MAX),
        scale("tolerance", 0.01, "rad", high=math.pi, open_high=True, physical=False),
        scale("hold_time", 1.0, "s", high=100.0, physical=False),
        integrator(None, "exact", "magnus", "euler", "rk4", "dop853", "rk45", "lsoda", "radau", default_text='"exact"'),
        options(names="atol (magnus) / substeps / rtol, atol"),
    )

    STATE = Fields(
        angle("theta", "the body's angle"),
        angle("psi", "the beanie's"),
        number("momentum", "kg m²/s", "μ; else the body could not be held",
               bound=Bound(lambda env, values: env.momentum_bound(), "0.9 I₂ · max_beanie_speed")),
    )
    OPTIONS = Options(angle("target", "θ*"))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        self.body_inertia, self.beanie_inertia, self.tolerance = a.body_inertia, a.beanie_inertia, a.tolerance
        self.max_beanie_speed, self.hold_time = a.max_beanie_speed, a.hold_time
        inertias = {"body_inertia": self.body_inertia, "beanie_inertia": self.beanie_inertia}
        super().__init__(
            "SO2", functools.partial(elroys_beanie.connection, **inertias), shape_low=[-math.inf],
            shape_high=[math.inf], dt=a.dt, max_shape_speed=self.max_beanie_speed, render_mode=render_mode,
            vectorized=True, integrator=a.integrator,
            exact_segment=functools.partial(elroys_beanie.exact_segment, **inertias), **stepper_options,
        )
        self.state = BeanieState(np.zeros(1), np.zeros(1), 0.0, MOMENTUM_RANGE[0], 0.0, 0.0)

    def _observation_space(self):
        mu = self.momentum_bound()
        low, high = np.array([-1.0, -1.0, -mu, 0.0, -1.0], np.float32), np.array([1.0, 1.0, mu, 1.0, 1.0], np.float32)
        return spaces.Box(low, high)

    def momentum_bound(self):
        """The largest |μ| a reset takes: 0.9 I₂ · max_beanie_speed, so that the beanie can still hold the body."""
        return 0.9 * self.beanie_inertia * self.max_beanie_speed

    def start(self, options, ops=SCALAR):
        """At rest at θ = ψ = 0, μ and θ* drawn from np_random; traced (``connenv.jax``, ops its namespace), the same
        draws from its key."""
        rng = self.np_random
        momentum = rng.uniform(*MOMENTUM_RANGE) * rng.choice((-1.0, 1.0))
        values = self.reset_values(options, {"momentum": momentum, "target": rng.uniform(-math.pi, math.pi)})
        theta, psi, momentum, target = (values[key] for key in ("theta", "psi", "momentum", "target"))
        return BeanieState(entries_vector(theta), entries_vector(psi), 0.0, ops.real(momentum), ops.real(target), 0.0)

    def advance(self, state, s_dot, stepper, ops=SCALAR):
        return self.drifted(state, super().advance(state, s_dot, stepper, ops), ops)

    def drifted(self, before, moved, ops=SCALAR):
        """The connection's step `moved` plus the dynamic phase μ dt/(I₁ + I₂) on θ, and the hold counted."""
        phase = elroys_beanie.dynamic_phase(before.momentum, self.dt, self.body_inertia, self.beanie_inertia)
        state = moved.replace(g=moved.g + (phase[..., None] if traced(ops) else np.asarray(phase)[..., None]))
        inside = abs(self.error(state, ops)) <= self.tolerance
        return state.replace(held=ops.where(inside, before.held + self.dt, 0.0))

    def error(self, state, ops=SCALAR):
        """θ* − θ wrapped into [−π, π]."""
        turn = state.target - (float(state.g[0]) if ops is SCALAR else state.g[..., 0])
        return ops.atan2(ops.sin(turn), ops.cos(turn))

    def success(self, state, ops=SCALAR):
        return state.held >= self.hold_time - HOLD_SLACK

    def observe(self, state, ops=SCALAR):
        e = self.error(state, ops)
        held = ops.clip(state.held / self.hold_time, 0.0, 1.0)
        fine = ops.clip(e / (FINE_SCALE * self.tolerance), -1.0, 1.0)
        return ops.pack([ops.sin(e), ops.cos(e), state.momentum, held, fine])

    def reward(self, before, after, info, ops=SCALAR):
        e_before, e_after = abs(self.error(before, ops)), abs(info["error"])
        off = ops.real(e_after > self.tolerance) * ops.clip(e_after / (FINE_SCALE * self.tolerance), 0.0, 1.0)
        return e_before - e_after - OFF_TARGET_COST * off + SUCCESS_BONUS * ops.real(info["is_success"])

    def describe(self, state, ops=SCALAR):
        state_dict = {"theta": ops.real(state.g[..., 0]), "psi": ops.real(state.s[..., 0]),
                      "momentum": ops.real(state.momentum), "t": state.t}  # fmt: skip
        error = self.error(state, ops)
        return {
            "state": state_dict, "target": ops.real(state.target), "error": ops.real(error),
            "held": ops.real(state.held), "is_success": ops.flag(self.success(state, ops)),
        }


SPECS = (
    Spec(
        "connenv/ElroysBeanie-v0", ElroysBeanieEnv, max_episode_steps=200, dt_max=DT_MAX,
        physics="ElroysBeanie.md", measure=Measure("time to hold", "s", "time_to_success"), controllers=("dead_beat",),
        golden=(("beanie", {"max_episode_steps": 60, "tolerance": 0.5, "hold_time": 0.1}, None),),
        jax=({},),
        bench="beanie",
    ),
)
