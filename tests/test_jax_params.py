"""Physical parameters as traced inputs of connenv.jax: rows stepped by one compiled ``vmap(step_env)``, each with
its own parameter values, are the numpy model's rows stepped with those values; a second set of values runs the
same compiled step; ``sample_params`` draws as ``randomize`` does (uniform, log-uniform for a scale, in the declared
ranges, linked parameters refused at the corners)."""

from __future__ import annotations

import dataclasses
import math
import os

import gymnasium as gym
import numpy as np
import pytest

os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()  # as test_jax
jax = pytest.importorskip("jax")
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp

import connenv.jax as cj
from connenv.envs.spec import registry

STEP_RTOL = 1e-12  # as tests/test_jax.py's, entry by entry of max(1, |x|)
ROWS = 3
WITH_PARAMS = [spec.id for spec in registry.values() if hasattr(spec.env, "ARGS") and any(
    p.physical and p.kind in ("scale", "interval") for p in spec.env.ARGS.params.values())]  # 17 of 19 ids


def traced_names(env):
    """The physical parameters the env traces, with a number at make (an optional one that is None stays None)."""
    return [f.name for f in dataclasses.fields(env.default_params.physical)
            if f.name not in env.static and getattr(env.default_params.physical, f.name) is not None]


@pytest.mark.parametrize("env_id", WITH_PARAMS, ids=[i.removeprefix("connenv/") for i in WITH_PARAMS])
def test_rows_of_their_own_params_step_as_the_numpy_model_and_compile_once(env_id):
    kwargs = cj.checked_kwargs(env_id)
    env, params = cj.make(env_id, **kwargs)
    model = gym.make(env_id, **kwargs).unwrapped.model
    names = traced_names(env)
    if not names:
        assert not [n for n in vars(params.physical) if n not in env.static], env.static
        pytest.skip(f"{env_id}: every parameter static ({env.static})")
    base = params.physical
    ranges = {n: (0.9 * getattr(base, n), 1.1 * getattr(base, n)) for n in names if getattr(base, n) > 0.0}
    traces = []

    @jax.jit
    def step(X, A, P):
        traces.append(1)
        return jax.vmap(env.transition)(X, A, P)[0]

    numpy_env = gym.make(env_id, **kwargs).unwrapped
    X = np.stack([model.pack(numpy_env.reset(seed=seed)[0] is not None and numpy_env.state) for seed in range(ROWS)])
    rng = np.random.default_rng(0)
    A = rng.uniform(numpy_env.action_space.low, numpy_env.action_space.high, (ROWS, *numpy_env.action_space.shape))
    for seed in (0, 1):  # a second set of values: the same compiled step
        keys = jax.random.split(jax.random.key(seed), ROWS)
        P = jax.vmap(env.sample_params, (0, None))(keys, ranges)
        x_next = np.asarray(step(jnp.asarray(X), jnp.asarray(A), P))
        rows = [{n: float(getattr(P.physical, n)[i]) for n in ranges} for i in range(ROWS)]
        for row in rows:
            assert all(ranges[n][0] <= v <= ranges[n][1] for n, v in row.items()), row
        assert len({tuple(row.values()) for row in rows}) == ROWS  # each row its own values
        expected = model.step(X, A, params=rows)
        assert (np.isnan(x_next) == np.isnan(expected)).all()
        worst = np.nanmax(np.abs(x_next - expected) / np.maximum(1.0, np.abs(expected)))
        print(f"{env_id} (traced {names}, static {list(env.static)}): largest difference {worst:.2g}")
        assert worst <= STEP_RTOL
    assert len(traces) == 1


def test_a_traced_parameter_moves_the_step():
    """The traced value is the one used: another g changes the swing's momentum after a step by the closed form's
    amount (ṗ = −m g r sin θ to first order), not a constant the compiled step kept."""
    env, params = cj.make("connenv/Swing-v0")
    step = jax.jit(env.transition)
    x = jnp.asarray(env.model.pack(env.env.start({"state": {"theta": 0.5, "r": 2.0, "p": 0.0}})))
    heavy = dataclasses.replace(params, physical=dataclasses.replace(params.physical, g=12.0))
    p = env.state_names.index("p")
    kick = [float(step(x, jnp.zeros(1), P)[0][p] - x[p]) for P in (params, heavy)]
    assert kick[1] / kick[0] == pytest.approx(12.0 / 9.81, rel=1e-2)
    # and a reset of traced parameters: the swing starts at r_max with the energy of its own g
    reset = jax.jit(env.reset_env)
    for P in (params, heavy):
        state = reset(jax.random.key(0), P)[1]
        info = env.model.info(np.asarray(state.x))
        g = P.physical.g
        assert info["energy"] == pytest.approx(-g * 2.0 * math.cos(info["state"]["theta"]), rel=1e-12)


def test_sample_params_draws_the_randomize_law_and_refuses_what_randomize_refuses():
    env, params = cj.make("connenv/KapitzaPendulum-v0")
    keys = jax.random.split(jax.random.key(0), 4000)
    ranges = {"length": (0.5, 2.0), "g": (9.0, 10.0), "a_max": (0.01, 0.4)}
    drawn = jax.vmap(env.sample_params, (0, None))(keys, ranges).physical
    length, a_max = np.asarray(drawn.length), np.asarray(drawn.a_max)
    assert length.min() >= 0.5 and length.max() <= 2.0 and (a_max <= length).all()
    # a scale is log-uniform: half its draws below the geometric mean of the ends (a uniform law puts 38% there)
    assert np.mean(length < 1.0) == pytest.approx(0.5, abs=0.03)
    assert np.asarray(drawn.mass).ravel()[0] == params.physical.mass  # not drawn: the make-time value
    with pytest.raises(ValueError, match="a_max"):  # linked: a_max must stay below length at every corner
        env.sample_params(keys[0], {"length": (0.2, 1.0), "a_max": (0.05, 0.5)})
    with pytest.raises(ValueError, match="static"):
        env.sample_params(keys[0], {"damping": (0.0, 0.1)})
    swing, _ = cj.make("connenv/Swing-v0")
    with pytest.raises(ValueError, match="static"):  # r_max sets the observation space
        swing.sample_params(keys[0], {"r_max": (2.0, 2.2)})
    assert math.isfinite(float(env.sample_params(keys[0], {}).physical.length))
    coin, _ = cj.make("connenv/RollingCoinSurface-v0")  # its g declared an interval: uniform
    g = np.asarray(jax.vmap(coin.sample_params, (0, None))(keys, {"g": (5.0, 20.0)}).physical.g)
    assert np.mean(g < 10.0) == pytest.approx(1 / 3, abs=0.03)  # log-uniform would put half there
