"""The Kapitza pendulum's step limit: the largest step that still holds the pendulum inverted and agrees with
the exact motion, against the vibration frequency ω, in the env and for a smooth vibration.

    python docs/kapitza_sampling.py [--quick]

The pivot vibrates vertically, u₂ = a cos ωt, a = 0.05 l (the amplitude of the issue's threshold test), at
a²ω² = r × 2 g l for several margins r. From θ = π + 0.1 at rest, each method runs T = 2 s at each step of
a geometric grid up to ω dt = π, largest first, and the table gives the largest step that *holds* (|θ − π| ≤ 0.3
throughout, finite) and that *agrees* (holds, and θ stays within 0.01 rad of the reference).

1. The env (KapitzaPendulum-v0, v_max raised so that the pivot can follow): the pivot moves along the chords
   of the cosine at constant velocity over each control step dt, and each stepper integrates those segments;
   the reference is the exact stepper at the same dt. A segment at constant pivot velocity is a uniformly
   moving frame in which the rod is a plain pendulum: nothing fast is left inside it.
2. A smooth vibration integrated directly, Newton's θ̈ = −(g + ü₂(t)) sin θ / l with ü₂ = −aω² cos ωt inside
   the step, by the explicit Euler, semi-implicit Euler (the classic-control integrators) and RK4 steps, written
   here because the core's steppers take u̇ constant over a segment; the reference is DOP853 at rtol 1e-10.

`python -m connenv.bench stability --env kapitza` maps the env's steppers up to 4 steps a vibration period;
this script goes on to the sampling limit itself, sets it beside the smooth vibration, and measures the
reference controller's regime. Writes docs/kapitza_sampling.csv and docs/kapitza_sampling.png.
"""

from __future__ import annotations

import argparse
import csv
import math
from functools import partial
from pathlib import Path

import gymnasium as gym
import numpy as np
from scipy.integrate import solve_ivp

import connenv  # noqa: F401
from connenv.core import StepperError

CASES = [(0.05, margin) for margin in (1.5, 3.0, 10.0, 30.0, 100.0)] + [(0.08, 3.0)]  # (a in m, a²ω²/(2 g l))
CONTROLLER = (0.08, 3.0)  # the reference controller's vibration: a = 0.8 a_max, three times the threshold
DT_GRID = np.geomspace(0.05, 1e-5, 26)  # largest first
DURATION = 2.0  # s
STEPPERS = {
    "env: exact": {},
    "env: rk4 ×1": {"integrator": "rk4", "substeps": 1},
    "env: dop853 1e-6": {"integrator": "dop853", "rtol": 1e-6, "atol": 1e-8},
}
G, L = 9.81, 1.0
OUT = Path(__file__).parent


def run_env(stepper: dict, a: float, omega: float, dt: float) -> np.ndarray | None:
    """θ after each step of the env driven along the chords of a cos ωt, or None if the stepper raised."""
    env = gym.make(
        "connenv/KapitzaPendulum-v0", dt=float(dt), v_max=1e4, tolerance=3.1, max_episode_steps=10**7, **stepper
    ).unwrapped
    env.reset(options={"state": {"theta": math.pi + 0.1}})
    steps = round(DURATION / dt)
    samples = a * np.cos(omega * dt * np.arange(steps + 1))
    thetas = np.empty(steps)
    try:
        for k in range(steps):
            env.step(np.array([(samples[k + 1] - samples[k]) / dt / env.v_max], np.float32))
            thetas[k] = env.state.y[0]
    except StepperError:
        return None
    return thetas


def newton(a, omega):
    """(θ, θ̇)′ for the smooth vertical vibration u₂ = a cos ωt."""
    return lambda t, theta, theta_dot: (theta_dot, -(G - a * omega**2 * math.cos(omega * t)) * math.sin(theta) / L)


def euler(f, t, y, h):
    d = f(t, *y)
    return y[0] + h * d[0], y[1] + h * d[1]


def semi_implicit_euler(f, t, y, h):
    theta_dot = y[1] + h * f(t, *y)[1]
    return y[0] + h * theta_dot, theta_dot


def rk4(f, t, y, h):
    k1 = f(t, *y)
    k2 = f(t + h / 2, y[0] + h / 2 * k1[0], y[1] + h / 2 * k1[1])
    k3 = f(t + h / 2, y[0] + h / 2 * k2[0], y[1] + h / 2 * k2[1])
    k4 = f(t + h, y[0] + h * k3[0], y[1] + h * k3[1])
    return tuple(y[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]) for i in range(2))


SMOOTH = {"smooth: euler": euler, "smooth: semi-implicit euler": semi_implicit_euler, "smooth: rk4": rk4}


