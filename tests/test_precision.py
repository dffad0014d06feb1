"""Speed against accuracy: the benchmark machinery on short runs (the charts themselves come from
`python -m connenv.bench all`), the default steppers across each env's documented range, and steppers that
diverge raising StepperError that names the stepper, dt and the parameter."""

import csv
import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv.bench import charts, precision, stability
from connenv.core import StepperError

VALLEY_KAPPA_MAX = stability.VALLEY_KAPPA_MAX


def make(env_id, **kwargs):
    return gym.make(env_id, **kwargs).unwrapped


# -- the benchmark machinery -------------------------------------------------------------------------------


def test_work_precision_chart_puts_the_closed_form_on_the_front_and_flags_euler(tmp_path):
    """20 steps of the swing at r_max from π/2: the closed form is the default and on the Pareto front; RK4 errs,
    and explicit Euler's energy error passes the env's bound (0.1 m g r_max) in the 14th step."""
    steppers = [("exact", {}), ("euler", {"substeps": 1}), ("rk4", {"substeps": 1})]
    rows, csv_path, png_path = precision.chart("swing", tmp_path, fraction=0.04, steppers=steppers)
    by_name = {row["options"]: row for row in rows}
    assert by_name["exact"]["default"] and by_name["exact"]["pareto"]
    assert 0.0 < by_name["rk4 ×1"]["error"] < 1e-4
    assert "Euler(substeps=1) diverged" in by_name["euler ×1"]["diverged"] and not by_name["euler ×1"]["pareto"]
    with open(csv_path) as f:
        assert [line["integrator"] for line in csv.DictReader(f)] == ["exact", "euler", "rk4"]
    assert png_path.stat().st_size > 10_000


def test_stability_map_shrinks_the_symplectic_step_with_the_swings_period(tmp_path):
    """Semi-implicit Euler is stable for ω dt < 2 on the oscillator, ω = √(g/r_min): the largest dt that keeps
    the energy within 0.1 m g r_min falls as r_min does, and the closed form has none on the grid."""
    rows, csv_path, png_path = stability.chart(
        "swing", tmp_path, smallest=1e-2, values=(0.1, 1.6), methods=[("semi_implicit_euler", {}), ("exact", {})]
    )
    sie = rows["semi_implicit_euler"]
    assert 0.0 < sie[0.1] < sie[1.6] and sie[1.6] * math.sqrt(9.81 / 1.6) < 2.0
    assert rows["exact"] == {0.1: 1.0, 1.6: 1.0}
    assert png_path.stat().st_size > 10_000


# -- documented range: the default stepper keeps its accuracy ------------------------------------------------


TIGHT_DOP853 = {"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}


def random_steps(env, steps, seed=0, **reset):
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed, **reset)
    for _ in range(steps):
        obs, _, _, _, info = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32))
        assert np.all(np.isfinite(obs))
    return info


@pytest.mark.parametrize("r_min", [0.05, 0.8, 1.9])
@pytest.mark.parametrize("dt", [0.01, 0.05, 0.5])
def test_swing_closed_form_conserves_energy_across_radii_and_steps(r_min, dt):
    """Pumped by random jumps of r in [r_min, 2], over the top at r_min = 0.05: the energy changes only by the
    jumps' work; on held segments the exact stepper keeps it to 1e-9 of m g r_max over 100 steps (rounding, 1e-15,
    except within 1e-6 of the separatrix, where DOP853 at rtol 1e-10 takes the step)."""
    env = make("connenv/Swing-v0", r_min=r_min, dt=dt, target_amplitude=math.pi)
    random_steps(env, 100)
    assert abs(env.state.energy_error) <= 1e-9 * env.system.mass * env.system.g * env.r_max


@pytest.mark.parametrize("lever", [0.6, 0.1, 0.01])
@pytest.mark.parametrize("dt", [0.01, 0.05, 0.2])
def test_skier_default_keeps_energy_as_the_barycentre_nears_the_centre_of_curvature(lever, dt):
    """The default on the valley with h_max up to 1 − κ h_max = 0.01 (the projected RK8 at 0.6, DOP853 at rtol 1e-8
    nearer), over 100 random steps: the energy error on held segments stays within 2e-6 of m g Δz, and until the
    episode ends (a rim) the state follows DOP853 at rtol 1e-13 within 1e-6 m and 1e-6 of the momentum scale m v*
    (documented in SkierEnv)."""
    kwargs = {"h_max": (1.0 - lever) / VALLEY_KAPPA_MAX, "dt": dt}
    env = make("connenv/Skier-v0", **kwargs)
    default = "rk8_energy" if lever >= 0.5 else "dop853"
    assert env.stepper == make("connenv/Skier-v0", **kwargs, integrator=default).stepper
    random_steps(env, 100)
    assert abs(env.state.energy_error) <= 2e-6 * env.system.mass * env.system.g * (env.z_goal - env.z_floor)
    env, reference = make("connenv/Skier-v0", **kwargs), make("connenv/Skier-v0", **kwargs, **TIGHT_DOP853)
    assert steps_to_the_end(env, 100) == steps_to_the_end(reference, 100)
    assert abs(env.state.y[0] - reference.state.y[0]) <= 1e-6
    assert abs(env.state.y[1] - reference.state.y[1]) <= 1e-6 * env.system.mass * env.speed_scale


