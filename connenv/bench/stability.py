"""Stability maps: the largest dt at which a stepper keeps the env's invariant bounded, against the parameter that
breaks steppers, one curve per method (docs/precision/<env>_stability.png and .csv).

    python -m connenv.bench stability [--env swing skier ball kapitza shell bead coin beanie coin_surface tube snake
                                      sleigh cat rigid_body] [--quick]

For every parameter value and method, dt runs down the grid 1, 10^(-1/4), …, 10^-4 s (to 10^-3 with --quick;
from 0.25 s down for the shell, whose gait needs 8 steps per loop) and the first dt at which a whole episode
stays bounded is the method's largest stable dt: the env raised no
StepperError and the invariant's error stayed within the bound below at every step. A map's key is the ``bench``
of its env's Spec, from which its id is read (`connenv.bench.common.bench_spec`). At constant control:

- swing: r held at r_min (action −1) from θ₀ = 1 rad at rest, 10 s; parameter r_min (ω = √(g/r_min));
  bounded: |E − E(0)| ≤ 0.1 m g r_min.
- skier: standing, h held at h_max (action +1) on the valley from x₀ = 2 m at rest, 10 s; parameter
  min(1 − κ h_max) over the trail, set by h_max = (1 − λ)/κ_max; bounded: |E − E(0)| ≤ 0.1 m g H.
- ball: seeded random velocities for N steps whatever dt; parameter N, the horizon; bounded: ‖RᵀR − I‖ ≤ 1e-6
  (the env's own bound: past it the env raises).
- tube: bent at seeded random rates for 1 s whatever dt; parameter max_bend_rate (the bend per step
  is max_bend_rate · dt); bounded: ‖RᵀR − I‖ ≤ 1e-9 (the env's own bound: past it the env raises).
- cat: from R = I bent at s = (0.5, 0), its bend swept round the circle β = 0.5 at the full speed
  (ṡ = 6 rad/s, γ̇ = 12 rad/s), each step's velocity the chord between samples of the circle, 1 s whatever dt
  (fall_time 100 s); parameter J/I (axial_inertia, transverse_inertia 0.01): the roll per radian of sweep near the
  straight cat grows as (2I − J)/(8J), and a long step's chord cuts close to it; bounded: ‖gᵀg − I‖ ≤ 1e-9 (the
  env's own bound: past it the env raises). Every method turns the cat about its spine only; what breaks is g's
  orthogonality.
- kapitza: from θ₀ = π + 0.1, the pivot vibrated vertically, u₂ = a cos ωt, a = 0.05 m,
  each step's velocity the chord between samples (v_max = a ω), 2 s; parameter ω; bounded: the env's energy
  error (in the pivot's frame, on segments of constant u̇) within 0.1 m g l (the env's own bound). The grid
  starts at π/(2ω), 4 steps per period: a coarser dt samples another control. Inverted is stable for
  a²ω² > 2 g l, ω > 89 rad/s.
- shell: full model from the body momentum (0.3, 0.1, 0.05), the mass circling its box, u* = (u1_max cos 2πt/T,
  u2_max sin 2πt/T), T = 2 s, for 10 s; parameter the mass ratio m/(M + λ₁), set by m; bounded: the spatial
  momentum within 0.1 of its norm (the env's own bound). The reduced model is not mapped: its motion is
  geometric, so a step's error depends on the path of u over the step and not on dt.
- coin: steered and rolled at full rates (action (1, 1)) from the origin, 10 s: the contact point
  runs round a circle of radius ρ = R φ̇/θ̇ at θ̇ = max_steer_rate; parameter max_steer_rate (the circle's angular
  rate); bounded: within 0.1 ρ of the exact circle at every step. The exact step is the circle's chord.
- beanie: at μ = 0.7 with seeded random beanie speeds, 10 s; parameter I₂/I₁ (beanie_inertia,
  body_inertia 1); bounded: the integrated momentum balance within 1e-9 rad. θ̇ is constant over a step of
  constant ψ̇, so every method's step is exact and the map is flat: every method holds at the top of the grid.
- coin_surface: on the bowl z = (x² + y²)/(2ρ), from rest at (0, −1) heading along y
  (action 0, θ = 0 held), 10 s: the coin oscillates through the bottom, ÿ = −(2 g/(3ρ)) y, harmonic at
  ω = √(2 g/(3ρ)); parameter the bowl's radius ρ; bounded: |E − E(0)| ≤ 0.1 E(0) (E(0) = m g/(2ρ), the
  bottom at E = 0).
- bead: on the horizontal bar (g = 0), spun at constant θ̇ = omega_max (action +1) from r₀ = 0.5 m
  at rest, for six e-folds of the bead's growth (6/omega_max s: r grows 200-fold), on a bar long enough to hold
  it; parameter omega_max, the rate of that growth; bounded: r within 0.1 of the closed form r₀ cosh ωt (ω =
  omega_max; g = 0, from rest) at every step. The grid starts at half the episode (ω dt = 3): in one step a method
  may land near the closed form by chance.
- snake: full model from the body momentum 𝕀_loc ξ of ξ = (0.3 m/s, 0.1 m/s, 0.05 rad/s), bent at α = π/3, the
  joints circling, (α*, β*) = π/3 (cos 2πt/T,
  sin 2πt/T), T = 2 s, for 10 s; parameter the links' aspect ratio a/b (a = 0.5 m), which sets the ratio of the
  added masses across and along a link, λ₂/λ₁ = (a/b)²; bounded: the spatial momentum within 0.1 of its norm (the
  env's own bound). The reduced model is not mapped, as the shell's.
- sleigh: from v = 1 m/s, the mass at C driven to the box's corner at max_mass_speed (action
  (1, 1) held: it stops at the walls, whatever dt), then held there, 10 s; parameter max_mass_speed (the sleigh
  is not fit for jumps: the move is a kick that grows with the speed, and so do the rates of the motion after it);
  bounded: the env's energy error, the change of T while the mass is held, within 1e-2 (1 + T) (the env's own
  bound).

- rigid_body: the free rigid body, a system without an env: a slender body against its slenderness I₃/I₁
  (connenv.bench.rigid_body).

A method on the grey band (printed "≥") found no limit on the grid; "< 10^-4" (at the bottom) means none on the
grid held.
"""

