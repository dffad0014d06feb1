"""The same physics on JAX: for every id whose spec declares JAX make kwargs, the traced step (connenv.jax) is the
numpy env's step to rounding, its forward-mode Jacobians are the model's complex-step ones, a failing step is
reported as data, and the functional interface keeps gymnax's conventions."""

from __future__ import annotations

import dataclasses
import math
import os

import gymnasium as gym
import numpy as np
import pytest

# XLA's CPU backend without LLVM's optimization passes: the traced steps compile several times faster, and these
# tests run each compiled program on a few thousand states at most, so its speed does not matter here; the results
# are IEEE arithmetic either way (the tolerances below hold at both levels)
os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()
jax = pytest.importorskip("jax")
jax.config.update("jax_enable_x64", True)  # noqa: E402  (connenv.jax asks for float64; tests run in their own process)
import jax.numpy as jnp  # noqa: E402
import scipy.special  # noqa: E402

import connenv.jax as cj  # noqa: E402
from connenv.envs.spec import registry  # noqa: E402
from connenv.core.backend import FLOATS  # noqa: E402
from connenv.core.steppers import StepperError  # noqa: E402
from connenv.jax.namespace import ellipj  # noqa: E402

CASES = [(spec.id, kwargs) for spec in registry.values() for kwargs in spec.jax]
IDS = [i.removeprefix("connenv/") + (f"-{kw.__name__}" if callable(kw) else "".join(f"-{k}={v}" for k, v in kw.items()))
       for i, kw in CASES]  # a builder's kwargs by its example's name
SEEDS, STEPS = 20, 1000
STEP_RTOL = 1e-12
"""|x_jax − x_numpy| ≤ STEP_RTOL · max(1, |x_numpy|) entry by entry after one step: XLA's sin, cos, atan2 and its
order of operations round differently from libm and numpy by an ulp or so, which a step's few dozen operations grow
to a few times 1e-16; the floor of 1 stands for quantities that are all roundoff (an exact step's energy error)."""
JACOBIAN_RTOL = 1e-10


def trajectories(env_id, kwargs):
    """States, actions and what the numpy env did from them: SEEDS episodes of up to STEPS steps of random actions
    (an episode that ends is followed by the next seed's)."""
    env = gym.make(env_id, **kwargs).unwrapped
    model = env.model
    rng = np.random.default_rng(0)
    X, A, X1, R, T, O, E = [], [], [], [], [], [], []
    for seed in range(SEEDS):
        env.reset(seed=seed)
        for _ in range(STEPS // 10 if SEEDS * STEPS > 2000 and seed % 2 else STEPS):
            a = rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32)
            X.append(model.pack(env.state))
            obs, reward, terminated, _, _ = env.step(a)
            A.append(a), X1.append(model.pack(env.state)), R.append(reward), T.append(terminated), O.append(obs)
            E.append(seed)
            if terminated:
                break
    return env, *(np.array(v) for v in (X, A, X1, R, T, O, E))


@pytest.fixture(scope="module", params=CASES, ids=IDS)
def case(request):
    env_id, kwargs = request.param
    kwargs = kwargs() if callable(kwargs) else kwargs  # a builder's example (Spec.jax)
    jenv, params = cj.make(env_id, **kwargs)
    return jenv, params, trajectories(env_id, kwargs)


@pytest.fixture(scope="module")
def one_step(case):
    """The traced step of one state (not vmapped), compiled once per case."""
    return jax.jit(case[0].transition)


def test_the_traced_step_is_the_numpy_step_to_rounding(case, one_step):
    jenv, params, (env, X, A, X1, R, T, O, E) = case
    step = jax.jit(jax.vmap(lambda x, a: jenv.transition(x, a)))
    x1, obs, reward, terminated, info, failed = step(jnp.asarray(X), jnp.asarray(A))
    x1 = np.asarray(x1)
    worst = np.max(np.abs(x1 - X1) / np.maximum(1.0, np.abs(X1)))
    print(f"{jenv.name}: {len(X)} states, largest difference {worst:.2g} of max(1, |x|)")
    assert worst <= STEP_RTOL
    assert not np.any(failed)
    np.testing.assert_array_equal(np.asarray(terminated), T)
    np.testing.assert_allclose(np.asarray(reward), R, rtol=STEP_RTOL, atol=STEP_RTOL)
    if isinstance(obs, dict):  # a goal env's: each key's rows
        observed, expected = obs, {key: np.array([o[key] for o in O]) for key in obs}
    else:
        observed, expected = {"": obs}, {"": O}
    for key, value in observed.items():  # float32's rounding
        np.testing.assert_allclose(np.asarray(value), expected[key], rtol=2 * np.finfo(np.float32).eps, atol=1e-7,
                                   err_msg=key)
    # one state, not vmapped, gives what the rows give, to the ulp or two by which XLA's code for one row and for a
    # batch may round apart (its fusions differ: KapitzaSwingUp-v0's θ and p, by an ulp or two)
    one = one_step(jnp.asarray(X[7]), jnp.asarray(A[7]))[0]
    assert np.max(np.abs(np.asarray(one) - x1[7]) / np.maximum(1.0, np.abs(x1[7]))) <= 1e-15


TRAJECTORY_RTOL = 1e-11
"""Largest difference of a whole JAX trajectory from numpy's (up to 1000 steps of the same random actions from the
same state, seeds 0, 2 and 4), as a fraction of max(1, |x|): each step rounds differently by ~1e-16 (above), and the
flow carries that difference along, growing it where the motion is unstable (the Kapitza pivot's fast oscillation
stretches it most). The test prints each id's; docs/guides/jax.md tables them."""


