"""The reference controllers of ChaplyginSleigh-v0 over seeds 0..N−1 (N = 20, or --seeds N): success, steps to
the target (docs/sleigh_controller.csv), and the paths of P on the first 20 (docs/sleigh_controller.png), quoted in
docs/physics/ChaplyginSleigh.md.

    PYTHONPATH=. python docs/sleigh_controller.py [--seeds N]   (from the repository root)
"""

import argparse
import csv
import math
from pathlib import Path

import gymnasium as gym
import matplotlib
import numpy as np

import connenv  # noqa: F401  (registers the envs)
from agents.controllers.chaplygin_sleigh import ShakePlanner, TailFirst

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = Path(__file__).resolve().parent
SHOWN = 20  # seeds whose paths are drawn


def episode(law, seed):
    """(success, steps, bearing of the target from the nose in degrees, path of P) of one seeded episode."""
    env = gym.make("connenv/ChaplyginSleigh-v0")
    controller = law(env.unwrapped)
    obs, info = env.reset(seed=seed)
    bearing = math.degrees(math.atan2(obs[1], obs[0]))
    path = [(0.0, 0.0)]
    for step in range(1000):
        obs, _, terminated, truncated, info = env.step(controller.predict(obs, episode_start=np.array([step == 0]))[0])
        path.append((info["state"]["x"], info["state"]["y"]))
        if terminated or truncated:
            break
    return bool(info["is_success"]), step + 1, bearing, info["target"], np.array(path)


def summary(results):
    done = [steps for success, steps, *_ in results if success]
    return f"{len(done)}/{len(results)} reached" + (f", median {np.median(done):.0f} steps" if done else "")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=20)
    seeds = range(parser.parse_args().seeds)
    laws = {"ShakePlanner": ShakePlanner, "TailFirst": TailFirst}
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    rows = []
    for ax, (name, law) in zip(axes, laws.items()):
        results = [episode(law, seed) for seed in seeds]
        for seed, (success, steps, bearing, target, path) in zip(seeds, results):
            rows.append([name, seed, f"{bearing:.1f}", success, steps])
            if seed >= SHOWN:
                continue
            color = "tab:blue" if success else "tab:red"
            ax.plot(path[:, 0], path[:, 1], color=color, lw=0.8)
            ax.add_patch(plt.Circle(target, 0.1, color=color, fill=False))
            ax.annotate(str(seed), target, fontsize=7, xytext=(4, 4), textcoords="offset points")
        print(f"{name}: {summary(results)}; steps {[steps if success else None for success, steps, *_ in results]}")
        ax.plot(0, 0, "k>", ms=10)
        ax.set_aspect("equal")
        ax.set_xlim(-4, 4)
        ax.set_ylim(-4, 4)
        ax.grid(alpha=0.3)
        ax.set_title(
            f"{name}: {summary(results[:SHOWN])} (seeds 0–{SHOWN - 1}; red: not within 1000 steps)", fontsize=9
        )
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    fig.suptitle("ChaplyginSleigh-v0: paths of the knife edge P from rest at the origin, heading +x (▸)", fontsize=10)
    fig.tight_layout()
    fig.savefig(HERE / "sleigh_controller.png", dpi=80)
    with open(HERE / "sleigh_controller.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["controller", "seed", "target bearing from the nose (deg)", "success", "steps"])
        writer.writerows(rows)


if __name__ == "__main__":
    main()