from __future__ import annotations

import math

import numpy as np

from connenv.bench import rigid_body
from connenv.bench.charts import StabilityMap, cell, plot_stability, top_of, write_stability_csv
from connenv.bench.common import OUTPUT, beanie_balance, describe, draw_charts, env_id, make_env, parse_chart_args
from connenv.core import StepperError

BOUND = 0.1  # relative invariant error that counts as bounded (the ball: the env's 1e-6 off SO(3))


def held(action):
    a = np.asarray(action, np.float32)
    return lambda value, t, dt, rng: a


def energy_unbounded(scale):
    return lambda env, info, start: abs(info["energy"] - start["energy"]) > BOUND * scale(env)


def momentum_unbounded(env, info, start):
    s0 = np.asarray(start["spatial_momentum"])
    return np.linalg.norm(np.asarray(info["spatial_momentum"]) - s0) > BOUND * np.linalg.norm(s0)


def env_bound(env, info, start):
    return False  # the env raises StepperError past its own bound


def spin_unbounded(env, info, start):
    """|r − r₀ cosh ωt| > 0.1 r₀ cosh ωt: off the horizontal bar's closed form from rest at θ̇ = ω = omega_max."""
    exact = start["state"]["r"] * math.cosh(env.omega_max * info["state"]["t"])
    return abs(info["state"]["r"] - exact) > BOUND * abs(exact)


BEAD_E_FOLDS = 6.0  # the bead's episode: r grows by cosh 6, about 200-fold


def loop_gait(value, t, dt, rng):
    phase = 2 * math.pi * (t + dt) / 2.0
    return np.array([math.cos(phase), math.sin(phase)], np.float32)


def joint_circle(value, t, dt, rng):
    phase = 2 * math.pi * (t + dt) / 2.0
    return np.array([0.5 * math.cos(phase), 0.5 * math.sin(phase)], np.float32)


def snake_start(ratio):
    """Bent at α = π/3, with the body momentum 𝕀_loc ξ of the body velocity ξ = (0.3 m/s, 0.1 m/s, 0.05 rad/s)."""
    from connenv.systems.snake_swimmer import SnakeSwimmer

    shape = np.array([math.pi / 3, 0.0])
    momentum = SnakeSwimmer(b=0.5 / ratio).locked_inertia(shape) @ np.array([0.3, 0.1, 0.05])
    return {"state": {"alpha": shape[0], "momentum": tuple(momentum.tolist())}}


def random_velocity(value, t, dt, rng):
    return rng.uniform(-1.0, 1.0, 2).astype(np.float32)


