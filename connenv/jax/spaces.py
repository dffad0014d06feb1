"""Spaces of the functional env, gymnax's shape: ``sample(key)``, ``contains(x)``, ``shape``, ``dtype``, ``low`` and
``high``; made from the numpy env's Gymnasium Box, whose bounds they keep."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True, eq=False)
class Box:
    low: np.ndarray
    high: np.ndarray
    shape: tuple
    dtype: np.dtype

    def sample(self, key):
        """Uniform in the box (the box's bounds finite), in its dtype."""
        return jax.random.uniform(key, self.shape, jnp.float32 if self.dtype == np.float32 else float,
                                  jnp.asarray(self.low), jnp.asarray(self.high)).astype(self.dtype)

    def contains(self, x):
        x = jnp.asarray(x)
        return (x.shape == self.shape) & jnp.all((x >= self.low) & (x <= self.high))


def space_of(space) -> Box:
    """The Box of a Gymnasium Box (a Dict observation space: TypeError naming it)."""
    if not hasattr(space, "low"):
        raise TypeError(f"connenv.jax takes Box spaces; {space} is not one")
    return Box(space.low, space.high, space.shape, space.dtype)
