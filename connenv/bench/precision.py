"""Work–precision charts: for every stepper, the time per env step against the state error after a fixed episode
and the drift of the invariant, one chart per env (docs/precision/<env>_precision.png and .csv).

    python -m connenv.bench precision [--env swing skier ball kapitza shell bead connection coin beanie coin_surface
                                       coin_plane tube snake sleigh cat rigid_body] [--quick]

Each env runs the same episodes under every candidate stepper (`connenv.bench.common.candidates`). A case's key
is the ``bench`` of its env's Spec, from which its id is read (`connenv.bench.common.bench_spec`); coin_plane is
the coin_surface env's:

- swing: from rest at θ₀ = π/2, 500 steps (25 s) at action +1 (r = r_max); reference: the closed-form
  flow. State error: |θ − θ_ref| at the end (rad). Invariant: max |E(t) − E(0)| / (m g r), E conserved at held r.
- skier: from rest at x₀ = 5.5 m, near the rim, standing (h = h_max), 500 steps at action +1;
  reference: DOP853 at rtol 1e-13, atol 1e-15. State error: |x − x_ref| at the end (m). Invariant:
  max |E(t) − E(0)| / (m g H), H = 3 m the valley's depth.
- ball: from R = I, 200 steps (one episode) of seeded random velocities; reference: the exact
  step, exact for every piecewise-constant velocity. State error: the angle between R and R_ref at the end
  (rad). Invariant: max ‖RᵀR − I‖ over the episode (orthogonality).
- kapitza: dt = 0.005 s, from θ₀ = π + 0.1, the pivot vibrated vertically, u₂ = a cos ωt
  with a = 0.05 m, ω = 150 rad/s (inverted is stable: a²ω² > 2 g l), each step's velocity the chord between
  samples, 400 steps (2 s); reference: the exact step. State error: |θ − θ_ref| at the end (rad). Invariant:
  the env's energy error, the change of E in the pivot's frame over the segments of constant u̇, max over the
  episode in units of m g l.
- shell: 300 steps of seeded random mass positions, from rest (the reduced model, the default
  episode) and from the body momentum (0.3, 0.1, 0.05) (the full Kirchhoff model); reference: DOP853 at rtol
  1e-13, atol 1e-15. State error: max-norm of the pose (x, y, θ) error at the end (m, rad), for each model.
  Invariant: max |S(t) − S(0)| / |S(0)| of the spatial momentum S in the full model. Besides the common
  candidates, the Magnus step (`integrator="magnus"`: the reduced model's connection; DOP853 on the full model).
- coin: from the origin, 200 steps (one episode) of seeded random rates; reference: the exact
  step (the chord of each arc). State error: |(x, y) − the reference's| at the end (m). Invariant: the largest
  distance of the track from the reference's over the episode (m): rolling has no conserved quantity.
- beanie: at μ = 0.7, 200 steps of seeded random beanie speeds; reference: the exact step.
  State error: |θ − θ_ref| at the end (rad). Invariant: the integrated momentum balance
  |(I₁ + I₂)(θ − θ₀) + I₂ (ψ − ψ₀) − μ t| / (I₁ + I₂) (rad), 0 for the flow.
- bead: from rest at r₀ = −0.5 m, θ₀ = 0, 300 steps (6 s) of the actions that a tilt law
  (θ̇ = 9 (θ_d − θ), sin θ_d = (3 (r − r*) + 3 ṙ)/g, r* = 0.5 m) takes on the exact step, replayed open loop;
  reference: DOP853 at rtol 1e-13, atol 1e-15. State error: |r − r_ref| at the end (m). Invariant: none holds
  while the bar turns, so the second panel is max |r(t) − r_ref(t)| over the episode (m).
- tube: from R = I, 200 steps (one episode) of seeded random bending rates; reference: the exact
  step (one exponential per step, exact for piecewise-constant rates). State error: the angle between R and R_ref
  at the end (rad). Invariant: max ‖RᵀR − I‖ over the episode. Besides the common candidates, the builder's Magnus
  step.
- cat: from R = I, straight, 200 steps of seeded random bend velocities (fall_time 2 s, so that the
  cat does not land), the bend stopping at max_bend; reference: the exact step (Gauss–Legendre on the roll's
  integral, exact to rounding). State error: the angle between g and g_ref at the end (rad). Invariant: max
  ‖gᵀg − I‖ over the episode. Besides the common candidates, the builder's Magnus step.
- snake: 300 steps of seeded random joint commands, from rest (the reduced model) and from the
  body momentum (0.3, 0.1, 0.05) (the full model), as the shell's; the same reference, errors and invariant. Of the
  Magnus step only the default (atol 1e-12; DOP853 at rtol 1e-10 on the full model): the rule it fixes for the
  reduced model is the same over the usual range of atol (docs/physics/SnakeSwimmer.md, measured by this bench), so
  rows of other atol would differ only in DOP853's atol on the full model.
- connection: on SO(3), body frame, the non-flat connection `twisted`, 300 steps of seeded random
  shape velocities within [-1, 1]²; reference: DOP853 at rtol 1e-13 on ġ = g ξ^ in coordinates. State error:
  max |R − R_ref| over the entries at the end. Invariant: max ‖RᵀR − I‖ over the episode (orthogonality).
- coin_surface: on its default hill, from rest at the start with θ₀ = 0.3, 200 steps (10 s) of
  seeded random steering rates; reference: DOP853 at rtol 1e-13, atol 1e-15. State error: |(x, y) − (x, y)_ref| at
  the end (m). Invariant: max |E − E(0)| / (m g Δz), Δz the arena's height range (the env's scale).
- coin_plane: the same on the plane z = −0.25 y (surface="plane"); reference: the exact step.
- sleigh: from v = 1 m/s, ω = 1 rad/s, 300 steps of seeded random mass velocities in the box
  (the mass stops at its walls, where it is held), then 300 steps from v = 1 m/s, ω = 2 rad/s with the mass held
  at u = (0.1, 0.2) m; reference: DOP853 at rtol 1e-13, atol 1e-15. State error: max-norm of the (x, y, φ) error
  at the end (m, rad), for each episode. Invariant: the env's energy error, the change of the kinetic energy T over
  the segments where the mass is held, max over the episodes in units of T at reset.

Time: median µs of env.step over the first episode (the reduced one for the shell), and its ratio to the median
Pendulum-v1 step timed beside it. A stepper that raises StepperError (non-finite, or the env's invariant bound)
is charted as diverged (a red ×, at the top), with the message in the CSV. The Pareto front is taken over
(time ratio, largest state error) among the steppers that did not diverge; the printout says whether each env's
default stepper is on it. The reference's own row has error 0 (charted at 1e-17). --quick runs a fifth of every
episode.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from connenv.bench import rigid_body
from connenv.bench.charts import DIVERGED, Case, Episode, pareto, plot_precision, write_precision_csv
from connenv.bench.common import (
    OUTPUT,
    beanie_balance,
    candidates,
    describe,
    draw_charts,
    env_id,
    make_env,
    parse_chart_args,
    pendulum,
    run,
)
from connenv.systems.rolling_ball import rotation_angle

TIGHT = ("dop853", {"rtol": 1e-13, "atol": 1e-15})
EXACT = ("exact", {})


MAGNUS = tuple(("magnus", {"atol": atol}) for atol in (1e-6, 1e-8, 1e-10, 1e-12))


def twisted(s):
    """A non-flat connection on SO(3) over a 2-D shape space (the connection case's)."""
    return np.array([[1.0 + s[1] ** 2, 0.5], [math.sin(s[0]), 1.0], [0.3, s[0] * s[1]]])


def held(action):
    return lambda steps, rng: np.tile(np.asarray(action, np.float32), (steps, 1))


def uniform(size):
    return lambda steps, rng: rng.uniform(-1.0, 1.0, (steps, size)).astype(np.float32)


def vibration(amplitude, omega, dt, v_max):
    """Actions that move the pivot along u₂ = a cos ωt: each step's velocity is the chord between samples."""

    def actions(steps, rng):
        t = dt * np.arange(steps + 1)
        return (amplitude * np.diff(np.cos(omega * t)) / (dt * v_max)).astype(np.float32)[:, None]

    return actions


KAPITZA_VIBRATION = (0.05, 150.0)  # a (m), ω (rad/s): a²ω² = 56 m²/s² > 2 g l = 19.6, so inverted is stable


def energy_drift(scale):
    def drift(env, info, start):
        return abs(info["energy"] - start["energy"]) / scale(env)

    return drift


def momentum_drift(env, info, start):
    if info["model"] != "full":
        return math.nan
    s0 = np.asarray(start["spatial_momentum"])
    return float(np.linalg.norm(np.asarray(info["spatial_momentum"]) - s0) / np.linalg.norm(s0))


SWIMMER = (
    (
        Episode("reduced", {"state": {}}, uniform(2), 300),
        Episode("full", {"state": {"momentum": (0.3, 0.1, 0.05)}}, uniform(2), 300),
    ),
    lambda env, ref: float(np.max(np.abs(env.state.pose - ref.state.pose))),
    "max |S − S(0)| / |S(0)| (full model)",
    momentum_drift,
    "m, rad",
)
"""The swimmers' (shell's, snake's) episodes from rest and with a momentum, pose error, and momentum drift."""


COIN_SURFACE = (
    (Episode("random θ̇", {"state": {"theta": 0.3}}, uniform(1), 200),),
    lambda env, ref: float(np.hypot(*(env.state.y[:2] - ref.state.y[:2]))),
    "max |E − E(0)| / (m g Δz)",
    energy_drift(lambda env: env.system.mass * env.system.g * env.height_range),
    "m",
)
"""The coin's episode on a surface and on the plane (its reference then the exact step), position error, energy."""


def attitude_gap(env, ref):
    """The angle between the attitudes g (in SO(3)) of the env and the reference env."""
    return float(rotation_angle(env.state.g.reshape(3, 3) @ ref.state.g.reshape(3, 3).T))


def coin_track_error(env, info, start):
    """The distance of the coin from the exact step's track at this step (the episode's seeded actions)."""
    steps = round(info["state"]["t"] / env.dt)
    track = _coin_track(env.dt, max(steps, 1))
    return float(np.hypot(info["state"]["x"] - track[steps - 1, 0], info["state"]["y"] - track[steps - 1, 1]))


_TRACKS: dict = {}


def _coin_track(dt, steps):
    """(x, y) after each of the first `steps` steps of the coin case's episode, by the exact step."""
    key = (dt, "coin")
    if key not in _TRACKS or len(_TRACKS[key]) < steps:
        env = make_env(env_id("coin"), *EXACT)
        env.reset(seed=0, options={"state": {}})
        track = [env.step(a)[4]["state"] for a in uniform(2)(max(steps, 200), np.random.default_rng(0))]
        _TRACKS[key] = np.array([(s["x"], s["y"]) for s in track])
    return _TRACKS[key]


BEAD_START, BEAD_TARGET, BEAD_STEPS = -0.5, 0.5, 300  # m, m, steps
BEAD_EPISODE = {"state": {"r": BEAD_START}, "target": BEAD_TARGET}


def tilt_actions(steps, rng):
    """The actions of the tilt law on the bead's exact step (see the module), as a fixed sequence."""
    env = make_env(env_id("bead"), None, {})
    info = env.reset(seed=0, options=BEAD_EPISODE)[1]
    actions = []
    for _ in range(steps):
        state = info["state"]
        sine = np.clip((3.0 * (state["r"] - BEAD_TARGET) + 3.0 * state["r_dot"]) / env.g, -0.5, 0.5)
        rate = 9.0 * (math.asin(sine) - state["theta"])
        actions.append(np.array([np.clip(rate / env.omega_max, -1.0, 1.0)], np.float32))
        info = env.step(actions[-1])[4]
    return np.array(actions)


@functools.cache
def bead_reference():
    """r(t) after every step of the bead's whole episode under the reference stepper (a shortened episode's
    actions are the first of the whole one's)."""
    env = make_env(env_id("bead"), *TIGHT)
    trajectory = []
    actions = tilt_actions(BEAD_STEPS, None)
    run(env, BEAD_EPISODE, actions, measure=lambda env, info: trajectory.append(info["state"]["r"]))
    return np.array(trajectory)


def bead_drift(env, info, start):
    return abs(info["state"]["r"] - bead_reference()[round(info["state"]["t"] / env.dt) - 1])


CASES = {
    "swing": Case(
        env_id("swing"),
        EXACT,
        (Episode("θ₀=π/2", {"state": {"theta": math.pi / 2, "theta_dot": 0.0}}, held([1.0]), 500),),
        lambda env, ref: abs(env.state.y[0] - ref.state.y[0]),
        "max |E − E(0)| / (m g r)",
        energy_drift(lambda env: env.system.mass * env.system.g * env.state.r),
        "rad",
    ),
    "skier": Case(
        env_id("skier"),
        TIGHT,
        (Episode("x₀=5.5", {"state": {"x": 5.5, "h": 1.0}}, held([1.0]), 500),),
        lambda env, ref: abs(env.state.y[0] - ref.state.y[0]),
        "max |E − E(0)| / (m g H)",
        energy_drift(lambda env: env.system.mass * env.system.g * env.trail.H),
        "m",
        steppers=(
            *(("rk8", {"substeps": n}) for n in (1, 2, 4)),
            *(("rk8_energy", {"substeps": n}) for n in (1, 2)),
            *(("gauss6", {"substeps": n}) for n in (1, 2, 4)),
        ),
    ),
    "ball": Case(
        env_id("ball"),
        EXACT,
        (Episode("random v", {"state": {"R": np.eye(3)}}, uniform(2), 200),),
        lambda env, ref: float(rotation_angle(env.state.R @ ref.state.R.T)),
        "max ‖RᵀR − I‖",
        lambda env, info, start: float(np.linalg.norm(env.state.R.T @ env.state.R - np.eye(3))),
        "rad",
    ),
    "kapitza": Case(
        env_id("kapitza"),
        EXACT,
        (
            Episode(
                "θ₀=π+0.1",
                {"state": {"theta": math.pi + 0.1, "u": (0.0, KAPITZA_VIBRATION[0])}},
                vibration(*KAPITZA_VIBRATION, dt=0.005, v_max=10.0),
                400,
            ),
        ),
        lambda env, ref: abs(env.state.y[0] - ref.state.y[0]),
        "max |energy error| / (m g l)",
        lambda env, info, start: abs(env.state.energy_error) / (env.system.mass * env.system.g * env.system.length),
        "rad",
    ),
    "shell": Case(
        env_id("shell"),
        TIGHT,
        *SWIMMER,
        steppers=MAGNUS,
    ),
    "coin": Case(
        env_id("coin"),
        EXACT,
        (Episode("random rates", {"state": {}}, uniform(2), 200),),
        lambda env, ref: float(np.hypot(*(env.state.g - ref.state.g))),
        "max distance from the exact track (m)",
        coin_track_error,
        "m",
        steppers=MAGNUS,
    ),
    "beanie": Case(
        env_id("beanie"),
        EXACT,
        (Episode("μ=0.7", {"state": {"momentum": 0.7}}, uniform(1), 200),),
        lambda env, ref: abs(env.state.g[0] - ref.state.g[0]),
        "max |momentum balance| / (I₁ + I₂) (rad)",
        beanie_balance,
        "rad",
        steppers=MAGNUS,
    ),
    "bead": Case(
        env_id("bead"),
        TIGHT,
        (Episode("tilt law", BEAD_EPISODE, tilt_actions, BEAD_STEPS),),
        lambda env, ref: abs(env.state.y[0] - ref.state.y[0]),
        "max |r(t) − r_ref(t)| (m)",
        bead_drift,
        "m",
    ),
    "tube": Case(
        env_id("tube"),
        EXACT,
        (Episode("random κ", {"state": {"R": np.eye(3)}}, uniform(2), 200),),
        attitude_gap,
        "max ‖RᵀR − I‖",
        lambda env, info, start: float(np.linalg.norm(info["state"]["R"].T @ info["state"]["R"] - np.eye(3))),
        "rad",
        steppers=MAGNUS,
    ),
    "cat": Case(
        env_id("cat"),
        EXACT,
        (Episode("random ṡ", {"state": {"R": np.eye(3)}}, uniform(2), 200),),
        attitude_gap,
        "max ‖gᵀg − I‖",
        lambda env, info, start: float(env.group.off_group(env.state.g.reshape(3, 3))),
        "rad",
        {"fall_time": 2.0},
        MAGNUS,
    ),
    "snake": Case(
        env_id("snake"),
        TIGHT,
        *SWIMMER,
        steppers=(("magnus", {}),),  # one row: other atol fix the same rule (module docstring)
    ),
    "connection": Case(
        env_id("connection"),
        TIGHT,
        (Episode("random ṡ", {}, uniform(2), 300),),
        lambda env, ref: float(np.max(np.abs(env.state.g - ref.state.g))),
        "max ‖RᵀR − I‖",
        lambda env, info, start: float(env.group.off_group(info["state"]["g"])),
        "",
        {"group": "SO3", "connection": twisted, "shape_low": [-1.0, -1.0], "shape_high": [1.0, 1.0], "dt": 0.1},
        MAGNUS,
    ),
    "coin_surface": Case(env_id("coin_surface"), TIGHT, *COIN_SURFACE),
    "coin_plane": Case(env_id("coin_surface"), EXACT, *COIN_SURFACE, {"surface": "plane"}),
    "sleigh": Case(
        env_id("sleigh"),
        TIGHT,
        (
            Episode("random u̇", {"state": {"v": 1.0, "omega": 1.0}, "target": (100.0, 0.0)}, uniform(2), 300),
            Episode(
                "held",
                {"state": {"v": 1.0, "omega": 2.0, "u_along": 0.1, "u": 0.2}, "target": (100.0, 0.0)},
                held([0.0, 0.0]),
                300,
            ),
        ),
        lambda env, ref: float(np.max(np.abs(env.state.y[:3] - ref.state.y[:3]))),
        "max |energy error| / T(0)",
        lambda env, info, start: abs(env.state.energy_error) / start["energy"],
        "m, rad",
    ),
}


def actions_of(episode, steps):
    return episode.actions(steps, np.random.default_rng(0))


def references(case, steps_of):
    """The reference env at the end of each episode."""
    envs = []
    for episode in case.episodes:
        env = make_env(case.env_id, *case.reference, **case.kwargs)
        run(env, episode.reset, actions_of(episode, steps_of(episode)))
        envs.append(env)
    return envs


def measure_stepper(case, integrator, options, steps_of, clock, reference_envs):
    """One row: time, error per episode and drift, or None where the env refuses the stepper."""
    row = {"integrator": integrator, "options": describe(integrator, options), "diverged": ""}
    drift, errors = 0.0, {}
    for k, (episode, reference) in enumerate(zip(case.episodes, reference_envs)):
        env = make_env(case.env_id, integrator, options, **case.kwargs)
        if env is None:
            return None
        actions = actions_of(episode, steps_of(episode))
        start = env.reset(seed=0, options=episode.reset)[1]
        worst = [0.0]

        def measure(env, info, start=start, worst=worst):
            value = case.drift(env, info, start)
            if not math.isnan(value):
                worst[0] = max(worst[0], value)

        times, pendulum_times, failure = run(env, episode.reset, actions, measure=measure, clock_against=clock)
        if k == 0:
            row["us_per_step"] = float(np.median(times) * 1e6)
            row["ratio"] = float(np.median(times) / np.median(pendulum_times))
            row["pendulum_us"] = float(np.median(pendulum_times) * 1e6)
        if failure:
            row["diverged"] = f"{episode.label}: {failure}"
            errors[episode.label] = DIVERGED
            drift = DIVERGED
        else:
            errors[episode.label] = case.error(env, reference)
            drift = max(drift, worst[0])
    row["errors"] = errors
    row["drift"] = drift
    row["error"] = max(errors.values())
    return row


def default_row(case, rows):
    """The row whose stepper is the env's default (the stepper of the env made without kwargs)."""
    default = make_env(case.env_id, None, {}, **case.kwargs).stepper
    for row in rows:
        env = make_env(case.env_id, row["integrator"], row["stepper_options"], **case.kwargs)
        if env is not None and env.stepper == default:
            return row
    return None


def chart(name, folder=OUTPUT, fraction=1.0, steppers=None):
    """Measure, print, and write <name>_precision.csv and .png into folder; episodes shortened by `fraction`,
    `steppers` (integrator, options) instead of every candidate."""
    case = CASES[name]

    def steps_of(episode):
        return max(round(episode.steps * fraction), 1)

    clock = pendulum()
    print(f"\n{case.env_id}: {', '.join(f'{e.label} ({steps_of(e)} steps)' for e in case.episodes)}")
    labels = [e.label for e in case.episodes]
    errors = " | ".join(f"error {label}" for label in labels)
    print(f"| stepper | µs/step | × Pendulum-v1 | {errors} | {case.invariant} |")
    print("|---|---|---|" + "---|" * len(labels) + "---|")
    rows, reference_envs = [], references(case, steps_of)
    for integrator, options in steppers or [*candidates(), *case.steppers]:
        row = measure_stepper(case, integrator, options, steps_of, clock, reference_envs)
        if row is None:
            continue
        row["stepper_options"] = options
        rows.append(row)
        cells = [f"{row['errors'][lab]:.1e}" for lab in labels] + [f"{row['drift']:.1e}"]
        note = f"  (diverged: {row['diverged']})" if row["diverged"] else ""
        timing = f"{row['us_per_step']:.0f} | {row['ratio']:.1f}"
        print(f"| {row['options']} | {timing} | " + " | ".join(cells) + f" |{note}", flush=True)
    pareto(rows)
    default = default_row(case, rows)
    for row in rows:
        row["default"] = row is default
    print(f"Pendulum-v1: median {np.median([r['pendulum_us'] for r in rows]):.1f} µs/step over the rows' medians")
    front = sorted((r for r in rows if r["pareto"]), key=lambda r: r["ratio"])
    print("Pareto front: " + ", ".join(r["options"] for r in front))
    verdict = "on the Pareto front" if default["pareto"] else "NOT on the Pareto front"
    print(
        f"default: {default['options']}: error {default['error']:.2e} {case.error_unit}, drift {default['drift']:.2e}, "
        f"{default['us_per_step']:.0f} µs/step, {default['ratio']:.1f}× Pendulum-v1: {verdict}"
    )
    return rows, write_precision_csv(name, case, rows, folder), plot_precision(name, case, rows, folder, fraction)


def parse_args(argv=None):
    names = [*CASES, "rigid_body"]  # rigid_body: a system without an env (connenv.bench.rigid_body)
    return parse_chart_args("precision", __doc__.split("\n")[0], names, "a fifth of every episode", argv)


def main(argv=None):
    args = parse_args(argv)
    fraction = 0.2 if args.quick else 1.0

    def draw(name):
        return rigid_body.precision_chart(OUTPUT, fraction) if name == "rigid_body" else chart(name, fraction=fraction)

    draw_charts("precision", args.env, draw)
