"""The seeded random rollout the env tests compare for determinism (tests/ is on sys.path under pytest)."""

import numpy as np


def seeded_rollout(env, seed, steps, extras, options=None, flatten=np.ravel):
    """Observations, rewards and extras(info) of `steps` uniform random actions from reset(seed), resetting
    when an episode ends, as one flat array."""
    obs, _ = env.reset(seed=seed, options=options)
    env.action_space.seed(seed)
    trace = [flatten(obs)]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace.append(np.append(flatten(obs), [reward, *extras(info)]))
        if terminated or truncated:
            trace.append(flatten(env.reset()[0]))
    return np.concatenate(trace)
