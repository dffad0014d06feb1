"""RollingBall-v0, RollingBallPose-v0, RollingBallGoal-v0: reorient a ball by rolling it without turning."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces
from scipy.spatial.transform import Rotation

from connenv.core.steppers import StepperError, make_stepper
from connenv.core.validation import check_keys, check_number, check_stepper_options, finite_action
from connenv.envs.base import RenderedEnv
from connenv.systems.rolling_ball import RollingBall, attitude_error, from_six_d, rotation_angle, six_d

TIME_COST = 0.01  # reward paid per step until success
ORTHONORMAL_TOL = 1e-9  # ‖RᵀR − I‖ and |det R − 1| allowed in a reset state or target
DRIFT_LIMIT = 1e-6  # ‖RᵀR − I‖ past which a stepper has left SO(3): StepperError
POSITION_BOUND = 3.0  # |observed position| / (4πρ) is clipped here


def check_rotation(name: str, value) -> np.ndarray:
    """value as a 3×3 rotation matrix (float64), or ValueError: never re-orthonormalized."""
    R = np.asarray(value, dtype=np.float64) if np.size(value) == 9 else None
    if R is None or R.shape != (3, 3):
        raise ValueError(f"{name} has shape {np.shape(value)}; expected a 3×3 rotation matrix")
    if not np.isfinite(R).all():
        raise ValueError(f"{name}={R.tolist()} is not finite")
    drift = float(np.linalg.norm(R.T @ R - np.eye(3)))
    det = float(np.linalg.det(R))
    if drift > ORTHONORMAL_TOL or abs(det - 1.0) > ORTHONORMAL_TOL:
        raise ValueError(
            f"{name}={R.tolist()} is not a rotation: ‖RᵀR − I‖ = {drift:.3g}, det R = {det:.12g}; "
            f"both must be within {ORTHONORMAL_TOL} of 0 and 1"
        )
    return R


class RollingBallEnv(RenderedEnv):
    r"""
    ## Description

    A ball of radius ρ rolls on a plane without slipping and without turning (spinning about the vertical); the
    controller assigns the velocity v of its centre. A kinematic model is all this scene needs, since the
    velocities are the controls: with R the attitude (body → space),

        ω = e_z × v / ρ,    Ṙ = ω̂ R,    (ẋ, ẏ) = v,

    and a step at constant v is exact, R ← exp(Δt ω̂) R (Rodrigues). Rolling straight tilts the ball about a
    horizontal axis; turning it about the vertical takes a loop, by the spherical area the loop encloses
    (holonomy; Lioe 2004, Lawton slides 7–10). The goal is to reach a target attitude R*, position free; the
    shortest way is an arc of a circle (the sub-Riemannian geodesic), whose length `info["distance"]` gives.

    ## Action Space

    `Box(-1, 1, (2,), float32)`: v = v_max · a. An action with |a| > 1 is projected radially onto the unit disk
    (the speed is at most v_max, the direction kept); a wrong shape or a non-finite value raises ValueError.

    | Num | Action | Min | Max |
    |-----|--------|-----|-----|
    | 0 | vx / v_max | -1 | 1 |
    | 1 | vy / v_max | -1 | 1 |

    ## Observation Space

    `Box(-1, 1, (6,), float32)`: the attitude error P = R R*ᵀ in the continuous 6-D form (its first two
    columns; Zhou et al. 2019). P = I at the target. In the space frame the error rolls as the ball does,
    Ṗ = ω̂ P, so the observation is a Markov state (the body-frame error R*ᵀR is not: its rate depends on R*).

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–2 | first column of P: where the body's x axis is, in target coordinates rotated to space | -1 | 1 |
    | 3–5 | second column of P | -1 | 1 |

    ## Rewards

    With e the geodesic angle between R and R* (rad), e before the step and e′ after it:

        reward = e − e′ − 0.01

    Summed to success: e₀ − e_T − 0.01·steps. A step changes e by at most v_max·dt/ρ (0.1 rad by default);
    the constant pays for time.

    ## Starting State

    R = I at the origin, t = 0, and R* uniform on SO(3) (scipy's `Rotation.random` on np_random).
    `reset(options={"state": {"x", "y", "R"}, "target": R*})` sets any of them; R and R* must be rotation
    matrices to 1e-9 (‖RᵀR − I‖, |det R − 1|), else ValueError: they are never re-orthonormalized.

    ## Episode End

    Terminated when e ≤ `tolerance` (`info["is_success"]`). Truncated after 200 steps by the registration's time
    limit: the holonomy planner, the longer of the two reference controllers, needs at most ρ(π + π + π)/(v_max dt)
    + 4 = 99 steps.

    ## Arguments

    | kwarg | default | range |
    |---|---|---|
    | radius | 1.0 | (0, ∞) m |
    | v_max | 1.0 | (0, ∞) m/s |
    | dt | 0.1 | (0, ∞) s |
    | tolerance | 0.05 | (0, π) rad |
    | integrator | "exact" | "exact" (Rodrigues), "euler", "rk4", "dop853", "rk45", "lsoda", "radau" on Ṙ = ω̂R |
    | substeps (euler, rk4) / rtol, atol (scipy) | | see `connenv.core.steppers` |

    The default exact step is the closed form for any radius and dt: R stays on SO(3) to rounding, 1e-14 over
    200 random steps (`python -m connenv.bench precision`), and straight rolls match Ry(vt/ρ) to 1e-12.

    A stepper that diverges raises `connenv.core.StepperError` naming the stepper, dt and the parameters: a
    non-finite state, or R more than 1e-6 off SO(3) (‖RᵀR − I‖, the invariant of Ṙ = ω̂R). Semi-implicit Euler
    is refused (ValueError): the model is kinematic, R is no (q, p) pair, and the method would be explicit Euler.

    Every `info` has `"state"` (`x`, `y`, `R` (3×3), `t`), `"angle_error"` (e, rad), `"path_length"` (m rolled
    since reset), `"distance"` (the optimal arc's length from the start attitude, m), `"path_ratio"` (path
    length / distance) and `"is_success"`.
    """

    metadata = {**RenderedEnv.metadata, "measures": ("angle_error", "path_ratio")}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        radius: float = 1.0,
        v_max: float = 1.0,
        dt: float = 0.1,
        tolerance: float = 0.05,
        integrator: str = "exact",
        **stepper_options,
    ):
        super().__init__(render_mode, check_number("dt", dt, 0.0, open_low=True))
        self.v_max = check_number("v_max", v_max, 0.0, open_low=True)
        self.tolerance = check_number("tolerance", tolerance, 0.0, math.pi, open_low=True, open_high=True)
        self.system = RollingBall(check_number("radius", radius, 0.0, open_low=True))
        check_stepper_options(type(self).__name__, stepper_options, type(self))
        self.stepper = make_stepper(integrator, self.system, **stepper_options)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = self._observation_space()
        self.R, self.R_target, self.position = np.eye(3), np.eye(3), np.zeros(2)
        self._update_error()  # self.error, P = R R*ᵀ, and self.angle_error, its angle e
        self.t, self.path_length, self.distance = 0.0, 0.0, 0.0
        self.path = [self.position]

    # -- Gymnasium API -------------------------------------------------------

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = dict(options or {})
        check_keys("reset options", options, {"state", "target"})
        self.R, self.position, self.t, self.path_length = np.eye(3), np.zeros(2), 0.0, 0.0
        self.R_target = Rotation.random(rng=self.np_random).as_matrix()
        if "state" in options:
            self._set_state(options["state"])
        if "target" in options:
            self.R_target = check_rotation("target", options["target"])
        self.path = [self.position]
        self._update_error()
        self.distance = self.system.optimal_arc(Rotation.from_matrix(self.error)).length
        return self._obs(), self._info()

    def step(self, action):
        a = finite_action(action, self.action_space)
        v = self.v_max * a / max(1.0, float(np.hypot(*a)))
        before = self._progress()
        try:
            R = self.stepper(self.system, self.R.ravel(), self.position, v, self.dt).reshape(3, 3)
            drift = float(np.linalg.norm(R.T @ R - np.eye(3)))
            if not drift <= DRIFT_LIMIT:
                raise StepperError(f"{self.stepper} left SO(3): ‖RᵀR − I‖ = {drift:.3g} > {DRIFT_LIMIT}")
        except StepperError as error:
            raise self._stepper_error(error) from error
        self.R, self.position = R, self.position + v * self.dt
        self._update_error()
        self.t += self.dt
        self.path_length += float(np.hypot(*v)) * self.dt
        self.path.append(self.position)
        info = self._info()
        reward = self._reward(before, info)
        if self.render_mode == "human":
            self.render()
        return self._obs(), reward, info["is_success"], False, info

    def _make_renderer(self):
        from connenv.envs.rendering import RollingBallRenderer

        return RollingBallRenderer(self.system.radius, self.render_mode, self.metadata["render_fps"])

    def _draw(self, renderer):
        return renderer.draw(self.R, self.R_target, np.array(self.path), self.t, self.angle_error)

    # -- task ----------------------------------------------------------------

    def _observation_space(self):
        return spaces.Box(-1.0, 1.0, (6,), np.float32)

    def _obs(self):
        return six_d(self.error).astype(np.float32)

    def _progress(self):
        """What the reward pays the decrease of: the angle error (rad)."""
        return self.angle_error

    def _reward(self, before, info):
        return before - self._progress() - TIME_COST

    def _success(self):
        return self.angle_error <= self.tolerance

    # -- internals -----------------------------------------------------------

    def _set_state(self, state):
        check_keys("options['state']", state, {"x", "y", "R"})
        x = check_number("state x", state.get("x", 0.0))
        y = check_number("state y", state.get("y", 0.0))
        self.position = np.array([x, y])
        if "R" in state:
            self.R = check_rotation("state R", state["R"])

    def parameters(self):
        return {"radius": self.system.radius, "v_max": self.v_max}

    def _update_error(self):
        self.error = attitude_error(self.R, self.R_target)
        self.angle_error = float(rotation_angle(self.error))

    def _info(self):
        return {
            "state": {"x": self.position[0], "y": self.position[1], "R": self.R.copy(), "t": self.t},
            "angle_error": self.angle_error,
            "path_length": self.path_length,
            "distance": self.distance,
            "path_ratio": self.path_length / self.distance if self.distance > 0 else math.nan,
            "is_success": bool(self._success()),
        }


class RollingBallPoseEnv(RollingBallEnv):
    r"""
    ## Description

    RollingBall-v0's ball, now to reach the target attitude R* *and* return its centre to the origin. Rolling
    the centre along a closed path changes the attitude by holonomy, so position and attitude are steered
    together: five degrees of freedom from two controls.

    ## Observation Space

    `Box(8,) float32`: the attitude error P = R R*ᵀ in 6-D form, as in RollingBall-v0, then the position.

    | Num | Observation | Min | Max |
    |-----|-------------|-----|-----|
    | 0–5 | P, first two columns | -1 | 1 |
    | 6 | x / (4πρ), clipped | -3 | 3 |
    | 7 | y / (4πρ), clipped | -3 | 3 |

    4πρ bounds the holonomy planner's excursion from the origin.

    ## Rewards

    With e the angle error (rad) and d = |(x, y)| the distance to the origin, before (e, d) and after (e′, d′):

        reward = e − e′ + (d − d′)/ρ − 0.01

    ## Episode End

    Terminated when e ≤ `tolerance` and d ≤ `position_tolerance` (0.05 m). Truncated after 300 steps: the
    holonomy planner needs at most ρ(2π + 2π)/(v_max dt) + 7 = 133 steps.

    ## Arguments

    Those of RollingBall-v0, and `position_tolerance` = 0.05, in (0, ∞) m. Everything else, the starting state,
    the action and `info` (plus `"position_error"`, d), is RollingBall-v0's.
    """

    metadata = {**RollingBallEnv.metadata, "measures": ("angle_error", "position_error", "path_length")}

    def __init__(self, render_mode: str | None = None, *, position_tolerance: float = 0.05, **kwargs):
        self.position_tolerance = check_number("position_tolerance", position_tolerance, 0.0, open_low=True)
        super().__init__(render_mode, **kwargs)

    def _observation_space(self):
        high = np.array([1.0] * 6 + [POSITION_BOUND] * 2, np.float32)
        return spaces.Box(-high, high, dtype=np.float32)

    def _obs(self):
        scaled = np.clip(self.position / (4 * math.pi * self.system.radius), -POSITION_BOUND, POSITION_BOUND)
        return np.concatenate([six_d(self.error), scaled]).astype(np.float32)

    def _progress(self):
        return self.angle_error + float(np.hypot(*self.position)) / self.system.radius

    def _success(self):
        return super()._success() and float(np.hypot(*self.position)) <= self.position_tolerance

    def _info(self):
        return {**super()._info(), "position_error": float(np.hypot(*self.position))}


class RollingBallGoalEnv(RollingBallEnv):
    r"""
    ## Description

    RollingBall-v0's task as a goal-conditioned env for hindsight experience replay (SB3's `HerReplayBuffer`),
    after gymnasium-robotics' GoalEnv: dict observations and a vectorized `compute_reward`.

    ## Observation Space

    `Dict`, each entry `Box(-1, 1, (6,), float32)` holding a rotation in 6-D form (first two columns):

    | Key | Observation |
    |-----|-------------|
    | observation | the attitude R |
    | achieved_goal | the attitude R |
    | desired_goal | the target R* |

    Nothing in `observation` depends on the goal, so a relabelled goal leaves it valid.

    ## Rewards

    Sparse: `compute_reward(achieved_goal, desired_goal, info)` = −1 while the geodesic angle between the two
    exceeds `tolerance`, else 0; it takes batches (leading axes) and the env's reward is its value.

    Everything else is RollingBall-v0's; `compute_terminated` is success, `compute_truncated` False (the time
    limit truncates).
    """

    def _observation_space(self):
        box = spaces.Box(-1.0, 1.0, (6,), np.float32)
        return spaces.Dict({"observation": box, "achieved_goal": box, "desired_goal": box})

    def _update_error(self):
        super()._update_error()
        self.goals = six_d(self.R).astype(np.float32), six_d(self.R_target).astype(np.float32)  # achieved, desired

    def _obs(self):
        achieved, desired = self.goals
        return {"observation": achieved.copy(), "achieved_goal": achieved.copy(), "desired_goal": desired.copy()}

    def _reward(self, before, info):
        return float(self.compute_reward(*self.goals, info))

    def _success(self):
        return bool(self.compute_terminated(*self.goals, None))

    def goal_angle(self, achieved_goal, desired_goal):
        """Geodesic angle between attitudes in 6-D form, over leading batch axes."""
        return rotation_angle(attitude_error(from_six_d(achieved_goal), from_six_d(desired_goal)))

    def compute_reward(self, achieved_goal, desired_goal, info):
        return -(self.goal_angle(achieved_goal, desired_goal) > self.tolerance).astype(np.float32)

    def compute_terminated(self, achieved_goal, desired_goal, info):
        return self.goal_angle(achieved_goal, desired_goal) <= self.tolerance

    def compute_truncated(self, achieved_goal, desired_goal, info):
        return np.zeros(np.shape(self.goal_angle(achieved_goal, desired_goal)), bool)