TRAJECTORY_RTOL_OF = {"Skier-v0": 1e-9}
"""Skier-v0: its state's energy error, the sum of each projected step's change of E (E ≈ 800 J, a difference of
large numbers), is all roundoff: a few ulp of E a step, summed over 1000 steps, pass TRAJECTORY_RTOL in that entry
alone, while x and p stay within it (the test prints the difference)."""


def test_whole_trajectories_follow_numpys(case, one_step):
    jenv, params, (env, X, A, X1, R, T, O, E) = case
    worst = 0.0
    for seed in (0, 2, 4):
        rows = np.flatnonzero(E == seed)
        x = jnp.asarray(X[rows[0]])
        for k in rows:
            x = one_step(x, jnp.asarray(A[k]))[0]
            worst = max(worst, float(np.max(np.abs(np.asarray(x) - X1[k]) / np.maximum(1.0, np.abs(X1[k])))))
    print(f"{jenv.name}: whole trajectories differ by {worst:.2g} of max(1, |x|)")
    assert worst <= TRAJECTORY_RTOL_OF.get(jenv.name, TRAJECTORY_RTOL)


def test_forward_mode_jacobians_are_the_models_complex_step_ones(case):
    """jax.jacfwd of the step is model.jacobians' complex step at states of the numpy env's trajectories, ties of max,
    min and sort included: under ties="one-sided", whose derivative at a tie is the complex step's one-sided one (a
    pivot at its end stop, which random actions reach); the default rule ("linear") takes the second argument's
    there, the same derivative everywhere else (test_reverse_mode_is_forward_mode_transposed)."""
    jenv, params, (env, X, A, *_) = case
    jenv = cj.FunctionalEnv(jenv.env, jenv.max_episode_steps, ties="one-sided")
    pick = np.linspace(0, len(X) - 1, 20).astype(int)
    jac = jax.jit(jax.vmap(jax.jacfwd(lambda x, a: jenv.transition(x, a)[0], argnums=(0, 1))))
    JA, JB = (np.asarray(J) for J in jac(jnp.asarray(X[pick]), jnp.asarray(A[pick], float)))
    MA, MB = env.model.jacobians(X[pick], A[pick])
    for mine, theirs in ((JA, MA), (JB, MB)):
        assert np.max(np.abs(mine - theirs) / np.maximum(1.0, np.abs(theirs))) <= JACOBIAN_RTOL


def test_a_diverging_step_is_a_flag_with_the_state_held():
    """Explicit Euler over a 10 s step from the top of a fast swing: the numpy env raises StepperError (its energy
    error past the bound); the JAX step reports it, holds the state and truncates the episode."""
    kwargs, start = {"integrator": "euler", "dt": 10.0}, {"state": {"theta": 3.0, "theta_dot": 7.7, "r": 1.6}}
    env = gym.make("connenv/Swing-v0", **kwargs).unwrapped
    env.reset(seed=0, options=start)
    x = env.model.pack(env.state)
    with pytest.raises(StepperError):
        env.step(np.array([1.0], np.float32))
    jenv, params = cj.make("connenv/Swing-v0", **kwargs)
    state = cj.EnvState(jnp.asarray(x), jnp.int32(0))
    obs, after, reward, terminated, truncated, info = jax.jit(jenv.step_env)(jax.random.key(0), state, jnp.ones(1),
                                                                             params)
    assert bool(info["stepper_failed"]) and bool(truncated) and not bool(terminated)
    np.testing.assert_array_equal(np.asarray(after.x), x)


@pytest.mark.parametrize("env_id", ["connenv/Swing-v0", "connenv/KapitzaPendulum-v0"])
def test_semi_implicit_euler_traces_as_numpy_steps_it(env_id):
    """Semi-implicit Euler (symplectic on the swing; Gymnasium's, first order, on the Kapitza pendulum, whose q̇
    depends on q) on rows: the JAX step is numpy's model step to rounding, at 2 substeps, from states along random
    episodes of the exact step."""
    kwargs = {"integrator": "semi_implicit_euler", "substeps": 2}
    env = gym.make(env_id).unwrapped
    stepped = gym.make(env_id, **kwargs).unwrapped.model
    rng = np.random.default_rng(0)
    X = []
    for seed in range(4):
        env.reset(seed=seed)
        for _ in range(30):
            X.append(env.model.pack(env.state))
            env.step(env.action_space.sample())
    X = np.array(X)
    A = rng.uniform(env.action_space.low, env.action_space.high, (len(X), *env.action_space.shape))
    jenv, params = cj.make(env_id, **kwargs)
    mine = np.asarray(jax.jit(jax.vmap(lambda x, a: jenv.transition(x, a, params)[0]))(X, A))
    theirs = stepped.step(X, A)
    assert np.max(np.abs(mine - theirs) / np.maximum(1.0, np.abs(theirs))) <= STEP_RTOL
    assert np.max(np.abs(theirs - env.model.step(X, A))) > 1e-6  # it is not the exact step


