"""Benchmark of the steppers on Swing-v0: energy drift and speed, to choose the default.

    python -m connenv.bench [--quick] [--integrators exact rk4 ...]

Every candidate runs a 1000-step episode of Swing-v0 at constant control
(action +1 held, so r = r_max = 2 m throughout) from rest at θ₀ = π/2, the
task's target amplitude, and (unless --quick) from rest at θ₀ = 3.0, near the
top, where the period is long and the flow is close to the separatrix.

Energy drift is max_t |E(t) − E(0)| / (m g r) over the episode, E from
info["energy"] (E(0) from reset). E is conserved at constant r, and m g r is
its natural scale: E runs from −m g r (at rest at the bottom) to m g r (at rest
at the top), and E(0) itself is 0 at θ₀ = π/2, so a drift relative to E(0)
would be meaningless. A candidate passes if its drift is ≤ 1e-8 from every start.

Speed is the median wall time of env.step, on the unwrapped envs (no
TimeLimit, order-enforcing or checker wrappers). Each Swing step is timed right
after a step of Gymnasium's Pendulum-v1 (unwrapped, constant action), so the
ratio of the two medians holds on a machine busy with other work, where the
absolute times do not. The default is the fastest passing candidate.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time

import gymnasium as gym
import numpy as np
import scipy

import connenv  # noqa: F401  (registers connenv/Swing-v0)
from connenv.core.steppers import INTEGRATORS

STEPS = 1000
DRIFT_LIMIT = 1e-8
STARTS = {"π/2": math.pi / 2, "3.0": 3.0}  # θ₀, from rest
SCIPY_RTOLS = (1e-6, 1e-8, 1e-10, 1e-12)
ATOL_PER_RTOL = 1e-2  # atol = rtol · 1e-2 on (θ, p)


def candidates():
    """(integrator, make kwargs) for every stepper the benchmark compares."""
    yield "exact", {}
    for substeps in (1, 2, 4, 8, 16, 32):
        yield "rk4", {"substeps": substeps}
    for integrator in ("dop853", "lsoda", "rk45", "radau"):
        for rtol in SCIPY_RTOLS:
            yield integrator, {"rtol": rtol, "atol": rtol * ATOL_PER_RTOL}


def run_episode(integrator, options, theta0, pendulum):
    """One episode at constant control: (energy drift, Swing step times, Pendulum step times) in s."""
    env = gym.make("connenv/Swing-v0", integrator=integrator, **options).unwrapped
    _, info = env.reset(options={"state": {"theta": theta0, "theta_dot": 0.0}})
    energy_scale = env.system.mass * env.system.g * env.r
    action, pendulum_action = np.array([1.0], np.float32), np.array([0.0], np.float32)
    energy0, drift = info["energy"], 0.0
    swing_times, pendulum_times = np.empty(STEPS), np.empty(STEPS)
    clock = time.perf_counter
    for i in range(STEPS):
        start = clock()
        pendulum.step(pendulum_action)
        middle = clock()
        _, _, _, _, info = env.step(action)
        end = clock()
        pendulum_times[i], swing_times[i] = middle - start, end - middle
        drift = max(drift, abs(info["energy"] - energy0) / energy_scale)
    assert env.r == env.r_max, "the control was not held at r_max"
    env.close()
    return drift, swing_times, pendulum_times


def describe(options):
    if "substeps" in options:
        return f"substeps={options['substeps']}"
    if options:
        return f"rtol={options['rtol']:.0e} atol={options['atol']:.0e}"
    return "closed form"


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m connenv.bench", description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="only the start θ₀ = π/2 (half the time)")
    parser.add_argument("--integrators", nargs="+", choices=INTEGRATORS, metavar="NAME", help="only these integrators")
    args = parser.parse_args(argv)
    starts = {"π/2": STARTS["π/2"]} if args.quick else STARTS

    print(f"connenv.bench  {datetime.datetime.now().isoformat(timespec='seconds')}")
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"gymnasium {gym.__version__}, {os.cpu_count()} cores, {platform.machine()}, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    print(
        f"Swing-v0 (unwrapped), {STEPS} steps of dt = 0.05 s at action +1 (r = r_max = 2 m), from rest at "
        f"θ₀ = {', '.join(starts)}; drift = max |E(t) − E(0)| / (m g r); "
        f"time = median µs per env.step; ratio = that / median of Pendulum-v1 steps interleaved with it\n"
    )
    pendulum = gym.make("Pendulum-v1").unwrapped
    pendulum.reset(seed=0)

    drifts = [f"drift θ₀={name}" for name in starts]
    header = ["integrator", "options", "µs/step", "× Pendulum-v1", *drifts, "pass"]
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    results, all_pendulum_times, t_start = [], [], time.perf_counter()
    for integrator, options in candidates():
        if args.integrators and integrator not in args.integrators:
            continue
        drifts, swing_times, pendulum_times = [], [], []
        try:
            for theta0 in starts.values():
                drift, swing, pend = run_episode(integrator, options, theta0, pendulum)
                drifts.append(drift)
                swing_times.append(swing)
                pendulum_times.append(pend)
        except ArithmeticError as error:  # a stepper that blows up fails, and the table says why
            print(f"| {integrator} | {describe(options)} | – | – | {type(error).__name__}: {error} | fail |")
            continue
        swing_us = np.median(np.concatenate(swing_times)) * 1e6
        ratio = np.median([np.median(s) / np.median(p) for s, p in zip(swing_times, pendulum_times)])
        passed = max(drifts) <= DRIFT_LIMIT
        all_pendulum_times += pendulum_times
        results.append((ratio, integrator, options, passed))
        cells = [integrator, describe(options), f"{swing_us:.0f}", f"{ratio:.1f}", *(f"{d:.1e}" for d in drifts)]
        print("| " + " | ".join(cells) + f" | {'pass' if passed else 'FAIL'} |", flush=True)

    pendulum_us = np.median(np.concatenate(all_pendulum_times)) * 1e6
    print(f"\nPendulum-v1 (unwrapped): median {pendulum_us:.1f} µs/step over all interleaved steps")
    print(f"wall time of the benchmark: {time.perf_counter() - t_start:.0f} s")
    passing = sorted((r for r in results if r[3]), key=lambda r: r[0])
    if passing:
        ratio, integrator, options, _ = passing[0]
        print(
            f"fastest stepper with drift ≤ {DRIFT_LIMIT:.0e}: {integrator} ({describe(options)}), "
            f"{ratio:.1f}× Pendulum-v1 per step"
        )
        for ratio_next, integrator_next, options_next, _ in passing[1:3]:
            print(f"  next: {integrator_next} ({describe(options_next)}), {ratio_next:.1f}× Pendulum-v1")
    else:
        print(f"no stepper holds the drift ≤ {DRIFT_LIMIT:.0e}")


if __name__ == "__main__":
    main()
