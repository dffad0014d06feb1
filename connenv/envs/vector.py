"""Native vector envs: N copies of a connenv task stepped together over numpy arrays.

Each vector env keeps one single env, its *prototype*: it checks the make kwargs, holds the spaces, the system
and the constants, and its task functions (``connenv.envs.base``: command, observe, describe, reward,
terminated) are the ones the vector env calls, on its state of arrays over the rows, with the array operations of
``BATCH`` in place of the scalar ones of ``SCALAR``. `vector_env` makes the vector env of a task, whose
``advance(state, command, stepper, ops)`` then runs with the batched stepper and ``BATCH``. Once rows' physical
parameters may differ (``randomize``, `connenv.core.context`), each row is stepped by its own single env, made with
its values: the single env's numbers, at about the speed of a SyncVectorEnv.

Seeding, resets and autoreset are Gymnasium's SyncVectorEnv's, so that row i of a vector env and env i of a
SyncVectorEnv made from the same id and kwargs follow the same episodes (to rounding; tests):

- ``reset(seed=s)`` seeds row i with s + i (a list seeds row i with its i-th entry; None draws fresh entropy for
  rows never seeded and keeps the others' generators), as ``gym.make(id).reset(seed=s + i)`` would;
- every reset of row i, the first and the automatic ones, runs the prototype's ``reset`` with row i's generator,
  so the start states are the single env's draws; ``options`` go to every row, and automatic resets take none;
- autoreset is NEXT_STEP (``metadata["autoreset_mode"]``, as in Gymnasium's CartPoleVectorEnv): the step after
  a row terminates or truncates resets it, ignores its action and returns its reset observation and info with
  reward 0 and both flags False;
- ``max_episode_steps`` (the registration's, passed by ``gym.make_vec``) truncates as TimeLimit does;
- ``reset(options={"reset_mask": mask})`` resets only the rows in mask, as SyncVectorEnv's partial reset
  (``agents.vec_env`` uses it to give SB3 its same-step autoreset).

Steppers are the prototype's through ``connenv.core.batched.batched``, which keeps row i on the single state's
path (adaptive scipy methods get per-row step control); where rows cut their steps differently (ramps, end
stops) each row runs its own control segments. The single envs' divergence checks (the stepper's error on an
invariant, the drift off SO(3)) run on every row, and a StepperError names the env, dt and the parameters.
Infos are Gymnasium's vector convention, a dict of arrays over the batch (nested for ``"state"``), each key ``k``
with its mask ``"_k"`` (the rows it is about: all of them, but for a partial reset). Actions are an array
(N, *single action shape); a wrong shape or a non-finite entry raises ValueError. Rendering is the single env's.
"""

from __future__ import annotations

import copy
import math
import sys
from typing import ClassVar

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from connenv.core.backend import BATCH
from connenv.core.batched import batched
from connenv.core.model import flatten, layout
from connenv.core.steppers import StepperError
from connenv.envs.base import State