SO3_METHODS = (  # the candidates on the tube and the cat, connections on SO(3)
    ("euler", {}),
    ("rk4", {}),
    ("rk4", {"substeps": 4}),
    ("dop853", {"rtol": 1e-8, "atol": 1e-10}),
    ("magnus", {}),
    ("exact", {}),
)
CAT_BEND = 0.5  # rad: β of the cat's swept circle


def bend_sweep(ratio, t, dt, rng):
    """The chord velocity between samples of the circle CAT_BEND (cos ωt, sin ωt) at ω = 6/CAT_BEND, as an action of
    max_bend_speed 6 rad/s."""
    omega = 6.0 / CAT_BEND
    chord = CAT_BEND * np.array([math.cos(omega * (t + dt)) - math.cos(omega * t),
                                 math.sin(omega * (t + dt)) - math.sin(omega * t)])  # fmt: skip
    return (chord / (6.0 * dt)).astype(np.float32)


KAPITZA_AMPLITUDE = 0.05  # a, m: the pivot's vibration u₂ = a cos ωt


def pivot_vibration(omega, t, dt, rng):
    """The chord velocity from a cos ωt to a cos ω(t + dt), as an action of v_max = a ω."""
    return np.array([(math.cos(omega * (t + dt)) - math.cos(omega * t)) / (omega * dt)], np.float32)


VALLEY_KAPPA_MAX = 3.0 / 2 * (2 * math.pi / 12.0) ** 2  # κ at the bottom of f = H(1 − cos 2πx/L)/2, H = 3, L = 12
FIXED = (("euler", {}), ("semi_implicit_euler", {}), ("rk4", {}))


def off_circle(env, info, start):
    """Whether the coin has left the exact circle it rolls at action (1, 1) by more than BOUND · ρ."""
    rho = env.radius * env.rates[1] / env.rates[0]
    s = info["state"]
    half = 0.5 * env.rates[0] * s["t"]
    chord = env.radius * env.rates[1] * s["t"] * (math.sin(half) / half if half else 1.0)
    exact = start["state"]["x"] + chord * math.sin(half), start["state"]["y"] + chord * math.cos(half)
    return math.hypot(s["x"] - exact[0], s["y"] - exact[1]) > BOUND * rho


def balance_broken(env, info, start):
    """Whether the beanie's integrated momentum balance has moved by more than 1e-9 rad."""
    return beanie_balance(env, info, start) > 1e-9


def random_speed(value, t, dt, rng):
    return rng.uniform(-1.0, 1.0, 1).astype(np.float32)
