"""The swing with an assigned radius: conservation laws, closed forms and the pumping law."""

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import connenv  # noqa: F401  (registers the envs)
from agents.controllers.swing import PiccoliKulkarni
from connenv.core import make_stepper
from connenv.systems.swing import Swing, ellipj_one

G = 9.81
R_MIN, R_MAX = 1.6, 2.0
RHO = R_MAX / R_MIN


def make(**kwargs):
    return gym.make("connenv/Swing-v0", **kwargs).unwrapped


def energy_drift(env, steps, action, state):
    """max |E(t) − E(0)| / (m g r) at a held radius."""
    _, info = env.reset(options={"state": state})
    r = info["state"]["r"]
    e0, worst = info["energy"], 0.0
    for _ in range(steps):
        _, _, _, _, info = env.step(np.array([action], np.float32))
        worst = max(worst, abs(info["energy"] - e0))
    return worst / (env.system.mass * env.system.g * r)


@pytest.mark.parametrize(
    "integrator, options, tolerance",
    [("exact", {}, 1e-12), ("dop853", {"rtol": 1e-12, "atol": 1e-14}, 1e-9), ("rk4", {"substeps": 32}, 1e-8)],
)
def test_energy_is_conserved_at_constant_radius(integrator, options, tolerance):
    env = make(integrator=integrator, **options)
    assert energy_drift(env, 1000, 1.0, {"theta": 1.5, "theta_dot": 0.3, "r": R_MAX}) < tolerance


def test_energy_of_a_swing_over_the_top_is_conserved():
    env = make(target_amplitude=math.pi)
    assert energy_drift(env, 1000, -1.0, {"theta": 0.0, "theta_dot": 5.0, "r": R_MIN}) < 1e-12


@pytest.mark.parametrize("theta", [0.0, 0.3, -1.2, 2.5])
def test_a_radius_jump_conserves_angular_momentum_and_does_the_work_of_the_constraint(theta):
    """Over a vanishing step the jump r → r′ keeps p and changes E by
    p²/(2m)(1/r′² − 1/r²) − m g cos θ (r′ − r)."""
    env = make(dt=1e-9)
    _, info = env.reset(options={"state": {"theta": theta, "theta_dot": 1.7, "r": R_MAX}})
    before = info
    _, _, _, _, after = env.step(np.array([-1.0], np.float32))
    p, r, r2 = before["state"]["p"], R_MAX, R_MIN
    assert after["state"]["p"] == pytest.approx(p, abs=1e-7)
    assert after["state"]["theta_dot"] == pytest.approx(before["state"]["theta_dot"] * RHO**2, rel=1e-7)
    work = p**2 / 2 * (1 / r2**2 - 1 / r**2) - G * math.cos(theta) * (r2 - r)
    assert after["energy"] - before["energy"] == pytest.approx(work, rel=1e-7)


def test_a_jump_is_the_limit_of_a_fast_continuous_move():
    """With the radial speed bounded by v, the state after a step approaches the jump's as 1/v."""
    state = {"theta": 0.4, "theta_dot": -1.0, "r": R_MAX}
    jump = make()
    jump.reset(options={"state": state})
    jump.step(np.array([-1.0], np.float32))
    errors = []
    for speed in (10.0, 100.0, 1000.0):
        env = make(max_radial_speed=speed)
        env.reset(options={"state": state})
        env.step(np.array([-1.0], np.float32))
        assert env.state.r == R_MIN
        errors.append(np.max(np.abs(env.state.y - jump.state.y)))
    assert errors[0] > errors[1] > errors[2] and errors[2] < 1e-3
    assert errors[1] / errors[2] == pytest.approx(10.0, rel=0.2)


