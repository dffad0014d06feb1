"""Physical parameters as context: set per episode, drawn per episode (per row in the vector env), observed, and
answered by the physics as theory says."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import connenv  # noqa: F401  (registers the envs)
from agents.controllers.kapitza import KapitzaVibration


def make(env_id="connenv/Swing-v0", **kwargs):
    return gym.make(env_id, **kwargs).unwrapped


def test_reset_params_set_the_physics_for_the_episode_and_the_next_reset_restores_the_make_kwargs():
    env = make()
    _, info = env.reset(seed=0, options={"params": {"g": 3.0}})
    assert env.system.g == 3.0 and info["params"]["g"] == 3.0
    _, info = env.reset(seed=0)
    assert env.system.g == 9.81 and "params" not in info


def test_randomized_draws_repeat_with_the_seed_stay_in_range_and_are_log_uniform_for_a_scale():
    env = make(randomize={"g": (2.0, 32.0)})
    draws = []
    for seed in range(400):
        draws.append(env.reset(seed=seed)[1]["params"]["g"])
    again = [make(randomize={"g": (2.0, 32.0)}).reset(seed=seed)[1]["params"]["g"] for seed in range(5)]
    assert again == draws[:5]
    assert min(draws) >= 2.0 and max(draws) <= 32.0
    # log-uniform: half the draws lie below the geometric mean 8 (uniform: a fifth); σ = 0.025 over 400 draws
    assert abs(np.mean(np.array(draws) < 8.0) - 0.5) < 0.1


def test_a_randomized_episode_steps_as_an_env_made_with_its_parameters():
    env = make(randomize={"g": (7.0, 12.0), "mass": (0.5, 2.0)})
    _, info = env.reset(seed=3)
    fixed = make(g=info["params"]["g"], mass=info["params"]["mass"])
    fixed.reset(seed=0, options={"state": {k: info["state"][k] for k in ("theta", "theta_dot", "r")}})
    for a in np.linspace(-1, 1, 20):
        obs, reward, *_ = env.step(np.array([a]))
        obs_fixed, reward_fixed, *_ = fixed.step(np.array([a]))
        assert np.array_equal(obs, obs_fixed) and reward == reward_fixed


def test_observed_parameters_are_appended_normalized_over_their_range():
    env = gym.make("connenv/Swing-v0", randomize={"g": (4.0, 16.0)}, observe_params=True)
    obs, info = env.reset(seed=1, options={"params": {"g": 8.0}})
    assert env.observation_space.shape == (5,) and obs in env.observation_space
    assert obs[-1] == pytest.approx(0.0, abs=1e-7)  # 8 is the geometric middle of [4, 16]
    obs, info = env.reset(seed=1)
    assert obs[-1] == pytest.approx(2 * math.log(info["params"]["g"] / 4.0) / math.log(4.0) - 1.0, abs=1e-6)


def test_vector_rows_draw_and_step_as_the_single_envs_seeded_alike():
    kwargs = {"randomize": {"g": (7.0, 12.0)}, "observe_params": True}
    vector = gym.make_vec("connenv/Swing-v0", num_envs=3, vectorization_mode="vector_entry_point", **kwargs)
    singles = [gym.make("connenv/Swing-v0", **kwargs) for _ in range(3)]
    obs, info = vector.reset(seed=5)
    for i, env in enumerate(singles):
        obs_i, info_i = env.reset(seed=5 + i)
        assert np.array_equal(obs[i], obs_i) and info["params"]["g"][i] == info_i["params"]["g"]
    for a in np.linspace(-1, 1, 30):  # each row steps by the single env of its parameters: the same numbers
        obs, reward, *_ = vector.step(np.full((3, 1), a, np.float32))
        for i, env in enumerate(singles):
            obs_i, reward_i, *_ = env.step(np.array([a], np.float32))
            assert np.array_equal(obs[i], obs_i) and reward[i] == reward_i


@pytest.mark.parametrize(
    ("kwargs", "options", "message"),
    [
        ({"randomize": {"tolerance": (0.1, 0.2)}}, None, "'tolerance' is not a physical parameter"),
        ({"randomize": {"g": (0.0, 5.0)}}, None, "g=0.0"),
        ({"randomize": {"g": (5.0, 2.0)}}, None, "low must be at most high"),
        ({"randomize": {"g": 5.0}}, None, "must be a pair"),
        ({"observe_params": True}, None, "give randomize"),
        ({}, {"params": {"length": 1.0}}, "'length'] are not physical parameters"),
        ({}, {"params": {"g": -1.0}}, "g=-1.0"),
    ],
)
def test_bad_parameters_are_named_before_anything_changes(kwargs, options, message):
    with pytest.raises(ValueError, match=message):
        env = make(**kwargs)
        env.reset(seed=0)
        before = env.system
        try:
            env.reset(seed=0, options=options)
        finally:
            assert env.system is before


def test_a_parameter_that_would_change_the_observation_space_is_refused():
    """The skier observes κ h_max within ±k*, k* = max |κ| h_max: h_max may not vary."""
    with pytest.raises(ValueError, match="changes Skier-v0's observation space"):
        make("connenv/Skier-v0", randomize={"h_max": (0.9, 1.1)})


def deviation(env, policy, length, steps=2000):
    obs, _ = env.reset(options={"params": {"length": length}, "state": {"theta": math.pi + 0.1}})
    for _ in range(steps):
        obs, *_, info = env.step(policy.predict(obs)[0])
    return info["max_deviation"]


def test_the_kapitza_threshold_moves_with_the_length():
    """One vibration, a²ω² = 1.5 × 2 g l₀: it holds l = l₀/2 and l₀ inverted (a²ω² > 2 g l) and not 2 l₀."""
    env = make("connenv/KapitzaPendulum-v0", tolerance=3.0, a_max=0.2)
    policy = KapitzaVibration(env, amplitude=0.05, margin=1.5)
    assert deviation(env, policy, 0.5) < 0.15 and deviation(env, policy, 1.0) < 0.15
    assert deviation(env, policy, 2.0) > 1.0


def integrated(r0, v0, theta0, omega, tau, g):
    """(r, ṙ) at tau from r̈ = ω² r − g sin(θ₀ + ω t), by DOP853 at rtol = atol = 1e-13."""
    sol = solve_ivp(lambda t, z: [z[1], omega**2 * z[0] - g * math.sin(theta0 + omega * t)], (0.0, tau),
                    [r0, v0], method="DOP853", rtol=1e-13, atol=1e-13)  # fmt: skip
    return sol.y[:, -1]


@pytest.mark.parametrize("g", [1.62, 9.81, 24.8])
def test_the_bead_follows_its_closed_form_under_each_g(g):
    env = make("connenv/BeadOnBar-v1")
    env.reset(seed=0, options={"params": {"g": g}, "state": {"r": 0.3, "r_dot": -0.4, "theta": 0.7}})
    for _ in range(10):
        _, _, _, _, info = env.step(np.array([0.5]))
    r, r_dot = integrated(0.3, -0.4, 0.7, 0.5 * env.omega_max, 10 * env.dt, g)
    assert info["state"]["r"] == pytest.approx(r, abs=1e-9) and info["state"]["r_dot"] == pytest.approx(r_dot, abs=1e-9)


@pytest.mark.parametrize(("body", "beanie"), [(1.0, 0.25), (0.3, 0.9), (2.0, 2.0)])
def test_the_beanies_geometric_phase_follows_the_inertias(body, beanie):
    """One turn of the beanie at μ = 0 turns the body by −2π I₂/(I₁+I₂), whatever the inertias. The observed μ is
    bounded by 0.9 I₂ · max_beanie_speed, so I₂ is a make kwarg and I₁ an episode's parameter."""
    steps = 10
    env = make("connenv/ElroysBeanie-v0", max_beanie_speed=2 * math.pi / (steps * 0.05), beanie_inertia=beanie)
    params = {"body_inertia": body}
    env.reset(seed=0, options={"params": params, "state": {"theta": 0.0, "momentum": 0.0}, "target": 0.0})
    for _ in range(steps):
        env.step(np.array([1.0]))
    assert env.state.g[0] == pytest.approx(-2 * math.pi * beanie / (body + beanie), abs=1e-12)


