"""Bressan's skier: conservation, the jump, the halfpipe as a swing, the escape threshold and the pumping law."""

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.special import ellipk

import connenv  # noqa: F401  (registers the envs)
from agents.controllers.skier import SkierPumping
from connenv.core import JumpClass, classify, make_stepper
from connenv.core.mechanics import vector_field
from connenv.systems.skier import Skier, barycentre_height, reach
from connenv.systems.swing import Swing
from connenv.systems.trails import Halfpipe, Trail, Valley, make_trail

H, L, H_MIN, H_MAX, G, MASS = 3.0, 12.0, 0.5, 1.0, 9.81, 70.0
DEFAULT_STARTS = np.concatenate([-np.linspace(0.5, 2.0, 7), np.linspace(0.5, 2.0, 7)])


def make(**kwargs):
    return gym.make("connenv/Skier-v0", **kwargs).unwrapped


SYMBOLIC = ("a*x**2 + b*cos(x)", {"a": 0.2, "b": 0.3, "domain": (-4.0, 4.0)})


@pytest.mark.parametrize("trail, params", [("valley", {}), ("halfpipe", {}), SYMBOLIC])
def test_generic_core_agrees_with_the_hand_derived_field_and_finds_it_strongly_fit(trail, params):
    skier = Skier(make_trail(trail, params))
    rng = np.random.default_rng(1)
    x = rng.uniform(skier.trail.lo, skier.trail.hi, 12)
    y = np.stack([x, rng.normal(0.0, 300.0, 12)], -1)
    h, h_dot = rng.uniform(H_MIN, H_MAX, (12, 1)), rng.normal(0.0, 2.0, (12, 1))
    np.testing.assert_allclose(skier.vector_field(y, h, h_dot), vector_field(skier, y, h, h_dot), rtol=1e-8, atol=1e-8)
    assert classify(skier, x[:, None], h) is JumpClass.STRONGLY_FIT


@pytest.mark.parametrize("integrator, options", [("dop853", {}), ("rk4", {"substeps": 32})])
@pytest.mark.parametrize("x0", [2.0, 5.5])
def test_energy_is_conserved_at_constant_height(integrator, options, x0):
    """1000 steps at h = h_max, from rest up to near the rim: drift ≤ 1e-8 of m g H."""
    env = make(integrator=integrator, **options)
    _, info = env.reset(options={"state": {"x": x0, "h": H_MAX}})
    e0, worst = info["energy"], 0.0
    for _ in range(1000):
        _, _, _, _, info = env.step(np.array([1.0], np.float32))
        worst = max(worst, abs(info["energy"] - e0))
    assert worst / (MASS * G * H) <= 1e-8


@pytest.mark.parametrize("x, x_dot", [(0.0, 4.0), (1.3, -2.0), (-4.0, 1.0)])
def test_a_fast_rise_keeps_p_and_does_the_work_of_the_jump(x, x_dot):
    """Raise h from h_min to h_max in 1e-5 s: p is unchanged (to the ramp's time) and E grows by
    ΔE = p²/(2m)(1/w′² − 1/w²) + m g cos φ (h′ − h), the jump's work."""
    skier = Skier(Valley(), mass=MASS)
    w = lambda h: skier.geometry(x, h)[5]  # noqa: E731
    y0 = np.array([x, MASS * w(H_MIN) ** 2 * x_dot])
    ramp, speed = 1e-5, (H_MAX - H_MIN) / 1e-5
    y1 = make_stepper("dop853", rtol=1e-12, atol=1e-10)(skier, y0, np.array([H_MIN]), np.array([speed]), ramp)
    assert y1[1] == pytest.approx(y0[1], rel=1e-4)
    sigma = math.sqrt(1.0 + skier.trail.derivatives(x)[1] ** 2)
    work = y0[1] ** 2 / (2 * MASS) * (1 / w(H_MAX) ** 2 - 1 / w(H_MIN) ** 2) + MASS * G * (H_MAX - H_MIN) / sigma
    assert skier.energy(y1, H_MAX) - skier.energy(y0, H_MIN) == pytest.approx(work, rel=1e-4)


