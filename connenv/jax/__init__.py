"""connenv on JAX: every registered env's step and reset as pure functions (jit, vmap, grad), from the same physics
and task code as the numpy envs. Needs the ``[jax]`` extra and float64 (see `make`); ``import connenv`` does not
import this package nor jax."""

from __future__ import annotations

import gymnasium as gym

from connenv.jax.env import EnvParams, EnvState, FunctionalEnv

__all__ = ["make", "checked_kwargs", "FunctionalEnv", "EnvState", "EnvParams"]


def checked_kwargs(env_id: str) -> dict:
    """The first make kwargs whose JAX step the tests check against numpy (the id's ``Spec.jax``; a builder's is a
    maker of its example, called here)."""
    from connenv.envs.spec import spec

    first = spec(env_id).jax[0]
    return first() if callable(first) else dict(first)


def make(env_id: str, ties: str = "linear", **kwargs) -> tuple[FunctionalEnv, EnvParams]:
    """(env, params) of a registered id with its make kwargs: ``env.reset(key, params)``, ``env.step(key, state,
    action, params)``. ``ties`` is the derivative of max, min and sort at a tie of their values (a pivot at its end
    stop; `connenv.jax.namespace.TIES`): "linear" (the default), the second argument's (the command, the stop),
    which forward and reverse mode both take and agree on; "one-sided", numpy's ``model.jacobians``' (the complex
    step's), which forward mode alone takes (jvp, jacfwd). float64 is required, as exactness is what connenv is for: JAX computes in float32 unless
    ``jax.config.update("jax_enable_x64", True)`` was called first, which a library does not do behind its user's
    back; without it, a RuntimeError says so."""
    import jax

    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "connenv.jax needs float64: call jax.config.update('jax_enable_x64', True) (or set JAX_ENABLE_X64=1) "
            "before making an env"
        )
    import connenv  # noqa: F401  (registers the ids)
    from connenv.jax.namespace import check_ties

    check_ties(ties)

    from connenv.envs.spec import registry, spec

    if not spec(env_id).jax:
        ready = sorted(i for i, s in registry.items() if s.jax)
        raise NotImplementedError(f"{env_id} has no JAX version yet; connenv.jax traces {ready}")
    max_steps = gym.spec(env_id).max_episode_steps
    numpy_env = gym.make(env_id, **kwargs).unwrapped
    steps = kwargs.get("max_episode_steps", max_steps)
    env = FunctionalEnv(numpy_env, steps, ties)
    numpy_env.close()
    needs = getattr(numpy_env, "JAX_NEEDS", None)  # a builder: its user's functions may not trace
    if needs is not None:
        _check_traces(env, env_id, needs)
    return env, env.default_params


def _check_traces(env: FunctionalEnv, env_id: str, needs: str):
    """A builder's step and reset traced once (jax.eval_shape: no compile), else a TypeError saying what its user's
    functions need (``needs``, the env's ``JAX_NEEDS``) and what failed."""
    import jax
    import jax.numpy as jnp

    x, action = jnp.zeros(len(env.state_names)), jnp.zeros(env.action_space().shape)
    try:
        jax.eval_shape(env.transition, x, action)
        jax.eval_shape(env.reset, jax.random.key(0))
    except TypeError as error:  # JAX's tracer errors (a numpy function or float() on a traced array) are TypeErrors
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise TypeError(f"{env_id} with these make kwargs does not trace: {needs} (tracing it raised "
                        f"{type(error).__name__}: {first})") from error
