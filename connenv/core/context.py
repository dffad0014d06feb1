"""Physical parameters as an episode's context, as CARL frames it (Benjamins et al., TMLR 2023): set per episode by
``reset(options={"params": {...}})``, drawn per episode by ``gym.make(id, randomize={name: (low, high)})``, and
seen by the agent with ``observe_params=True``.

A parameter is one of the env's declared physical numbers (its ARGS marked physical: a length, a mass, g); a value
is a real number checked against the declared range given the others. A range is a pair (low, high) of real numbers;
a draw is uniform on [low, high], or log-uniform where the parameter is a scale (a length, a mass, an inertia: its
order of magnitude is what is unknown), from the env's ``np_random``, so seeded runs repeat, and lies in [low, high]
with the ends exact. Ranges that could draw values the env refuses (linked parameters: the snake's b below a) are
refused at make, naming the constraint. Observed, each randomized parameter is appended to the observation
normalized to [-1, 1] over its range (in logarithm for a scale), clipped there (a goal env's Dict observation gets
them as its key "params"); the others stay hidden. The spaces must not depend on a parameter that varies: a
parameter that would change them (the skier's h_max sets the curvature's bound) is refused, at make.
"""

from __future__ import annotations

import dataclasses
import itertools
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
        """A value in [low, high], the ends exact: a draw that rounding puts past an end (exp of the logarithms'
        draw, or the product of a width and a fraction) is that end, and an empty range draws its one value."""
        if self.log:
            value = math.exp(rng.uniform(math.log(self.low), math.log(self.high)))
        else:
            value = rng.uniform(self.low, self.high)
        return min(max(float(value), self.low), self.high)

    def normalized(self, value: float) -> float:
        """value on [-1, 1] over the range (of the logarithms for a scale), clipped; 0 for an optional parameter that
        is off (None), as at make before the first reset draws it."""
        if value is None:
            return 0.0
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
            self._check_corners(env)

    def _check_corners(self, env):
        """ValueError unless the env can be made at every corner of the ranges' box (each parameter at its low or
        its high end), observing in the env's own spaces there: linked parameters (the snake's b below a, the
        shell's box inside its ellipse) are checked where they come closest, so that every draw is one a reset
        takes. The constraints are monotone in each parameter, so the corners bound the box."""
        names, made_kwargs = list(self.ranges), type(env)(**self.kwargs)
        for ends in itertools.product(("low", "high"), repeat=len(names)):
            corner = {name: getattr(self.ranges[name], end) for name, end in zip(names, ends)}
            try:
                made = type(env)(**{**self.kwargs, **corner})
            except ValueError as error:
                raise ValueError(f"randomize={self.written()} can draw values {env.name} refuses, at {corner}: "
                                 f"{error}") from None
            for space in ("observation_space", "action_space"):
                if getattr(made, space) != getattr(made_kwargs, space):
                    raise ValueError(f"randomize={self.written()} changes {env.name}'s {space.replace('_', ' ')}, "
                                     f"which a parameter that varies must not: {getattr(made, space)} at {corner}, "
                                     f"{getattr(made_kwargs, space)} at the make kwargs")

    def written(self) -> dict:
        return {name: (r.low, r.high) for name, r in self.ranges.items()}

    def _check_ranges(self, env, randomize) -> dict[str, Range]:
        check_mapping("randomize", randomize)
        ranges = {}
        for name, bounds in randomize.items():
            if name not in self.declared:
                raise ValueError(f"randomize: {name!r} is not a physical parameter of {env.name}; valid: "
                                 f"{sorted(self.declared)}")
            ends = bounds.tolist() if isinstance(bounds, np.ndarray) and bounds.ndim == 1 else bounds
            if not (isinstance(ends, (tuple, list)) and len(ends) == 2 and all(map(is_real, ends))):
                raise ValueError(f"randomize[{name!r}]={bounds!r} must be a pair (low, high) of real numbers")
            low, high = (float(b) for b in ends)
            if not low <= high:
                raise ValueError(f"randomize[{name!r}]=({low!r}, {high!r}): low must be at most high")
            ranges[name] = Range(low, high, self.declared[name].kind == "scale" and low > 0.0)
        return ranges

    def check_given(self, given) -> dict:
        """The values a reset's "params" option gives, as far as they can be checked alone: declared names, each a
        real number (None where the parameter may be None); their ranges are checked with the others' (`checked`)."""
        check_mapping('reset option "params"', given)
        unknown = set(given) - set(self.declared)
        if unknown:
            raise ValueError(f'reset option "params": {sorted(unknown)} are not physical parameters; valid: '
                             f"{sorted(self.declared)}")
        for name, value in given.items():
            if not (is_real(value) or value is None and self.declared[name].optional):
                raise ValueError(f'reset option "params": {name}={value!r} must be a real number in '
                                 f"{self.declared[name].span()}")
        return dict(given)

    def draw(self, rng, given) -> dict:
        """This episode's values: the make-time ones, the randomized ones drawn (in the order of ``randomize``),
        then those ``given`` by the reset options (`check_given`)."""
        values = {**self.base, **{name: r.draw(rng) for name, r in self.ranges.items()}}
        if given is not None:
            values.update(given)
        return values

    def checked(self, env, values: dict) -> dict:
        """values checked as make kwargs are, each against its range given the others (ValueError naming one out
        of it), as floats: a value equal to the current one is checked too (True and 1 + 0j equal 1.0)."""
        args, _ = env.ARGS.check(env.name, type(env), {**self.kwargs, **values})
        return {name: args[name] for name in self.declared}

    def observation_space(self, space: spaces.Box | spaces.Dict) -> spaces.Box | spaces.Dict:
        """space with the observed parameters' [-1, 1] appended: to the Box, or as a key "params" of a Dict (a
        goal env's, whose "observation", "achieved_goal" and "desired_goal" stay as they are)."""
        k = len(self.ranges)
        if isinstance(space, spaces.Dict):
            return spaces.Dict({**space.spaces, "params": spaces.Box(-1.0, 1.0, (k,), np.float32)})
        low = np.concatenate([space.low, -np.ones(k, np.float32)])
        high = np.concatenate([space.high, np.ones(k, np.float32)])
        return spaces.Box(low, high, dtype=np.float32)

    def take(self, values: dict):
        """These values as the current ones: whether they moved from the make-time ones (a reset set them), and the
        observed ones normalized, once per episode rather than every step."""
        self.current, self.moved = values, values != self.base
        self.observed = np.array([r.normalized(values[name]) for name, r in self.ranges.items()], np.float32)


def is_real(value) -> bool:
    """Whether value is a real number: an int or a float (numpy's too), not a bool, a complex or a string."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def physical_params(env) -> dict:
    """The env's declared physical numbers (ARGS marked physical, scale or interval), by name."""
    args = getattr(env, "ARGS", None)
    if args is None or not hasattr(env, "args"):
        return {}
    return {name: p for name, p in args.params.items() if p.physical and p.kind in ("scale", "interval")}