def test_bounded_radial_speed_moves_r_at_that_speed():
    env = make(max_radial_speed=2.0, dt=0.05)
    env.reset(options={"state": {"theta": 0.2, "r": R_MAX}})
    env.step(np.array([-1.0], np.float32))
    assert env.state.r == pytest.approx(R_MAX - 0.1, abs=1e-12)
    env.step(np.array([-1.0], np.float32))
    env.step(np.array([-1.0], np.float32))
    assert env.state.r == pytest.approx(1.7, abs=1e-12)
    for _ in range(2):
        env.step(np.array([-1.0], np.float32))
    assert env.state.r == R_MIN


@pytest.mark.parametrize("integrator", ["exact", "dop853", "rk4"])
def test_small_amplitude_period_is_two_pi_root_r_over_g(integrator):
    """After 2π√(r/g) a small oscillation is back where it started: the phase error is the
    finite-amplitude correction 2π·A²/16 ≈ 4e-7 at A = 1e-3; a period off by 1e-5 would fail."""
    r, amplitude = 1.8, 1e-3
    swing = Swing(g=G)
    stepper = make_stepper(integrator, swing, **({"substeps": 200} if integrator == "rk4" else {}))
    y0 = np.array([amplitude, 0.0])
    theta, p = stepper(swing, y0, np.array([r]), np.zeros(1), 2 * math.pi * math.sqrt(r / G))
    omega = math.sqrt(G / r)
    phase_error = math.hypot(theta - amplitude, p / (swing.mass * r**2 * omega)) / amplitude
    assert phase_error < 1e-6


def test_large_amplitude_period_is_four_k_root_r_over_g():
    """The pendulum's period at amplitude A is 4 K(sin²(A/2)) √(r/g): checked with DOP853."""
    r, amplitude = 1.6, 1.5
    swing = Swing(g=G)
    period = 4 * ellipk(math.sin(amplitude / 2) ** 2) * math.sqrt(r / G)
    y0 = np.array([amplitude, 0.0])
    y = make_stepper("dop853", rtol=1e-12, atol=1e-14)(swing, y0, np.array([r]), np.zeros(1), period)
    np.testing.assert_allclose(y, y0, atol=1e-8)
    assert swing.quarter_period(r, amplitude) == pytest.approx(period / 4)


@pytest.mark.parametrize(
    "theta, theta_dot", [(0.3, 0.0), (1.5, 0.7), (-2.0, -3.0), (0.1 + 2 * math.pi, 0.5), (0.5, 9.0), (7.0, -8.0)]
)
def test_closed_form_flow_equals_numerical_integration(theta, theta_dot):
    """Libration and rotation (both senses, wound angles): the elliptic flow is DOP853's to 1e-10."""
    swing, r = Swing(mass=1.3, g=G), np.array([1.7])
    y0 = np.array([theta, swing.mass * r[0] ** 2 * theta_dot])
    reference = make_stepper("dop853", rtol=1e-13, atol=1e-13)(swing, y0, r, np.zeros(1), 0.83)
    np.testing.assert_allclose(swing.exact_flow(y0, r, 0.83), reference, atol=1e-10)


@pytest.mark.parametrize("offset", [0.0, 1e-6, 1e-5, 1e-3])
def test_exact_stepper_is_right_at_and_near_the_upright_equilibrium(offset):
    """Near the separatrix scipy's ellipj is inaccurate and at θ = π, θ̇ = 0 the elliptic phase is
    infinite; the exact stepper must still agree with DOP853 there, in a batch with an ordinary state.
    The reference is tight and the top is unstable (growth e^{ωt}), so the match is to 1e-6."""
    swing, tau, r = Swing(), 6.0, np.array([1.8])
    y = np.array([[math.pi - offset, 0.0], [0.3, 0.0]])
    reference = make_stepper("dop853", rtol=1e-13, atol=1e-13)(swing, y, r, np.zeros(1), tau)
    np.testing.assert_allclose(make_stepper("exact", swing)(swing, y, r, np.zeros(1), tau), reference, atol=1e-6)
    if offset >= 1e-6:
        assert reference[0, 0] < 3.0  # it has fallen away from the top


