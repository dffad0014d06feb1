"""connenv on JAX: every registered env's step and reset as pure functions (jit, vmap, grad), from the same physics
and task code as the numpy envs. Needs the ``[jax]`` extra and float64 (see `make`); ``import connenv`` does not
import this package nor jax."""

from __future__ import annotations

import gymnasium as gym

from connenv.jax.env import EnvParams, EnvState, FunctionalEnv

__all__ = ["make", "FunctionalEnv", "EnvState", "EnvParams"]


def make(env_id: str, **kwargs) -> tuple[FunctionalEnv, EnvParams]:
    """(env, params) of a registered id with its make kwargs: ``env.reset(key, params)``, ``env.step(key, state,
    action, params)``. float64 is required, as exactness is what connenv is for: JAX computes in float32 unless
    ``jax.config.update("jax_enable_x64", True)`` was called first, which a library does not do behind its user's
    back; without it, a RuntimeError says so."""
    import jax

    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "connenv.jax needs float64: call jax.config.update('jax_enable_x64', True) (or set JAX_ENABLE_X64=1) "
            "before making an env"
        )
    import connenv  # noqa: F401  (registers the ids)

    from connenv.envs.spec import registry, spec

    if not spec(env_id).jax:
        ready = sorted(i for i, s in registry.items() if s.jax)
        raise NotImplementedError(f"{env_id} has no JAX version yet; connenv.jax traces {ready}")
    max_steps = gym.spec(env_id).max_episode_steps
    numpy_env = gym.make(env_id, **kwargs).unwrapped
    steps = kwargs.get("max_episode_steps", max_steps)
    env = FunctionalEnv(numpy_env, steps)
    numpy_env.close()
    return env, env.default_params
