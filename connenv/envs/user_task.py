"""A user's task for the two builders (ActiveConstraintEnv, ConnectionEnv), checked where it meets the env.

A task is any object with ``reset(np_random) -> state dict``, ``reward(state, next_state) -> float`` and
``terminated(state) -> bool``, and optionally ``observation(state) -> array``, ``is_success(state) -> bool`` and an
``observation_space`` (a Gymnasium space), all on the state dicts of ``info["state"]``. Its interface is checked at
construction (``task=3`` is a TypeError naming ``task`` and what it needs), and every answer where the step uses it,
after the step's physics (the env's state is the new one), row by row in the vector env: a task's mistake is an error
naming its method, never a NaN reward or an infinite observation passed on to the learner:

- ``reset``: a mapping of the builder's state keys (ValueError otherwise; the builder checks the values);
- ``reward``: a real number, finite (TypeError, ValueError);
- ``terminated``, ``is_success``: a bool, a number or a 0-d array (TypeError); without ``is_success`` it is False;
- ``observation``: real numbers, finite in float32, of the shape it had at construction (TypeError, ValueError).

`UserTask` wraps the task; `BuilderTask` is the task code both builders share around it.
"""

from __future__ import annotations

import math
import numbers

import numpy as np
from gymnasium import spaces

from connenv.core.backend import SCALAR
from connenv.core.validation import check_keys, check_returned
from connenv.envs.base import each_row

REQUIRED = {
    "reset": "reset(np_random) -> state dict",
    "reward": "reward(state, next_state) -> float",
    "terminated": "terminated(state) -> bool",
}
OPTIONAL = {"observation": "observation(state) -> array", "is_success": "is_success(state) -> bool"}


class UserTask:
    """The task (see the module) as the builders call it; ``keys``: the builder's state keys ``reset`` may give."""

    def __init__(self, task, keys):
        missing = [name for name in REQUIRED if not callable(getattr(task, name, None))]
        missing += [name for name in OPTIONAL if hasattr(task, name) and not callable(getattr(task, name))]
        if missing:
            needs = ", ".join(REQUIRED.values())
            raise TypeError(
                f"task={task!r} must be an object with methods {needs}, and optionally "
                f"{' and '.join(OPTIONAL.values())}, on state dicts as in info['state']; its {missing} "
                f"{'is' if len(missing) == 1 else 'are'} missing or not callable"
            )
        space = getattr(task, "observation_space", None)
        if space is not None and not isinstance(space, spaces.Space):
            raise TypeError(f"task.observation_space={space!r} must be a gymnasium.spaces.Space, or absent")
        self.task, self.keys, self.shape = task, set(keys), None
        self.has_observation = hasattr(task, "observation")

    def __repr__(self):
        return repr(self.task)

    def reset(self, np_random) -> dict:
        state = self.task.reset(np_random)
        check_keys("the state of task.reset(np_random)", state, self.keys)
        return dict(state)

    def reward(self, before, after, ops=SCALAR):
        return each_row(lambda b, a: _real("task.reward(state, next_state)", self.task.reward(b, a)), [before, after],
                        ops)  # fmt: skip

    def terminated(self, state, ops=SCALAR):
        return each_row(lambda d: _flag("task.terminated(state)", self.task.terminated(d)), [state], ops)

    def is_success(self, state, ops=SCALAR):
        """task.is_success(state), False without it (a bool, or one per row)."""
        if not hasattr(self.task, "is_success"):
            return False if ops is SCALAR else np.zeros(len(state["t"]), bool)
        return each_row(lambda d: _flag("task.is_success(state)", self.task.is_success(d)), [state], ops)

    def observation(self, state, ops=SCALAR):
        return each_row(self._observation, [state], ops)

    def observation_space(self, first):
        """The task's, else an unbounded float32 Box of the shape of ``first``, which every observation must have."""
        self.shape = first.shape
        space = getattr(self.task, "observation_space", None)
        return space if space is not None else spaces.Box(-np.inf, np.inf, first.shape, np.float32)

    def _observation(self, state):
        name = "task.observation(state)"
        observation = check_returned(name, self.task.observation(state), expected="real numbers, finite in float32")
        observation = observation.astype(np.float32)
        if not np.all(np.isfinite(observation)):
            raise ValueError(f"{name} returned {observation!r} in float32, beyond float32's range; expected finite")
        if self.shape is not None and observation.shape != self.shape:
            raise ValueError(f"{name} returned shape {observation.shape}; it was {self.shape} at construction")
        return observation


