"""Work–precision of ActiveConstraintEnv's steppers on systems given by their Lagrangian: the measurement behind its
default (DOP853 at rtol 1e-10).

    python -m connenv.bench generic [--quick]

Episodes, each 200 steps of seeded random actions (dt = 0.05 s) from a fixed state:

- swing: T = ½ (ṙ² + r² θ̇²), V = −g r cos θ, r ∈ [1.6, 2] jumping to the command (strongly fit), θ₀ = 1;
- bead: T = ½ (ṙ² + r² θ̇²), V = g r sin θ, the bar's angle θ ∈ [−1, 1] at θ̇ = a · 1 rad/s (general), r₀ = 0.3.

Error: max |y − y_ref| / (1 + max |y_ref|) over (q, p) at the end, the reference DOP853 at rtol 1e-13, atol 1e-15.
Cost: evaluations of the vector field per step, which a busy machine does not blur, and the median µs of env.step
with its ratio to Pendulum-v1's timed beside it. The printout marks the steppers on the Pareto front of
(evaluations, error).
"""

from __future__ import annotations

import argparse

import numpy as np
import sympy as sp

from connenv import cli
from connenv.bench.common import describe, header, pendulum, run
from connenv.envs.active_constraint import ActiveConstraintEnv

G = 9.81
r, r_dot, theta, theta_dot = sp.symbols("r r_dot theta theta_dot")
T = (r_dot**2 + r**2 * theta_dot**2) / 2
SYSTEMS = {  # (kinetic, potential, q, u), make kwargs, reset state
    "swing": ((T, -G * r * sp.cos(theta), [theta], [r]), {"u_low": 1.6, "u_high": 2.0}, {"q": [1.0]}),
    "bead": (
        (T, G * r * sp.sin(theta), [r], [theta]),
        {"u_low": -1.0, "u_high": 1.0, "max_control_speed": 1.0},
        {"q": [0.3]},
    ),
}
TIGHT = {"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}
CANDIDATES = [("rk4", {"substeps": s}) for s in (1, 2, 4, 8, 16)] + [
    ("dop853", {"rtol": rtol, "atol": rtol * 1e-2}) for rtol in (1e-6, 1e-8, 1e-10, 1e-12)
]


def measure(name, steps):
    (kinetic, potential, q, u), kwargs, start = SYSTEMS[name]
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, 1))
    reference = ActiveConstraintEnv.from_lagrangian(kinetic, potential, q, u, **kwargs, **TIGHT)
    run(reference, {"state": start}, actions)
    clock = pendulum()
    rows = []
    for integrator, options in CANDIDATES:
        env = ActiveConstraintEnv.from_lagrangian(kinetic, potential, q, u, **kwargs, integrator=integrator, **options)
        env.field = Counting(env.field)
        times, pendulum_times, failure = run(env, {"state": start}, actions, clock_against=clock)
        error = np.max(np.abs(env.state.y - reference.state.y)) / (1.0 + np.max(np.abs(reference.state.y)))
        ratio = np.median(times) / np.median(pendulum_times)
        label = describe(integrator, options)
        rows.append((label, env.field.calls / steps, np.median(times) * 1e6, ratio, np.inf if failure else error))
    return rows


class Counting:
    """A system whose vector field counts its calls."""

    def __init__(self, system):
        self.system, self.n, self.calls = system, system.n, 0

    def vector_field(self, y, u, u_dot):
        self.calls += 1
        return self.system.vector_field(y, u, u_dot)


def main(argv=None):
    parser = cli.ArgumentParser(
        prog="python -m connenv.bench generic",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--quick", action="store_true", help="50 steps instead of 200")
    args = parser.parse_args(argv)
    header("generic")
    for name in SYSTEMS:
        rows = measure(name, 50 if args.quick else 200)
        columns = f"{'stepper':<18} {'evals/step':>10} {'µs/step':>9} {'× Pendulum':>11} {'rel. error':>11}  front"
        print(f"\n{name}: {columns}")
        for label, calls, us, ratio, error in rows:
            front = not any(o[1] <= calls and o[4] < error or o[1] < calls and o[4] <= error for o in rows)
            mark = "*" if front else ""
            print(f"{'':<{len(name) + 2}}{label:<18} {calls:10.1f} {us:9.0f} {ratio:11.1f} {error:11.1e}  {mark}")


if __name__ == "__main__":
    main()
