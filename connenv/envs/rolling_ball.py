"""RollingBall-v0, RollingBallPose-v0, RollingBallGoal-v0: reorient a ball by rolling it without turning."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces
from scipy.spatial.transform import Rotation

from connenv.core.backend import SCALAR, concat, namespace, traced, vector
from connenv.core.integrators import make_stepper
from connenv.core.params import Args, Bound, integrator, options, scale, step
from connenv.core.segments import run_segments
from connenv.core.state import Fields, Options, number, rotation
from connenv.core.validation import finite_action, ndim
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from connenv.envs.vector import TaskVectorEnv
from connenv.rendering.rolling_ball import RollingBallRenderer
from connenv.systems.rolling_ball import (
    RollingBall,
    attitude_error,
    check_so3,
    from_six_d,
    quaternion_matrix,
    rotation_angle,
    six_d,
    six_d_angle,
)

DT_MAX = 100.0  # s: the longest dt, within which the default stepper keeps up from every allowed reset state
TIME_COST = 0.01  # reward paid per step until success
POSITION_BOUND = 3.0  # |observed position| / (4πρ) is clipped here


def position_bound(env, values):
    """|x|, |y| given at reset, m: the position RollingBallPose-v0 observes."""
    return POSITION_BOUND * 4 * math.pi * env.system.radius


@dataclass
class BallState(State):
    """R (body → space), the target R*, the centre (x, y); P = R R*ᵀ and its angle e (rad), read by observation and
    reward; the time t; the path length; the distance, the optimal arc's length from the start (NaN if unmeasured)."""

    R: np.ndarray
    R_target: np.ndarray
    position: np.ndarray
    error: np.ndarray
    angle_error: float
    t: float
    path_length: float
    distance: float

    unmeasured: ClassVar[tuple[str, ...]] = ("distance",)


@dataclass
class GoalBallState(BallState):
    """BallState with the goals R (achieved), R* (desired) in float32 6-D form and their angle, computed once for the
    reward and the success."""

    achieved_goal: np.ndarray
    desired_goal: np.ndarray
    goal_error: float


