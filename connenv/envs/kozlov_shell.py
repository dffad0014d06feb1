"""KozlovShell-v0: swim an elliptic shell through an ideal fluid to a target by moving a mass inside it."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from connenv.core.backend import SCALAR
from connenv.core.lie import fixed_rule
from connenv.core.params import Args, Bound, integrator, options, scale, step
from connenv.core.state import vector
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Spec
from connenv.envs.swimmer import INTEGRATORS, SWIMMER, PlanarSwimmer, swimmer_state
from connenv.rendering.kozlov_shell import KozlovShellRenderer
from connenv.systems.kozlov_shell import KozlovShell, ReducedKozlovShell

DT_MAX = 1.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
DEFAULT_INTEGRATOR = "magnus"


def disc_inertia(args):
    """The default shell inertia J: a uniform elliptic disc's, shell_mass (a² + b²)/4."""
    return args["shell_mass"] * (args["a"] ** 2 + args["b"] ** 2) / 4


@dataclass
class ShellState(State):
    """The pose (x, y, θ), body momentum (P₁, P₂, Π) (0 in the reduced model), mass position u, target (x, y), time t;
    full: whether it steps the full model, whose spatial momentum stays at momentum0, its value at reset."""

    components: ClassVar[dict] = {"pose": ("x", "y", "theta"), "momentum": ("P1", "P2", "Pi"), "u": ("u1", "u2"),
                                  "target": ("target_x", "target_y")}

    pose: np.ndarray
    momentum: np.ndarray
    u: np.ndarray
    target: np.ndarray
    t: float
    full: bool
    momentum0: np.ndarray