MAPS = {
    "coin": StabilityMap(
        env_id("coin"),
        "max_steer_rate θ̇ (rad/s)",
        (1.0, 10.0, 100.0, 1000.0),
        lambda omega: {"max_steer_rate": omega},
        lambda omega: {"state": {}},
        held([1.0, 1.0]),
        lambda value, dt: math.ceil(10.0 / dt),
        off_circle,
        (("euler", {}), ("rk4", {}), ("magnus", {}), ("dop853", {"rtol": 1e-8, "atol": 1e-10}), ("exact", {})),
    ),
    "beanie": StabilityMap(
        env_id("beanie"),
        "I₂/I₁",
        (0.1, 0.25, 1.0, 4.0),
        lambda ratio: {"beanie_inertia": ratio, "max_beanie_speed": max(4 * math.pi, 1.2 / ratio)},
        lambda ratio: {"state": {"momentum": 0.7}},
        random_speed,
        lambda value, dt: math.ceil(10.0 / dt),
        balance_broken,
        (("euler", {}), ("rk4", {}), ("magnus", {}), ("dop853", {"rtol": 1e-8, "atol": 1e-10}), ("exact", {})),
    ),
    "swing": StabilityMap(
        env_id("swing"),
        "r_min (m)",
        (0.01, 0.03, 0.1, 0.3, 1.0, 1.6),
        lambda r: {"r_min": r, "r_max": 2.0},
        lambda r: {"state": {"theta": 1.0, "theta_dot": 0.0, "r": r}},
        held([-1.0]),
        lambda value, dt: math.ceil(10.0 / dt),
        energy_unbounded(lambda env: env.system.mass * env.system.g * env.r_min),
        (*FIXED, ("exact", {})),
    ),
    "skier": StabilityMap(
        env_id("skier"),
        "min (1 − κ h_max) on the trail",
        (0.6, 0.3, 0.1, 0.03, 0.01),
        lambda lever: {"h_max": (1.0 - lever) / VALLEY_KAPPA_MAX},
        lambda lever: {"state": {"x": 2.0, "h": (1.0 - lever) / VALLEY_KAPPA_MAX}},
        held([1.0]),
        lambda value, dt: math.ceil(10.0 / dt),
        energy_unbounded(lambda env: env.system.mass * env.system.g * env.trail.H),
        (*FIXED, ("rk8", {}), ("dop853", {"rtol": 1e-8, "atol": 1e-10}), ("rk8_energy", {})),  # the default: ⌈dt/0.05⌉
    ),
    "ball": StabilityMap(
        env_id("ball"),
        "horizon N (steps)",
        (10, 100, 1000, 10000),
        lambda n: {},
        lambda n: {"state": {}},
        random_velocity,
        lambda n, dt: n,
        env_bound,
        (
            ("euler", {}),
            ("rk4", {}),
            ("rk4", {"substeps": 4}),
            ("lsoda", {"rtol": 1e-8, "atol": 1e-10}),
            ("dop853", {"rtol": 1e-8, "atol": 1e-10}),
            ("exact", {}),
        ),
    ),
    "tube": StabilityMap(
        env_id("tube"),
        "max_bend_rate (rad/s)",
        (0.1, 1.0, 10.0, 100.0),
        lambda rate: {"max_bend_rate": rate},
        lambda rate: {"state": {}},
        random_velocity,
        lambda rate, dt: math.ceil(1.0 / dt),
        env_bound,
        SO3_METHODS,
    ),
    "cat": StabilityMap(
        env_id("cat"),
        "J/I",
        (0.3, 0.1, 0.03, 0.01, 0.003),
        lambda ratio: {"axial_inertia": 0.01 * ratio, "fall_time": 100.0},
        lambda ratio: {"state": {"R": np.eye(3), "bend": [CAT_BEND, 0.0]}},
        bend_sweep,
        lambda ratio, dt: math.ceil(1.0 / dt),
        env_bound,
        SO3_METHODS,
    ),
    "kapitza": StabilityMap(
        env_id("kapitza"),
        "vibration frequency ω (rad/s)",
        (100.0, 200.0, 400.0, 800.0, 1600.0),
        lambda omega: {"v_max": KAPITZA_AMPLITUDE * omega},
        lambda omega: {"state": {"theta": math.pi + 0.1, "u": (0.0, KAPITZA_AMPLITUDE)}},
        pivot_vibration,
        lambda omega, dt: math.ceil(2.0 / dt),
        env_bound,
        (*FIXED, ("exact", {})),
        largest=lambda omega: math.pi / (2 * omega),  # 4 steps per period: a coarser dt would sample another control
    ),
    "shell": StabilityMap(
        env_id("shell"),
        "mass ratio m/(M + λ₁)",
        (0.1, 0.3, 1.0, 3.0, 10.0, 30.0),
        lambda ratio: {"mass": ratio * (1.0 + math.pi * 0.25)},  # M = 1, λ₁ = ρπb² = π/4
        lambda ratio: {"state": {"u": (0.5, 0.0), "momentum": (0.3, 0.1, 0.05)}},
        loop_gait,
        lambda value, dt: math.ceil(10.0 / dt),
        momentum_unbounded,
        (*FIXED, ("dop853", {"rtol": 1e-8, "atol": 1e-10})),
        largest=lambda ratio: 0.25,  # 8 steps per loop of the gait: a coarser dt would sample another control
    ),
    "coin_surface": StabilityMap(
        env_id("coin_surface"),
        "bowl radius ρ (m)",
        (10.0, 1.0, 0.1, 0.01, 0.001),
        lambda rho: {"surface": "bowl", "surface_params": {"radius": rho}},
        lambda rho: {"state": {"x": 0.0, "y": -1.0, "theta": 0.0}},
        held([0.0]),
        lambda value, dt: math.ceil(10.0 / dt),
        lambda env, info, start: abs(info["energy"] - start["energy"]) > BOUND * start["energy"],
        (*FIXED, ("rk4", {"substeps": 8}), ("dop853", {"rtol": 1e-10, "atol": 1e-12})),
        largest=lambda rho: 0.5,  # the env's longest dt
    ),
    "bead": StabilityMap(
        env_id("bead"),
        "spin rate omega_max (rad/s)",
        (1.0, 3.0, 10.0, 30.0, 100.0, 300.0),
        lambda omega: {"omega_max": omega, "g": 0.0, "half_length": 100.0},
        lambda omega: {"state": {"r": 0.5}, "target": 1.0},
        held([1.0]),
        lambda omega, dt: math.ceil(BEAD_E_FOLDS / omega / dt - 1e-9),
        spin_unbounded,
        (*FIXED, ("dop853", {"rtol": 1e-8, "atol": 1e-10}), ("exact", {})),
        largest=lambda omega: BEAD_E_FOLDS / (2.0 * omega),  # at least 2 steps: one may land near by chance
    ),
    "snake": StabilityMap(
        env_id("snake"),
        "aspect ratio a/b of the links",
        (2.0, 5.0, 10.0, 30.0, 100.0),
        lambda ratio: {"b": 0.5 / ratio},
        snake_start,
        joint_circle,
        lambda value, dt: math.ceil(10.0 / dt),
        momentum_unbounded,
        (*FIXED, ("dop853", {"rtol": 1e-8, "atol": 1e-10}), ("magnus", {})),  # magnus: the default, DOP853 rtol 1e-10
        largest=lambda ratio: 0.25,  # 8 steps per loop of the gait: a coarser dt would sample another control
    ),
    "sleigh": StabilityMap(
        env_id("sleigh"),
        "max_mass_speed (m/s)",
        (0.5, 4.0, 32.0, 256.0, 2048.0),
        lambda speed: {"max_mass_speed": speed},
        lambda speed: {"state": {"v": 1.0}, "target": (100.0, 0.0)},
        held([1.0, 1.0]),
        lambda value, dt: math.ceil(10.0 / dt),
        env_bound,
        (*FIXED, ("rk4", {"substeps": 2}), ("dop853", {"rtol": 1e-8, "atol": 1e-10})),
    ),
}


