"""The coin rolled by gravity: the closed form on a plane, energy conservation, straight lines at a fixed heading,
and why the default task needs steering."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from connenv.core.integrators import make_stepper
from connenv.systems.rolling_coin_surface import SERIES_BELOW, RollingCoinPlane, RollingCoinSurface, phi_pairs
from connenv.systems.surfaces import Hill, Plane, Symbolic

ID = "connenv/RollingCoinSurface-v0"
G, R = 9.81, 0.5


def closed_form(slope, theta0, omega, t):
    """From rest at the origin with θ = θ₀ + Ω t on z = sx x + sy y: R φ̇ = −(2 g/(3Ω)) ∫ (sx sin θ + sy cos θ) Ω dt,
    and (x, y) its integrals, in real trigonometric form (B the constant of R φ̇ = B + (k/Ω)(sx cos θ − sy sin θ))."""
    sx, sy = slope
    k, theta = 2 * G / 3, theta0 + omega * t
    speed = -(k / omega) * (sx * (math.cos(theta0) - math.cos(theta)) + sy * (math.sin(theta) - math.sin(theta0)))
    b = -(k / omega) * (sx * math.cos(theta0) - sy * math.sin(theta0))
    c2, s2, c20, s20 = math.cos(2 * theta), math.sin(2 * theta), math.cos(2 * theta0), math.sin(2 * theta0)
    x = b * (math.cos(theta0) - math.cos(theta)) / omega + (k / omega) * (
        sx * (c20 - c2) / (4 * omega) - sy * t / 2 + sy * (s2 - s20) / (4 * omega)
    )
    y = b * (math.sin(theta) - math.sin(theta0)) / omega + (k / omega) * (
        sx * t / 2 + sx * (s2 - s20) / (4 * omega) + sy * (c2 - c20) / (4 * omega)
    )
    return x, y, speed


@pytest.mark.parametrize(
    "slope, theta0, action", [((0.0, -0.25), 0.4, 0.5), ((0.15, -0.3), -1.0, -1.0), ((-0.2, 0.1), 2.5, 0.13)]
)
def test_on_a_plane_at_constant_steering_from_rest_the_env_follows_the_closed_form_to_1e_9(slope, theta0, action):
    """The default stepper on a plane (the exact step), 60 steps at θ̇ = Ω, against the trigonometric integrals."""
    env = gym.make(ID, surface="plane", slope=slope, max_episode_steps=10**6).unwrapped
    env.reset(options={"state": {"x": 0.0, "y": 0.0, "theta": theta0}, "target": (5.0, 5.0)})
    omega = action * env.max_steer_rate
    for _ in range(60):
        info = env.step(np.array([action]))[4]
        x, y, speed = closed_form(slope, theta0, omega, info["state"]["t"])
        state = info["state"]
        assert abs(state["x"] - x) < 1e-9 and abs(state["y"] - y) < 1e-9
        assert abs(R * state["phi_dot"] - speed) < 1e-9
        assert state["theta"] == pytest.approx(theta0 + omega * state["t"], abs=1e-12)


@pytest.mark.parametrize("omega", [0.0, 1e-9, 1e-4, 0.3, 2.0, -7.0])
def test_the_exact_step_agrees_with_dop853_on_the_ode_for_every_steering_rate(omega):
    """The closed form against the vector field integrated at rtol 1e-13, from a rolling state, including Ω = 0
    and Ω → 0 (where the φ-functions are evaluated without cancellation)."""
    system = RollingCoinPlane(Plane((0.1, -0.25)))
    exact, tight = make_stepper("exact", system), make_stepper("dop853", system, rtol=1e-13, atol=1e-15)
    y = np.array([0.3, -0.2, 0.1, 1.7])
    a = exact(system, y, np.array([0.7]), np.array([omega]), 0.8)
    b = tight(system, y, np.array([0.7]), np.array([omega]), 0.8)
    assert np.max(np.abs(a - b)) < 1e-11


def reference_phi(alpha: float):
    """(φ₁(iα), φ₂(iα)) as (sin α/α, (1 − cos α)/α, (1 − cos α)/α², (α − sin α)/α²) in 700-digit arithmetic: enough
    for the cancellations down to α = 1e-300 (mpmath, which sympy requires)."""
    import mpmath

    if alpha == 0.0:
        return 1.0, 0.0, 0.5, 0.0
    with mpmath.workdps(700):
        a = mpmath.mpf(alpha)
        return tuple(float(v) for v in (mpmath.sin(a) / a, (1 - mpmath.cos(a)) / a, (1 - mpmath.cos(a)) / a**2,
                                        (a - mpmath.sin(a)) / a**2))  # fmt: skip


def test_phi_pairs_match_high_precision_at_zero_tiny_angles_and_across_the_series_threshold():
    """Each real and imaginary part to 1e-15 (a few ulp) where the series is summed (|α| < SERIES_BELOW), including
    α = 1e-300 and 1e-8 where the direct forms cancel to nothing; to 2e-14 past it, where α − sin α cancels by at
    most 6/α² ≈ 67 ulp at α = 0.3; φ(0) = (1, ½) exactly."""
    alpha = np.array([0.0, 1e-300, -1e-8, 1e-5, 0.3 - 1e-12, 0.3, 0.3 + 1e-12, 2.0])
    p1r, p1i, p2r, p2i = phi_pairs(alpha)
    assert (p1r[0], p1i[0], p2r[0], p2i[0]) == (1.0, 0.0, 0.5, 0.0)
    for i, a in enumerate(alpha):
        got = (p1r[i], p1i[i], p2r[i], p2i[i])
        rtol = 1e-15 if abs(a) < SERIES_BELOW else 2e-14
        for value, reference in zip(got, reference_phi(float(a))):
            assert abs(value - reference) <= rtol * abs(reference), (a, value, reference)


SURFACES = [
    {},
    {"surface": "plane"},
    {"surface": "bowl"},
    {"surface": "0.05*x**2 - 0.25*y + a*sin(x)*cos(y)", "surface_params": {"a": 0.1}},
]


@pytest.mark.parametrize("kwargs", SURFACES, ids=["hill", "plane", "bowl", "sympy"])
def test_energy_drifts_by_at_most_1e_9_of_m_g_dz_over_an_episode_of_random_steering(kwargs):
    """E = ¾ m R² φ̇² + m g z is conserved whatever the steering: over 200 steps (the episode's limit) of random
    θ̇, with the default stepper, |E − E₀| ≤ 1e-9 m g Δz (Δz the arena's height range)."""
    env = gym.make(ID, max_episode_steps=10**6, **kwargs).unwrapped
    _, info = env.reset(seed=1)
    e0, scale = info["energy"], env.system.mass * env.system.g * env.height_range
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(200):
        info = env.step(rng.uniform(-1, 1, 1))[4]
        worst = max(worst, abs(info["energy"] - e0))
    assert worst <= 1e-9 * scale
    assert abs(info["state"]["phi_dot"]) > 0.5  # it rolled


def test_at_a_fixed_heading_the_coin_rolls_on_a_straight_line_over_any_surface():
    """ẋ : ẏ = sin θ : cos θ whatever z: at a held heading the track is the line through the start along it, and
    on the hill the coin, aimed at the hill, climbs it, stops and rolls back along that line."""
    env = gym.make(ID, max_episode_steps=10**6).unwrapped
    env.reset(options={"state": {"x": 0.2, "y": 0.0, "theta": 0.05}})
    direction = np.array([math.sin(0.05), math.cos(0.05)])
    ys = []
    for _ in range(80):
        state = env.step(np.array([0.0]))[4]["state"]
        offset = np.array([state["x"] - 0.2, state["y"]])
        assert abs(offset[0] * direction[1] - offset[1] * direction[0]) < 1e-12
        ys.append(state["y"])
    assert max(ys) < 2.0 and ys[-1] < max(ys) - 0.5  # it stopped short of the hill's top and came back


def test_the_default_task_needs_steering_every_straight_line_to_a_target_climbs_above_the_start():
    """From rest the coin can only reach points below its start height; a held heading keeps it on a straight line
    (above), and on the default hill the line from the start to each target the reset may draw rises above the
    start: no fixed heading reaches a target."""
    env = gym.make(ID).unwrapped
    z0 = env.surface.height(0.0, 0.0)[0]
    s = np.linspace(0.0, 1.0, 401)
    for angle in np.linspace(-env.target_angle, env.target_angle, 21):
        tx, ty = 4.0 * math.sin(angle), 4.0 * math.cos(angle)
        assert env.surface.height(tx, ty)[0] < z0  # the target is below the start
        assert np.max(env.surface.height(s * tx, s * ty)[0]) > z0 + 0.15  # the line to it rises above the start


def test_a_symbolic_surface_is_the_built_in_one_it_spells():
    """The hill and the plane as sympy text: the same heights and gradients, and the same trajectory."""
    spelled = Symbolic("-0.25*y + exp(-(x**2 + (y - 2)**2)/(2*0.6**2))")
    x, y = np.random.default_rng(0).uniform(-6, 6, (2, 50))
    for a, b in zip(spelled.height(x, y), Hill().height(x, y)):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-15)
    stepper = make_stepper("dop853", rtol=1e-12, atol=1e-14)
    y0, u, u_dot = np.array([0.0, 0.0, 0.0, 0.0]), np.array([0.3]), np.array([0.8])
    a = stepper(RollingCoinSurface(Symbolic("0.1*x - 0.25*y")), y0, u, u_dot, 1.0)
    b = stepper(RollingCoinSurface(Plane((0.1, -0.25))), y0, u, u_dot, 1.0)
    np.testing.assert_allclose(a, b, atol=1e-13)


def test_the_batched_vector_field_and_exact_step_are_the_single_state_ones_row_by_row():
    """The system over a batch (arrays over rows, as the vector env calls it) against one state at a time: the hill's
    vector field and the plane's exact step."""
    rng = np.random.default_rng(2)
    y, u, u_dot = rng.uniform(-1, 1, (5, 4)), rng.uniform(-3, 3, (5, 1)), rng.uniform(-2, 2, (5, 1))
    hill, plane = RollingCoinSurface(Hill()), RollingCoinPlane(Plane((0.1, -0.25)))
    batch = hill.vector_field(y, u, u_dot)
    for i in range(5):
        np.testing.assert_allclose(batch[i], hill.vector_field(y[i], u[i], u_dot[i]), rtol=1e-14, atol=1e-15)
    batch = plane.exact_segment(y, u, u_dot, 0.05)
    for i in range(5):
        np.testing.assert_allclose(batch[i], plane.exact_segment(y[i], u[i], u_dot[i], 0.05), rtol=1e-14, atol=1e-15)


def test_a_diverging_stepper_raises_naming_the_energy_error_dt_and_the_parameters_never_nan():
    """Explicit Euler gains energy on every step of a turn: past 1e-3 m g Δz the env raises StepperError."""
    from connenv.core import StepperError

    env = gym.make(ID, integrator="euler", max_episode_steps=10**6).unwrapped
    obs, _ = env.reset(seed=0)
    with pytest.raises(StepperError, match=r"energy error.*dt = 0.05.*max_steer_rate = 2.0"):
        for _ in range(400):
            obs = env.step(np.array([1.0]))[0]
            assert np.all(np.isfinite(obs))


def test_on_a_plane_the_models_jacobians_are_the_closed_forms_derivatives():
    """The plane's closed form computes with complex numbers (a plane vector x + i y); the model's complex-step
    Jacobians must not mix their own imaginary part with those (they did: ∂x_next/∂x off by 2.5). Against central
    differences of the step, h = 1e-6, relative to each column's largest entry, at rows of random states and actions,
    and on the hill (its RK steps) as well."""
    for kwargs in ({"surface": "plane"}, {}):
        env = gym.make(ID, **kwargs).unwrapped
        model, rng = env.model, np.random.default_rng(3)
        rows = []
        for seed in range(3):
            env.reset(seed=seed)
            env.step(rng.uniform(-0.8, 0.8, env.action_space.shape).astype(np.float32))
            rows.append(model.pack(env.state))
        x, a = np.array(rows), rng.uniform(-0.8, 0.8, (3, *env.action_space.shape))
        A, B = model.jacobians(x, a)
        moving = [j for j, name in enumerate(model.state_names) if np.ptp(x[:, j]) > 0 or name in ("x", "y")]
        for j in moving:
            h = 1e-6 * max(1.0, np.max(np.abs(x[:, j])))
            up, down = x.copy(), x.copy()
            up[:, j] += h
            down[:, j] -= h
            central = (model.step(up, a) - model.step(down, a)) / (2 * h)
            scale = np.max(np.abs(central), axis=1, keepdims=True) + 1e-9
            assert np.all(np.abs(A[:, :, j] - central) <= 1e-6 * scale + 1e-9), (kwargs, model.state_names[j])
        up, down = a + 1e-6, a - 1e-6
        central = (model.step(x, up) - model.step(x, down)) / 2e-6
        np.testing.assert_allclose(B.sum(-1), central, rtol=1e-6, atol=1e-8, err_msg=str(kwargs))