class RollingBallEnv(TaskEnv):
    r"""
    ## Description

    A ball of radius ρ rolls on a plane without slipping and without turning (spinning about the vertical); the
    controller assigns the velocity v of its centre: with R the attitude (body → space), ω = e_z × v / ρ, Ṙ = ω̂ R,
    (ẋ, ẏ) = v. Rolling straight tilts the ball about a horizontal axis; a loop turns it about the vertical by the
    spherical area it encloses (holonomy; Lioe 2004, Lawton slides 7–10). Goal: a target attitude R*, position free,
    reached shortest by a circular arc (the sub-Riemannian geodesic) of length `info["distance"]`.

    ## Action Space

    `Box(-1, 1, (2,), float32)`: v = (vx, vy) = v_max · a, |a| > 1 projected radially onto the unit disk, not clipped.

    ## Observation Space

    `Box(-1, 1, (6,), float32)`: P = R R*ᵀ (I at the target) in continuous 6-D form, its first two columns (Zhou et al.
    2019). P rolls as the ball does, Ṗ = ω̂ P: a Markov state, unlike the body-frame R*ᵀR (its rate depends on R*).

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–2 | first column of P: where the body's x axis is, in target coordinates rotated to space | -1 | 1 |
    | 3–5 | second column of P | -1 | 1 |

    ## Rewards

    With e the geodesic angle between R and R* (rad), e before the step and e′ after it:

        reward = e − e′ − 0.01

    A step changes e by ≤ v_max·dt/ρ (0.1 rad by default), the constant pays for time; summed: e₀ − e_T − 0.01·steps.

    ## Starting State

    R = I at the origin, t = 0, and R* uniform on SO(3) (scipy's `Rotation.random` on np_random).
    `reset(options={"state": {...}, "target": R*})` sets any of these exactly:

    ## Episode End

    Terminated when e ≤ `tolerance` (`info["is_success"]`). Truncated after 200 steps by the registration's time limit:
    the holonomy planner, the slower reference controller, needs at most ρ(π + π + π)/(v_max dt) + 4 = 99 steps.

    ## Arguments

    The default step at constant v is exact, R ← exp(dt ω̂) R (Rodrigues), for any radius and dt; semi-implicit Euler is
    refused (R is no (q, p) pair). Diverged: R more than 1e-6 off SO(3) (‖RᵀR − I‖). Every `info` has `"state"` (`x`,
    `y`, `R` (3×3), `t`), `"angle_error"` (e, rad), `"path_length"` (m since reset), `"distance"` (m), `"path_ratio"`
    (path length / distance, 1 if the start is the target) and `"is_success"`.
    """

    renderer = RollingBallRenderer

    metadata = {**TaskEnv.metadata, "measures": ("angle_error", "path_ratio")}
    measures_distance = True  # whether start solves for the optimal arc (info "distance"); the vector env may not

    ARGS = Args(
        scale("radius", 1.0, "m"),
        scale("v_max", 1.0, "m/s"),
        step(0.1, DT_MAX),
        scale("tolerance", 0.05, "rad", high=math.pi, open_high=True, physical=False),
        integrator("exact", "exact", "euler", "rk4", "dop853", "rk45", "lsoda", "radau",
                   about="exact: Rodrigues'; the others step Ṙ = ω̂R"),
        options(),
    )

    STATE = Fields(
        number("x", "m", "RollingBallPose-v0's observed range", bound=Bound(position_bound, "12πρ")),
        number("y", "m", bound=Bound(position_bound, "12πρ")),
        rotation("R"),
    )
    OPTIONS = Options(rotation("target", "R*"))

    def __init__(self, render_mode: str | None = None, **kwargs):
        a, stepper_options = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.v_max, self.tolerance, self.system = a.v_max, a.tolerance, RollingBall(a.radius)
        self.stepper = make_stepper(a.integrator, self.system, **stepper_options)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = self._observation_space()
        self.state = self.at(np.eye(3), np.eye(3), np.zeros(2), 0.0, 0.0, math.nan)

    def check_action(self, action):
        """The action as a finite float array of the space's shape (else ValueError), unclipped: command projects it."""
        return finite_action(action, self.action_space)

    def _observation_space(self):
        return spaces.Box(-1.0, 1.0, (6,), np.float32)

    def at(self, R, R_target, position, t, path_length, distance, ops=SCALAR):
        """The state at attitude R and centre position, with its error P = R R*ᵀ and angle e."""
        error = attitude_error(R, R_target)
        return BallState(R, R_target, position, error, ops.real(rotation_angle(error)), t, path_length, distance)

    def start(self, options, ops=SCALAR):
        """R = I at the origin, R* uniform: scipy's Rotation.random on np_random; traced (``connenv.jax``, ops its
        namespace), a normal quaternion from its key, the same distribution (scipy's own draw), and no distance
        measured (NaN: the optimal arc's root search does not trace)."""
        if traced(ops):
            target = quaternion_matrix(self.np_random.normal(size=4))
        else:
            target = Rotation.random(rng=self.np_random).as_matrix()
        values = self.reset_values(options, {"target": target})
        s = self.at(values["R"], values["target"], vector(values["x"], values["y"]), 0.0, 0.0, math.nan, ops)
        if not self.measures_distance or traced(ops):
            return s
        return s.replace(distance=self.system.optimal_arc(Rotation.from_matrix(s.error)).length)

    def advance(self, s, v, stepper, ops=SCALAR):
        """The state after a step at velocity v (one, or one per row with ops=BATCH and a batched stepper)."""
        y = s.R.reshape(*s.R.shape[:-2], 9)
        R = run_segments(stepper, self.system, y, [(s.position, v, self.dt)])[0].reshape(s.R.shape)
        check_so3(stepper, R)
        path_length = s.path_length + ops.hypot(v[..., 0], v[..., 1]) * self.dt
        return self.at(R, s.R_target, s.position + v * self.dt, s.t + self.dt, path_length, s.distance, ops)

    def command(self, a):
        """v = v_max a, a (2,) or (N, 2) projected radially onto the unit disk, scaled down first if |a| overflows."""
        if a.ndim == 1:
            length = math.hypot(a[0], a[1])
            if length == math.inf:
                a = a / np.max(np.abs(a))
                length = math.hypot(a[0], a[1])
            return self.v_max * a / max(1.0, length)
        ops = namespace(a)
        with np.errstate(over="ignore"):
            length = ops.hypot(a[:, 0], a[:, 1])
        huge = ops.real_part(length) == math.inf
        if ops.any(huge):  # every row on JAX's (connenv.jax), the others left by where
            largest = ops.maximum(ops.abs(ops.real_part(a[:, 0])), ops.abs(ops.real_part(a[:, 1])))  # np.max's
            a = ops.where(huge[:, None], a / ops.where(huge, largest, 1.0)[:, None], a)
            length = ops.hypot(a[:, 0], a[:, 1])
        return self.v_max * a / ops.maximum(1.0, length)[:, None]

    def observe(self, s, ops=SCALAR):
        return six_d(s.error).astype(np.float32)

    def progress(self, s, ops=SCALAR):
        """What the reward pays the decrease of: the angle error (rad)."""
        return s.angle_error

    def reward(self, before, after, info, ops=SCALAR):
        return self.progress(before, ops) - self.progress(after, ops) - TIME_COST

    def success(self, s, ops=SCALAR):
        return s.angle_error <= self.tolerance

    def describe(self, s, ops=SCALAR):
        info = {
            "state": {"x": s.position[..., 0], "y": s.position[..., 1], "R": s.R.copy(), "t": s.t},
            "angle_error": s.angle_error, "path_length": s.path_length,
        }
        if self.measures_distance:  # else not known: left out rather than NaN
            ratio = ops.where(s.distance > 0, s.path_length / ops.maximum(s.distance, 1e-300), 1.0)
            info |= {"distance": s.distance, "path_ratio": ratio}
        return {**info, "is_success": ops.flag(self.success(s, ops))}