def test_an_ended_episode_resets_and_hands_over_its_last_observation():
    """Swing-v0 at its target amplitude (held over the step at r_max): terminated, and step gives
    the next episode's first observation, the last one in info."""
    env = gym.make("connenv/Swing-v0", target_amplitude=0.3).unwrapped
    env.reset(seed=0, options={"state": {"theta": 0.31, "theta_dot": 0.0, "r": 2.0}})
    jenv, params = cj.make("connenv/Swing-v0", target_amplitude=0.3)
    x = env.model.pack(env.state)
    obs_numpy, *_ = env.step(np.array([1.0], np.float32))
    state = cj.EnvState(jnp.asarray(x), jnp.int32(0))
    obs, after, reward, terminated, truncated, info = jax.jit(jenv.step)(jax.random.key(3), state, jnp.ones(1), params)
    assert bool(terminated) and not bool(truncated)
    np.testing.assert_allclose(np.asarray(info["final_observation"]), obs_numpy, atol=1e-7)
    assert int(after.time) == 0 and abs(float(after.x[0])) <= 0.1  # a fresh start: |θ₀| in [0.05, 0.1]


def test_the_time_limit_truncates():
    jenv, params = cj.make("connenv/Swing-v0")
    obs, state = jenv.reset(jax.random.key(0), params)
    state = cj.EnvState(state.x, jnp.int32(params.max_steps_in_episode - 1))
    *_, terminated, truncated, info = jenv.step_env(jax.random.key(1), state, jnp.zeros(1), params)
    assert bool(truncated) and not bool(terminated)


def test_the_reset_draws_the_numpy_envs_distribution():
    """Swing-v0 starts at rest at r_max with |θ₀| uniform on [0.05, 0.1] and either sign, from a key."""
    jenv, params = cj.make("connenv/Swing-v0")
    obs, states = jax.vmap(jenv.reset, (0, None))(jax.random.split(jax.random.key(0), 4000), params)
    theta, p, r = (np.asarray(states.x[:, i]) for i in range(3))
    assert np.all((np.abs(theta) >= 0.05) & (np.abs(theta) <= 0.1)) and np.all(p == 0.0) and np.all(r == 2.0)
    assert abs(np.mean(theta > 0) - 0.5) < 0.05 and abs(np.mean(np.abs(theta)) - 0.075) < 0.002


def test_the_ball_reset_draws_a_uniform_target():
    """RollingBall-v0 starts at R = I at the origin with R* uniform on SO(3) (Haar: E[R*] = 0, E[tr R*] = 0), drawn
    from a key as a normal quaternion; no distance is measured (NaN: the optimal arc's root search does not trace)."""
    jenv, params = cj.make("connenv/RollingBall-v0")
    obs, states = jax.vmap(jenv.reset, (0, None))(jax.random.split(jax.random.key(0), 4000), params)
    fields = jenv.state_of(np.asarray(states.x))
    R, target = np.asarray(fields.R), np.asarray(fields.R_target)
    assert np.all(R == np.eye(3)) and np.all(np.asarray(fields.position) == 0.0)
    np.testing.assert_allclose(target @ np.swapaxes(target, -1, -2), np.broadcast_to(np.eye(3), target.shape),
                               atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(target), 1.0, atol=1e-14)
    assert np.max(np.abs(target.mean(axis=0))) < 0.05 and abs(np.trace(target, axis1=1, axis2=2).mean()) < 0.05
    assert np.all(np.isnan(np.asarray(fields.distance)))
    P = np.swapaxes(target, 1, 2)  # R R*ᵀ at R = I
    np.testing.assert_array_equal(np.asarray(obs), np.concatenate([P[..., 0], P[..., 1]], -1).astype(np.float32))


def test_the_goal_env_observes_a_dict_and_resets_with_its_last_one():
    """RollingBallGoal-v0: the Dict observation space of Boxes (gymnax's spaces.Dict), a dict observation from the
    reset and the step, and the autoreset's last observation a dict, the numpy env's from the same state."""
    env = gym.make("connenv/RollingBallGoal-v0", tolerance=1.5).unwrapped
    env.reset(seed=0, options={"target": np.eye(3)})
    jenv, params = cj.make("connenv/RollingBallGoal-v0", tolerance=1.5)
    space = jenv.observation_space(params)
    assert set(space.spaces) == {"observation", "achieved_goal", "desired_goal"}
    sample = space.sample(jax.random.key(0))
    assert bool(space.contains(sample)) and all(v.dtype == np.float32 and v.shape == (6,) for v in sample.values())
    obs, state = jenv.reset(jax.random.key(1), params)
    assert bool(space.contains(obs))
    x = env.model.pack(env.state)
    obs_numpy, reward, terminated, *_ = env.step(np.array([0.1, 0.0], np.float32))  # at the target: success
    obs, after, reward_jax, terminated_jax, truncated, info = jax.jit(jenv.step)(
        jax.random.key(3), cj.EnvState(jnp.asarray(x), jnp.int32(0)), jnp.asarray([0.1, 0.0]), params)
    assert terminated and bool(terminated_jax) and float(reward_jax) == reward == 0.0
    for key, value in obs_numpy.items():
        np.testing.assert_array_equal(np.asarray(info["final_observation"][key]), value)
    assert int(after.time) == 0 and bool(space.contains(obs))


def test_the_traced_jacobi_elliptic_functions_are_scipys():
    """sn, cn, dn and am by cephes' descending Landen recurrence at a fixed trip count, against scipy's ellipj over
    the whole parameter range and the series at its ends (dn, near cn = 0, differs most)."""
    rng = np.random.default_rng(1)
    u = rng.uniform(-20.0, 20.0, 20000)
    m = np.concatenate([rng.uniform(0.0, 1.0, 19990), [0.0, 1e-12, 1e-10, 1e-9, 1e-5, 0.5, 1 - 1e-9, 1 - 1e-10,
                                                       1 - 1e-12, 1.0]])
    for mine, theirs in zip(ellipj(jnp.asarray(u), jnp.asarray(m)), scipy.special.ellipj(u, m)):
        assert np.max(np.abs(np.asarray(mine) - theirs)) <= 1e-13


