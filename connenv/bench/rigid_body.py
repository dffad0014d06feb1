"""The free rigid body (connenv.systems.rigid_body, a system without an env) in the work–precision chart and the
stability map: ``python -m connenv.bench precision --env rigid_body`` and ``stability --env rigid_body``.

Precision: the body I = (1, 2, 2.5) kg m², |M| = 1, R(0) = I, 60 steps of dt = 0.5 s (about one period of M),
from M(0) on the plane M₂ = 0 at two energies: midway between the separatrix and the axis of largest inertia
(2E = (1/I₂ + 1/I₃)/2) and near the separatrix (M² = 2 E I₂ (1 + 1e-4)). Reference: the exact flow with Magnus
pieces of at most 0.005 rad. State error: max of the angle between R and R_ref (rad) and |M − M_ref|/|M| at the
end. Invariant: max over the episode of |E − E(0)|/E(0) and |RM − m(0)|/|M| (the spatial momentum). Steppers: the
exact flow (the default, Magnus pieces of at most ``max_turn``), Strang's splitting, RK4 and DOP853; each step is
``advance(body, y, dt, stepper)``, timed right after a step of Gymnasium's Pendulum-v1.

Stability: a slender body I = (I₃/λ, I₃ − I₃/(2λ), I₃), I₃ = 1, λ = I₃/I₁ the parameter, from M(0) = (1, 1, 1)/√3
for 10 s: |ω₁| = |M₁|/I₁ grows with λ; bounded: |E − E(0)| ≤ 0.1 E(0), |RM − m(0)| ≤ 0.1 |M| and ‖RᵀR − I‖ ≤ 0.1
at every step, and no StepperError.
"""

from __future__ import annotations

import math
import time

import numpy as np

from connenv.bench.charts import (
    DIVERGED,
    Case,
    Episode,
    StabilityMap,
    cell,
    pareto,
    plot_precision,
    plot_stability,
    top_of,
    write_precision_csv,
    write_stability_csv,
)
from connenv.bench.common import describe as common_describe
from connenv.bench.common import pendulum
from connenv.core import StepperError
from connenv.systems.rigid_body import RigidBody, advance, make_stepper, state
from connenv.systems.rolling_ball import rotation_angle

INERTIA = (1.0, 2.0, 2.5)
DT, STEPS = 0.5, 60
DEFAULT = ("exact", {"max_turn": RigidBody.max_turn})
REFERENCE_TURN = 0.005
CANDIDATES = (
    *(("exact", {"max_turn": turn}) for turn in (0.8, 0.4, 0.2, 0.1, 0.05, 0.025)),
    *(("splitting", {"substeps": n}) for n in (1, 4, 16, 64)),
    *(("rk4", {"substeps": n}) for n in (1, 2, 4, 8)),
    *(("dop853", {"rtol": rtol, "atol": rtol * 1e-2}) for rtol in (1e-6, 1e-8, 1e-10, 1e-12)),
)


def start(inertia, two_E):
    """|M| = 1 on the plane M₂ = 0 with Σ M_i²/I_i = 2E."""
    I1, _, I3 = inertia
    x = (1.0 / I3 - two_E) / (1.0 / I3 - 1.0 / I1)
    return np.array([math.sqrt(x), 0.0, math.sqrt(1.0 - x)])


EPISODES = {
    "between": start(INERTIA, 0.5 * (1.0 / INERTIA[1] + 1.0 / INERTIA[2])),
    "near separatrix": start(INERTIA, 1.0 / (INERTIA[1] * (1.0 + 1e-4))),
}


def describe(integrator, options):
    if integrator == "exact":
        return f"exact max_turn {options['max_turn']:g}"
    return common_describe(integrator, options)


def body_and_stepper(integrator, options, inertia=INERTIA):
    """(RigidBody, stepper): the exact flow's option max_turn belongs to the body."""
    if integrator == "exact":
        return RigidBody(inertia, options["max_turn"]), make_stepper("exact")
    return RigidBody(inertia), make_stepper(integrator, **options)


def invariants_drift(body, y, start):
    E, norm, m = body.invariants(y)
    E0, norm0, m0 = body.invariants(start)
    return max(abs(E - E0) / E0, float(np.linalg.norm(m - m0)) / norm0)


def episode(integrator, options, M0, steps, clock=None):
    """(final y, max drift, step times, Pendulum-v1 step times, failure or None)."""
    body, stepper = body_and_stepper(integrator, options)
    y0 = y = state(M0)
    times, reference_times, drift, still = [], [], 0.0, np.array([0.0], np.float32)
    for _ in range(steps):
        if clock is not None:
            begin = time.perf_counter()
            clock.step(still)
        middle = time.perf_counter()
        try:
            y = advance(body, y, DT, stepper)
        except StepperError as error:
            return y, math.inf, times, reference_times, str(error)
        end = time.perf_counter()
        times.append(end - middle)
        if clock is not None:
            reference_times.append(middle - begin)
        drift = max(drift, invariants_drift(body, y, y0))
    return y, drift, times, reference_times, None


def state_error(y, reference):
    R, R_ref = y[3:].reshape(3, 3), reference[3:].reshape(3, 3)
    return max(float(rotation_angle(R @ R_ref.T)), float(np.linalg.norm(y[:3] - reference[:3])))


