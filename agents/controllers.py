"""Analytic reference controllers. Each answers SB3's ``predict(obs, deterministic=True) -> (action, state)``,
so the evaluation treats an analytic law and a trained network alike. Observations may be batched."""

from __future__ import annotations

import numpy as np


class PiccoliKulkarni:
    """Pump a swing (Piccoli & Kulkarni 2005): stand, r = r_min, while the swing moves away
    from the bottom (sin θ · θ̇ > 0); squat, r = r_max, while it moves toward it.

    Each half swing then multiplies 1 − cos(amplitude) by (r_max/r_min)³. The
    law is read off the Swing-v0 observation (cos θ, sin θ, θ̇ scaled, r scaled)
    and needs none of the env's parameters.
    """

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, dtype=np.float32)
        away = obs[..., 1] * obs[..., 2] > 0.0
        return np.where(away, -1.0, 1.0).astype(np.float32)[..., None], state


ANALYTIC = {"connenv/Swing-v0": PiccoliKulkarni}


def analytic_policy(env_id: str):
    """The analytic reference controller of a registered env."""
    if env_id not in ANALYTIC:
        raise ValueError(f"no analytic controller for env {env_id!r}; known: {sorted(ANALYTIC)}")
    return ANALYTIC[env_id]()
