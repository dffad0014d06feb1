"""Benchmark of the steppers on an env: energy drift and speed, the table that chose the defaults.

    python -m connenv.bench steppers [--env swing|skier|ball] [--quick] [--integrators exact rk4 ...]

(also as `python -m connenv.bench [--env ...]`). The work–precision charts of `python -m connenv.bench precision`
supersede it for choosing; it stays for the tables in docs/steppers.md.

Every candidate runs a 1000-step episode at constant control (action +1 held)
from two starts (the first only with --quick); each env by the ``bench`` of its Spec:

- swing: r = r_max = 2 m, from θ₀ = π/2, the task's target amplitude, and
  θ₀ = 3.0, near the top, where the flow is close to the separatrix. Energy
  scale m g r: E runs from −m g r (at rest at the bottom) to m g r (at the top),
  and E(0) itself is 0 at θ₀ = π/2, so a drift relative to E(0) would be meaningless.
- skier: standing, h = h_max = 1 m, on the valley from x₀ = 2.0 (the far end
  of the default starts) and x₀ = 5.5, near the rim (the most energy an episode
  holds before success). Energy scale m g H, H = 3 m the valley's depth.
- ball: a straight roll at v = (v_max, 0) from R₀ = I and from
  R₀ = Rx(2), whose closed form is R(t) = Ry(v_max t/ρ) R₀.

For the swing and the skier the drift is the energy's, max_t |E(t) − E(0)| /
scale over the episode, E from info["energy"] (E(0) from reset); E is
conserved at constant control. For the ball it is the state error against the
closed form, max_t of the angle between R(t) and Ry(v_max t/ρ) R₀ (which also
bounds the drift off SO(3)). A candidate passes if its drift is ≤ 1e-8 from
every start.

Speed is the median wall time of env.step, on the unwrapped envs (no
TimeLimit, order-enforcing or checker wrappers). Each env step is timed right
after a step of Gymnasium's Pendulum-v1 (unwrapped, constant action), so the
ratio of the two medians holds on a machine busy with other work, where the
absolute times do not. The default is the fastest passing candidate. Candidates the env cannot take
(the exact flow where the system has none) are left out.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import os
import platform
import time

import gymnasium as gym
import numpy as np
import scipy
from scipy.spatial.transform import Rotation

import connenv  # noqa: F401  (registers the envs)
from connenv import cli
from connenv.bench.common import env_id
from connenv.core.integrators import INTEGRATORS
from connenv.systems.rolling_ball import rotation_angle

STEPS = 1000
DRIFT_LIMIT = 1e-8


@dataclasses.dataclass(frozen=True)
class Bench:
    env_id: str
    starts: dict  # label -> reset state
    measure: str  # what the drift measures, as printed
    drift: object  # (env, info at reset, info) -> the drift at that step
    control: str  # what the held action +1 means


def energy_drift(scale):
    """|E − E(0)| / scale, the scale a function of the env."""
    return lambda env, info0, info: abs(info["energy"] - info0["energy"]) / scale(env)


def straight_roll_error(env, info0, info):
    """Angle between R(t) and its closed form Ry(v_max t/ρ) R₀ for the held action (1, 0)."""
    exact = Rotation.from_rotvec([0.0, env.v_max * info["state"]["t"] / env.system.radius, 0.0]).as_matrix()
    return float(rotation_angle(info["state"]["R"] @ (exact @ info0["state"]["R"]).T))


BENCHES = {
    "swing": Bench(
        env_id("swing"),
        {"θ₀=π/2": {"theta": math.pi / 2, "theta_dot": 0.0}, "θ₀=3.0": {"theta": 3.0, "theta_dot": 0.0}},
        "|E(t) − E(0)| / (m g r)",
        energy_drift(lambda env: env.system.mass * env.system.g * env.state.r),
        "r = r_max = 2 m",
    ),
    "skier": Bench(
        env_id("skier"),
        {"x₀=2.0": {"x": 2.0, "h": 1.0}, "x₀=5.5": {"x": 5.5, "h": 1.0}},
        "|E(t) − E(0)| / (m g H)",
        energy_drift(lambda env: env.system.mass * env.system.g * env.trail.H),
        "h = h_max = 1 m on the valley",
    ),
    "ball": Bench(
        env_id("ball"),
        {"R₀=I": {"R": np.eye(3)}, "R₀=Rx(2)": {"R": Rotation.from_rotvec([2.0, 0.0, 0.0]).as_matrix()}},
        "angle between R(t) and its closed form",
        straight_roll_error,
        "v = (v_max, 0), a straight roll",
    ),
}
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


def run_episode(bench, integrator, options, start, pendulum):
    """One episode at constant control: (drift, env step times, Pendulum step times) in s."""
    env = gym.make(bench.env_id, integrator=integrator, **options).unwrapped
    info0 = env.reset(options={"state": start})[1]
    action = np.zeros(env.action_space.shape, np.float32)
    action[0] = 1.0
    pendulum_action, drift = np.array([0.0], np.float32), 0.0
    swing_times, pendulum_times = np.empty(STEPS), np.empty(STEPS)
    clock = time.perf_counter
    for i in range(STEPS):
        start = clock()
        pendulum.step(pendulum_action)
        middle = clock()
        _, _, _, _, info = env.step(action)
        end = clock()
        pendulum_times[i], swing_times[i] = middle - start, end - middle
        drift = max(drift, bench.drift(env, info0, info))
    env.close()
    return drift, swing_times, pendulum_times


def describe(options):
    if "substeps" in options:
        return f"substeps={options['substeps']}"
    if options:
        return f"rtol={options['rtol']:.0e} atol={options['atol']:.0e}"
    return "closed form"


def main(argv=None):
    parser = cli.ArgumentParser(prog="python -m connenv.bench steppers", description=__doc__.split("\n")[0])
    parser.add_argument("--env", choices=sorted(BENCHES), default="swing")
    parser.add_argument("--quick", action="store_true", help="only the first start (half the time)")
    parser.add_argument("--integrators", nargs="+", choices=INTEGRATORS, metavar="NAME", help="only these integrators")
    args = parser.parse_args(argv)
    bench = BENCHES[args.env]
    starts = dict(list(bench.starts.items())[:1]) if args.quick else bench.starts

    print(f"connenv.bench  {datetime.datetime.now().isoformat(timespec='seconds')}")
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"gymnasium {gym.__version__}, {os.cpu_count()} cores, {platform.machine()}, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    dt = gym.make(bench.env_id).unwrapped.dt
    print(
        f"{bench.env_id} (unwrapped), {STEPS} steps of dt = {dt} s at action +1 ({bench.control}), from "
        f"{', '.join(starts)}; drift = max over the episode of the {bench.measure}; "
        f"time = median µs per env.step; ratio = that / median of Pendulum-v1 steps interleaved with it\n"
    )
    pendulum = gym.make("Pendulum-v1").unwrapped
    pendulum.reset(seed=0)

    drifts = [f"drift {name}" for name in starts]
    header = ["integrator", "options", "µs/step", "× Pendulum-v1", *drifts, "pass"]
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    results, all_pendulum_times, t_start = [], [], time.perf_counter()
    for integrator, options in candidates():
        if args.integrators and integrator not in args.integrators:
            continue
        drifts, swing_times, pendulum_times = [], [], []
        try:
            for start in starts.values():
                drift, swing, pend = run_episode(bench, integrator, options, start, pendulum)
                drifts.append(drift)
                swing_times.append(swing)
                pendulum_times.append(pend)
        except ValueError:  # a stepper this env cannot take
            continue
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