def precision_chart(folder, fraction=1.0, steppers=None):
    """Measure, print, and write rigid_body_precision.csv and .png into folder (the env charts' format)."""
    steps = max(round(STEPS * fraction), 1)
    case = Case(
        "free rigid body (connenv.systems.rigid_body)",
        ("exact", {"max_turn": REFERENCE_TURN}),
        tuple(Episode(label, {}, None, STEPS) for label in EPISODES),
        None,
        "max |E − E(0)|/E(0), |RM − m(0)|/|M|",
        None,
        "rad",
    )
    clock = pendulum()
    labels = list(EPISODES)
    print(f"\n{case.env_id}: I = {INERTIA}, dt = {DT} s, " + ", ".join(f"{label} ({steps} steps)" for label in labels))
    print(f"| stepper | µs/step | × Pendulum-v1 | {' | '.join(f'error {label}' for label in labels)} | drift |")
    print("|---|---|---|" + "---|" * len(labels) + "---|")
    references = {label: episode(*case.reference, M0, steps)[0] for label, M0 in EPISODES.items()}
    rows = []
    for integrator, options in steppers or CANDIDATES:
        row = {"integrator": integrator, "options": describe(integrator, options), "diverged": "", "errors": {}}
        row["drift"] = 0.0
        for k, (label, M0) in enumerate(EPISODES.items()):
            y, drift, times, pendulum_times, failure = episode(integrator, options, M0, steps, clock)
            if k == 0:
                row["us_per_step"] = float(np.median(times) * 1e6)
                row["ratio"] = float(np.median(times) / np.median(pendulum_times))
                row["pendulum_us"] = float(np.median(pendulum_times) * 1e6)
            row["errors"][label] = DIVERGED if failure else state_error(y, references[label])
            row["drift"] = max(row["drift"], drift)
            row["diverged"] = row["diverged"] or (f"{label}: {failure}" if failure else "")
        row["error"] = max(row["errors"].values())
        row["default"] = (integrator, options) == DEFAULT
        rows.append(row)
        cells = [f"{row['errors'][label]:.1e}" for label in labels] + [f"{row['drift']:.1e}"]
        print(f"| {row['options']} | {row['us_per_step']:.0f} | {row['ratio']:.1f} | " + " | ".join(cells) + " |",
              flush=True)  # fmt: skip
    pareto(rows)
    print(f"Pendulum-v1: median {np.median([r['pendulum_us'] for r in rows]):.1f} µs/step over the rows' medians")
    front = sorted((r for r in rows if r["pareto"]), key=lambda r: r["ratio"])
    print("Pareto front: " + ", ".join(r["options"] for r in front))
    default = next(r for r in rows if r["default"])
    verdict = "on the Pareto front" if default["pareto"] else "NOT on the Pareto front"
    print(
        f"default: {default['options']}: error {default['error']:.2e} rad, drift {default['drift']:.2e}, "
        f"{default['us_per_step']:.0f} µs/step, {default['ratio']:.1f}× Pendulum-v1: {verdict}"
    )
    csv_path = write_precision_csv("rigid_body", case, rows, folder)
    return rows, csv_path, plot_precision("rigid_body", case, rows, folder, fraction)


STABILITY_DURATION = 10.0  # s
BOUND = 0.1


def slender(ratio):
    """I = (I₃/λ, I₃ − I₃/(2λ), I₃), I₃ = 1: I₁ < I₂ < I₃ = I₁ + I₂ − I₁/2 ≤ I₁ + I₂ for λ > 1.5."""
    return (1.0 / ratio, 1.0 - 0.5 / ratio, 1.0)


def stays_bounded(ratio, integrator, options, dt):
    body, stepper = body_and_stepper(integrator, options, slender(ratio))
    y0 = y = state(np.ones(3) / math.sqrt(3.0))
    try:
        for _ in range(math.ceil(STABILITY_DURATION / dt - 1e-9)):
            y = advance(body, y, dt, stepper)
            R = y[3:].reshape(3, 3)
            if invariants_drift(body, y, y0) > BOUND or np.linalg.norm(R.T @ R - np.eye(3)) > BOUND:
                return False
    except StepperError:
        return False
    return True


STABILITY_RATIOS = (2.0, 10.0, 100.0, 1000.0)
STABILITY_METHODS = (
    ("exact", {"max_turn": RigidBody.max_turn}),
    ("splitting", {"substeps": 1}),
    ("rk4", {"substeps": 1}),
    ("dop853", {"rtol": 1e-8, "atol": 1e-10}),
)


def stability_chart(folder, smallest=1e-4, values=None, methods=None):
    """Measure, print, and write rigid_body_stability.csv and .png into folder (the env maps' format)."""
    values = values or STABILITY_RATIOS
    grid = [10 ** (-k / 4) for k in range(0, 1 + round(-4 * math.log10(smallest)))]
    stability_map = StabilityMap(
        "free rigid body (connenv.systems.rigid_body)", "slenderness I₃/I₁", values, *(None,) * 5, methods or ()
    )
    print(f"\n{stability_map.env_id}: largest stable dt (s) against {stability_map.parameter}")
    print("| method | " + " | ".join(f"{v:g}" for v in values) + " |")
    print("|---|" + "---|" * len(values))
    rows = {}
    for integrator, options in methods or STABILITY_METHODS:
        method = describe(integrator, options)
        rows[method] = {
            value: next((dt for dt in grid if stays_bounded(value, integrator, options, dt)), 0.0) for value in values
        }
        cells = [cell(dt, top_of(stability_map, value, grid), grid) for value, dt in rows[method].items()]
        print(f"| {method} | " + " | ".join(cells) + " |", flush=True)
    path = write_stability_csv("rigid_body", stability_map, rows, grid, folder)
    return rows, path, plot_stability("rigid_body", stability_map, rows, grid, folder)