class KozlovShellEnv(PlanarSwimmer, TaskEnv):
    r"""
    ## Description

    An elliptic shell, semi-axes a along body x, b along body y, floats in an unbounded planar ideal fluid at rest at
    infinity (Kozlov & Ramodanov 2001); the controller assigns the body-frame position u of a point mass m inside (an
    *active constraint*, Bressan), which moves the shell through the fluid's added masses λ₁ = ρπb², λ₂ = ρπa²,
    λ₃ = ρπ(a² − b²)²/8 (docs/physics/kozlov-shell.md). With g = (x, y, θ) the pose and μ = (P₁, P₂, Π) the body
    momentum of shell, fluid and mass: from rest (the default) μ stays 0 and the motion is geometric (a mechanical
    connection), integrated on (x, y, θ) alone, a closed loop of u moving the shell alike at any speed (loops turn it,
    figure-eights translate it); a nonzero initial momentum switches the episode to the full (Kirchhoff) model on
    (x, y, θ, μ), conserving the spatial momentum. Goal: the shell's centre within `success_radius` of a target.

    ## Action Space

    `Box([-1, -1], [1, 1], float32)`: the commanded mass position u* = (action[0] · u1_max, action[1] · u2_max) in the
    body frame, to which the mass moves straight over the step, u̇ = (u* − u)/dt.

    ## Observation Space

    `Box(9,) float32` (M, J: the shell's mass and inertia), target and momentum (0 in the reduced model) clipped:

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | target in the body frame, along body x, m | -3 | 3 |
    | 1 | target in the body frame, along body y, m | -3 | 3 |
    | 2 | cos θ | -1 | 1 |
    | 3 | sin θ | -1 | 1 |
    | 4 | u₁ / u1_max | -1 | 1 |
    | 5 | u₂ / u2_max | -1 | 1 |
    | 6 | P₁ / (M + m + λ₁), m/s | -10 | 10 |
    | 7 | P₂ / (M + m + λ₂), m/s | -10 | 10 |
    | 8 | Π / (J + λ₃), rad/s | -10 | 10 |

    ## Rewards

    With d the distance from the shell's centre to the target before the step and d′ after it, progress in units of the
    success radius (one per 5 cm at the default) and a cost of time:

        reward = (d − d′) / success_radius − 0.01    (summed to success: (d₀ − d_T) / success_radius − 0.01 · steps)

    ## Starting State

    At rest (μ = 0, u = 0) at the origin, θ = 0, t = 0; the target a uniform [0.5, 1.0] m away in a uniform direction
    (np_random). `reset(options={"state": {...}, "target": (x, y)})` sets any of these exactly:

    ## Episode End

    Terminated when the shell's centre is within `success_radius` of the target at the end of a step
    (`info["is_success"]`); truncated after 300 steps (30 s at the default dt) by the registration's time limit, ample
    for the gait planner (`agents.controllers.kozlov_shell`).

    ## Arguments

    By default the reduced model takes the Lie-group step on SE(2) (`connenv.core.lie`), its quadrature rule the
    cheapest meeting atol on every one-dt motion of the mass (chosen at construction), the full model (no connection) by
    DOP853; semi-implicit Euler is explicit Euler on the reduced model. Diverged: the full model's spatial momentum
    moved over 0.1 of its norm since reset. Every `info` has `"state"` (`x`, `y`, `theta`, `u`, `momentum` (μ), `t`, in
    SI), `"spatial_momentum"` ((R(θ)P, Π + x P_y − y P_x), conserved), `"target"` (x, y), `"distance"` (m), `"model"`
    ("reduced" or "full") and `"is_success"`. The evaluation table averages the final `"distance"`.
    """

    renderer = KozlovShellRenderer
    state_class = ShellState
    TARGET_DISTANCES = (0.5, 1.0)  # m
    TOLERANCES: ClassVar[dict] = {"rtol": 1e-8, "atol": 1e-10}

    metadata: ClassVar[dict] = {**TaskEnv.metadata, "measures": ("distance",)}

    JAX_STATIC = ("a", "b", "shell_mass", "shell_inertia", "rho", "mass", "u1_max", "u2_max")
    # they set the Lie-group step's fixed rule (shell_rule: its pieces)

    ARGS = Args(
        scale("a", 1.0, "m", "semi-axis along body x, a ≥ b"),
        scale("b", 0.5, "m", "at most a"),
        scale("shell_mass", 1.0, "kg"),
        scale("shell_inertia", None, "kg m²", optional=True, typical=Bound(disc_inertia, "shell_mass (a² + b²)/4"),
              default_text="None: shell_mass (a² + b²)/4"),
        scale("rho", 1.0, "kg/m²", "fluid density", low=0.0),
        scale("mass", 1.0, "kg", "the inner mass"),
        scale("u1_max", 0.5, "m", "with the box's corners inside the ellipse"),
        scale("u2_max", 0.25, "m", "likewise"),
        step(0.1, DT_MAX),
        scale("success_radius", 0.05, "m", high=0.5, open_high=True, physical=False),
        integrator(DEFAULT_INTEGRATOR, *INTEGRATORS),
        options("rtol 1e-8, atol 1e-10"),
    )

    STATE = swimmer_state(vector("u", 2, "m", "the mass, in the box |u₁| ≤ u1_max, |u₂| ≤ u2_max", bound="u_max"))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        if a.b > a.a:
            raise ValueError(
                f"b={a.b!r} is out of range: must be in (0, a={a.a!r}]; the axes are ordered so that a, the larger "
                "semi-axis, lies along body x (swap them and turn the task by 90°)"
            )
        if (a.u1_max / a.a) ** 2 + (a.u2_max / a.b) ** 2 >= 1.0:
            raise ValueError(
                f"u1_max={a.u1_max!r}, u2_max={a.u2_max!r}: the box of the mass reaches outside the shell; its corners "
                f"must lie inside the ellipse, (u1_max/a)² + (u2_max/b)² < 1 with a={a.a!r}, b={a.b!r}"
            )
        self.u_max = np.array([a.u1_max, a.u2_max])
        params = {key: getattr(a, key) for key in ("a", "b", "shell_mass", "rho", "mass", "shell_inertia")}
        reduced = ReducedKozlovShell(**params)
        self.success_radius, self.shape_bounds = a.success_radius, self.u_max.tolist()
        self.target_unit = 1.0  # m
        self.build(KozlovShell(**params), reduced, a.integrator, stepper_options,
                   lambda atol: shell_rule(reduced, tuple(self.u_max), self.dt, atol))  # fmt: skip

    def parameters(self):
        system = self.full_system
        ratio = round(system.mass / (system.shell_mass + system.added_masses[0]), 12)
        return {**super().parameters(), "m/(M + λ₁)": ratio, "model": "full" if self.state.full else "reduced"}

    def advance(self, s, u_cmd, stepper, ops=SCALAR):
        """The mass moves straight to u_cmd over dt: one state, or rows with the vector env's stepper and ops=BATCH."""
        segments = [(s.u, (u_cmd - s.u) / self.dt, self.dt)]
        pose, momentum = self.swim(s, segments, segments, stepper, ops)
        return ShellState(pose, momentum, u_cmd, s.target, s.t + self.dt, s.full, s.momentum0)

    def command(self, a):
        """The commanded mass position u* of action a."""
        return a * self.u_max

    def shape(self, s):
        return s.u

    def start_shape(self, values):
        return values["u"]

    def shape_info(self, s, ops=SCALAR):
        return {"u": ops.vector(s.u)}


@functools.cache
def shell_rule(system, u_max, dt, atol):
    """The reduced model's Lie-group rule (pieces, points; `connenv.core.lie.fixed_rule`), judged on the straight
    motions in one step between any two of the box's corners, edge midpoints and centre (corner to corner the worst)."""
    grid = [np.array([i * u_max[0], j * u_max[1]]) for i in (-1, 0, 1) for j in (-1, 0, 1)]
    segments = [(a, (b - a) / dt, dt) for a in grid for b in grid if np.any(a != b)]
    return fixed_rule(system, segments, atol)


SPECS = (
    Spec(
        "connenv/KozlovShell-v0", KozlovShellEnv, max_episode_steps=300, dt_max=DT_MAX,
        physics="kozlov-shell.md", **SWIMMER, fast_start={"state": {"momentum": (27.0, 20.0, 5.0)}},
        golden=(
            ("shell", {"max_episode_steps": 60, "success_radius": 0.3}, None),
            (
                "shell_dop853",
                {"max_episode_steps": 60, "success_radius": 0.3, "integrator": "dop853", "rtol": 1e-8, "atol": 1e-10},
                None,
            ),
            ("shell_full", {"max_episode_steps": 60}, {"state": {"momentum": (0.3, -0.2, 0.1)}}),
        ),
        bench="shell",
        jax=({},),
    ),
)
