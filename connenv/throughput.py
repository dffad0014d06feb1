"""Throughput: single-env steps/s against Gymnasium's Pendulum-v1, and native vector env-steps/s against
Gymnasium's SyncVectorEnv of the same env.

    python -m connenv.throughput [--envs ID ...] [--sizes 1 64 1024 4096] [--sync-max 1024] [--seconds 0.5]

Single envs: each env from ``gym.make(id)`` (its registered wrappers included) and Pendulum-v1 from
``gym.make("Pendulum-v1")`` are stepped alternately with random actions, each step timed alone, resets left out
of the timing; the figures are the medians, and the ratio is the env's median step time over Pendulum-v1's,
measured in the same loop, so that it holds on a machine busy with other work, where the absolute times do not.

Vector envs: ``gym.make_vec(id, N, vectorization_mode="vector_entry_point")`` (native) and the same with
``"sync"`` (Gymnasium's SyncVectorEnv of N single envs), reset once (untimed), then stepped with random actions in
alternating blocks of about ``seconds / ROUNDS`` each; autoresets are part of the steps, as in training. The
figure is N × steps / time, the median over the blocks. SyncVectorEnv's cost per env hardly depends on N, and its
first reset at N = 4096 takes minutes on the envs whose reset solves for an optimal arc, so it runs only up to
``--sync-max`` (default 1024). Targets (issue 7): single-env step ≤ 1.0× Pendulum-v1; native vector ≥ 5 M
env-steps/s at N = 4096 for Swing and Skier, ≥ 1 M for RollingBall, KozlovShell and the Kapitza pendulum.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import time

import gymnasium as gym
import numpy as np
import scipy

import connenv  # noqa: F401  (registers the envs)

SINGLE_STEPS = 3000
ROUNDS = 5
SIZES = (1, 64, 1024, 4096)
VECTOR_TARGETS = {
    "connenv/Swing-v0": 5e6,
    "connenv/Skier-v0": 5e6,
    "connenv/RollingBall-v0": 1e6,
    "connenv/KozlovShell-v0": 1e6,
    "connenv/KapitzaPendulum-v0": 1e6,
    "connenv/KapitzaSwingUp-v0": 1e6,
}


def single_step_times(env_id: str, steps: int, seed: int = 0):
    """Median step times (s) of env_id and of Pendulum-v1, stepped alternately, each step timed alone."""
    envs = [gym.make(env_id), gym.make("Pendulum-v1")]
    times = [[], []]
    for k, env in enumerate(envs):
        env.reset(seed=seed)
        env.action_space.seed(seed + k)
    actions = [[env.action_space.sample() for _ in range(256)] for env in envs]
    for i in range(steps):
        for k, env in enumerate(envs):
            action = actions[k][i % 256]
            start = time.perf_counter()
            _, _, terminated, truncated, _ = env.step(action)
            times[k].append(time.perf_counter() - start)
            if terminated or truncated:
                env.reset()
    return statistics.median(times[0]), statistics.median(times[1])


def vector_rates(env_id: str, n: int, seconds: float, sync: bool, seed: int = 0):
    """Median env-steps/s of the native vector env and of SyncVectorEnv (None unless sync) at N = n."""
    modes = ["vector_entry_point"] + (["sync"] if sync else [])
    envs = [gym.make_vec(env_id, n, vectorization_mode=mode) for mode in modes]
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, (16, *envs[0].action_space.shape)).astype(np.float32)
    rates = [[] for _ in envs]
    for env in envs:
        env.reset(seed=seed)
        env.step(actions[0])
    for _ in range(ROUNDS):
        for k, env in enumerate(envs):
            steps, start = 0, time.perf_counter()
            while (elapsed := time.perf_counter() - start) < seconds / ROUNDS or steps == 0:
                env.step(actions[steps % len(actions)])
                steps += 1
            rates[k].append(n * steps / elapsed)
    for env in envs:
        env.close()
    medians = [statistics.median(r) for r in rates]
    return medians[0], (medians[1] if sync else None)


def main(argv=None):
    ids = sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", nargs="+", default=ids, choices=ids, metavar="ID")
    parser.add_argument("--sizes", nargs="+", type=int, default=list(SIZES), help="N of the vector envs")
    parser.add_argument("--sync-max", type=int, default=1024, help="largest N at which SyncVectorEnv runs")
    parser.add_argument("--seconds", type=float, default=0.5, help="timed seconds per vector env and N")
    parser.add_argument("--single-steps", type=int, default=SINGLE_STEPS)
    parser.add_argument("--skip-single", action="store_true")
    parser.add_argument("--skip-vector", action="store_true")
    args = parser.parse_args(argv)
    print(
        f"# {datetime.datetime.now():%Y-%m-%d %H:%M}, {platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"gymnasium {gym.__version__}"
    )
    misses = []
    if not args.skip_single:
        print("\nsingle env, gym.make, median of env.step; Pendulum-v1 stepped alternately in the same loop")
        print(f"{'env':28} {'µs/step':>9} {'steps/s':>9} {'Pendulum µs':>12} {'× Pendulum':>11}  target ≤ 1.0×")
        for env_id in args.envs:
            env_time, pendulum_time = single_step_times(env_id, args.single_steps)
            ratio = env_time / pendulum_time
            verdict = "met" if ratio <= 1.0 else "MISSED"
            misses += [] if ratio <= 1.0 else [f"{env_id} single {ratio:.1f}×"]
            print(
                f"{env_id:28} {env_time * 1e6:9.1f} {1 / env_time:9.0f} {pendulum_time * 1e6:12.1f} "
                f"{ratio:11.2f}  {verdict}"
            )
    if not args.skip_vector:
        print("\nvector envs, M env-steps/s (median of blocks; autoresets included)")
        print(f"{'env':28} {'N':>5} {'native':>9} {'sync':>9} {'native/sync':>12}  target at N=4096")
        for env_id in args.envs:
            for n in args.sizes:
                native, sync = vector_rates(env_id, n, args.seconds, n <= args.sync_max)
                target = VECTOR_TARGETS.get(env_id) if n == 4096 else None
                verdict = "" if target is None else f"≥ {target / 1e6:.0f} M: " + ("met" if native >= target else "MISSED")
                if target is not None and native < target:
                    misses.append(f"{env_id} N=4096 {native / 1e6:.2f} M/s")
                sync_text = f"{sync / 1e6:9.4f}" if sync else f"{'-':>9}"
                ratio_text = f"{native / sync:12.1f}" if sync else f"{'-':>12}"
                print(f"{env_id:28} {n:5} {native / 1e6:9.4f} {sync_text} {ratio_text}  {verdict}")
    print("\nmissed: " + ("; ".join(misses) if misses else "none"))


if __name__ == "__main__":
    main()