@pytest.mark.parametrize(
    ("env_id", "randomize", "constraint"),
    [
        ("connenv/SnakeSwimmer-v0", {"a": (0.3, 0.6), "b": (0.05, 0.4)}, r"b=0.4 .* a=0.3\)"),
        ("connenv/FallingCat-v0", {"transverse_inertia": (0.005, 0.02), "axial_inertia": (0.001, 0.008)},
         r"axial_inertia=0.008 .* transverse_inertia=0.005\)"),
        ("connenv/KapitzaPendulum-v0", {"length": (0.1, 1.0), "a_max": (0.05, 0.2)}, r"a_max=0.2 .* length=0.1\)"),
        ("connenv/KapitzaSwingUp-v0", {"length": (0.1, 1.0), "a_max": (0.05, 0.2)}, r"a_max=0.2 .* length=0.1\)"),
        ("connenv/KozlovShell-v0", {"a": (0.5, 1.0), "b": (0.4, 0.8)}, r"u1_max=0.5, u2_max=0.25: .* corners must lie inside the ellipse"),
    ],
)
def test_linked_ranges_that_some_draws_would_break_are_refused_at_make_naming_the_constraint(
        env_id, randomize, constraint):
    """b < a (the snake), I_axial < I (the cat), a_max < l (Kapitza), the box inside the ellipse (the shell): a
    range is refused at make where one of its draws would be refused at reset, with the corner and the constraint."""
    with pytest.raises(ValueError, match=f"can draw values {env_id[8:]} refuses, at {{.*}}: {constraint}"):
        gym.make(env_id, randomize=randomize)


