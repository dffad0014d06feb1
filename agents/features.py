"""Features extractors: what a policy computes from an observation before its MLP, where the MLP should not have to.

The rolling ball's goal env (RollingBallGoalEnv) observes the attitude R and the target R* (6-D form each), as HER
needs: a relabelled goal must leave the observation valid, so the env cannot observe their product. But the optimal
arc is a feedback law of the attitude error P = R R*ᵀ alone, and an MLP given R and R* does not learn to compose
them (its clones reach 1–5%, and 99–100% from P: docs/guides/reference-results.md). ``AttitudeError`` computes P
inside the policy, from whatever goal HER puts beside the attitude, so relabelling stays valid.

In an rl-zoo3 hyperparameter file (whose policy_kwargs string is evaluated without imports):

    policy_kwargs: "dict(features_extractor_class=__import__('agents.features').features.AttitudeError)"
"""

from __future__ import annotations

import gymnasium as gym
import torch as th
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor


def from_six_d(x: th.Tensor) -> th.Tensor:
    """Rotation matrices (..., 3, 3) from the 6-D form (the first two columns), by Gram–Schmidt."""
    a, b = x[..., :3], x[..., 3:]
    c1 = a / th.linalg.vector_norm(a, dim=-1, keepdim=True)
    b = b - (c1 * b).sum(-1, keepdim=True) * c1
    c2 = b / th.linalg.vector_norm(b, dim=-1, keepdim=True)
    return th.stack([c1, c2, th.linalg.cross(c1, c2)], dim=-1)


class AttitudeError(BaseFeaturesExtractor):
    """The 6-D form of P = R R*ᵀ, R from "achieved_goal" and R* from "desired_goal": the observation of
    RollingBallEnv, computed from RollingBallGoalEnv's. No parameters; "observation" (R again) is left out, since the
    task is invariant under a common rotation of R and R*."""

    def __init__(self, observation_space: gym.spaces.Dict):
        super().__init__(observation_space, features_dim=6)

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        P = from_six_d(observations["achieved_goal"]) @ from_six_d(observations["desired_goal"]).transpose(-1, -2)
        return th.cat([P[..., :, 0], P[..., :, 1]], dim=-1)