def test_float64_is_asked_for_not_switched_on():
    jax.config.update("jax_enable_x64", False)
    try:
        with pytest.raises(RuntimeError, match="jax_enable_x64"):
            cj.make("connenv/Swing-v0")
    finally:
        jax.config.update("jax_enable_x64", True)


def test_every_id_has_a_jax_version_and_a_stepper_without_one_is_refused_by_name():
    """Every registered id declares the make kwargs its JAX step is checked with; scipy's adaptive integrators, whose
    step-size control does not trace, are a TypeError at make naming the stepper and the ones that trace."""
    assert all(spec.jax for spec in registry.values()), [i for i, spec in registry.items() if not spec.jax]
    with pytest.raises(TypeError, match=r"(?is)Swing-v0's stepper .*dop853.* no JAX version.*'rk4'"):
        cj.make("connenv/Swing-v0", integrator="dop853")


@pytest.mark.parametrize("env_id", ["connenv/FallingCat-v0", "connenv/TubeTwist-v0"])
def test_the_jacobians_at_rest_at_the_start_are_the_models(env_id):
    """From the start at rest with a zero action: the falling cat's β = 0 (√β² has no derivative there; β² is
    stationary) and the tube's T = T₀ (hypot's apex), where JAX's own derivatives are NaN or not the complex step's.
    From there under a nonzero action, the reward's derivative in it is the numpy reward's central difference: finite
    where the cat's spine lies on its start (its error √|spine × start|² at 0, whose derivative leaked ∞ · 0 = NaN)."""
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    model = env.model
    x, a = model.pack(env.state), np.zeros(env.action_space.shape)
    jenv, _ = cj.make(env_id)

    def step(x, a):
        x_next, _, reward, *_ = jenv.transition(x, a)
        return x_next, reward

    jacobians = jax.jit(jax.jacfwd(step, argnums=(0, 1)))
    (JA, JB), _ = jacobians(jnp.asarray(x), jnp.asarray(a))
    MA, MB = model.jacobians(x[None], a[None])
    for mine, theirs in ((JA, MA[0]), (JB, MB[0])):
        assert np.max(np.abs(np.asarray(mine) - theirs) / np.maximum(1.0, np.abs(theirs))) <= JACOBIAN_RTOL
    # the reward's derivative at a nonzero action (the same compiled function), against numpy's central difference
    b, h = np.linspace(0.3, -0.2, a.size), 1e-6
    _, (_, reward_by_action) = jacobians(jnp.asarray(x), jnp.asarray(b))

    def reward(b):
        return model.reward(x, b, model.step(x, b))

    central = [(reward(b + h * e) - reward(b - h * e)) / (2 * h) for e in np.eye(a.size)]
    assert np.all(np.isfinite(np.asarray(reward_by_action)))
    np.testing.assert_allclose(np.asarray(reward_by_action), central, rtol=1e-6, atol=1e-8)


def test_the_cats_stop_at_the_disc_differentiates_in_reverse_mode():
    """falling_cat.disc_segment (the bend stopped where β reaches max_bend) on rows staying inside the disc from the
    straight cat (β = 0, whose root √b² is at 0), leaving it from its edge (c = 0), moving in from its edge but ending
    out (the quotient not taken is 0/0) and crossing it: jax.grad equals jax.jacfwd, finite, as the root and the
    quotients of the rows that do not take them are kept from 0 by where (reverse mode multiplied their cotangent 0
    by an infinite derivative: NaN)."""
    from connenv.systems import falling_cat

    s = jnp.array([[0.0, 0.0], [0.5, 0.0], [0.5, 0.0], [0.3, 0.1]])
    v = jnp.array([[0.3, -0.2], [1.0, 0.5], [-0.1, 10.0], [8.0, 0.0]])

    def total(s, v):
        tau, s_end, v_end = falling_cat.disc_segment(s, v, 0.5, 0.05)
        return jnp.sum(tau * jnp.arange(1.0, 5.0)) + jnp.sum(s_end * jnp.array([1.0, 2.0])) + jnp.sum(v_end)

    reverse, forward = jax.jit(lambda s, v: (jax.grad(total, (0, 1))(s, v), jax.jacfwd(total, (0, 1))(s, v)))(s, v)
    for mine, theirs in zip(reverse, forward):
        assert np.all(np.isfinite(np.asarray(mine)))
        np.testing.assert_allclose(np.asarray(mine), np.asarray(theirs), rtol=1e-14, atol=1e-14)


def test_reset_options_set_the_start_as_the_numpy_envs_do_traced_or_drawn_from_the_key():
    """KapitzaSwingUp-v0 released at rest at θ = 2 rad: the JAX reset with the numpy env's reset options gives its
    observation and state (to rounding), the values given as numbers or traced under jit; a function of the task as
    options draws from the key (agents.curriculum's kapitza_release: |θ| on [0.1, π], at rest)."""
    from agents import curriculum

    jenv, params = cj.make("connenv/KapitzaSwingUp-v0")
    env = gym.make("connenv/KapitzaSwingUp-v0").unwrapped
    options = {"state": {"theta": 2.0, "theta_dot": 0.0, "u": (0.0, 0.0), "u_dot": (0.0, 0.0)}}
    obs, _ = env.reset(seed=0, options=options)
    x = env.model.pack(env.state)
    mine = jenv.reset(jax.random.key(0), params, options)
    traced = jax.jit(lambda k, theta: jenv.reset(k, params, {"state": {**options["state"], "theta": theta}}))(
        jax.random.key(1), 2.0)
    for jax_obs, state in (mine, traced):
        np.testing.assert_allclose(np.asarray(state.x), x, rtol=STEP_RTOL, atol=STEP_RTOL)
        np.testing.assert_allclose(np.asarray(jax_obs), obs, rtol=1e-6)  # float32 observations
    starts = curriculum.jax_starts("kapitza_release")[0]
    _, states = jax.vmap(lambda k: jenv.reset(k, params, starts))(jax.random.split(jax.random.key(2), 2000))
    theta, p = np.asarray(states.x[:, 0]), np.asarray(states.x[:, 1])
    assert np.all((np.abs(theta) >= 0.1) & (np.abs(theta) <= np.pi)) and np.all(p == 0.0)
    assert np.max(np.abs(theta)) > 3.0 and abs(np.mean(theta > 0) - 0.5) < 0.05  # up to inverted, either side


