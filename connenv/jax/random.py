"""A JAX key dressed as the numpy Generator that a task's ``start`` draws from (``self.np_random``), so that the
starting-state distribution is written once: the numpy env draws it from its seeded Generator, the JAX env from a
key, the same distribution with other draws."""

from __future__ import annotations

import jax
import jax.numpy as jnp


class KeyGenerator:
    """numpy.random.Generator's methods that tasks call, on a JAX key split at each draw."""

    def __init__(self, key):
        self.key = key

    def _next(self):
        self.key, key = jax.random.split(self.key)
        return key

    def uniform(self, low=0.0, high=1.0, size=None):
        shape = () if size is None else tuple(jnp.atleast_1d(jnp.asarray(size)).tolist()) if not isinstance(
            size, tuple) else size
        return jax.random.uniform(self._next(), shape, float, low, high)

    def random(self, size=None):
        return self.uniform(0.0, 1.0, size)

    def normal(self, loc=0.0, scale=1.0, size=None):
        shape = () if size is None else (size if isinstance(size, tuple) else (size,))
        return loc + scale * jax.random.normal(self._next(), shape, float)

    def integers(self, low, high=None, size=None):
        low, high = (0, low) if high is None else (low, high)
        shape = () if size is None else (size if isinstance(size, tuple) else (size,))
        return jax.random.randint(self._next(), shape, low, high)

    def choice(self, a, size=None):
        shape = () if size is None else (size if isinstance(size, tuple) else (size,))
        return jax.random.choice(self._next(), jnp.asarray(a), shape)
