"""Start curricula: training episodes that start where the task's own start rarely leads, through the env's reset
options, while the periodic and the final evaluations keep the task's start.

The Kapitza swing-up's agents pump energy in but do not learn to catch and hold the pendulum, which only a swing
that reaches the top slowly shows them; its clones show that the network can (docs/guides/reference-results.md).
Some of the training episodes are released at rest from any angle, up to inverted: the hold is then learned where it
is paid, and each higher start is a swing-up already partly done. The agents of the bead on a bar bring the bead to
rest short of the target; some training episodes put the target close to the bead, where the last centimetres are
the task.

A curriculum is a hyperparameter of train.py (agents/hyperparams), the name of a function here, which rl-zoo3 never
sees; train.py wraps the training env alone in ``StartCurriculum(env, starts)``. On ``--backend jax`` the same start
function draws from a JAX key (connenv.jax's reset takes it as its options), and agents.jax_ppo restarts that share
of the ended training rows from it (`jax_starts`).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

SHARE = 0.5  # of the training episodes started by the curriculum


class StartCurriculum(gym.Wrapper):
    """Each reset is the env's own; with probability `share` (drawn from the env's np_random, so that a seeded run
    repeats) it is followed by a reset with the options `starts(env, info)` gives, and that episode is truncated after
    `max_steps` (None: the env's time limit)."""

    def __init__(self, env: gym.Env, starts, share: float = SHARE, max_steps: int | None = None):
        super().__init__(env)
        self.starts, self.share, self.max_steps = starts, share, max_steps
        self.steps, self.limit = 0, None

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        self.steps, self.limit = 0, None
        if options is None and self.env.unwrapped.np_random.uniform() < self.share:
            obs, info = self.env.reset(options=self.starts(self.env.unwrapped, info))
            self.limit = self.max_steps
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.steps += 1
        return obs, reward, terminated, truncated or (self.limit is not None and self.steps >= self.limit), info


def kapitza_release(env, info) -> dict:
    """Released at rest from |θ| uniform on [0.1, π] rad from hanging, either side, the pivot at the centre."""
    theta = env.np_random.uniform(0.1, math.pi) * env.np_random.choice([-1.0, 1.0])
    return {"state": {"theta": theta, "theta_dot": 0.0, "u": (0.0, 0.0), "u_dot": (0.0, 0.0)}}


def bead_near_target(env, info) -> dict:
    """The bead where the task put it, the target 0.02–0.2 L from it, toward the bar's centre if it would lie past
    0.8 L."""
    L, r = env.half_length, info["state"]["r"]
    offset = env.np_random.uniform(0.02, 0.2) * L * env.np_random.choice([-1.0, 1.0])
    target = r + offset if abs(r + offset) <= 0.8 * L else r - offset
    return {"state": {"r": r}, "target": float(np.clip(target, -L, L))}


CURRICULA = {
    "kapitza_release": (kapitza_release, {"max_steps": 2000}),
    "bead_near_target": (bead_near_target, {}),
}


NEEDS_INFO = {"bead_near_target"}  # starts that read the reset's info, which the JAX trainer does not give


def jax_starts(name: str) -> tuple:
    """(starts, share, max_steps) of a curriculum for PPO on connenv.jax (agents.jax_ppo), whose reset calls
    ``starts(task, None)`` with the task drawing from a JAX key: ValueError naming it where it cannot."""
    starts, options = entry(name)
    if name in NEEDS_INFO:
        raise ValueError(f"curriculum {name!r} reads the reset's info, which --backend jax does not give; there: "
                         f"{sorted(set(CURRICULA) - NEEDS_INFO)}")  # fmt: skip
    return (lambda task: starts(task, None)), options.get("share", SHARE), options.get("max_steps")


def entry(name: str) -> tuple:
    """(starts, options) of a curriculum named in the hyperparameters: ValueError naming it and the known ones."""
    if name not in CURRICULA:
        raise ValueError(f"curriculum {name!r} is not one of {sorted(CURRICULA)}")
    return CURRICULA[name]


def wrapper(name: str):
    """The env wrapper of a curriculum named in the hyperparameters: ValueError naming it and the known ones."""
    starts, options = entry(name)
    return lambda env: StartCurriculum(env, starts, **options)
