"""SB3 on the native vector envs: a stable_baselines3 VecEnv over a Gymnasium VectorEnv.

SB3 takes its own VecEnv, not a Gymnasium VectorEnv, and the two disagree on what a step returns when an episode
ends. Gymnasium's native envs autoreset on the *next* step (NEXT_STEP) and return the last observation now; SB3
wants the first observation of the new episode now, the last one in ``info["terminal_observation"]``, and
``info["TimeLimit.truncated"]`` where the time limit, not the task, ended it (so that the value bootstraps).
``NativeVecEnv`` does the translation: after a step in which rows end, it resets them at once by Gymnasium's
partial reset (``reset(options={"reset_mask": done})``), so a row's episodes are the single env's.

    from agents.vec_env import make_native_vec_env
    venv = make_native_vec_env(env_id, n_envs=8, seed=0)   # VecMonitor(NativeVecEnv(...)), env_id a connenv id
    PPO("MlpPolicy", venv).learn(10_000)

Seeds are SB3's: ``seed(s)`` seeds row i with s + i at the next reset, which the native env passes on as
``gym.make(id).reset(seed=s + i)`` would take it. ``get_attr`` and ``env_method`` answer from the vector env's
prototype (one single env holding the make kwargs every row shares): ``env_method("compute_reward", ...)``, which
SB3's HER calls, is the goal env's batched reward.
"""

from __future__ import annotations

import os

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env import VecEnv, VecMonitor

import connenv  # noqa: F401  (registers the envs)


class NativeVecEnv(VecEnv):
    """An SB3 VecEnv over a Gymnasium VectorEnv with NEXT_STEP autoreset and partial resets (connenv's native
    vector envs)."""

    def __init__(self, venv: gym.vector.VectorEnv):
        if venv.metadata.get("autoreset_mode") is not AutoresetMode.NEXT_STEP:
            raise ValueError(f"{venv} has autoreset_mode={venv.metadata.get('autoreset_mode')!r}; expected NEXT_STEP")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self.actions = None

    def reset(self):
        seed = None if all(s is None for s in self._seeds) else self._seeds
        options = self._options[0] or None  # SB3 keeps one dict per env; the native env takes one for all rows
        obs, info = self.venv.reset(seed=seed, options=options)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = rows_of(info, self.num_envs)
        return obs

    def step_async(self, actions):
        self.actions = actions

    def step_wait(self):
        obs, rewards, terminated, truncated, info = self.venv.step(self.actions)
        done = terminated | truncated
        infos = rows_of(info, self.num_envs)
        if done.any():
            for i in np.flatnonzero(done):
                infos[i]["terminal_observation"] = row(obs, i)
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            obs, reset_info = self.venv.reset(options={"reset_mask": done})
            for i, reset_row in enumerate(rows_of(reset_info, self.num_envs)):
                if done[i]:
                    self.reset_infos[i] = reset_row
        return obs, rewards.astype(np.float32), done, infos

    def close(self):
        self.venv.close()

    def get_attr(self, attr_name, indices=None):
        return [getattr(self.venv.env, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name, value, indices=None):
        raise AttributeError(f"set_attr({attr_name!r}): the rows of a native vector env share one prototype")

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        method = getattr(self.venv.env, method_name)
        return [method(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False for _ in self._get_indices(indices)]


def row(batch, i):
    """Row i of a batch of observations (an array, or a dict of arrays)."""
    return {key: value[i] for key, value in batch.items()} if isinstance(batch, dict) else batch[i]


def rows_of(info, n):
    """A Gymnasium vector info (dict of arrays with "_key" masks) as SB3's list of n per-row dicts."""
    rows = [{} for _ in range(n)]
    for key, value in info.items():
        if key.startswith("_"):
            continue
        mask = info.get(f"_{key}", np.ones(n, bool))
        parts = rows_of(value, n) if isinstance(value, dict) else value
        for i in np.flatnonzero(mask):
            rows[i][key] = parts[i]
    return rows


def make_native_vec_env(env_id, n_envs=1, seed=None, env_kwargs=None, monitor_dir=None, monitor_kwargs=None):
    """``gym.make_vec(env_id, n_envs, vectorization_mode="vector_entry_point")`` for SB3: NativeVecEnv under
    VecMonitor (episode returns and lengths, written to monitor_dir/vector.monitor.csv if given), seeded as
    SB3's make_vec_env seeds."""
    venv = gym.make_vec(env_id, n_envs, vectorization_mode="vector_entry_point", **(env_kwargs or {}))
    filename = None if monitor_dir is None else os.path.join(monitor_dir, "vector")
    if monitor_dir is not None:
        os.makedirs(monitor_dir, exist_ok=True)
    env = VecMonitor(NativeVecEnv(venv), filename=filename, **(monitor_kwargs or {}))
    if seed is not None:
        env.seed(seed)
    return env