class BuilderTask:
    """The task code both builders share, on the state dicts of their ``state_dict(state, ops)``: a user's task
    (`UserTask`) and draw callback taken at construction (`adopt`), the reset state's values (`start_values`), and
    ``observe`` (the task's observation, else the builder's ``raw_observation``), ``reward``, ``describe`` and
    ``terminated`` (without a task: reward 0, no success, no end)."""

    task: UserTask | None = None

    def adopt(self, task, draw, keys):
        """The user's task (checked) and draw callback, ``keys`` the state keys its reset may give; and whether the env
        observes its raw state (not a task's or a subclass's observation), which each step keeps in float32's range."""
        if draw is not None and not callable(draw):
            raise ValueError(f"draw={draw!r} must be a callable draw(state, canvas) or None")
        self.task, self.draw = (None if task is None else UserTask(task, keys)), draw
        self.observes_task = self.task is not None and self.task.has_observation
        self.observes_state = type(self).observe is BuilderTask.observe and not self.observes_task

    def _observation_space(self):
        """The task's observation space (of its observation of the start state), else an unbounded float32 Box of the
        raw observation's shape."""
        if self.observes_task:
            return self.task.observation_space(self.observe(self.state))
        return spaces.Box(-np.inf, np.inf, self.raw_observation(self.state).shape, np.float32)

    def start_values(self, options, defaults):
        """The reset state's values: options["state"] over the task's reset (where there is a task) over defaults
        (`TaskEnv.reset_values`); the options' keys checked first, before the task's reset draws."""
        check_keys("reset options", options, {"state", *self.OPTIONS.names})
        if self.task is not None:
            defaults = self.STATE.check(self, self.task.reset(self.np_random), defaults, "the state of task.reset")
        return self.reset_values(options, defaults)

    def observe(self, s, ops=SCALAR):
        return self.task.observation(self.state_dict(s, ops), ops) if self.observes_task else self.raw_observation(s)

    def reward(self, before, after, info, ops=SCALAR):
        if self.task is None:
            return ops.real(0.0 * after.t)
        return self.task.reward(self.state_dict(before, ops), info["state"], ops)

    def describe(self, s, ops=SCALAR):
        state = self.state_dict(s, ops)
        success = ops.flag(0.0 * s.t != 0.0) if self.task is None else self.task.is_success(state, ops)
        return {"state": state, "is_success": success}

    def terminated(self, s, info, ops=SCALAR):
        return info["is_success"] if self.task is None else self.task.terminated(info["state"], ops)


def _real(name, value) -> float:
    """value as a finite float: a real number or a 0-d array of one, else TypeError or ValueError naming it."""
    value = _unwrapped(value)
    if not isinstance(value, numbers.Real):
        raise TypeError(f"{name} returned {value!r}; expected a real number")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} returned {value!r}; expected a finite number")
    return value


def _flag(name, value) -> bool:
    """value as a bool: a bool, a number or a 0-d array of one, else TypeError naming it."""
    value = _unwrapped(value)
    if not isinstance(value, (bool, np.bool_, numbers.Real)):
        raise TypeError(f"{name} returned {value!r}; expected a bool")
    return bool(value)


def _unwrapped(value):
    """A 0-d numeric array as its number (what numpy returns for a reduction of one row); anything else as it is."""
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "biuf":
        return value.item()
    return value
