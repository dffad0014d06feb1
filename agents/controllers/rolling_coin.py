"""Reference controller of RollingCoin-v0, from its geometry: the turn–roll–turn planner. It answers SB3's
``predict`` on the env's observations (batched or not)."""

from __future__ import annotations

import numpy as np

ALIGNED = 1e-4  # rad: a heading within this of the line to the target rolls (float32 observations: ~1e-7)
ARRIVED = 0.01  # m: closer than this the coin turns to the target heading (the tolerance is 0.05 m)


def wrap(angle):
    return np.arctan2(np.sin(angle), np.cos(angle))


class CoinPlanner:
    """Park RollingCoin-v0: turn to face the target (or to put it straight behind), roll to it, turn to θ*.

    What it optimizes: the time of turn–roll–turn paths at the rate bounds. The roll takes |d|/(R φ̇_max) whatever
    is chosen; the two turns take (|β| + |θ* − θ − β|)/θ̇_max, β the first turn, so it rolls forwards (β the
    bearing of the target, atan2(d·r, d·f)) or backwards (β + π), whichever makes |β| + |θ* − θ − β| (wrapped)
    the smaller. Each step asks for the rest of the current leg, clipped to the rate bound, so a leg ends exactly
    on a step (the env's step is exact). Once aligned the choice holds: rolling on costs |θ* − θ| ≤ π, reversing
    π more. It is a feedback law of the observation (d·f, d·r, sin(θ* − θ), cos(θ* − θ)), restarted from
    wherever the coin is.
    """

    def __init__(self, env):
        self.turn_step = env.rates[0] * env.dt  # rad per step at a = 1
        self.roll_step = env.radius * env.rates[1] * env.dt  # m per step at a = 1

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(obs, np.float64)
        ahead, right = obs[..., 0], obs[..., 1]
        heading = np.arctan2(obs[..., 2], obs[..., 3])
        forward = np.arctan2(right, ahead)
        backward = wrap(forward + np.pi)
        cost_forward = np.abs(forward) + np.abs(wrap(heading - forward))
        cost_backward = np.abs(backward) + np.abs(wrap(heading - backward))
        turn = np.where(cost_forward <= cost_backward, forward, backward)
        far = np.hypot(ahead, right) > ARRIVED
        rolling = far & (np.abs(turn) <= ALIGNED)
        steer = np.where(far, np.where(rolling, 0.0, turn), heading) / self.turn_step
        roll = np.where(rolling, ahead, 0.0) / self.roll_step
        return np.clip(np.stack([steer, roll], axis=-1), -1.0, 1.0).astype(np.float32), state


def turn_roll_turn(env):
    return CoinPlanner(env)


CLONES = {"connenv/RollingCoin-v0": {"rounds": 0, "greedy_episodes": 20}}
"""agents.imitate's diagnosis (agents.imitate.Budget's fields where not its defaults). No DAgger: the planner rolls
only within ALIGNED of the line to the target, so it labels every state a clone visits near that line "turn, do not
roll", and the DAgger rollouts' own success fell over the rounds. The reward is dense-shaped, so a greedy ascent of
it is diagnosed too."""
