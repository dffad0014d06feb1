"""RollingCoinSurface-v0: steer a coin that gravity rolls over a surface, to a target downhill."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR, namespace
from connenv.core.backend import vector as entries_vector
from connenv.core.integrators import make_stepper
from connenv.core.params import Args, Bound, given, integrator, interval, options, step
from connenv.core.segments import check_drift, run_segments
from connenv.core.state import Fields, Options, angle, number, vector
from connenv.core.validation import MAGNITUDE_BOUND
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.rendering.rolling_coin_surface import CoinSurfaceRenderer
from connenv.systems.rolling_coin_surface import RollingCoinPlane, RollingCoinSurface
from connenv.systems.surfaces import LENGTH_MIN, check_surface, make_surface

DT_MAX = 0.5  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
TIME_COST = 0.01  # reward paid per step until the episode ends
SPEED_BOUND = 3.0  # |observed speed| / v* is clipped here, and bounds the speed given at reset


def roll_rate_bound(env, values):
    """|φ̇| given at reset, rad/s: |R φ̇| ≤ SPEED_BOUND v*."""
    return SPEED_BOUND * env.speed_scale / env.system.radius
ENERGY_ERROR_BOUND = 1e-3  # |E − E(0)| / (m g Δz_arena) past which a stepper has diverged: StepperError
TARGET_ANGLES = 33  # directions sampled in the target's cone when the construction checks that it lies downhill
GENERAL_INTEGRATOR = ("rk4", {"substeps": 8})  # the default off the plane (bench: precision, stability)
SCALE_MIN = 1e-6  # the least mass (kg) and g (m/s²)
START = {"bowl": (0.0, -4.0)}  # the start on a built-in surface where the origin is not it


@dataclass
class CoinSurfaceState(State):
    """y = (x, y, φ, φ̇); the heading θ; the target (x, y); t; E and E₀ (at reset); where the last step started (x, y)
    and its chord's closest approach to the target, m."""

    components: ClassVar[dict] = {"y": ("x", "y", "phi", "phi_dot"), "target": ("target_x", "target_y"),
                                  "previous": ("previous_x", "previous_y")}
    phase: ClassVar[tuple] = ("phi", "phi_dot", "theta")

    y: np.ndarray
    theta: float
    target: np.ndarray
    t: float
    energy: float
    energy0: float
    previous: np.ndarray
    miss: float


