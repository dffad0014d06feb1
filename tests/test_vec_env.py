"""SB3 on the native vector envs: NativeVecEnv gives SB3 the episodes SB3's own DummyVecEnv of single envs gives,
and train.py trains through it."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

import connenv  # noqa: F401
from agents.vec_env import NativeVecEnv, make_native_vec_env


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("connenv/Skier-v0", {"max_episode_steps": 15, "target_x": 0.3}),
        ("connenv/RollingBallGoal-v0", {"max_episode_steps": 20, "tolerance": 2.0}),
    ],
)
def test_native_vec_env_steps_as_sb3s_dummy_vec_env(env_id, kwargs):
    """Same seed, same actions: the same observations (the reset one where an episode ends), rewards, dones,
    terminal observations, TimeLimit.truncated (the time limit, not success, ended it) and successes."""
    n = 3
    native = NativeVecEnv(gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", **kwargs))
    dummy = DummyVecEnv([lambda: gym.make(env_id, **kwargs)] * n)
    native.seed(5)
    dummy.seed(5)
    obs_native, obs_dummy = native.reset(), dummy.reset()
    actions = np.random.default_rng(0).uniform(-1, 1, (60, n, *native.action_space.shape)).astype(np.float32)
    ends = {True: 0, False: 0}
    for action in actions:
        assert_close(obs_native, obs_dummy)
        obs_native, rewards, dones, infos = native.step(action)
        obs_dummy, rewards_dummy, dones_dummy, infos_dummy = dummy.step(action)
        assert np.allclose(rewards, rewards_dummy, rtol=1e-6) and np.array_equal(dones, dones_dummy)
        for info, info_dummy, done in zip(infos, infos_dummy, dones):
            assert info["is_success"] == info_dummy["is_success"]
            if done:
                assert_close(info["terminal_observation"], info_dummy["terminal_observation"])
                assert info["TimeLimit.truncated"] == info_dummy["TimeLimit.truncated"]
                ends[info["TimeLimit.truncated"]] += 1
    assert ends[True] > 0 and ends[False] > 0  # episodes ended by the time limit and by success


def assert_close(a, b):
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_close(a[key], b[key])
    else:
        assert np.allclose(a, b, rtol=1e-6, atol=1e-6)


def test_native_vec_env_answers_her_from_the_prototype():
    venv = make_native_vec_env("connenv/RollingBallGoal-v0", n_envs=2, seed=0)
    obs = venv.reset()
    (rewards,) = venv.env_method("compute_reward", obs["achieved_goal"], obs["desired_goal"], {}, indices=[0])
    assert rewards.shape == (2,) and set(rewards) <= {-1.0, 0.0}
    assert venv.get_attr("tolerance") == [0.05, 0.05]


def test_train_py_trains_ppo_on_the_native_vector_env(tmp_path, train, check_run):
    argv = ["--vector-env", "--timesteps", "300", "--runs", str(tmp_path), "--eval-episodes", "2", "--eval-freq", "1024"]
    results = train.main(argv)
    assert results["timesteps"] == 8 * 256  # ppo.yml: 8 envs, 256 steps each per rollout
    check_run(results, "ppo")
    periodic = np.load(Path(results["model"]).parent / "evaluations.npz")
    assert list(periodic["timesteps"]) == [1024, 2048]
    assert (Path(results["model"]).parent / "vector.monitor.csv").is_file()