def test_the_cat_and_tube_resets_draw_their_distributions():
    """FallingCat-v0 starts straight at rest, upside down: g = Rz(ψ) Rx(π + δ), |δ| ≤ 0.2, its heading frame's first
    column the (horizontal) spine; TubeTwist-v0 at R = R₀ = I with ψ* uniform on [0.3, 3]; both from a key."""
    keys = jax.random.split(jax.random.key(0), 4000)
    jenv, params = cj.make("connenv/FallingCat-v0")
    obs, states = jax.vmap(jenv.reset, (0, None))(keys, params)
    cat = jenv.state_of(np.asarray(states.x))
    g, H = np.asarray(cat.g).reshape(-1, 3, 3), np.asarray(cat.heading).reshape(-1, 3, 3)
    np.testing.assert_allclose(g @ np.swapaxes(g, 1, 2), np.broadcast_to(np.eye(3), g.shape), atol=1e-14)
    roll = np.arctan2(g[:, 2, 1], g[:, 2, 2])
    assert np.all(np.pi - np.abs(roll) <= 0.2 + 1e-12) and np.all(g[:, 2, 0] == 0.0)
    np.testing.assert_array_equal(H[:, :, 0], g[:, :, 0])
    assert np.all(np.asarray(cat.s) == 0.0) and np.all(np.asarray(cat.s_dot) == 0.0) and np.all(np.asarray(cat.t) == 0)
    jenv, params = cj.make("connenv/TubeTwist-v0")
    obs, states = jax.vmap(jenv.reset, (0, None))(keys, params)
    tube = jenv.state_of(np.asarray(states.x))
    target = np.asarray(tube.target)
    assert np.all((target >= 0.3) & (target <= 3.0)) and abs(target.mean() - 1.65) < 0.05
    assert np.all(np.asarray(tube.g) == np.eye(3).ravel()) and np.all(np.asarray(tube.R0) == np.eye(3).ravel())


def test_the_coin_on_a_surface_resets_to_its_distribution():
    """RollingCoinSurface-v0 starts at rest at the origin, θ uniform on [−π, π), the target target_distance from it
    within ±target_angle of the steepest descent, from a key; E = E₀ there, the numpy env's start energy."""
    jenv, params = cj.make("connenv/RollingCoinSurface-v0")
    obs, states = jax.vmap(jenv.reset, (0, None))(jax.random.split(jax.random.key(0), 4000), params)
    coin = jenv.state_of(np.asarray(states.x))
    env = gym.make("connenv/RollingCoinSurface-v0").unwrapped
    env.reset(seed=0)
    theta, target = np.asarray(coin.theta), np.asarray(coin.target).reshape(-1, 2)
    assert np.all(np.asarray(coin.y).reshape(-1, 4) == 0.0) and np.all(np.asarray(coin.energy) == env.state.energy0)
    assert np.all(np.abs(theta) <= math.pi) and abs(np.mean(theta)) < 0.1 and abs(np.std(theta) - math.pi / 3**0.5) < 0.05
    np.testing.assert_allclose(np.hypot(*target.T), env.target_distance, rtol=1e-14)
    bearing = np.arctan2(target[:, 0], target[:, 1]) - env.downhill
    assert np.all(np.abs(bearing) <= env.target_angle + 1e-12) and np.std(bearing) > 0.9 * env.target_angle / 3**0.5


def _numpy_connection(s):
    """A(s) = [[cos s₁]] by numpy's cos, which converts its argument: no JAX version."""
    return np.array([[np.cos(s[0])]])


def test_a_connection_or_system_that_does_not_trace_is_a_type_error_saying_what_is_needed():
    """Connection-v0 of a connection written with numpy's functions, ActiveConstraint-v0 of a fit system's jumps
    (scipy's DOP853): a TypeError at make naming what the user's functions need; the builders' systems that trace
    (a bead's general one by velocity, the ball's constant connection) are made, and their reset traces."""
    from connenv import examples

    kwargs = dict(group="SO2", connection=_numpy_connection, shape_low=[-1.0], shape_high=[1.0], integrator="rk4")
    with pytest.raises(TypeError, match="namespace of its argument"):
        cj.make("connenv/Connection-v0", **kwargs)
    with pytest.raises(TypeError, match="fit system's jumps"):
        cj.make("connenv/ActiveConstraint-v0", **{**examples.rotor(), "integrator": "rk4"})
    for env_id, made in (("connenv/ActiveConstraint-v0", examples.bead()),
                         ("connenv/Connection-v0", examples.rolling_ball())):
        jenv, params = cj.make(env_id, **made, integrator="rk4")
        env = gym.make(env_id, **made, integrator="rk4").unwrapped
        env.reset(seed=0)
        obs, state = jenv.reset(jax.random.key(0), params)
        np.testing.assert_array_equal(np.asarray(state.x), env.model.pack(env.state))


