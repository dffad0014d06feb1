"""A reference controller for ChaplyginSleigh-v0: an oscillating mass with a bias that steers (after Osborne &
Zenkov 2005), closed around the bearing of the target.

Shaking the mass across the sled pushes the knife edge backward: on the orthogonal bundle (the sleigh at rest) the
only thrust is ṗ₁ ∝ −u̇₂². Shaking it along the axis and across together, in phase or in antiphase, turns the sled:
ṗ₂ ∝ u̇₁ u̇₂. The law shakes the mass at max_mass_speed back and forth along a line through C at the angle
θ = π/2 + clip(k β, ±(π/2 − θ_min)) from the axis, β the bearing of the target seen from the tail (P looking
backward): across the sled (pure thrust, tail first toward the target) when β = 0, tilted to turn the tail toward
the target otherwise. Each step: the mass reverses at ±amplitude along the line, and any offset off the line is
brought back within the step.
"""

from __future__ import annotations

import math

import numpy as np


class TailFirst:
    """The law of the module, from the observation of ChaplyginSleigh-v0 (target along and across the axis, v, ω,
    u₂/rail, u̇₂/ṁax, u₁/max(box, rail), u̇₁/ṁax) and the env's rail, box, max_mass_speed and dt."""

    def __init__(self, env, gain: float = 3.0, amplitude: float = 0.3, min_angle: float = 0.3):
        self.rail, self.box = env.rail, env.box
        self.speed, self.dt = env.max_mass_speed, env.dt
        self.gain, self.amplitude, self.min_angle = gain, amplitude, min_angle

    def action(self, obs):
        along, across, _, _, u2, u2_dot, u1, u1_dot = (float(x) for x in obs)
        beta = math.remainder(math.atan2(across, along) - math.pi, 2 * math.pi)
        turn = max(-(math.pi / 2 - self.min_angle), min(math.pi / 2 - self.min_angle, self.gain * beta))
        d = np.array([math.cos(math.pi / 2 + turn), math.sin(math.pi / 2 + turn)])
        u = np.array([u1 * max(self.box, self.rail), u2 * self.rail])
        xi, xi_dot = float(u @ d), float(np.array([u1_dot, u2_dot]) @ d)
        reach = min(self.amplitude, self.rail / max(abs(d[1]), 1e-9), self.box / max(abs(d[0]), 1e-9))
        sign = 1.0 if (xi_dot > 0 and xi < reach) or (xi_dot <= 0 and xi <= -reach) else -1.0
        return np.clip(sign * d - (u - xi * d) / (self.speed * self.dt), -1.0, 1.0).astype(np.float32)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float32)
        if obs.ndim == 1:
            return self.action(obs), state
        return np.stack([self.action(o) for o in obs]), state