def test_the_env_jump_leaves_x_and_p_unchanged():
    """A step of dt → 0 isolates the jump: standing up changes h, not (x, p)."""
    env = make(dt=1e-12)
    _, before = env.reset(options={"state": {"x": 1.0, "x_dot": 3.0}})
    _, _, _, _, after = env.step(np.array([1.0], np.float32))
    assert after["state"]["h"] == H_MAX
    assert after["state"]["p"] == pytest.approx(before["state"]["p"], rel=1e-9)
    assert after["state"]["x"] == pytest.approx(before["state"]["x"], abs=1e-9)
    assert after["state"]["x_dot"] > before["state"]["x_dot"]  # w shrank where κ > 0


@pytest.mark.parametrize("h", [H_MIN, 0.8])
def test_halfpipe_at_constant_height_is_a_pendulum_of_length_r_minus_h(h):
    """φ = arcsin(x/R) follows the pendulum of length R − h (the swing's elliptic flow), and returns
    to its start after the period 4 K(sin²(A/2)) √((R − h)/g)."""
    R, A, dt = 5.0, 0.9, 0.05
    env = make(trail="halfpipe", h_min=h, h_max=h + 0.1, dt=dt)
    _, info = env.reset(options={"state": {"x": R * math.sin(A), "h": h}})
    swing, r = Swing(mass=MASS, g=G), np.array([R - h])
    period = 4 * ellipk(math.sin(A / 2) ** 2) * math.sqrt((R - h) / G)
    steps = round(period / dt)
    for k in range(1, steps + 1):
        _, _, _, _, info = env.step(np.array([-1.0], np.float32))
        phi = math.asin(info["state"]["x"] / R)
        theta = swing.exact_flow(np.array([A, 0.0]), r, k * dt)[0]
        assert phi == pytest.approx(theta, abs=1e-7)
    phi_at_period = swing.exact_flow(np.array([A, 0.0]), r, period)[0]
    assert phi_at_period == pytest.approx(A, abs=1e-9)
    assert math.asin(info["state"]["x"] / R) == pytest.approx(A, abs=0.05 * (steps * dt - period) + 1e-3)


def test_escape_is_impossible_at_constant_height_from_every_default_start():
    """Energy bound: at rest at |x₀| ≤ 2 with any held h (a jump from h_min at the start included),
    z = f(x₀) + h cos φ₀ stays below the rim's f = H plus h; and rollouts confirm it."""
    valley = Valley()
    x0 = np.linspace(-2.0, 2.0, 401)
    f, f1, _, _ = valley.profile(x0)
    for h in (H_MIN, 0.75, H_MAX):
        assert np.max(f + h / np.sqrt(1 + f1**2)) < H + h
    env = make()
    for x in (-2.0, 2.0):
        for a in (-1.0, 0.0, 1.0):
            env.reset(options={"state": {"x": x}})
            for _ in range(1000):
                _, _, terminated, _, info = env.step(np.array([a], np.float32))
                assert not terminated
            assert abs(info["state"]["x"]) < L / 2


def pump(env, x0):
    """Run the analytic controller from rest at x0: (success, time, number of stand-ups)."""
    obs, info = env.reset(options={"state": {"x": x0}})
    policy, stand_ups, terminated = SkierPumping(), 0, False
    for _ in range(1000):
        h = info["state"]["h"]
        obs, _, terminated, _, info = env.step(policy.predict(obs)[0])
        stand_ups += info["state"]["h"] > h
        if terminated:
            break
    return terminated, info["state"]["t"], stand_ups


def test_the_analytic_controller_escapes_from_every_default_start_in_three_to_seven_half_cycles():
    env = make()
    for x0 in DEFAULT_STARTS:
        success, t, half_cycles = pump(env, x0)
        assert success, f"no escape from x0={x0}"
        assert 3 <= half_cycles <= 7, (x0, half_cycles)