def test_closed_form_flow_broadcasts_over_a_batch():
    swing = Swing()
    y = np.stack([np.linspace(-3, 3, 7), np.linspace(-20, 20, 7)], -1)
    r = np.linspace(1.6, 2.0, 7)[:, None]
    batched = swing.exact_flow(y, r, 0.5)
    single = np.array([swing.exact_flow(y[i], r[i], 0.5) for i in range(7)])
    np.testing.assert_allclose(batched, single, rtol=1e-14, atol=1e-14)


def test_one_state_flow_takes_scipys_own_elliptic_functions():
    """The single env's direct call of Jacobi's sn, cn, dn is scipy's ufunc to the bit, across the phase and the
    parameter up to the separatrix band, so one state and a batch follow the same closed form."""
    rng = np.random.default_rng(0)
    w = rng.uniform(0.0, 30.0, 2000)
    m = np.concatenate([rng.uniform(0.0, 1.0, 1000), 1.0 - 10.0 ** rng.uniform(-6, -1, 1000)])
    ufunc = np.stack(ellipj(w, m), axis=-1)
    direct = np.array([ellipj_one(float(a), float(b)) for a, b in zip(w, m)])
    assert np.array_equal(direct, ufunc)


def pumped_amplitudes(theta0):
    """Amplitudes while squatting (r = r_max, energy conserved), one per half swing, under the
    Piccoli–Kulkarni law; and the time to reach π/2."""
    env = gym.make("connenv/Swing-v0")
    obs, info = env.reset(options={"state": {"theta": theta0}})
    policy, amplitudes, terminated = PiccoliKulkarni(), [], False
    while not terminated:
        sign = np.sign(info["state"]["theta"])
        obs, _, terminated, truncated, info = env.step(policy.predict(obs)[0])
        assert not truncated
        if np.sign(info["state"]["theta"]) != sign:  # crossed the bottom squatting; the jump comes next step
            assert info["state"]["r"] == R_MAX
            amplitudes.append(info["amplitude"])
    return np.array(amplitudes), info["state"]["t"]


def test_the_controller_follows_the_pumping_law():
    """(1 − cos θₙ₊₁) = ρ³ (1 − cos θₙ) per half swing. The switches come up to one step late; a
    switch δ late costs of order (ω δ)² of the gain, (g/r_min) dt² ≈ 1.5 %; we allow 3 %."""
    amplitudes, _ = pumped_amplitudes(0.1)
    assert len(amplitudes) >= 6
    ratios = (1 - np.cos(amplitudes[1:])) / (1 - np.cos(amplitudes[:-1]))
    np.testing.assert_allclose(ratios, RHO**3, rtol=0.03)


def ideal_pumping_time(theta0, target, r_min=R_MIN, r_max=R_MAX, g=G):
    """Time to reach the target amplitude with exact switching: a quarter period at r_max with
    amplitude θₙ, the jump at the bottom to θₙ₊₁ by the pumping law, a quarter period at r_min, and
    so on, until the jump at the bottom reaches the target. Quarter periods K(sin²(A/2))√(r/g)."""

    def quarter(r, amplitude):
        return ellipk(math.sin(amplitude / 2) ** 2) * math.sqrt(r / g)

    amplitude, time = theta0, 0.0
    while True:
        time += quarter(r_max, amplitude)
        amplitude = math.acos(1 - (r_max / r_min) ** 3 * (1 - math.cos(amplitude)))
        if amplitude >= target:
            return time
        time += quarter(r_min, amplitude)


def test_controller_reaches_pi_over_2_within_ten_percent_of_ideal_switching():
    ideal = ideal_pumping_time(0.1, math.pi / 2)
    assert ideal == pytest.approx(10.32, abs=0.01)  # eight half swings
    _, time = pumped_amplitudes(0.1)
    assert ideal - 0.05 <= time <= 1.1 * ideal
