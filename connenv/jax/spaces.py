"""Spaces of the functional env, gymnax's shape: a Box has ``sample(key)``, ``contains(x)``, ``shape``, ``dtype``,
``low`` and ``high``; a Dict (gymnax's ``spaces.Dict``: ``spaces``, a dict of Boxes) samples a dict from one key
split over its keys and contains a dict whose every entry its Box contains. Made from the numpy env's Gymnasium Box
or Dict, whose bounds they keep."""

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


@dataclasses.dataclass(frozen=True, eq=False)
class Dict:
    spaces: dict

    def sample(self, key):
        """A dict of samples, each Box's from its own key (the key split over the keys, in the dict's order)."""
        keys = jax.random.split(key, len(self.spaces))
        return {name: space.sample(k) for (name, space), k in zip(self.spaces.items(), keys)}

    def contains(self, x):
        if not isinstance(x, dict) or set(x) != set(self.spaces):
            return jnp.asarray(False)
        inside = jnp.asarray(True)
        for name, space in self.spaces.items():
            inside = inside & space.contains(x[name])
        return inside


def space_of(space) -> Box | Dict:
    """The Box of a Gymnasium Box, the Dict of Boxes of a Gymnasium Dict of Boxes (another space: TypeError naming
    it)."""
    if hasattr(space, "spaces") and isinstance(space.spaces, dict):
        return Dict({name: space_of(s) for name, s in space.spaces.items()})
    if not hasattr(space, "low"):
        raise TypeError(f"connenv.jax takes Box spaces and Dicts of them; {space} is neither")
    return Box(space.low, space.high, space.shape, space.dtype)