@pytest.mark.parametrize("env_id, unit", [("connenv/SnakeSwimmer-v0", 3.0), ("connenv/KozlovShell-v0", 1.0)])
def test_the_swimmer_resets_draw_their_targets(env_id, unit):
    """The swimmers start at rest at the origin in the reduced model, the target uniform in distance (TARGET_DISTANCES
    body lengths: the snake's 6a = 3 m; the shell's in metres) and in direction, from a key."""
    jenv, params = cj.make(env_id)
    obs, states = jax.vmap(jenv.reset, (0, None))(jax.random.split(jax.random.key(0), 4000), params)
    fields = jenv.state_of(np.asarray(states.x))
    target = np.asarray(fields.target)
    low, high = jenv.env.TARGET_DISTANCES
    distance = np.hypot(target[:, 0], target[:, 1]) / unit
    assert np.all((distance >= low) & (distance <= high)) and abs(distance.mean() - (low + high) / 2) < 0.02 * high
    assert abs(np.mean(target[:, 1] > 0) - 0.5) < 0.05
    assert np.all(np.asarray(fields.pose) == 0.0) and np.all(np.asarray(fields.momentum) == 0.0)
    assert not np.any(np.asarray(fields.full)) and np.all(np.asarray(fields.momentum0) == 0.0)


