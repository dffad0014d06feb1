"""Stand-ups (pumping half-cycles) the analytic controller needs to escape Skier-v0, over seeds 0..99.

    python docs/skier_half_cycles.py
"""
import collections

import gymnasium as gym
import numpy as np

from agents.controllers.skier import SkierPumping

env = gym.make("connenv/Skier-v0"); pol = SkierPumping(); counts = collections.Counter(); times = []
for seed in range(100):
    obs, info = env.reset(seed=seed); done = False; ups = 0
    while not done:
        h = info["state"]["h"]; obs, _, term, trunc, info = env.step(pol.predict(obs)[0]); done = term or trunc
        ups += info["state"]["h"] > h
    assert term
    counts[ups] += 1; times.append(info["state"]["t"])
print("stand-ups (pumping half-cycles) to escape over seeds 0..99:", {int(k): v for k, v in sorted(counts.items())})
print(f"time to escape: mean {np.mean(times):.2f} s, min {min(times):.2f}, max {max(times):.2f}")