class RollingCoinSurfaceEnv(TaskEnv):
    r"""
    ## Description

    A vertical coin of radius R and mass m rolls without slipping over a surface of height z(x, y) under gravity g. The
    controller steers its heading θ (from the y-axis), an active constraint; gravity rolls it where it points,
    ẋ = R sin θ φ̇, ẏ = R cos θ φ̇ (φ the rolling angle), sped by the slope along it (docs/physics/RollingCoinSurface.md).
    Steering does no work: E = ¾ m R² φ̇² + m g z is conserved, and a coin at rest reaches exactly the points below it.
    At a held heading it rolls straight; by default a plane sloping down along +y has a hill in the way.

    ## Action Space

    `Box(-1, 1, (1,), float32)`: the steering rate θ̇ = a · max_steer_rate, held over the step.

    ## Observation Space

    `Box(9,) float32`, each entry clipped to its bounds (x and y reach theirs only off the arena, which ends the
    episode); D = `target_distance`, L the arena's half-width, G its steepest slope and v* = √(4 g Δz/3) the speed
    after a drop of Δz = z_max − z_min over |x|, |y| ≤ L:

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0 | x / L | -1 | 1 |
    | 1 | y / L | -1 | 1 |
    | 2 | (x* − x) / D, to the target | -2L/D | 2L/D |
    | 3 | (y* − y) / D | -2L/D | 2L/D |
    | 4 | sin θ | -1 | 1 |
    | 5 | cos θ | -1 | 1 |
    | 6 | rolling speed R φ̇ / v* (positive along the heading) | -3 | 3 |
    | 7 | z_x / G, the slope at the coin | -1 | 1 |
    | 8 | z_y / G | -1 | 1 |

    ## Rewards

    `d − d′ − 0.01`, d and d′ the distance (m) from the coin to the target before and after the step.

    ## Starting State

    At rest, φ = 0, at the origin ((0, −4) on the bowl), θ uniform in [−π, π). The target: `target_distance` from the
    start, in a direction uniform within ±`target_angle` of the steepest descent (all checked at construction to be
    reachable: in the arena, below the start); by default 4 m downhill, up to 1 m aside.
    `reset(options={"state": {...}, "target": (x, y)})` sets any of these exactly; a target above the coin's energy
    cannot be reached:

    ## Episode End

    Terminated on success (`info["is_success"]`), the step's chord passing within `tolerance` of the target (the track
    stays within v dt² max_steer_rate/8 of it, 2.5 mm at 4 m/s by default), or, without success, when the coin leaves
    the arena, |x| or |y| > L. Truncated after 200 steps (10 s at the default dt) by the registration's time limit.

    ## Arguments

    `surface_params`: bowl: radius=5.0 in [1e-3, 1e3] (z = (x² + y²)/(2 radius)); hill: height=1.0 in [0, 1e3],
    width=0.6 in [1e-3, 1e3], center=(0, 2); a sympy surface: its symbols besides x and y, each in [−1e3, 1e3].

    On a plane the default step is exact (closed form at constant θ̇). Fixed steps fail on surfaces curved enough for the
    dt (where: `python -m connenv.bench stability --env coin_surface`, on a plane `--env coin_plane`); there take
    `integrator="dop853"`. Semi-implicit Euler takes q = (x, y, φ) and φ̇ for the momentum (3/2) m R² φ̇. Diverged:
    |E − E₀| > 1e-3 m g Δz. Every `info` has `"state"` (the Starting State's keys and `t`), `"energy"` (E, J, z = 0 the
    reference height), `"distance"` (d′), `"miss"` (the chord's closest approach), `"left_arena"` and `"is_success"`.
    """

    renderer = CoinSurfaceRenderer

    ARGS = Args(
        given("surface", "hill", '"plane", "bowl", "hill", or a sympy expression in x and y (or its text)'),
        given("slope", None, "(sx, sy), each in [−10, 10]: the plane's and hill's tilt, z = sx x + sy y (+ hill)",
              "None: (0, −0.25)"),
        given("surface_params", None, "per surface (below)"),
        interval("radius", 0.5, "m", LENGTH_MIN, MAGNITUDE_BOUND),
        interval("mass", 1.0, "kg", SCALE_MIN, MAGNITUDE_BOUND),
        interval("g", 9.81, "m/s²", SCALE_MIN, MAGNITUDE_BOUND),
        interval("max_steer_rate", 2.0, "rad/s", 0.0, MAGNITUDE_BOUND, open_low=True),
        step(0.05, DT_MAX),
        interval("tolerance", 0.1, "m", 0.0, MAGNITUDE_BOUND, open_low=True, physical=False),
        interval("target_distance", 4.0, "m", 0.0, MAGNITUDE_BOUND, open_low=True, physical=False),
        interval("target_angle", 0.25, "rad", 0.0, math.pi / 2, physical=False),
        interval("arena", 6.0, "m", 0.0, 1e3, "the half-width L of the square arena", open_low=True, physical=False),
        integrator(None, "exact", "euler", "semi_implicit_euler", "rk4", "dop853", "rk45", "lsoda", "radau",
                   default_text='"exact" on a plane, else "rk4"', about='"exact" on a plane only'),
        options("8 substeps (rk4)"),
    )

    STATE = Fields(
        number("x", "m", "in the arena", bound="arena"),
        number("y", "m", bound="arena"),
        angle("theta", "the heading"),
        angle("phi", "the roll angle"),
        number("phi_dot", "rad/s", "|R φ̇| ≤ 3 v*", bound=Bound(roll_rate_bound, "3 v*/R")),
    )
    OPTIONS = Options(vector("target", 2, "m", "(x, y), in the arena", bound="arena"))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.max_steer_rate, self.tolerance, self.target_distance = a.max_steer_rate, a.tolerance, a.target_distance
        self.target_angle, self.arena, surface, integrator = a.target_angle, a.arena, a.surface, a.integrator
        self.surface = make_surface(surface, a.slope, a.surface_params)
        on_plane = self.surface.gradient_is_constant()
        self.system = (RollingCoinPlane if on_plane else RollingCoinSurface)(self.surface, radius=a.radius, mass=a.mass,
                                                                              g=a.g)  # fmt: skip
        if integrator is None:
            integrator, defaults = ("exact", {}) if on_plane else GENERAL_INTEGRATOR
            stepper_options = {**defaults, **stepper_options}
        if integrator == "exact" and not on_plane:
            raise ValueError(f"integrator='exact' is the closed-form step on a plane; surface={surface!r} is not one")
        self.stepper = make_stepper(integrator, self.system, **stepper_options)

        z_min, z_max, self.slope_bound = check_surface(self.surface, self.arena)
        self.height_range = max(z_max - z_min, 1e-9)
        self.speed_scale = namespace(self.system.g).sqrt(4.0 * self.system.g * self.height_range / 3.0)
        self.start_point = self._start_point(surface)
        self.downhill = self._downhill()
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        reach = 2.0 * self.arena / self.target_distance
        high = np.array([1.0, 1.0, reach, reach, 1.0, 1.0, SPEED_BOUND, 1.0, 1.0], np.float32)
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        self.state = self.at(np.array([*self.start_point, 0.0, 0.0]), 0.0, np.zeros(2), 0.0, None, None)

    def _start_point(self, surface):
        start = START.get(surface, (0.0, 0.0)) if isinstance(surface, str) else (0.0, 0.0)
        if max(abs(start[0]), abs(start[1])) > self.arena:
            raise ValueError(f"arena={self.arena} does not hold the start {start}")
        return start

    def _downhill(self):
        """The heading of steepest descent at the start (rad from the y-axis), once every target the reset may draw is
        checked to lie in the arena and below the start."""
        x0, y0 = self.start_point
        z0, z_x, z_y = self.surface.height(x0, y0)
        if math.hypot(z_x, z_y) == 0.0:
            raise ValueError(f"the surface is flat at the start {self.start_point}: no direction is downhill")
        heading = math.atan2(-z_x, -z_y)
        angles = heading + np.linspace(-self.target_angle, self.target_angle, TARGET_ANGLES)
        xs, ys = x0 + self.target_distance * np.sin(angles), y0 + self.target_distance * np.cos(angles)
        outside = np.maximum(np.abs(xs), np.abs(ys)) > self.arena
        below = self.surface.height(xs, ys)[0] < z0
        if outside.any() or not below.all():
            i = int(np.flatnonzero(outside | ~below)[0])
            where = "outside the arena" if outside[i] else "not below the start"
            raise ValueError(
                f"target_distance={self.target_distance}, target_angle={self.target_angle}: the target "
                f"({xs[i]:.6g}, {ys[i]:.6g}) is {where} (start {self.start_point}, arena ±{self.arena} m)"
            )
        return heading

    def at(self, y, theta, target, t, energy0, previous, ops=SCALAR):
        """The state at y = (x, y, φ, φ̇) and θ, with E (E₀ := E where energy0 is None, at reset) and the closest
        approach of the chord from `previous` (None at reset: the coin's position)."""
        energy = ops.real(self.system.energy(y))
        previous = y[..., :2].copy() if previous is None else previous
        state = CoinSurfaceState(y, theta, target, t, energy, energy if energy0 is None else energy0, previous, 0.0)
        return state.replace(miss=self.closest_approach(state, ops))

    def start(self, options, ops=SCALAR):
        """At rest at the start point, θ and the target's direction drawn from np_random; traced (``connenv.jax``, ops
        its namespace), the same draws from its key."""
        theta = self.np_random.uniform(-math.pi, math.pi)
        angle = self.downhill + self.np_random.uniform(-self.target_angle, self.target_angle)
        x0, y0 = self.start_point
        target = entries_vector(x0 + self.target_distance * ops.sin(angle), y0 + self.target_distance * ops.cos(angle))
        values = self.reset_values(options, {"x": x0, "y": y0, "theta": theta, "target": target})
        y = entries_vector(values["x"], values["y"], values["phi"], values["phi_dot"])
        return self.at(y, values["theta"], values["target"], 0.0, None, None, ops=ops)

    def advance(self, s, rate, stepper, ops=SCALAR):
        """The state after a step at θ̇ = rate (one, or one per row with ops=BATCH and a batched stepper)."""
        theta, theta_dot = ops.column(s.theta), ops.column(rate)
        if ops is SCALAR:
            theta, theta_dot = np.array([theta]), np.array([theta_dot])
        y = run_segments(stepper, self.system, s.y, [(theta, theta_dot, self.dt)])[0]
        after = self.at(y, s.theta + rate * self.dt, s.target, s.t + self.dt, s.energy0, s.y[..., :2].copy(),
                        ops=ops)
        bound = ENERGY_ERROR_BOUND * self.system.mass * self.system.g * self.height_range
        check_drift(stepper, "energy error", after.energy - after.energy0, bound, " J")
        return after

    def closest_approach(self, s, ops=SCALAR):
        """Distance from the target to the chord from s.previous to the coin, m."""
        px, py = s.previous.T[0], s.previous.T[1]
        cx, cy = s.y.T[0] - px, s.y.T[1] - py
        tx, ty = s.target.T[0] - px, s.target.T[1] - py
        along = ops.clip((tx * cx + ty * cy) / ops.maximum(cx * cx + cy * cy, 1e-300), 0.0, 1.0)
        return ops.hypot(tx - along * cx, ty - along * cy)

    def command(self, a):
        return self.max_steer_rate * a.T[0]

    def distance(self, s, ops=SCALAR):
        return ops.hypot(s.target.T[0] - s.y.T[0], s.target.T[1] - s.y.T[1])

    def left_arena(self, s, ops=SCALAR):
        return ops.maximum(abs(s.y.T[0]), abs(s.y.T[1])) > self.arena

    def reward(self, before, after, info, ops=SCALAR):
        return self.distance(before, ops) - info["distance"] - TIME_COST

    def terminated(self, state, info, ops=SCALAR):
        return info["is_success"] | info["left_arena"]

    def observe(self, s, ops=SCALAR):
        x, y, v = s.y.T[0], s.y.T[1], self.system.radius * s.y.T[3]
        _, z_x, z_y = self.surface.height(x, y)
        reach, scale = 2.0 * self.arena / self.target_distance, 1.0 / max(self.slope_bound, 1e-300)
        return ops.pack([
            ops.clip(x / self.arena, -1.0, 1.0),
            ops.clip(y / self.arena, -1.0, 1.0),
            ops.clip((s.target.T[0] - x) / self.target_distance, -reach, reach),
            ops.clip((s.target.T[1] - y) / self.target_distance, -reach, reach),
            ops.sin(s.theta),
            ops.cos(s.theta),
            ops.clip(v / self.speed_scale, -SPEED_BOUND, SPEED_BOUND),
            ops.clip(z_x * scale, -1.0, 1.0),
            ops.clip(z_y * scale, -1.0, 1.0),
        ])

    def describe(self, s, ops=SCALAR):
        state = {"x": s.y.T[0], "y": s.y.T[1], "theta": s.theta, "phi": s.y.T[2], "phi_dot": s.y.T[3],
                 "t": s.t}
        return {
            "state": {k: ops.real(v) for k, v in state.items()}, "energy": s.energy, "distance": self.distance(s, ops),
            "miss": s.miss, "left_arena": ops.flag(self.left_arena(s, ops)),
            "is_success": ops.flag(s.miss <= self.tolerance),
        }


SPECS = (
    Spec(
        "connenv/RollingCoinSurface-v0", RollingCoinSurfaceEnv, max_episode_steps=200, dt_max=DT_MAX,
        physics="RollingCoinSurface.md", measure=Measure("time to target", "s", "time_to_success"),
        controllers=("steer",), variants=({}, {"surface": "plane"}),
        golden=(
            ("coin_surface", {"max_episode_steps": 40, "tolerance": 1.0}, None),
            ("coin_plane", {"max_episode_steps": 40, "tolerance": 1.0, "surface": "plane"}, None),
        ),
        bench="coin_surface",
        jax=({}, {"surface": "x**2/20 - y/4 + cos(x)*exp(-(y - 2)**2)/2"}, {"surface": "plane"}),
    ),
)
