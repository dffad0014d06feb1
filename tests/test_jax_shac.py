"""agents.jax_shac: the actor's gradient backpropagated through connenv.jax's step is the derivative of the window's
return (+ γ^h V of the target critic), and a few updates raise that return."""

import os

import numpy as np
import pytest

# as tests/test_jax.py: XLA without LLVM's optimization passes compiles several times faster; IEEE results either way
os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()
jax = pytest.importorskip("jax")
pytest.importorskip("optax")
jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp

import connenv.jax
from agents import jax_shac

ENV = "connenv/RollingBall-v0"  # reverse mode runs through its step (Rodrigues' exponential); cheap to compile


@pytest.fixture(scope="module")
def setup():
    env, params = connenv.jax.make(ENV)
    config = jax_shac.Config(n_timesteps=10**4, n_envs=8, horizon=2, net_arch=(16,), critic_iterations=1,
                             critic_minibatches=1, eval_episodes=1)  # fmt: skip
    trainer = jax_shac.Trainer(env, params, config)
    trainer.dtype = float
    with jax.disable_jit():  # eager: no compile
        runners = trainer.init(jnp.stack([jax.random.key(0)]))
    # float64 weights and inputs, so that a central difference resolves the derivative
    runners = {**runners, "params": jax.tree_util.tree_map(lambda v: v.astype(float), runners["params"]),
               "target_vf": jax.tree_util.tree_map(lambda v: v.astype(float) + 0.1, runners["target_vf"])}  # fmt: skip
    noise = jax.random.normal(jax.random.key(1), (config.horizon, 1, config.n_envs, trainer.act_dim))
    keys = jnp.stack([jax.random.split(jax.random.key(2), 1)] * config.horizon)
    return trainer, runners, noise, keys


COMPILED = {}


def value_and_grad(setup):
    """The actor's loss and its gradient at the fixture's rows and noise, compiled once for both tests."""
    if "loss" not in COMPILED:
        trainer, runners, noise, keys = setup
        COMPILED["loss"] = jax.jit(jax.value_and_grad(lambda a: trainer._window(a, runners, noise, keys)[0]))
    return COMPILED["loss"]


def test_actor_gradient_is_the_derivative_of_the_window_return(setup):
    """jax.grad of SHAC's actor loss (−(window return + γ^h V_target(s_h)) / (h N)) through two env steps equals its
    central difference along a random direction of the weights. The difference is taken at h = 1e-3 (its truncation
    error there, measured, 1e-6 relative) because the observation the critic reads is float32, as the env's space
    says: its rounding (≈ 1e-8 in the loss) over 2h. A term the backpropagation missed (the critic's, the second
    step's) would differ by percents (the critic's term alone, dropped, is ~3%)."""
    _trainer, runners, _noise, _keys = setup
    actors = {"pi": runners["params"]["pi"], "log_std": runners["params"]["log_std"]}
    _loss, gradient = value_and_grad(setup)(actors)
    leaves, tree = jax.tree_util.tree_flatten(actors)
    directions = [jax.random.normal(k, v.shape, float) for k, v in
                  zip(jax.random.split(jax.random.key(3), len(leaves)), leaves)]  # fmt: skip
    along = lambda eps: jax.tree_util.tree_unflatten(tree, [v + eps * d for v, d in zip(leaves, directions)])
    h = 1e-3
    difference = (value_and_grad(setup)(along(h))[0] - value_and_grad(setup)(along(-h))[0]) / (2 * h)
    analytic = sum(jnp.sum(g * d) for g, d in zip(jax.tree_util.tree_leaves(gradient), directions))
    assert abs(float(analytic)) > 1e-4  # the window's return depends on the actions (a gradient of 0 proves nothing)
    np.testing.assert_allclose(float(analytic), float(difference), rtol=1e-4)


def test_updates_raise_the_window_return(setup):
    """Ten steps of the trainer's actor optimizer (gradient norm clipped, Adam) on the backpropagated gradient lower
    the actor's loss (raise the window's return + γ^h V) on the same start rows and noise."""
    trainer, runners, _noise, _keys = setup
    actors = {"pi": runners["params"]["pi"], "log_std": runners["params"]["log_std"]}
    opt_state = trainer.actor_opt.init(actors)
    before = float(value_and_grad(setup)(actors)[0])
    for _ in range(10):
        _, gradient = value_and_grad(setup)(actors)
        updates, opt_state = trainer.actor_opt.update(gradient, opt_state, actors)
        actors = jax.tree_util.tree_map(lambda a, u: a + u, actors, updates)
    after = float(value_and_grad(setup)(actors)[0])
    assert after < before - 0.01 * abs(before), (before, after)
