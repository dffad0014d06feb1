"""Reference controllers of the rolling-ball envs: the optimal arc and the holonomy planner.

Both plan straight steps, one per env step, from the observation, and roll them open loop: each step is exact in
the exact model, so a plan lands on its target to rounding. They plan again whenever the observation is not the
one the plan predicted (a new episode, a disturbance) or the plan is spent. The plan is computed from the
float32 observation, whose rounding (about 1e-7) bounds how close they get.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from connenv.envs.rolling_ball import RollingBallPoseEnv
from connenv.systems.rolling_ball import RollingBall, from_six_d, split_legs

MATCH = 1e-5  # largest difference between the observed and the predicted attitude error (and position) of a plan
EXTRA_STEPS = 8  # steps beyond the arc's length/step a discrete arc may take


class PlanFollower:
    """Rolls a plan of straight steps (k, 2), from ``plan(E, position)``; E = R* Rᵀ the rotation still to roll."""

    def __init__(self, radius: float, v_max: float, dt: float, pose: bool = False):
        self.ball, self.step_length, self.pose = RollingBall(radius), v_max * dt, pose
        self.plans = {}  # row of the (batched) observation -> [remaining steps, predicted P, predicted position]

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        P, position = self.decode(obs)
        single = P.ndim == 2
        P, position = np.reshape(P, (-1, 3, 3)), np.reshape(position, (-1, 2))
        actions = np.array([self.act(i, P[i], position[i]) for i in range(len(P))], np.float32)
        return (actions[0] if single else actions), state

    def decode(self, obs):
        """(P = R R*ᵀ, position) from an observation of RollingBall-v0, RollingBallPose-v0 or RollingBallGoal-v0."""
        if isinstance(obs, dict):
            R, R_target = from_six_d(obs["achieved_goal"]), from_six_d(obs["desired_goal"])
            P = R @ np.swapaxes(R_target, -1, -2)
        else:
            obs = np.asarray(obs, np.float64)
            P = from_six_d(obs[..., :6])
        scale = 4 * math.pi * self.ball.radius
        position = obs[..., 6:8] * scale if self.pose else np.zeros((*P.shape[:-2], 2))
        return P, position

    def act(self, row, P, position):
        steps, P_expected, position_expected = self.plans.get(row, (np.zeros((0, 2)), None, None))
        if not len(steps) or np.abs(P - P_expected).max() > MATCH or np.abs(position - position_expected).max() > MATCH:
            steps = self.plan(Rotation.from_matrix(P.T), position if self.pose else None)
            if not len(steps):  # at the target to rounding
                return np.zeros(2)
        step = steps[0]
        P_next = Rotation.from_rotvec(self.ball.spin(step)).as_matrix() @ P
        self.plans[row] = (steps[1:], P_next, position + step if self.pose else position)
        return step / self.step_length

    def plan(self, rotation: Rotation, position) -> np.ndarray:
        raise NotImplementedError


class OptimalArc(PlanFollower):
    """The shortest rolling path to the target attitude, position free: an arc of a circle (Lioe 2004), found by
    `RollingBall.optimal_arc`, rolled as the discrete arc of the fewest steps no longer than v_max·dt each
    (`RollingBall.discrete_arc`: the same rotation exactly, in straight steps turning by a constant angle)."""

    def plan(self, rotation: Rotation, position=None) -> np.ndarray:
        if rotation.magnitude() == 0.0:
            return np.zeros((0, 2))
        arc = self.ball.optimal_arc(rotation)
        fewest = max(1, math.ceil(arc.length / self.step_length - 1e-9))
        for steps in range(fewest, fewest + EXTRA_STEPS):
            discrete = self.ball.discrete_arc(rotation, steps, arc)
            if discrete is not None and discrete.step_length <= self.step_length * (1 + 1e-12):
                return discrete.displacements()
        raise ArithmeticError(
            f"no discrete arc of {fewest}–{fewest + EXTRA_STEPS - 1} steps rolls {rotation.as_rotvec()}"
        )


class Holonomy(PlanFollower):
    """Turn about the vertical by the holonomy of loops, then tilt by one straight roll
    (`RollingBall.holonomy_legs`); with `pose`, two loops placed so that the centre ends at the origin. Each leg
    is rolled in full steps at v_max and one partial step."""

    def plan(self, rotation: Rotation, position=None) -> np.ndarray:
        return split_legs(self.ball.holonomy_legs(rotation, position), self.step_length)


def for_env(controller, env):
    """The controller for an unwrapped rolling-ball env, with its radius, v_max and dt; the pose task's asks for
    the position too."""
    return controller(env.system.radius, env.v_max, env.dt, isinstance(env, RollingBallPoseEnv))


def arc(env):
    return for_env(OptimalArc, env)


def holonomy(env):
    return for_env(Holonomy, env)


CLONES = {
    "connenv/RollingBall-v0": {"demonstrations": 200},
    "connenv/RollingBallPose-v0": {"demonstrations": 200, "epochs": 300, "rounds": 0, "greedy_episodes": 20},
    "connenv/RollingBallGoal-v0": {"demonstrations": 200},
}
"""agents.imitate's diagnosis (agents.imitate.Budget's fields where not its defaults). The ball is the goal env's
control: the same optimal arc and dense reward, with the attitude error P = R R*ᵀ observed instead of R and R*. No
DAgger for the pose: the holonomy planner, planned afresh inside a plan, places its loops anew, so it cannot label a
state it did not plan for. The pose's reward is dense-shaped, so a greedy ascent of it is diagnosed too (the goal
env's is sparse: a greedy step sees −1 everywhere)."""
