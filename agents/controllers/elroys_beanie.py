"""Reference controller of ElroysBeanie-v0, from its momentum balance: the dead-beat law. It answers SB3's
``predict`` on the env's observations (batched or not)."""

from __future__ import annotations

import numpy as np


class BeanieDeadBeat:
    """Turn ElroysBeanie-v0's body onto θ* in as few steps as the beanie's speed allows, then hold it.

    From μ = (I₁ + I₂) θ̇ + I₂ ψ̇, a step of constant ψ̇ turns the body by (μ − I₂ ψ̇) dt/(I₁ + I₂). The law asks
    for the turn e = θ* − θ in one step, ψ̇ = (μ − (I₁ + I₂) e/dt)/I₂, clipped to the speed bound: the fastest
    approach (the bound binds until the last step), landing exactly on θ*; there e = 0 gives ψ̇ = μ/I₂, the
    spin that holds the body still. It reads e from (sin e, cos e) and μ from the observation.
    """

    def __init__(self, env):
        self.total, self.beanie = env.body_inertia + env.beanie_inertia, env.beanie_inertia
        self.dt, self.speed = env.dt, env.max_beanie_speed

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float64)
        error, momentum = np.arctan2(obs[..., 0], obs[..., 1]), obs[..., 2]
        psi_dot = (momentum - self.total * error / self.dt) / self.beanie
        return np.clip(psi_dot / self.speed, -1.0, 1.0).astype(np.float32)[..., None], state


def dead_beat(env):
    return BeanieDeadBeat(env)
