"""A base for reference controllers that keep a plan per row of a batched observation."""

from __future__ import annotations

import numpy as np


class RowPlanner:
    """SB3's ``predict(obs, deterministic=True) -> (action, state)`` for one observation or a batch of rows: a
    subclass gives ``act(i, row)``, the action for row i (the i-th env of a vector env, whose plan it keeps)."""

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float64)
        single = obs.ndim == 1
        rows = np.reshape(obs, (-1, obs.shape[-1]))
        actions = np.array([self.act(i, row) for i, row in enumerate(rows)], np.float32)
        return (actions[0] if single else actions), state

    def act(self, i: int, obs: np.ndarray) -> np.ndarray:
        raise NotImplementedError
