"""Checks at the boundary: every bad input names the parameter, its value and the valid range."""

from __future__ import annotations

import inspect
import math

import numpy as np

from connenv.core.steppers import STEPPER_OPTIONS


def check_number(name: str, value, low: float = -math.inf, high: float = math.inf, *, open_low=False, open_high=False):
    """Return value as a float if it is a finite real in the interval, else raise ValueError."""
    interval = f"{'(' if open_low else '['}{low}, {high}{')' if open_high else ']'}"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name}={value!r} must be a real number in {interval}")
    value = float(value)
    below = value <= low if open_low else value < low
    above = value >= high if open_high else value > high
    if not math.isfinite(value) or below or above:
        raise ValueError(f"{name}={value!r} is out of range: must be finite and in {interval}")
    return value


def check_keys(name: str, given, allowed):
    """Raise ValueError if the mapping ``given`` has keys outside ``allowed``."""
    unknown = set(given) - set(allowed)
    if unknown:
        raise ValueError(f"unknown key(s) {sorted(unknown)} in {name}; valid keys: {sorted(allowed)}")


def check_stepper_options(env_name: str, options, env_cls):
    """Raise ValueError for make kwargs that are neither the env's parameters nor stepper options."""
    unknown = set(options) - set(STEPPER_OPTIONS)
    if unknown:
        params = [p for p in inspect.signature(env_cls.__init__).parameters if p not in ("self", "stepper_options")]
        raise ValueError(f"unknown parameter(s) {sorted(unknown)} for {env_name}; valid: {params + list(STEPPER_OPTIONS)}")


def check_action(action, space):
    """The action as a float array of the space's shape, finite, clipped into the space."""
    return np.minimum(np.maximum(finite_action(action, space), space.low), space.high)


def finite_action(action, space):
    """The action as a float array of the space's shape, finite, else ValueError; not clipped."""
    a = np.asarray(action, dtype=np.float64)
    if a.shape != space.shape:
        raise ValueError(f"action has shape {a.shape}; expected {space.shape} (action={action!r})")
    if not np.isfinite(a).all():
        raise ValueError(f"action={action!r} is not finite; expected values in [{space.low}, {space.high}]")
    return a