def stays_bounded(stability_map, value, integrator, options, dt):
    """True if the episode at this dt runs to its end with the invariant bounded; None if the env refuses."""
    env = make_env(stability_map.env_id, integrator, options, dt=dt, **stability_map.make(value))
    if env is None:
        return None
    start = env.reset(seed=0, options=stability_map.reset(value))[1]
    rng = np.random.default_rng(0)
    try:
        for k in range(stability_map.steps(value, dt)):
            info = env.step(stability_map.action(value, k * dt, dt, rng))[4]
            if stability_map.unbounded(env, info, start):
                return False
    except StepperError:
        return False
    return True


def largest_stable_dt(stability_map, value, integrator, options, grid):
    """The first dt of the grid (largest first, from the map's top for this value) that stays bounded; 0 if none
    does; None if the env refuses."""
    for dt in (dt for dt in grid if dt <= stability_map.largest(value)):
        bounded = stays_bounded(stability_map, value, integrator, options, dt)
        if bounded is None:
            return None
        if bounded:
            return dt
    return 0.0


def chart(name, folder=OUTPUT, smallest=1e-4, values=None, methods=None):
    """Measure, print, and write <name>_stability.csv and .png into folder; dt down to `smallest`, only `values`
    of the parameter and `methods` (integrator, options) if given."""
    stability_map = MAPS[name]
    values = values or stability_map.values
    grid = [10 ** (-k / 4) for k in range(0, 1 + round(-4 * math.log10(smallest)))]
    print(f"\n{stability_map.env_id}: largest stable dt (s) against {stability_map.parameter}")
    print("| method | " + " | ".join(f"{v:g}" for v in values) + " |")
    print("|---|" + "---|" * len(values))
    rows = {}
    for integrator, options in methods or stability_map.methods:
        method = describe(integrator, options)
        by_value = {}
        for value in values:
            dt = largest_stable_dt(stability_map, value, integrator, options, grid)
            if dt is None:
                break
            by_value[value] = dt
        if not by_value:
            continue
        rows[method] = by_value
        cells = [cell(dt, top_of(stability_map, value, grid), grid) for value, dt in by_value.items()]
        print(f"| {method} | " + " | ".join(cells) + " |", flush=True)
    path = write_stability_csv(name, stability_map, rows, grid, folder)
    return rows, path, plot_stability(name, stability_map, rows, grid, folder)


def parse_args(argv=None):
    names = [*MAPS, "rigid_body"]  # rigid_body: a system without an env (connenv.bench.rigid_body)
    return parse_chart_args("stability", __doc__.split("\n")[0], names, "dt down to 1e-3 only", argv)


def main(argv=None):
    args = parse_args(argv)
    smallest = 1e-3 if args.quick else 1e-4

    def draw(name):
        return rigid_body.stability_chart(OUTPUT, smallest) if name == "rigid_body" else chart(name, smallest=smallest)

    draw_charts("stability", args.env, draw)