def steps_to_the_end(env, steps, seed=0):
    """Random steps until the episode terminates or `steps` are taken; how many were taken."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    for taken in range(1, steps + 1):
        if env.step(rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32))[2]:
            break
    return taken


@pytest.mark.parametrize("radius, dt", [(0.1, 0.01), (1.0, 0.1), (10.0, 1.0)])
def test_ball_exact_step_rolls_the_closed_form_at_every_radius_and_step(radius, dt):
    """A straight roll by d turns the ball by d/ρ about e_z × d: after 100 steps R = Ry(100 v dt/ρ), to rounding."""
    env = make("connenv/RollingBall-v0", radius=radius, dt=dt, tolerance=1e-3)
    env.reset(seed=0, options={"state": {"R": np.eye(3)}})
    for _ in range(100):
        env.step(np.array([1.0, 0.0], np.float32))
    angle = 100 * env.v_max * dt / radius
    c, s = math.cos(angle), math.sin(angle)
    np.testing.assert_allclose(env.state.R, [[c, 0, s], [0, 1, 0], [-s, 0, c]], atol=1e-12)


@pytest.mark.parametrize("v_max", [1.0, 10.0, 100.0])
@pytest.mark.parametrize("dt", [0.001, 0.005, 0.05])
def test_kapitza_exact_step_conserves_the_pivot_frame_energy_on_every_segment(v_max, dt):
    """Random pivot velocities up to v_max (100 m/s reaches the end stops within a step, so steps split into
    segments): the exact step keeps E in the frame of each segment's u̇ to 1e-9 of m g l over 200 steps."""
    env = make("connenv/KapitzaPendulum-v0", v_max=v_max, dt=dt, tolerance=3.1)
    random_steps(env, 200)
    assert abs(env.state.energy_error) <= 1e-9 * env.system.mass * env.system.g * env.system.length


@pytest.mark.parametrize("ratio, dt", [(0.1, 0.25), (1.0, 0.1), (30.0, 0.02)])
def test_shell_default_follows_the_reference_at_every_mass_ratio(ratio, dt):
    """The full Kirchhoff model at mass ratios m/(M + λ₁) from 0.1 to 30: DOP853 (rtol 1e-8) stays within 2e-8
    of DOP853 at rtol 1e-13 over 100 random steps, and conserves the spatial momentum to 1e-12 relative."""
    momentum = {"state": {"momentum": (0.3, 0.1, 0.05)}}
    poses = []
    for options in ({}, {"integrator": "dop853", "rtol": 1e-13, "atol": 1e-15}):
        env = make("connenv/KozlovShell-v0", mass=ratio * (1.0 + math.pi / 4), dt=dt, **options)
        start = env.reset(seed=0, options=momentum)[1]["spatial_momentum"]
        end = random_steps(env, 100, options=momentum)["spatial_momentum"]
        poses.append(env.state.pose)
    assert np.abs(poses[0] - poses[1]).max() <= 2e-8
    assert np.linalg.norm(np.subtract(end, start)) <= 1e-12 * np.linalg.norm(start)


# -- divergence: StepperError naming the stepper, dt and the parameter ------------------------------------------


def test_a_diverging_stepper_raises_naming_stepper_dt_and_parameter_never_nan(diverging):
    env_id, kwargs, reset, action, message = diverging
    env = make(env_id, **kwargs)
    obs, _ = env.reset(seed=0, options={"state": reset})
    sign = np.asarray(action, np.float32)
    with pytest.raises(StepperError, match=message):
        for k in range(2000):
            alternating = env_id in ("connenv/KozlovShell-v0", "connenv/KapitzaPendulum-v0")
            obs = env.step(sign * (-1) ** k if alternating else sign)[0]
            assert np.all(np.isfinite(obs))


def test_the_front_counts_times_within_the_timings_noise_as_equal():
    """Two steppers with the same error whose times differ by 2% both stay on the front; 10% faster ousts."""
    rows = [
        {"ratio": 1.00, "error": 1e-9, "diverged": ""},
        {"ratio": 1.02, "error": 1e-9, "diverged": ""},
        {"ratio": 1.15, "error": 1e-9, "diverged": ""},
        {"ratio": 0.50, "error": 1e-3, "diverged": ""},
        {"ratio": 0.10, "error": 0.0, "diverged": "x"},
    ]
    charts.pareto(rows)
    assert [row["pareto"] for row in rows] == [True, True, False, True, False]