class RollingBallPoseEnv(RollingBallEnv):
    r"""
    ## Description

    RollingBall-v0's ball, to reach R* *and* bring its centre back to the origin: five degrees of freedom from two
    controls, steered together, since a closed path of the centre turns the ball by holonomy.

    ## Observation Space

    `Box(8,) float32`: P as in RollingBall-v0, then the position / 4πρ, a bound of the holonomy planner's excursion.

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–5 | P, first two columns | -1 | 1 |
    | 6 | x / (4πρ), clipped | -3 | 3 |
    | 7 | y / (4πρ), clipped | -3 | 3 |

    ## Rewards

    With e the angle error (rad) and d = |(x, y)| the distance to the origin, before (e, d) and after (e′, d′):

        reward = e − e′ + (d − d′)/ρ − 0.01

    ## Episode End

    Terminated when e ≤ `tolerance` and d ≤ `position_tolerance`. Truncated after 300 steps: the holonomy planner needs
    at most ρ(2π + 2π)/(v_max dt) + 7 = 133 steps.

    ## Arguments

    Everything else, the starting state, the action and `info` (plus `"position_error"`, d), is RollingBall-v0's.

    ## Open Challenge

    No agent of the reference results learns this task. The reward is a trap: a roll of length ℓ turns the ball at most
    ℓ/ρ and moves it ℓ away, so at the origin no action pays more than standing still, and the target is reached only
    through a loop whose first half loses reward; the holonomy planner keeps a plan, which no memoryless network is
    known to reproduce. Clones, curves: Reference results below; the planner, the one-step greedy policy, the attempts:
    the reference-results guide ("Why it did not learn, and what did", "What changed, and what is still open"). At the
    field's budget (JAX PPO, 10⁸ steps per seed), with a recurrent policy, and with exact gradients (SHAC): the open
    challenges' page of the baselines (docs/baselines/challenges.md).
    """

    metadata = {**RollingBallEnv.metadata, "measures": ("angle_error", "position_error", "path_length")}

    ARGS = RollingBallEnv.ARGS + (scale("position_tolerance", 0.05, "m", physical=False),)

    def __init__(self, render_mode: str | None = None, **kwargs):
        super().__init__(render_mode, **kwargs)
        self.position_tolerance = self.args.position_tolerance

    def _observation_space(self):
        high = np.array([1.0] * 6 + [POSITION_BOUND] * 2, np.float32)
        return spaces.Box(-high, high, dtype=np.float32)

    def observe(self, s, ops=SCALAR):
        position = s.position / (4 * math.pi * self.system.radius)
        if traced(ops):
            scaled = ops.clip(position, -POSITION_BOUND, POSITION_BOUND)
        else:
            scaled = np.minimum(np.maximum(position, -POSITION_BOUND), POSITION_BOUND)  # np.clip's wrapper costs more
        return concat([six_d(s.error), scaled], axis=-1).astype(np.float32)

    def progress(self, s, ops=SCALAR):
        return s.angle_error + ops.hypot(s.position[..., 0], s.position[..., 1]) / self.system.radius

    def success(self, s, ops=SCALAR):
        close = ops.hypot(s.position[..., 0], s.position[..., 1]) <= self.position_tolerance
        return super().success(s, ops) & close

    def describe(self, s, ops=SCALAR):
        return {**super().describe(s, ops), "position_error": ops.hypot(s.position[..., 0], s.position[..., 1])}