def run_smooth(method, a: float, omega: float, h: float) -> np.ndarray | None:
    """θ after each step h of a fixed-step method on the smooth vibration, or None if it left the reals."""
    f, y, steps = newton(a, omega), (math.pi + 0.1, 0.0), round(DURATION / h)
    thetas = np.empty(steps)
    with np.errstate(all="ignore"):
        for k in range(steps):
            y = method(f, k * h, y, h)
            if not math.isfinite(y[0]) or abs(y[0] - math.pi) > 10:
                return None
            thetas[k] = y[0]
    return thetas


def smooth_reference(a: float, omega: float, h: float) -> np.ndarray:
    f = newton(a, omega)
    steps = round(DURATION / h)
    t = h * np.arange(1, steps + 1)
    solution = solve_ivp(lambda t, y: f(t, *y), (0, t[-1]), [math.pi + 0.1, 0.0], t_eval=t, rtol=1e-10, atol=1e-12)
    return solution.y[0]


def largest_step(run, reference, omega) -> tuple[float, float]:
    """(largest step that holds, largest step that agrees with the reference): scanning from the largest step
    down to the first that agrees, the largest from which every smaller step held, and that one. Steps beyond
    ω h = π, two samples a period, are left out: there the chords alias to a slower motion."""
    holds = 0.0
    for h in DT_GRID[DT_GRID * omega <= math.pi]:
        thetas = run(h)
        held = thetas is not None and bool(np.all(np.abs(thetas - math.pi) <= 0.3))
        holds = (holds or h) if held else 0.0
        if held and np.max(np.abs(thetas - reference(h))) <= 0.01:
            return holds, h
    return holds, 0.0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="two margins only")
    args = parser.parse_args(argv)
    cases = CASES[:2] if args.quick else CASES
    rows = []
    print(f"l = {L} m, T = {DURATION} s; step grid {DT_GRID[0]:.2g}..{DT_GRID[-1]:.2g} s ({len(DT_GRID)} steps)")
    print("| method | a (m) | a²ω²/(2gl) | ω (rad/s) | largest step that holds (s) | ω·dt | that agrees (s) | ω·dt |")
    print("|---|---|---|---|---|---|---|---|")
    for a, margin in cases:
        omega = math.sqrt(2 * margin * G * L) / a
        methods = {name: partial(run_env, stepper, a, omega) for name, stepper in STEPPERS.items()}
        methods |= {name: partial(run_smooth, method, a, omega) for name, method in SMOOTH.items()}
        for name, method in methods.items():
            smooth = name.startswith("smooth")
            reference = partial(smooth_reference, a, omega) if smooth else partial(run_env, {}, a, omega)
            holds, agrees = largest_step(method, reference, omega)
            row = {"method": name, "a": a, "margin": margin, "omega": omega, "dt_holds": holds, "dt_agrees": agrees}
            rows.append(row)
            print(
                f"| {name} | {a:g} | {margin:g} | {omega:.1f} | {holds:.2g} | {omega * holds:.2f} | {agrees:.2g} "
                f"| {omega * agrees:.2f} |",
                flush=True,
            )
    with open(OUT / "kapitza_sampling.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows)


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for i, name in enumerate([*STEPPERS, *SMOOTH]):
        mine = [r for r in rows if r["method"] == name and r["a"] == 0.05]
        omega = [r["omega"] for r in mine]
        ax.loglog(omega, [r["dt_agrees"] for r in mine], "o-", color=f"C{i}", label=name)
        ax.loglog(omega, [r["dt_holds"] for r in mine], "x:", color=f"C{i}", alpha=0.6)
    omega = np.array([r["omega"] for r in rows if r["method"] == "env: exact" and r["a"] == 0.05])
    ax.loglog(omega, math.pi / omega, "k--", lw=0.8, label="ω dt = π (two samples a period)")
    ax.axhline(0.005, color="grey", lw=0.8)
    ax.text(omega[0], 0.0053, "default dt = 5 ms", color="grey", fontsize=8)
    a, margin = CONTROLLER
    controller = math.sqrt(2 * margin * G * L) / a
    ax.plot([controller], [0.005], "k*", ms=10, label=f"reference controller (a = {a} l, dt = 5 ms)")
    ax.set_xlabel("vibration frequency ω (rad/s), a = 0.05 l")
    ax.set_ylabel("largest stable dt (s)")
    ax.set_title("Kapitza pendulum: largest step within 0.01 rad (o) / still inverted (x)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "kapitza_sampling.png", dpi=120)


if __name__ == "__main__":
    main()
