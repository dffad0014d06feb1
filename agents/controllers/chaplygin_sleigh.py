"""Reference controllers for ChaplyginSleigh-v0, from its model: the mass shaken back and forth along a line through
C (the gaits of Osborne & Zenkov 2005, an oscillating mass, here in the box), the line chosen to reach the target.

Shaking the mass across the sled pushes the knife edge backward: on the orthogonal bundle (the sleigh at rest) the
only thrust is ṗ₁ ∝ −u̇₂². Shaking it along the axis and across together, in phase or in antiphase, turns the sled:
ṗ₂ ∝ u̇₁ u̇₂. A gait here is the line of angle θ from the axis, d = (cos θ, sin θ): the mass runs at max_mass_speed
along d and reverses at ±reach (the amplitude, or the box's wall), and any offset off the line is brought back
within the step (`shake`).

`ShakePlanner` (the reference): every `replan` steps it predicts, with the env's own model and stepper, where each
gait of a fan of lines θ = kπ/n (k = 0..n−1) held for `horizon` steps leaves P, from the current state (which the
observation gives entirely, in the sled's frame), and shakes along the line that ends nearest the target. Backward
runs are unstable and forward runs stable, so which line reaches the target changes along the way (turn, run tail
first, flip, run nose first); the model's prediction closes the loop around the target's bearing and distance.

`TailFirst` (a closed-form law, weaker): the line θ = π/2 + clip(k β, ±(π/2 − θ_min)), β the bearing of the target
seen from the tail: across (pure thrust, tail first) when β = 0, tilted to turn the tail toward the target otherwise.
It fails where the target lies ahead, and where the backward run flips over before reaching it.
"""

from __future__ import annotations

import math

import numpy as np

from connenv.core.batched import batched
from connenv.core.segments import bounded_segments_batch, run_segments


def shake(u, u_dot, d, reach, speed, dt):
    """Actions (n, 2) shaking the mass along the lines d (n, 2) through C, from the offsets u and velocities u̇
    (n, 2): at max_mass_speed along d, reversing at ±reach (n,), the part of u off the line removed within dt."""
    xi, xi_dot = np.sum(u * d, -1), np.sum(u_dot * d, -1)
    sign = np.where(((xi_dot > 0) & (xi < reach)) | ((xi_dot <= 0) & (xi <= -reach)), 1.0, -1.0)
    return np.clip(sign[:, None] * d - (u - xi[:, None] * d) / (speed * dt), -1.0, 1.0)


class Gaits:
    """Shared by the laws: the env's box, rail, max_mass_speed and dt; the state read off an observation."""

    def __init__(self, env, amplitude: float):
        if env.max_mass_speed is None:
            raise ValueError("the sleigh's controllers shake the mass at max_mass_speed; got max_mass_speed=None")
        self.u_high, self.speed, self.dt, self.amplitude = env.u_high, env.max_mass_speed, env.dt, amplitude

    def reach(self, d):
        """How far along each line d (n, 2) the mass goes: the amplitude, or the box's wall."""
        box, rail = self.u_high
        return np.minimum(
            self.amplitude,
            np.minimum(rail / np.maximum(np.abs(d[:, 1]), 1e-9), box / np.maximum(np.abs(d[:, 0]), 1e-9)),
        )

    def read(self, obs):
        """(target along, across, v, ω, u, u̇) of an observation."""
        along, across, v, omega, u2, u2_dot, u1, u1_dot = (float(x) for x in obs)
        u = np.array([u1 * max(self.u_high), u2 * self.u_high[1]])
        return along, across, v, omega, u, np.array([u1_dot, u2_dot]) * self.speed

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float32)
        if obs.ndim == 1:
            return self.action(obs, episode_start is not None and bool(np.any(episode_start))), state
        return np.stack([self.action(o, True) for o in obs]), state


class ShakePlanner(Gaits):
    """The planner of the module on the unwrapped ChaplyginSleigh-v0 (velocity control): `lines` gaits, each held
    `horizon` steps in the prediction, chosen again every `replan` steps and at an episode's start (`predict`'s
    episode_start, as SB3 passes it). It keeps its choice between replans, so it follows one episode at a time; on
    a batch of observations it chooses again for every row at every step."""

    def __init__(self, env, lines: int = 12, horizon: int = 60, replan: int = 5, amplitude: float = 0.3):
        super().__init__(env, amplitude)
        self.system, self.stepper = env.system, batched(env.stepper)
        angles = math.pi * np.arange(lines) / lines
        self.d = np.stack([np.cos(angles), np.sin(angles)], -1)
        self.horizon, self.replan = horizon, replan
        self.choice, self.count = 0, 0

    def ends(self, y, u, u_dot):
        """P after each gait held over the horizon, from y = (0, 0, 0, p₁, p₂) and (u, u̇): (lines, 2)."""
        n = len(self.d)
        y, u, u_dot = np.repeat(y[None], n, 0), np.repeat(u[None], n, 0), np.repeat(u_dot[None], n, 0)
        reach = self.reach(self.d)
        for _ in range(self.horizon):
            command = shake(u, u_dot, self.d, reach, self.speed, self.dt) * self.speed
            segments, u, u_dot = bounded_segments_batch(u, command, -self.u_high, self.u_high, self.dt)
            y, _ = run_segments(self.stepper, self.system, y, segments)
        return y[:, :2]

    def action(self, obs, new=False):
        along, across, v, omega, u, u_dot = self.read(obs)
        if new:
            self.count = 0
        if self.count % self.replan == 0:
            y = np.array([0.0, 0.0, 0.0, *self.system.momenta(v, omega, u, u_dot)])
            ends = self.ends(y, u, u_dot)
            self.choice = int(np.argmin(np.hypot(along - ends[:, 0], across - ends[:, 1])))
        self.count += 1
        d = self.d[self.choice : self.choice + 1]
        return shake(u[None], u_dot[None], d, self.reach(d), self.speed, self.dt)[0].astype(np.float32)


class TailFirst(Gaits):
    """The closed-form law of the module (gain k, θ_min = min_angle)."""

    def __init__(self, env, gain: float = 3.0, amplitude: float = 0.3, min_angle: float = 0.3):
        super().__init__(env, amplitude)
        self.gain, self.min_angle = gain, min_angle

    def action(self, obs, new=False):
        along, across, _, _, u, u_dot = self.read(obs)
        beta = math.remainder(math.atan2(across, along) - math.pi, 2 * math.pi)
        turn = max(-(math.pi / 2 - self.min_angle), min(math.pi / 2 - self.min_angle, self.gain * beta))
        d = np.array([[math.cos(math.pi / 2 + turn), math.sin(math.pi / 2 + turn)]])
        return shake(u[None], u_dot[None], d, self.reach(d), self.speed, self.dt)[0].astype(np.float32)


def planner(env):
    return ShakePlanner(env)


def tail_first(env):
    return TailFirst(env)