def test_linked_ranges_that_never_meet_are_taken_and_every_draw_resets():
    """b ≤ 0.25 < 0.3 ≤ a: each of the draws is a snake, though b's range lies above the default a/100 ... a."""
    env = make("connenv/SnakeSwimmer-v0", randomize={"a": (0.3, 0.6), "b": (0.05, 0.25)})
    for seed in range(50):
        params = env.reset(seed=seed)[1]["params"]
        assert 0.3 <= params["a"] <= 0.6 and 0.05 <= params["b"] <= 0.25


@pytest.mark.parametrize("bounds", [(9.81, 9.81), (9.81e6, 9.81e6), (9.81e-6, 9.81e-6), (2.0, 9.81e6), (9.81e-6, 3.0)])
def test_draws_lie_in_the_declared_range_with_its_ends_exact(bounds):
    """exp(uniform(log low, log high)) rounds past an end (9.81 → 9.809999999999999, 9.81e6 → 9.810000000000013e6,
    outside g's valid range): a draw is within [low, high], an empty range is its one value."""
    env = make(randomize={"g": bounds})
    draws = [env.reset(seed=seed)[1]["params"]["g"] for seed in range(200)]
    assert bounds[0] <= min(draws) and max(draws) <= bounds[1]
    if bounds[0] == bounds[1]:
        assert set(draws) == {bounds[0]}


@pytest.mark.parametrize("bounds", ["79", {7: 1, 9: 2}, (True, 2), (7, False), (7.0, 9 + 0j), (7.0,), (7, 8, 9),
                                    ("7", "9"), np.array([7.0, 9.0, 10.0]), None])
def test_a_range_is_a_pair_of_real_numbers(bounds):
    """A string of two digits, a dict's keys, a bool or a complex number are not a range."""
    with pytest.raises(ValueError, match=r"randomize\['g'\]=.* must be a pair \(low, high\) of real numbers"):
        make(randomize={"g": bounds})


def test_a_range_given_as_a_list_or_array_of_two_numbers_is_taken():
    for bounds in ([7, 12], np.array([7.0, 12.0]), (np.float32(7.0), np.int64(12))):
        assert make(randomize={"g": bounds}).context.ranges["g"].high == 12.0
