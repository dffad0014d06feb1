"""Physical parameters as an episode's context, as CARL frames it (Benjamins et al., TMLR 2023): set per episode by
``reset(options={"params": {...}})``, drawn per episode by ``gym.make(id, randomize={name: (low, high)})``, and
seen by the agent with ``observe_params=True``.

A parameter is one of the env's declared physical numbers (its ARGS marked physical: a length, a mass, g); a value
is checked against the declared range. A draw is uniform on [low, high], or log-uniform where the parameter is a
scale (a length, a mass, an inertia: its order of magnitude is what is unknown), from the env's ``np_random``, so
seeded runs repeat. Observed, each randomized parameter is appended to the observation normalized to [-1, 1] over
its range (in logarithm for a scale), clipped there; the others stay hidden. The observation space must not depend
on a parameter that varies: a parameter that would change it (the skier's h_max sets the curvature's bound) is
refused, at make.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from gymnasium import spaces

from connenv.core.validation import check_mapping


@dataclasses.dataclass(frozen=True)
class Range:
    """Where a randomized parameter is drawn: [low, high], log-uniform for a scale."""

    low: float
    high: float
    log: bool

    def draw(self, rng: np.random.Generator) -> float:
        if self.log:
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        return float(rng.uniform(self.low, self.high))

    def normalized(self, value: float) -> float:
        """value on [-1, 1] over the range (of the logarithms for a scale), clipped."""
        low, high, v = (math.log(x) for x in (self.low, self.high, value)) if self.log else (self.low, self.high, value)
        return min(max(2.0 * (v - low) / (high - low) - 1.0, -1.0), 1.0) if high > low else 0.0


class Context:
    """The parameters of an env's episodes: the make-time values ``base``, the ``ranges`` they are drawn from, and
    whether they are observed. ``varies``: whether episodes may differ from the make-time values (info
    ``"params"`` is reported then)."""

    def __init__(self, env, randomize, observe_params):
        declared = physical_params(env)
        self.base = {name: getattr(env.args, name) for name in declared} if declared else {}
        self.declared = declared
        self.ranges = self._check_ranges(env, randomize or {})
        if not isinstance(observe_params, (bool, np.bool_)):
            raise ValueError(f"observe_params={observe_params!r} must be True or False")
        if observe_params and not self.ranges:
            raise ValueError("observe_params=True observes the randomized parameters: give randomize={name: (low, "
                             "high)} too")
        self.observe = bool(observe_params)
        self.varies = bool(self.ranges)
        self.take(dict(self.base))
        self.kwargs = dict(env.kwargs)  # the make kwargs, without these
        if self.ranges:
            self._check_fixed_space(env)

    def _check_fixed_space(self, env):
        """ValueError unless the env made at the ranges' low ends and at their high ends observes in one space."""
        made = [type(env)(**{**self.kwargs, **{n: getattr(r, end) for n, r in self.ranges.items()}})
                for end in ("low", "high")]
        if made[0].observation_space != made[1].observation_space:
            raise ValueError(f"randomize={ {n: (r.low, r.high) for n, r in self.ranges.items()} } changes "
                             f"{env.name}'s observation space, which a parameter that varies must not: "
                             f"{made[0].observation_space} at the low ends, {made[1].observation_space} at the high")

    def _check_ranges(self, env, randomize) -> dict[str, Range]:
        check_mapping("randomize", randomize)
        ranges = {}
        for name, bounds in randomize.items():
            if name not in self.declared:
                raise ValueError(f"randomize: {name!r} is not a physical parameter of {env.name}; valid: "
                                 f"{sorted(self.declared)}")
            try:
                low, high = (float(b) for b in bounds)
            except (TypeError, ValueError):
                raise ValueError(f"randomize[{name!r}]={bounds!r} must be a pair (low, high) of numbers") from None
            for value in (low, high):
                self.declared[name].check(value, vars(env.args))
            if not low <= high:
                raise ValueError(f"randomize[{name!r}]=({low!r}, {high!r}): low must be at most high")
            ranges[name] = Range(low, high, self.declared[name].kind == "scale" and low > 0.0)
        return ranges

    def draw(self, rng, given) -> dict:
        """This episode's values: the make-time ones, the randomized ones drawn (in the order of ``randomize``),
        then those ``given`` by the reset options."""
        values = {**self.base, **{name: r.draw(rng) for name, r in self.ranges.items()}}
        if given is not None:
            check_mapping('reset option "params"', given)
            unknown = set(given) - set(self.declared)
            if unknown:
                raise ValueError(f'reset option "params": {sorted(unknown)} are not physical parameters; valid: '
                                 f"{sorted(self.declared)}")
            values.update(given)
        return values

    def observation_space(self, space: spaces.Box) -> spaces.Box:
        """space with the observed parameters' [-1, 1] appended."""
        k = len(self.ranges)
        low = np.concatenate([space.low, -np.ones(k, np.float32)])
        high = np.concatenate([space.high, np.ones(k, np.float32)])
        return spaces.Box(low, high, dtype=np.float32)

    def take(self, values: dict):
        """These values as the current ones: whether they moved from the make-time ones (a reset set them), and the
        observed ones normalized, once per episode rather than every step."""
        self.current, self.moved = values, values != self.base
        self.observed = np.array([r.normalized(values[name]) for name, r in self.ranges.items()], np.float32)


def physical_params(env) -> dict:
    """The env's declared physical numbers (ARGS marked physical, scale or interval), by name."""
    args = getattr(env, "ARGS", None)
    if args is None or not hasattr(env, "args"):
        return {}
    return {name: p for name, p in args.params.items() if p.physical and p.kind in ("scale", "interval")}
