"""What the benchmarks share: the header line, timed episodes beside Pendulum-v1, the stepper candidates, and the
output folder."""

from __future__ import annotations

import datetime
import os
import platform
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import scipy

import connenv  # noqa: F401  (registers the envs)
from connenv import cli
from connenv.envs.spec import Spec, registry

OUTPUT = Path(__file__).resolve().parents[2] / "docs" / "precision"
ATOL_PER_RTOL = 1e-2  # atol = rtol · 1e-2 for the scipy methods


def header(name: str):
    print(f"connenv.bench {name}  {datetime.datetime.now().isoformat(timespec='seconds')}")
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"gymnasium {gym.__version__}, {os.cpu_count()} cores, {platform.machine()}, "
        f"load average {os.getloadavg()[0]:.2f}",
        flush=True,
    )


def parse_chart_args(kind: str, description: str, names: list[str], quick: str, argv=None):
    """The arguments of ``python -m connenv.bench <kind>``: the charts to draw (--env) and --quick."""
    parser = cli.ArgumentParser(prog=f"python -m connenv.bench {kind}", description=description)
    parser.add_argument("--env", nargs="+", choices=sorted(names), default=names)
    parser.add_argument("--quick", action="store_true", help=quick)
    return parser.parse_args(argv)


def draw_charts(kind: str, names, draw):
    """Draw each named chart, ``draw(name) -> (rows, csv path, png path)``, saying what it wrote and the wall time."""
    header(kind)
    OUTPUT.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    for name in names:
        _, csv_path, png_path = draw(name)
        print(f"wrote {csv_path.relative_to(OUTPUT.parents[1])}, {png_path.relative_to(OUTPUT.parents[1])}")
    print(f"\nwall time: {time.perf_counter() - start:.0f} s")


def pendulum():
    """Gymnasium's Pendulum-v1, unwrapped and reset: the reference step timed beside every env step."""
    env = gym.make("Pendulum-v1").unwrapped
    env.reset(seed=0)
    return env


def bench_spec(key: str) -> Spec:
    """The Spec of the env whose cases are `key` in the benchmarks' tables (its ``bench``): the tables name an env
    by that key and read its id from the spec, so that the env's id is written in one place."""
    found = [spec for spec in registry.values() if spec.bench == key]
    if len(found) != 1:
        raise KeyError(f"bench key {key!r} names {len(found)} registered specs, not 1")
    return found[0]


def env_id(key: str) -> str:
    """The id of the env whose cases are `key` (`bench_spec`)."""
    return bench_spec(key).id


def describe(integrator: str, options: dict) -> str:
    if "substeps" in options:
        return f"{integrator} ×{options['substeps']}"
    if "rtol" in options:
        return f"{integrator} rtol {options['rtol']:.0e}"
    if "atol" in options:
        return f"{integrator} atol {options['atol']:.0e}"
    return integrator


def candidates(rtols=(1e-4, 1e-6, 1e-8, 1e-10, 1e-12)):
    """(integrator, make kwargs) of every stepper charted: the exact step, the two Euler methods of Gymnasium's
    classic control, RK4, and scipy's DOP853, LSODA and Radau (Radau, implicit and slow on these non-stiff
    problems, at its three loosest tolerances only)."""
    yield "exact", {}
    for integrator in ("euler", "semi_implicit_euler"):
        for substeps in (1, 4, 16):
            yield integrator, {"substeps": substeps}
    for substeps in (1, 2, 4, 8):
        yield "rk4", {"substeps": substeps}
    for integrator, tolerances in (("dop853", rtols), ("lsoda", rtols[1:]), ("radau", rtols[1:4])):
        for rtol in tolerances:
            yield integrator, {"rtol": rtol, "atol": rtol * ATOL_PER_RTOL}


def make_env(env_id: str, integrator: str | None, options: dict, **kwargs):
    """The unwrapped env with that stepper (None: its default), or None where the env refuses the stepper."""
    try:
        stepper = {} if integrator is None else {"integrator": integrator, **options}
        return gym.make(env_id, **kwargs, **stepper).unwrapped
    except ValueError:
        return None


def run(env, reset_options, actions, reference=None, measure=None, clock_against=None):
    """Reset env and step it through `actions`; with `clock_against` (Pendulum-v1) each env step is timed right
    after one of its steps. `measure(env, info)` is called after every step. Returns (step times, Pendulum
    times, error message or None); a StepperError ends the episode (its step is timed too) and its message is
    returned."""
    from connenv.core import StepperError

    env.reset(seed=0, options=reset_options)
    times, reference_times = [], []
    clock, still = time.perf_counter, np.array([0.0], np.float32)
    failure = None
    for action in actions:
        if clock_against is not None:
            start = clock()
            clock_against.step(still)
        middle = clock()
        try:
            info = env.step(action)[4]
        except StepperError as error:
            failure = str(error)
        end = clock()
        times.append(end - middle)
        if clock_against is not None:
            reference_times.append(middle - start)
        if failure:
            break
        if measure is not None:
            measure(env, info)
    return np.array(times), np.array(reference_times), failure


def beanie_balance(env, info, start):
    """|(I₁ + I₂)(θ − θ₀) + I₂ (ψ − ψ₀) − μ t| / (I₁ + I₂): the momentum balance integrated, rad."""
    s, s0 = info["state"], start["state"]
    total = env.body_inertia + env.beanie_inertia
    balance = total * (s["theta"] - s0["theta"]) + env.beanie_inertia * (s["psi"] - s0["psi"]) - s["momentum"] * s["t"]
    return abs(balance) / total