class RollingBallGoalEnv(RollingBallEnv):
    r"""
    ## Description

    RollingBall-v0's task as a goal-conditioned env for hindsight experience replay (SB3's `HerReplayBuffer`), after
    gymnasium-robotics' GoalEnv: dict observations and a vectorized `compute_reward`.

    ## Observation Space

    `Dict` of `Box(-1, 1, (6,), float32)` rotations in 6-D form; `observation` is goal-free: relabelling keeps it valid.

    | Key | Observation |
    |-----|-------------|
    | observation | the attitude R |
    | achieved_goal | the attitude R |
    | desired_goal | the target R* |

    ## Rewards

    Sparse: `compute_reward(achieved_goal, desired_goal, info)` = −1 while the geodesic angle between the two exceeds
    `tolerance`, else 0; it takes batches (leading axes) and the env's reward is its value. Everything else is
    RollingBall-v0's; `compute_terminated` is success, `compute_truncated` False (the time limit truncates).

    `compute_reward` is this env's, not its `gym.make` wrappers' (Gymnasium 1.x wrappers do not forward unknown
    attributes): HER reaches it through SB3's `env_method`, which unwraps, but SB3's `check_env(gym.make(...))` raises
    AttributeError on it, so check `check_env(env.unwrapped)`.
    """

    def _observation_space(self):
        box = spaces.Box(-1.0, 1.0, (6,), np.float32)
        return spaces.Dict({"observation": box, "achieved_goal": box, "desired_goal": box})

    def at(self, R, R_target, position, t, path_length, distance, ops=SCALAR):
        """RollingBall-v0's state, with the achieved and the desired goal."""
        state = super().at(R, R_target, position, t, path_length, distance, ops)
        achieved, desired = single_precision(six_d(R)), single_precision(six_d(R_target))
        error = ops.real(self.goal_angle(achieved, desired))
        return GoalBallState(**vars(state), achieved_goal=achieved, desired_goal=desired, goal_error=error)

    def observe(self, s, ops=SCALAR):
        """The goals as float32 copies (numpy's are float32 already; JAX's hold float32's values in float64)."""
        achieved, desired = s.achieved_goal, s.desired_goal
        return {"observation": achieved.astype(np.float32), "achieved_goal": achieved.astype(np.float32),
                "desired_goal": desired.astype(np.float32)}

    def reward(self, before, after, info, ops=SCALAR):
        """compute_reward(achieved, desired) of the state after, from its goal angle."""
        return -ops.real(after.goal_error > self.tolerance)

    def success(self, s, ops=SCALAR):
        """compute_terminated(achieved, desired) of the state, from its goal angle."""
        return s.goal_error <= self.tolerance

    def goal_angle(self, achieved_goal, desired_goal):
        """Geodesic angle between attitudes in 6-D form, over leading batch axes."""
        one = ndim(achieved_goal) == 1 and ndim(desired_goal) == 1
        if one and not (traced(namespace(achieved_goal)) or traced(namespace(desired_goal))):  # one pair: Python floats (JAX's reset: its rows' code)
            return six_d_angle(achieved_goal, desired_goal)
        return rotation_angle(attitude_error(from_six_d(achieved_goal), from_six_d(desired_goal)))

    def compute_reward(self, achieved_goal, desired_goal, info):
        return -(np.asarray(self.goal_angle(achieved_goal, desired_goal)) > self.tolerance).astype(np.float32)

    def compute_terminated(self, achieved_goal, desired_goal, info):
        return np.asarray(self.goal_angle(achieved_goal, desired_goal)) <= self.tolerance

    def compute_truncated(self, achieved_goal, desired_goal, info):
        return np.zeros(np.shape(self.goal_angle(achieved_goal, desired_goal)), bool)


