"""TubeTwist-v0: turn a tube about its own axis by bending it, since it cannot twist."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, concat, traced
from connenv.core.params import Args, integrator, options, scale, step
from connenv.core.segments import run_segments
from connenv.core.state import Fields, Options, number, rotation
from connenv.core.validation import MAGNITUDE_BOUND
from connenv.envs.connection import DT_MAX, ConnectionEnv, ConnectionState
from connenv.envs.spec import Measure, Spec
from connenv.rendering.tube import TubeRenderer
from connenv.systems.tube import BEND_CONNECTION, tangent_angle, twist

__all__ = ["DT_MAX", "TubeTwistEnv"]  # DT_MAX: ConnectionEnv's, which checks dt here

TIME_COST = 0.01  # reward paid per step until success
TARGET_RANGE = (0.3, 3.0)  # rad: ψ* drawn uniformly at reset


@dataclass
class TubeState(ConnectionState):
    """ConnectionState (g: R's 9 entries, s: the accumulated bend, t) with the start frame R₀ and the error
    E = Rz(ψ*)ᵀR₀ᵀR (9 entries each), the target ψ*, the twist ψ, the tangent's angle θ_T, the bend length so far."""

    R0: np.ndarray
    target: float
    error: np.ndarray
    twist: float
    tangent_error: float
    path_length: float


class TubeTwistEnv(ConnectionEnv):
    r"""
    ## Description

    The tip of a tube that bends but cannot twist, like surgical and imaging probes (Lawton): its frame R ∈ SO(3)
    (tip → space) has columns N, B, T (normal, binormal, tangent), and the controller sets the bending rates
    κ = (κ₁, κ₂) in the tip's frame, none about T: Ṙ = R ω̂, ω = (κ₁, κ₂, 0). N is parallel transported along the curve T
    traces on the unit sphere, so the tip turns about its axis only by a loop of T, by the area enclosed
    (counterclockwise seen from outside, mod 2π; docs/physics/TubeTwist.md). The task: turn it by a target angle ψ* and
    bring the tangent back. `ConnectionEnv` on SO(3), body frame, with shape s = ∫κ dt and a constant connection.

    The *twist* ψ (`info["twist"]`) is the angle N has turned about T from the start frame R₀ once T is carried back to
    T₀ along the great circle between them, G Q = Rz(ψ) with Q = R₀ᵀR and G that rotation: the area enclosed by T's path
    closed by that geodesic (ψ = 0 at T = −T₀, where none is singled out).

    ## Action Space

    `Box(-1, 1, (2,), float32)`: κ = a · max_bend_rate, constant over the step (κ₁ bends about N, κ₂ about B).

    ## Observation Space

    `Box(-1, 1, (11,), float32)`: the error E = Rz(ψ*)ᵀ R₀ᵀ R, the frame relative to the target frame R₀ Rz(ψ*)
    (E = I at the goal), which turns as the tip does, Ė = E ω̂, so it is a Markov state; then the twist error.

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–8 | E, row by row (row 2: T₀ in the tip's frame) | -1 | 1 |
    | 9 | cos(ψ − ψ*) | -1 | 1 |
    | 10 | sin(ψ − ψ*) | -1 | 1 |

    ## Rewards

    `e − e′ − 0.01`, with the cost e = θ_T + |ψ − ψ*| (θ_T the angle between T and T₀, the twist error wrapped into
    [−π, π)) before the step and e′ after it. Bending T radially away from T₀ costs θ_T; going round pays back the twist
    it adds, at tan(θ_T/2) per radian of bend, so the reward leads round a loop.

    ## Starting State

    R = R₀ = I, s = 0, t = 0, and ψ* uniform in [0.3, 3] rad. `reset(options={"state": {...}, "target": ψ*})` sets
    either:

    ## Episode End

    Terminated when θ_T and |ψ − ψ*| ≤ `tolerance` (`info["is_success"]`). Truncated after 200 steps, the registration's
    time limit; the cap controller (shortest loop) takes ≤ √(3 (4π − 3))/(max_bend_rate · dt) ≈ 108 steps.

    ## Arguments

    The default step, one exponential R ← R exp(dt ω̂), is exact and keeps R on SO(3) to rounding; the generic steppers
    integrate Ṙ = R ω̂ in coordinates and drift off. Diverged: ‖RᵀR − I‖ > 1e-9. Every `info` has `"state"` (`R`, `t`),
    `"twist"` (ψ), `"twist_error"` (ψ − ψ*, wrapped), `"tangent_error"` (θ_T), `"path_length"` (∫|κ| dt since reset,
    rad), `"path_ratio"` (path_length over √(A (4π − A)), A = |ψ*|: the length of a circle of area A, the shortest loop
    that does the task by the isoperimetric inequality on the sphere) and `"is_success"`.
    """

    renderer = TubeRenderer
    metadata = {**ConnectionEnv.metadata, "measures": ("path_ratio", "path_length")}

    ARGS = Args(
        scale("max_bend_rate", 1.0, "rad/s", high=MAGNITUDE_BOUND),
        step(0.05, DT_MAX),
        scale("tolerance", 0.02, "rad", high=math.pi, open_high=True, physical=False),
        integrator("exact", "exact", "magnus", "euler", "rk4", "dop853", "rk45", "lsoda", "radau",
                   about='"exact" is Rodrigues\''),
        options(),
    )

    STATE = Fields(rotation("R", "R₀, the tube's frame"))
    OPTIONS = Options(number("target", "rad", "ψ*", bound=math.pi))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        self.tolerance, infinite = a.tolerance, [math.inf, math.inf]
        super().__init__("SO3", BEND_CONNECTION, np.negative(infinite), infinite, dt=a.dt, frame="body",
                         max_shape_speed=a.max_bend_rate, render_mode=render_mode, integrator=a.integrator,
                         **stepper_options)  # fmt: skip
        self.state = self.at(np.eye(3).ravel(), np.zeros(2), 0.0, np.eye(3).ravel(), 1.0, 0.0)

    def _observation_space(self):
        return spaces.Box(-1.0, 1.0, (11,), np.float32)

    def at(self, g, s, t, R0, target, path_length, ops=SCALAR):
        """The state at R (g) from R₀, with its error from the target frame, its twist and its tangent angle."""
        lead = np.shape(g)[:-1]
        Q = np.swapaxes(R0.reshape(*lead, 3, 3), -1, -2) @ g.reshape(*lead, 3, 3)
        psi, theta = twist(Q, ops.atan2), tangent_angle(Q, ops.atan2, ops.hypot)
        xp = ops if traced(ops) else np  # numpy's cos and sin on the numpy paths (one state's too), as ever
        c, n = ops.column(xp.cos(target)), ops.column(xp.sin(target))
        rows = [c * Q[..., 0, :] + n * Q[..., 1, :], c * Q[..., 1, :] - n * Q[..., 0, :], Q[..., 2, :]]
        error = concat(rows, -1)
        return TubeState(g, s, t, R0, target, error, ops.real(psi), ops.real(theta), path_length)

    def start(self, options, ops=SCALAR):
        """R = R₀ = I, ψ* uniform in TARGET_RANGE; traced (``connenv.jax``, ops its namespace), ψ* from its key."""
        target = self.np_random.uniform(*TARGET_RANGE)
        values = self.reset_values(options, {"target": target if traced(ops) else float(target)})
        g = values["R"].ravel().copy()
        return self.at(g, np.zeros(2), 0.0, g.copy(), values["target"], 0.0, ops)

    def advance(self, state, kappa, stepper, ops=SCALAR):
        """The state after bending at the rates κ for dt (one state, or rows with ops=BATCH)."""
        g = run_segments(stepper, self.system, state.g, [(state.s, kappa, self.dt)])[0]
        self.check_group(g)
        length = state.path_length + ops.hypot(kappa[..., 0], kappa[..., 1]) * self.dt
        return self.at(g, state.s + kappa * self.dt, state.t + self.dt, state.R0, state.target, length, ops)

    def twist_error(self, s, ops=SCALAR):
        """ψ − ψ*, wrapped into [−π, π)."""
        return (s.twist - s.target + math.pi) % (2 * math.pi) - math.pi

    def observe(self, s, ops=SCALAR):
        e = self.twist_error(s, ops)
        xp = ops if traced(ops) else np
        return concat([s.error, xp.stack([xp.cos(e), xp.sin(e)], -1)], -1).astype(np.float32)

    def cost(self, s, ops=SCALAR):
        return s.tangent_error + abs(self.twist_error(s, ops))

    def reward(self, before, after, info, ops=SCALAR):
        return self.cost(before, ops) - self.cost(after, ops) - TIME_COST

    def success(self, s, ops=SCALAR):
        return (s.tangent_error <= self.tolerance) & (abs(self.twist_error(s, ops)) <= self.tolerance)

    def path_ratio(self, s, ops=SCALAR):
        """path_length over the shortest loop that does the task, a circle of area |ψ*| (1 for ψ* = 0)."""
        area = abs(s.target)
        shortest = ops.sqrt(area * (4 * math.pi - area))
        return ops.where(shortest > 0, s.path_length / ops.maximum(shortest, 1e-300), 1.0)

    def describe(self, s, ops=SCALAR):
        lead = np.shape(s.g)[:-1]
        return {
            "state": {"R": s.g.reshape(*lead, 3, 3).copy(), "t": s.t}, "twist": s.twist,
            "twist_error": ops.real(self.twist_error(s, ops)), "tangent_error": s.tangent_error,
            "path_length": s.path_length, "path_ratio": self.path_ratio(s, ops),
            "is_success": ops.flag(self.success(s, ops)),
        }


SPECS = (
    Spec(
        "connenv/TubeTwist-v0", TubeTwistEnv, max_episode_steps=200, dt_max=DT_MAX, physics="TubeTwist.md",
        measure=Measure("bend / shortest loop", "", "path_ratio"), controllers=("cap", "square"),
        play="mouse", variants=({}, {"integrator": "magnus"}),
        golden=(("tube", {"max_episode_steps": 40, "tolerance": 0.6}, None),),
        bench="tube", jax=({},),
    ),
)
