"""agents.features.AttitudeError computes, inside a policy, RollingBall-v0's observation from RollingBallGoal-v0's."""

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from scipy.spatial.transform import Rotation

import connenv  # noqa: F401
from agents.features import AttitudeError
from connenv.systems.rolling_ball import six_d


def features(extractor, obs):
    return extractor({key: th.as_tensor(value)[None] for key, value in obs.items()})[0].numpy()


def test_attitude_error_of_the_goal_env_is_the_rolling_ball_observation_along_an_episode():
    goal, ball = gym.make("connenv/RollingBallGoal-v0"), gym.make("connenv/RollingBall-v0")
    extractor = AttitudeError(goal.observation_space)
    obs, _ = goal.reset(seed=3)
    expected, _ = ball.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(20):
        np.testing.assert_allclose(features(extractor, obs), expected, atol=1e-6)  # float32 observations
        action = rng.uniform(-1, 1, goal.action_space.shape).astype(np.float32)
        obs, *_ = goal.step(action)
        expected, *_ = ball.step(action)


@pytest.mark.parametrize("seed", range(3))
def test_attitude_error_is_invariant_under_a_common_rotation_of_attitude_and_goal(seed):
    """P = R R*ᵀ = (R Q)(R* Q)ᵀ: what a relabelled pair shares with the original is all the policy sees."""
    R, R_target, Q = Rotation.random(3, random_state=seed).as_matrix()
    space = gym.make("connenv/RollingBallGoal-v0").observation_space
    extractor = AttitudeError(space)

    def obs(a, b):
        return {"observation": six_d(a).astype(np.float32), "achieved_goal": six_d(a).astype(np.float32),
                "desired_goal": six_d(b).astype(np.float32)}  # fmt: skip

    np.testing.assert_allclose(features(extractor, obs(R @ Q, R_target @ Q)), six_d(R @ R_target.T), atol=1e-6)
    assert np.linalg.norm(features(extractor, obs(R, R_target)) - six_d(R_target @ R.T)) > 1e-3  # order matters