def single_precision(x):
    """x in float32, as the goals are observed. On the complex rows of a Jacobian the real part is rounded and the
    imaginary part kept in float64: the rounding's derivative is 1, and complex64 would flush the complex step's
    i·1e-150 to 0. On JAX's rows (``connenv.jax``) the same convention: float32's values held in float64, the
    rounding's derivative 1 (JAX's astype(float32) would round the forward-mode tangent to float32 too)."""
    if np.iscomplexobj(x):
        return x.real.astype(np.float32) + 1j * x.imag
    if type(x) is not np.ndarray and traced(namespace(x)):
        return namespace(x).single_precision(x)
    return x.astype(np.float32)


class RollingBallVectorEnv(TaskVectorEnv):
    """RollingBall-v0 over a batch (``gym.make_vec("connenv/RollingBall-v0", num_envs=N)``, ``connenv.envs.vector``),
    base of the Pose and Goal vector envs. Takes make kwargs and ``measure_distance``: each start's optimal arc (infos
    ``"distance"``, ``"path_ratio"``, else absent) costs a root search per reset, dominating the batch's step."""

    single_env = RollingBallEnv

    def __init__(self, num_envs: int = 1, max_episode_steps: int | None = None, measure_distance=False, **kwargs):
        super().__init__(num_envs, max_episode_steps, **kwargs)
        self.env.measures_distance = bool(measure_distance)


BALL = {"dt_max": DT_MAX, "physics": "rolling-ball.md", "play": "mouse"}
SPECS = (
    Spec(
        "connenv/RollingBall-v0", RollingBallEnv, vector_base=RollingBallVectorEnv, max_episode_steps=200, **BALL,
        measure=Measure("path / optimal arc", "", "path_ratio"), controllers=("arc", "holonomy"),
        golden=(("ball", {"max_episode_steps": 50, "tolerance": 1.5}, None),), bench="ball",
        single_target=1.5, vector_target=0.1, jax=({},),
    ),
    Spec(
        "connenv/RollingBallPose-v0", RollingBallPoseEnv, vector_base=RollingBallVectorEnv,
        max_episode_steps=300, **BALL,
        measure=Measure("path length", "m", "path_length"), controllers=("holonomy",),
        golden=(("ball_pose", {"max_episode_steps": 50, "tolerance": 2.5, "position_tolerance": 0.3}, None),),
        single_target=1.5, jax=({},),
    ),
    Spec(
        "connenv/RollingBallGoal-v0", RollingBallGoalEnv, vector_base=RollingBallVectorEnv,
        max_episode_steps=200, **BALL,
        measure=Measure("path / optimal arc", "", "path_ratio"), controllers=("arc", "holonomy"),
        golden=(("ball_goal", {"max_episode_steps": 50, "tolerance": 1.5}, None),),
        single_target=3.0, jax=({},),
    ),
)