def test_on_the_halfpipe_the_controller_follows_the_swing_pumping_law():
    """Between stand-ups (at the bottom) and crouches (at the turning points) the halfpipe skier is a swing
    of radius R − h: 1 − cos φ grows by ((R − h_min)/(R − h_max))³ per half-cycle, up to the switching
    error of the 0.05 s control step."""
    R = 5.0
    env = make(trail="halfpipe")
    obs, info = env.reset(options={"state": {"x": 0.5}})
    policy, amplitudes, x_dot = SkierPumping(), [], info["state"]["x_dot"]
    for _ in range(1000):
        obs, _, terminated, _, info = env.step(policy.predict(obs)[0])
        if terminated:
            break
        if info["state"]["x_dot"] * x_dot < 0 or (x_dot == 0 and info["state"]["x_dot"] != 0):  # a turning point
            amplitudes.append(abs(math.asin(info["state"]["x"] / R)))
        x_dot = info["state"]["x_dot"]
    lifts = 1 - np.cos(amplitudes)
    ratio = ((R - H_MIN) / (R - H_MAX)) ** 3
    assert len(lifts) >= 4
    np.testing.assert_allclose(lifts[1:] / lifts[:-1], ratio, rtol=0.02)  # measured: within 0.5%


def test_arc_length_tabulated_by_simpson_equals_the_closed_forms():
    """Valley: Legendre's E(kx | −(Hk/2)²)/k; halfpipe: R arcsin(x/R)."""
    for trail in (Valley(), Halfpipe()):
        x = np.linspace(trail.lo, trail.hi, 37)
        tabulated = Trail.arc_length_on_domain(trail, x) - Trail.arc_length_on_domain(trail, 0.0)
        np.testing.assert_allclose(tabulated, trail.arc_length_on_domain(x), atol=1e-7)


def test_arc_length_continues_along_the_osculating_parabola():
    """Beyond the rim s grows as the quadrature of σ of the continued trail."""
    from scipy.integrate import quad

    valley = Valley()
    x = 7.0
    beyond = quad(lambda u: math.sqrt(1 + valley.derivatives(u)[1] ** 2), valley.hi, x, epsabs=1e-12)[0]
    assert valley.arc_length(x) == pytest.approx(valley.arc_length(valley.hi) + beyond, rel=1e-10)


def test_symbolic_and_callable_trails_equal_the_built_in_valley():
    k = 2 * math.pi / L
    a = H / 2
    callables = (
        lambda x: a * (1 - np.cos(k * x)),
        lambda x: a * k * np.sin(k * x),
        lambda x: a * k**2 * np.cos(k * x),
        lambda x: -a * k**3 * np.sin(k * x),
    )
    x = np.linspace(-6, 6, 25)
    built_in = Valley().profile(x)
    for trail in (
        make_trail("Hd*(1 - cos(2*pi*x/Ld))/2", {"Hd": H, "Ld": L, "domain": (-6, 6)}),
        make_trail(callables, {"domain": (-6, 6)}),
    ):
        np.testing.assert_allclose(trail.profile(x), built_in, rtol=1e-12, atol=1e-12)


def test_a_barycentre_past_the_centre_of_curvature_is_refused_at_the_worst_point():
    """The valley's bottom has radius of curvature 2/(H k²) = 2.43 m: h_max = 2.5 passes it, at x = 0."""
    with pytest.raises(ValueError, match=r"h_max=2.5 .* at x=0 .*radius 2.43"):
        make(h_max=2.5)


def test_the_reach_of_a_halfpipe_is_its_circle():
    """On a circle of radius R, κ = 1/R everywhere: the lever 1 − κ h_max is 1 − h_max/R, |κ| h_max = h_max/R, the
    lowest point is x = 0 and there the barycentre stands h_min above the bottom."""
    R, h_min, h_max = 5.0, 0.5, 1.5
    x_bottom, z_floor, kappa_bound, min_lever = reach(Halfpipe(R), h_min, h_max)
    assert x_bottom == pytest.approx(0.0, abs=1e-12) and z_floor == pytest.approx(h_min, rel=1e-12)
    assert kappa_bound == pytest.approx(h_max / R, rel=1e-12) and min_lever == pytest.approx(1 - h_max / R, rel=1e-12)
    assert barycentre_height(Halfpipe(R), np.array(3.0), h_min) == pytest.approx(R - 4.0 + h_min * 4.0 / R, rel=1e-12)