@pytest.mark.parametrize("env_id, n", [("connenv/Swing-v0", 64), ("connenv/KozlovShell-v0", 2048)])
def test_step_rows_is_the_vmapped_step(env_id, n):
    """step_rows (N envs in one call, a branch no row takes skipped) gives vmap(step_env)'s numbers to the bit; at
    N = 2048 the shell's Lie-group quadrature, which numpy's rows run in blocks of bounded memory, takes JAX's rows
    whole (it raised TracerArrayConversionError there before). The shell's full (Kirchhoff) model, a branch run only
    where some row is full, gives vmap's numbers with a third of the rows full as with none. A third of the rows at
    the time limit (more than one chunk of the resets, which step_rows runs on the done rows alone) are reset_rows'
    of the same key (to an ulp), the others step_env's; autoreset_rows with a key per group (two seeds' rows in one batch) resets
    each group from its own key."""
    jenv, params = cj.make(env_id)
    obs, states = jenv.reset_rows(jax.random.key(0), n, params)
    actions = jax.random.uniform(jax.random.key(1), (n, *jenv.action_space(params).shape), minval=-1.0, maxval=1.0)
    step_rows = jax.jit(jenv.step_rows)
    each = jax.jit(jax.vmap(jenv.step_env, (0, 0, 0, None)))
    batches = [states]
    if env_id == "connenv/KozlovShell-v0":  # a third of the rows in the full model, with a momentum
        numpy_env = gym.make(env_id).unwrapped
        numpy_env.reset(seed=0, options={"state": {"momentum": (0.3, -0.2, 0.1)}})
        full = np.arange(n) % 3 == 0
        batches.append(cj.EnvState(jnp.where(full[:, None], numpy_env.model.pack(numpy_env.state), states.x),
                                   states.time))
    for batch in batches:
        rows = step_rows(jax.random.key(2), batch, actions, params)
        alone = each(jax.random.split(jax.random.key(2), n), batch, actions, params)
        np.testing.assert_array_equal(np.asarray(rows[1].x), np.asarray(alone[1].x))
        np.testing.assert_array_equal(np.asarray(rows[2]), np.asarray(alone[2]))
        assert not np.any(np.asarray(rows[5]["stepper_failed"]))
    ending = np.arange(n) % 3 == 1
    at_limit = cj.EnvState(states.x, jnp.where(ending, params.max_steps_in_episode - 1, 0).astype(states.time.dtype))
    rows = step_rows(jax.random.key(2), at_limit, actions, params)
    alone = each(jax.random.split(jax.random.key(2), n), at_limit, actions, params)
    fresh = jenv.reset_rows(jax.random.key(2), n, params)[1]
    assert np.array_equal(np.asarray(rows[4]), ending)  # truncated
    # the resets are reset_rows' to an ulp: XLA's code for the gathered chunk and for N rows may round apart
    np.testing.assert_allclose(np.asarray(rows[1].x), np.where(ending[:, None], fresh.x, alone[1].x), rtol=1e-15,
                               atol=1e-15)
    np.testing.assert_array_equal(np.asarray(rows[1].time), np.where(ending, 0, alone[1].time))
    if env_id == "connenv/Swing-v0":  # two seeds' rows in one batch, a key each: each half its own key's resets
        keys = jax.random.split(jax.random.key(5), 2)
        obs, after, info = jax.jit(jenv.autoreset_rows)(keys, alone[0], alone[1], jnp.asarray(ending), alone[5], params)
        fresh = np.concatenate([np.asarray(jenv.reset_rows(k, n // 2, params)[1].x) for k in keys])
        np.testing.assert_allclose(np.asarray(after.x), np.where(ending[:, None], fresh, alone[1].x), rtol=1e-15,
                                   atol=1e-15)
        np.testing.assert_array_equal(np.asarray(info["final_x"]), np.asarray(alone[1].x))



def rollout_return(jenv, x0, steps):
    """The return of `steps` steps from x0 under actions (steps, *shape), plus a fixed weighting of the last state
    (a sparse or flat reward would make a vanishing gradient, which any rule passes)."""
    weights = jnp.linspace(0.5, 1.5, x0.shape[0])

    def total(actions):
        def one(x, a):
            x_next, _, reward, *_ = jenv.transition(x, a)
            return x_next, reward

        x, rewards = jax.lax.scan(one, x0, actions)
        return jnp.sum(rewards) + jnp.sum(weights * jnp.where(jnp.isfinite(x), x, 0.0))

    return total


REVERSE_RTOL = 1e-10
REVERSE_COMPILE = {
    "BeadOnBar-v0": 9, "BeadOnBar-v1": 10, "ChaplyginSleigh-v0": 17, "FallingCat-v0": 34, "KapitzaPendulum-v0": 67,
    "KapitzaSwingUp-v0": 73, "KozlovShell-v0": 22, "RollingBall-v0": 10, "RollingBallPose-v0": 12,
    "RollingBallGoal-v0": 14, "RollingCoin-v0": 13, "Skier-v0": 170, "SnakeSwimmer-v0": 126, "Swing-v0": 19,
    "TubeTwist-v0": 11,
    "RollingCoinSurface-v0-surface=x**2/20 - y/4 + cos(x)*exp(-(y - 2)**2)/2": 7,
}
"""CPU seconds to build and compile the test below for the cases (by test id) left to CONNENV_ALL_GRADIENTS=1
(measured at XLA's optimization level 0; Skier-v0's was stopped at 170 s, its trace alone takes 37 s): XLA compiles
a step's transpose several times slower than its forward mode, and CI's budget takes the seven cases that compile
in seconds, one per code path (the sympy surface's is the hill's). Their grad equals jacfwd too (measured:
docs/guides/jax.md, Gradients)."""


def _reverse_case(env_id, kwargs, name):
    if name not in REVERSE_COMPILE:
        return pytest.param(env_id, kwargs, id=name)
    reason = f"its reverse mode compiles in ~{REVERSE_COMPILE[name]} s of CPU; CONNENV_ALL_GRADIENTS=1 runs it"
    return pytest.param(env_id, kwargs, id=name, marks=pytest.mark.skipif(
        not os.environ.get("CONNENV_ALL_GRADIENTS"), reason=reason))


@pytest.mark.parametrize("env_id, kwargs", [_reverse_case(i, kw, name) for (i, kw), name in zip(CASES, IDS)])
def test_reverse_mode_is_forward_mode_transposed(env_id, kwargs):
    """jax.grad of a 2-step rollout's return (from the reset, random actions) equals jax.jacfwd's, both from one
    linearization in one compiled function: reverse mode transposes the step's linearization, which needs every rule
    it passes through linear in the tangents (the default tie rule, ties="linear"), forward mode pushes each action's
    direction through it. A NaN (a derivative of a branch where leaves out, leaking) fails it."""
    jenv, params = cj.make(env_id, **(kwargs() if callable(kwargs) else kwargs))
    _, state = jenv.reset(jax.random.key(0), params)
    actions = jax.random.uniform(jax.random.key(1), (2, *jenv.action_space(params).shape), minval=-0.6, maxval=0.6)
    total = rollout_return(jenv, state.x, 2)

    def both(actions):
        _, linear = jax.linearize(total, actions)
        (reverse,) = jax.linear_transpose(linear, actions)(1.0)  # jax.grad's transpose
        basis = jnp.eye(actions.size).reshape(actions.size, *actions.shape)
        return reverse, jax.vmap(linear)(basis).reshape(actions.shape)  # jax.jacfwd's columns

    reverse, forward = (np.asarray(v) for v in jax.jit(both)(actions))
    scale = np.max(np.abs(forward))
    print(f"{jenv.name}: |grad − jacfwd| / max|jacfwd| = {np.max(np.abs(reverse - forward)) / scale:.2g}")
    assert scale > 0.0 and np.all(np.isfinite(reverse)) and np.all(np.isfinite(forward))
    assert np.max(np.abs(reverse - forward)) <= REVERSE_RTOL * scale


def test_the_tie_rules_at_a_kink():
    """max(a, b) at a tie a = b: under "linear" b's derivative in every direction, a selection by the values, which
    reverse mode transposes; under "one-sided" the larger tangent's (the complex step's one-sided derivative), not
    linear, which it cannot (JAX raises: an AssertionError or a TypeError in JAX 0.10); away from a tie both are the
    derivative of the side the values pick. sort's tangents at a tie of the values: in the values' stable order under
    "linear", by the tangents under "one-sided"."""
    from connenv.jax.namespace import JAX, ties

    maximum, minimum = JAX.maximum_one_sided, JAX.minimum_one_sided
    weights = jnp.array([1.0, 2.0, 3.0])
    values, tangents = jnp.array([1.0, 1.0, 0.0]), jnp.array([5.0, 2.0, 0.0])
    with ties("linear"):
        assert [float(jax.jvp(maximum, (1.0, 1.0), (t, 2.0))[1]) for t in (3.0, -3.0)] == [2.0, 2.0]
        assert [float(jax.jvp(minimum, (1.0, 1.0), (t, 2.0))[1]) for t in (3.0, -3.0)] == [2.0, 2.0]
        assert [float(g) for g in jax.grad(maximum, (0, 1))(1.0, 1.0)] == [0.0, 1.0]
        assert [float(g) for g in jax.grad(maximum, (0, 1))(2.0, 1.0)] == [1.0, 0.0]
        assert [float(g) for g in jax.grad(minimum, (0, 1))(2.0, 1.0)] == [0.0, 1.0]
        assert np.asarray(jax.jvp(JAX.sort, (values,), (tangents,))[1]).tolist() == [0.0, 5.0, 2.0]
        assert np.asarray(jax.grad(lambda a: JAX.sort(a) @ weights)(values)).tolist() == [2.0, 3.0, 1.0]
    with ties("one-sided"):
        assert [float(jax.jvp(maximum, (1.0, 1.0), (t, 2.0))[1]) for t in (3.0, -3.0)] == [3.0, 2.0]
        assert [float(jax.jvp(minimum, (1.0, 1.0), (t, 2.0))[1]) for t in (3.0, -3.0)] == [2.0, -3.0]
        assert np.asarray(jax.jvp(JAX.sort, (values,), (tangents,))[1]).tolist() == [0.0, 2.0, 5.0]
        with pytest.raises((AssertionError, TypeError)):  # JAX 0.10's transpose of a comparison of tangents
            jax.grad(maximum)(1.0, 1.0)
    with pytest.raises(ValueError, match=r"ties='both'.*\['linear', 'one-sided'\]"):
        cj.make("connenv/Swing-v0", ties="both")
    jenv, params = cj.make("connenv/Swing-v0", ties="one-sided")  # the envs of other parameters trace by its rule
    for change in ({"g": 9.0}, {"r_max": 2.1}):  # traced, static
        other = jenv._for(cj.EnvParams(params.max_steps_in_episode, dataclasses.replace(params.physical, **change)))
        assert other is not jenv and other.ties == "one-sided"


def test_at_an_end_stop_the_tie_rules_take_their_sides():
    """A rotor on a body (ActiveConstraint-v0, velocity control) with the rotor's angle u at its low stop and a command
    beyond it: the stop's reach (u_low − u)/u̇ = 0 ties max(reach, 0). ∂x_next/∂x under ties="one-sided" is
    model.jacobians' (the complex step's one-sided derivative: u moved inside the range travels to the stop, turning
    the body); under "linear" it is the second argument's (the reach held at 0, u at the stop all step), which is
    model.jacobians' from just beyond the stop (1e-9), where max takes its second argument; and there jax.jacrev is
    jax.jacfwd, the rule being linear."""
    from connenv import examples

    kwargs = {**examples.rotor(), "control": "velocity", "max_control_speed": 2.0, "integrator": "rk4"}
    env = gym.make("connenv/ActiveConstraint-v0", **kwargs).unwrapped
    env.reset(seed=0, options={"state": {"u": [env.u_low[0]], "p": [0.3]}})
    x, a = env.model.pack(env.state), np.array([-0.5])
    beyond = x.copy()
    beyond[env.model.state_names.index("u1")] -= 1e-9
    (at_tie, _), (past_it, _) = (env.model.jacobians(v, a) for v in (x, beyond))
    for ties, expected in (("one-sided", at_tie), ("linear", past_it)):
        jenv, _ = cj.make("connenv/ActiveConstraint-v0", ties=ties, **kwargs)

        def step(x, jenv=jenv):
            return jenv.transition(x, jnp.asarray(a))[0]

        forward = np.asarray(jax.jit(jax.jacfwd(step))(jnp.asarray(x)))
        np.testing.assert_allclose(forward, expected, rtol=0.0, atol=1e-8, err_msg=ties)
        if ties == "linear":
            reverse = np.asarray(jax.jit(jax.jacrev(step))(jnp.asarray(x)))
            np.testing.assert_allclose(reverse, forward, rtol=0.0, atol=1e-15)
    assert np.max(np.abs(at_tie - past_it)) > 0.1  # the rotor's stop turns the body: the sides differ


def test_the_kapitza_separatrix_loop_has_a_fixed_trip_count():
    """The Kapitza pendulum's RK4 near the separatrix (its substeps per row from the segment's length): in a step
    being traced (``stepping(dt)``) it runs the count of the longest segment, dt's, so that reverse mode
    differentiates it (jax.grad equals jax.jacfwd), with the numpy code's numbers for one state; a segment longer than
    dt needs more trips than the bound and is a failure."""
    from connenv.jax.namespace import JAX, failures, stepping
    from connenv.systems.kapitza import KapitzaPendulum

    system = KapitzaPendulum(length=0.25)  # ω₀ = 6.26/s: dt = 0.01 s takes up to ⌈6.26⌉ = 7 substeps
    theta, spin, tau = np.array([3.0, 3.1]), np.array([0.2, -0.1]), np.array([0.01, 0.0037])

    def run(theta, spin, tau, dt):
        with failures() as failed, stepping(dt):
            out = system._near_separatrix(theta, spin, tau, JAX)
            return jnp.stack(out), jnp.any(jnp.stack([jnp.any(c) for c, _ in failed]))

    out, failed = jax.jit(run, static_argnums=3)(theta, spin, tau, 0.01)
    assert not bool(failed)
    for k in range(2):
        expected = system._near_separatrix(float(theta[k]), float(spin[k]), float(tau[k]), FLOATS)
        np.testing.assert_allclose(np.asarray(out)[:, k], expected, rtol=1e-15, atol=1e-15)
    def value(theta, spin, tau):
        return jnp.sum(run(theta, spin, tau, 0.01)[0] * jnp.array([[1.0], [0.3]]))

    both = jax.jit(lambda *args: (jax.grad(value, (0, 1, 2))(*args), jax.jacfwd(value, (0, 1, 2))(*args)))
    reverse, forward = both(theta, spin, tau)
    for mine, theirs in zip(reverse, forward):
        np.testing.assert_allclose(np.asarray(mine), np.asarray(theirs), rtol=1e-12, atol=1e-14)
    assert bool(jax.jit(run, static_argnums=3)(theta, spin, tau, 0.005)[1])  # 7 substeps past dt = 0.005's 4