class TaskVectorEnv(VectorEnv):
    """Base of the native vector envs (see the module; `vector_env` makes them). ``single_env`` is the task
    class; ``self.state`` is the prototype's State over the rows."""

    metadata: ClassVar[dict] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}
    single_env: type

    def __init__(self, num_envs: int = 1, max_episode_steps: int | None = None, **kwargs):
        for name, value, low in (("num_envs", num_envs, 1), ("max_episode_steps", max_episode_steps, 1)):
            if not (value is None and name == "max_episode_steps") and (
                isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low
            ):
                raise ValueError(f"{name}={value!r} must be an integer ≥ {low}")
        if kwargs.get("render_mode") is not None:
            raise ValueError(f"render_mode={kwargs['render_mode']!r}: a vector env does not render; use gym.make(id)")
        kwargs.pop("render_mode", None)
        self.env = self.single_env(**kwargs)
        self.stepper = batched(self.env.stepper)
        self.num_envs, self.max_episode_steps = int(num_envs), max_episode_steps
        self.single_action_space, self.single_observation_space = self.env.action_space, self.env.observation_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.metadata = {**self.metadata, "render_fps": self.env.metadata["render_fps"]}
        self.render_mode = None
        self.generators = [None] * self.num_envs  # row i's np_random
        self.steps = np.zeros(self.num_envs, np.int64)
        self.prev_done = np.zeros(self.num_envs, bool)
        self.all_rows = np.ones(self.num_envs, bool)  # the "_key" mask of every info key
        self.state = self.env.state.rows(self.num_envs)
        self.row_params = None  # each row's physical parameters, once they may differ (connenv.core.context)
        self.row_envs = [None] * self.num_envs  # then each row's own single env, which steps it
        self.entries = layout(self.env.state)  # how a row's state is read and written as one state

    def reset(self, *, seed=None, options=None):
        """Reset every row, or with ``options={"reset_mask": mask}`` (Gymnasium's partial reset, a bool array over
        the batch) the rows in mask; the other options go to each row's reset. The info masks are the rows reset."""
        super().reset(seed=seed if isinstance(seed, int) else None)
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed has {len(seeds)} entries; a list of seeds needs num_envs={self.num_envs}")
        options = dict(options or {})
        mask = np.asarray(options.pop("reset_mask", self.all_rows))
        if mask.shape != (self.num_envs,) or mask.dtype != bool or not mask.any():
            raise ValueError(f"reset_mask={mask!r} must be a bool array of shape ({self.num_envs},) with a True entry")
        saved = self._saved()
        try:
            for i in np.flatnonzero(mask):
                self._reset_row(i, seeds[i], options or None)
        except Exception:
            self._restore(saved)
            raise
        self.steps[mask] = 0
        self.prev_done[mask] = False
        return self._observe(self.state), self._with_masks(self._describe(self.state), mask)

    def step(self, actions):
        actions = self.check_action(actions)
        if self.row_params is None:
            state, info, reward, terminated = self._transition(self.env, self.advance, self.state, actions)
            obs = None
        else:  # each row's observation with its step, in the one pass over the rows
            state, info, reward, terminated, obs = self._each_row(self._transition_one, self.state, actions)
        self.state = state
        reward, terminated = np.asarray(reward, float), np.array(terminated, bool)
        self.steps += 1
        restart = np.flatnonzero(self.prev_done)
        for i in restart:
            self._reset_row(i)
        self.steps[restart] = 0
        if restart.size:
            info, obs = self._describe(self.state), None
        limit = math.inf if self.max_episode_steps is None else self.max_episode_steps
        truncated = self.steps >= limit
        reward[restart], terminated[restart], truncated[restart] = 0.0, False, False
        self.prev_done = terminated | truncated
        obs = self._observe(self.state) if obs is None else obs
        return obs, reward, terminated, truncated, self._with_masks(info)

    def _transition(self, env, advance, before, actions):
        """(state, info, reward, terminated) of rows stepped by env's task with advance(state, command)."""
        command = env.command(actions)
        try:
            state = advance(before, command)
        except StepperError as error:
            values = ", ".join(f"{key} = {value!r}" for key, value in env.parameters().items())
            where = f"{type(self).__name__} in the step from t = {np.min(before.t):.6g}..{np.max(before.t):.6g} s"
            raise StepperError(f"{error} [{where}, dt = {env.dt}, {values}]") from error
        info = env.report(env.describe(state, BATCH))
        return state, info, env.reward(before, state, info, BATCH), env.terminated(state, info, BATCH)

    # -- rows with their own parameters ------------------------------------------------

    @staticmethod
    def _transition_one(env, before, action):
        """(state, info, reward, terminated, observation) of one row's state, by the single env of its parameters."""
        try:
            state = env.advance(before, env.command(action), env.stepper)
        except StepperError as error:
            raise env._stepper_error(error, before.t) from error
        info = env.report(env.describe(state))
        return state, info, env.reward(before, state, info), env.terminated(state, info), env.observation(state)

    def _each_row(self, function, state, *arrays):
        """function(env, row's state, row's entries of arrays) for each row, by the single env of its parameters,
        stacked over the batch. Rows whose parameters are drawn per episode all differ: each runs the single env's
        path on its Python floats, which is the fastest way through one state."""
        X = flatten(state.fields(), self.entries)
        results = []
        for i in range(self.num_envs):
            row = type(state)(**{e.name: e.single(X[i]) for e in self.entries})
            results.append(function(self._row_env(i), row, *(a[i] for a in arrays)))
        return self._stacked(results)

    def _row_env(self, i):
        """Row i's own single env: the prototype's copy, with row i's parameters (rebuilt where they change)."""
        if self.row_envs[i] is None:
            self.row_envs[i] = copy.deepcopy(self.env)
        env = self.row_envs[i]
        if env.context.current != self.row_params[i]:  # values a reset has checked: taken without a second check
            env.take(env.made_with(self.row_params[i]), self.row_params[i])
        env.reports_params = True
        return env

    def _stacked(self, results):
        """Per-row results put together over the batch: States, dicts (infos), tuples of them, numbers, arrays."""
        first = results[0]
        if isinstance(first, tuple):
            return tuple(self._stacked([r[k] for r in results]) for k in range(len(first)))
        if isinstance(first, dict):
            return {key: self._stacked([r[key] for r in results]) for key in first}
        if isinstance(first, State):
            X = np.stack([flatten(r.fields(), self.entries) for r in results])
            return type(first)(**{e.name: e.rows(X) for e in self.entries})
        return np.stack([np.asarray(r) for r in results])

    def _describe(self, state):
        if self.row_params is None:
            return self.env.report(self.env.describe(state, BATCH))
        return self._each_row(lambda env, s: env.report(env.describe(s)), state)

    def _observe(self, state):
        if self.row_params is None:
            return self.env.observation(state, BATCH)
        return self._each_row(lambda env, s: env.observation(s), state)

    def check_action(self, actions):
        """The actions as the single env checks one: a finite array (N, *shape), clipped or projected into the
        space, else ValueError."""
        return type(self.env).check_action(self, actions)

    def _reset_row(self, i, seed=None, options=None):
        """Reset row i by the prototype's reset, with row i's generator (seeded anew if seed is given)."""
        if seed is not None or self.generators[i] is None:
            self.generators[i] = seeding.np_random(seed)[0]
        self.env.np_random = self.generators[i]
        self.env.reset(options=options)
        self.state.set_row(i, self.env.state)
        if self.env.reports_params:  # this row's parameters may differ from the others': its own from now on
            if self.row_params is None:
                self.row_params = [dict(self.env.context.base) for _ in range(self.num_envs)]
            self.row_params[i] = dict(self.env.context.current)
        elif self.row_params is not None:  # back to the make values, as the single env goes back to them
            self.row_params[i] = dict(self.env.context.current)
            if all(params == self.env.context.base for params in self.row_params):
                self.row_params = None  # every row at the make values: the batch path again, as a new vector env

    def _saved(self):
        """What a reset changes (the rows' generators and states, their parameters, the prototype's own), so that a
        reset whose options a row refuses leaves the vector env as it was."""
        generators = [(g, None if g is None else g.bit_generator.state) for g in self.generators]
        rows = None if self.row_params is None else [dict(p) for p in self.row_params]
        context = None if self.env.context is None else dict(vars(self.env.context))
        return generators, copy.deepcopy(self.state), rows, dict(vars(self.env)), context

    def _restore(self, saved):
        generators, self.state, self.row_params, env, context = saved
        for g, state in generators:
            if g is not None:
                g.bit_generator.state = state
        self.generators = [g for g, _ in generators]
        vars(self.env).clear()
        vars(self.env).update(env)
        if context is not None:
            vars(self.env.context).clear()
            vars(self.env.context).update(context)

    def _with_masks(self, info, mask=None):
        """Gymnasium's vector info: each key k with the mask "_k" of the rows it is about (default: all)."""
        mask = self.all_rows if mask is None else mask
        masked = {}
        for key, value in info.items():
            masked[key] = self._with_masks(value, mask) if isinstance(value, dict) else value
            masked[f"_{key}"] = mask
        return masked

    def advance(self, state, command):
        return self.env.advance(state, command, self.stepper, BATCH)


def vector_env(single_env: type, base: type = TaskVectorEnv) -> type:
    """The native vector env of a task class: a subclass of base (TaskVectorEnv, or the vector env of the class
    the task extends) that steps the rows by the task's own ``advance`` with the batched stepper. Named after the
    task and placed in its module, so that its "module:Class" entry point and pickles find it: one per task class,
    made once for all its ids (ValueError where a class of that name, or another base, is there already)."""
    name, module = single_env.__name__.removesuffix("Env") + "VectorEnv", sys.modules[single_env.__module__]
    existing = getattr(module, name, None)
    if existing is not None:
        if getattr(existing, "single_env", None) is single_env and issubclass(existing, base):
            return existing
        raise ValueError(f"{module.__name__}.{name} exists, and is no vector env of {single_env.__name__} on {base}")
    doc = f"{single_env.__name__} over a batch: the single env's advance over the rows (see connenv.envs.vector)."
    attributes = {"single_env": single_env, "__module__": single_env.__module__, "__qualname__": name, "__doc__": doc}
    cls = type(name, (base,), attributes)
    setattr(module, name, cls)
    return cls
