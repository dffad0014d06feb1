"""Reference controller of Swing-v0: Piccoli and Kulkarni's pumping law."""

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


def pumping(env):
    return PiccoliKulkarni()
