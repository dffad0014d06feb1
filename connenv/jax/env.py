"""The functional env: an env's model traced by JAX, with gymnax's interface.

``env.reset(key, params) -> (obs, state)`` and ``env.step(key, state, action, params) -> (obs, state, reward,
terminated, truncated, info)`` are pure functions of arrays: jit them, vmap them over keys, states and actions, and
differentiate them. The state is `EnvState`: the model's flat task state ``x`` (``model.state_names``; float64)
and the steps taken in the episode; ``model.pack``/``unpack`` carry a state between the numpy env and this one.
The observation is an array, or a dict of them (a goal env's, its space a `connenv.jax.spaces.Dict`).
``step`` resets an episode that has ended (terminated or truncated) from its key, as gymnax's does, and gives the
ended episode's last observation and state in ``info["final_observation"]`` and ``info["final_x"]``; ``step_env``
and ``reset_env`` are the step and the reset alone.

The step is the numpy env's own code, traced: the task's ``command``, ``advance``, ``observe``, ``describe``,
``reward`` and ``terminated`` run with ops = ``connenv.jax.namespace.JAX_TASK`` on rows of one (the numpy vector
env's path), and the physics asks its arrays for their namespace. A step whose stepper fails (where the numpy env
raises StepperError) holds the state, reports ``info["stepper_failed"]`` and ends the episode as truncated.
Everything it traces runs within the env's tie rule (``ties``, `connenv.jax.namespace.TIES`): the derivative of
max, min and sort at a tie, which decides whether reverse mode differentiates the step.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
from typing import Any

import jax
import jax.numpy as jnp

from connenv.core.backend import is_traced
from connenv.core.context import Context
from connenv.jax.namespace import JAX_TASK, check_ties, failures, stepping, ties
from connenv.jax.random import KeyGenerator
from connenv.jax.spaces import Box, Dict, space_of
from connenv.jax.steppers import traced_stepper

RESET_SHARE = 16
"""step_rows resets the rows that are done N / RESET_SHARE at a time (`FunctionalEnv._reset_where`)."""


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvState:
    """The model's flat task state x (n,) and the steps taken in the episode."""

    x: jax.Array
    time: jax.Array


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class EnvParams:
    """The episode's time limit (gymnax's ``max_steps_in_episode``) and the physical parameters (the model's Params),
    both traced leaves: jit compiles the step once for every value, and vmap batches over them (domain
    randomization). A parameter that sets the spaces or the step's structure (the env's ``JAX_STATIC``), or an
    optional one that is None, is static: another value of it is compiled anew, as ``model.with_params`` builds a
    model."""

    max_steps_in_episode: Any
    physical: Any


def under_tie_rule(method):
    """A method of FunctionalEnv that traces the env's code, run within its tie rule (``ties``)."""

    @functools.wraps(method)
    def traced(self, *args, **kwargs):
        with ties(self.ties):
            return method(self, *args, **kwargs)

    return traced


REGISTERED: set[type] = set()


def register_params(cls: type, static: tuple[str, ...]):
    """A model's Params class as a pytree: its traced parameters as leaves, the env's ``JAX_STATIC`` ones as its
    static structure (registered once per class: a class is one env's)."""
    if cls not in REGISTERED:
        names = [f.name for f in dataclasses.fields(cls)]
        jax.tree_util.register_dataclass(cls, [n for n in names if n not in static], [n for n in names if n in static])
        REGISTERED.add(cls)


class FunctionalEnv:
    """A registered env's step and reset as pure JAX functions (see the module); made by ``connenv.jax.make``."""

    def __init__(self, env, max_episode_steps: int, ties: str = "linear"):
        self.ties = check_ties(ties)  # the derivative at a tie of max, min and sort (connenv.jax.namespace.TIES)
        self.env = copy.deepcopy(env)
        self.model = self.env.model
        self.name = self.env.name
        self.max_episode_steps = max_episode_steps
        # an env of several systems (the swimmers' full and reduced models) has none: its stepper takes each as it comes
        self.stepper = traced_stepper(self.env.stepper, getattr(self.env, "system", None), self.name)
        self.entries = self.model.entries
        self.state_names = self.model.state_names
        self.num_actions = self.model.m
        self._action_space = space_of(self.env.action_space)
        self._observation_space = space_of(self.env.observation_space)
        self._low = jnp.asarray(self.env.action_space.low, float)
        self._high = jnp.asarray(self.env.action_space.high, float)
        self.static = tuple(getattr(self.env, "JAX_STATIC", ()))
        register_params(type(self.model.params), self.static)
        self._models = {self.model.params: self}
        self._contexts = {}

    def __repr__(self):
        return f"connenv.jax FunctionalEnv({self.name}, n={self.model.n}, m={self.model.m}, ties={self.ties!r})"

    @property
    def default_params(self) -> EnvParams:
        return EnvParams(self.max_episode_steps, self.model.params)

    def action_space(self, params: EnvParams | None = None) -> Box:
        return self._action_space

    def observation_space(self, params: EnvParams | None = None) -> Box | Dict:
        return self._observation_space

    # -- the state vector ------------------------------------------------------

    def state_of(self, X):
        """The task State of rows X (N, n)."""
        return type(self.env.state)(**{e.name: e.rows(X) for e in self.entries})

    def flatten(self, state) -> jax.Array:
        """Rows (N, n) of a task State of rows, float64."""
        fields = state.fields()
        parts = []
        for e in self.entries:
            value = jnp.asarray(fields[e.name])
            parts.append(jnp.reshape(value, (value.shape[0], -1)).astype(float))
        return jnp.concatenate(parts, axis=1)

    # -- the functional face ---------------------------------------------------

    def _for(self, params: EnvParams | None) -> FunctionalEnv:
        """The functional env of these physical parameters: this one where they are its own; where a static one
        differs, the env of those values (built once per value, as ``model.with_params``); and where a traced one is
        given, the numpy env's class made with the traced values (`traced_with`)."""
        if params is None or params.physical is self.model.params:
            return self
        physical, base = params.physical, self.model.params
        values = {f.name: getattr(physical, f.name) for f in dataclasses.fields(base)}
        env = self
        static = {name: values[name] for name in self.static}
        if any(value != getattr(base, name) for name, value in static.items()):
            key = tuple(static.items())
            if key not in self._models:
                other = FunctionalEnv(self.model.with_params(static).env, self.max_episode_steps, self.ties)
                other._models = self._models
                self._models[key] = other
            env = self._models[key]
        moved = {name: value for name, value in values.items() if name not in self.static and (
            is_traced(value) or value != getattr(base, name))}
        return env.traced_with(moved) if moved else env

    def traced_with(self, values: dict) -> FunctionalEnv:
        """This env with the physical parameters ``values`` (traced, or numbers): the numpy env's own class made with
        them, so that what its constructor derives from them (a system's constants, a bound, a scale of the
        observation) is derived once, by the same code, on traced numbers; its checks pass a traced value
        (`connenv.core.params.Param.check`). Its spaces are this env's (the static parameters set them)."""
        env = type(self.env)(**{**self.env.kwargs, **values})
        other = copy.copy(self)
        other.env, other.model = env, None
        other.stepper = traced_stepper(env.stepper, getattr(env, "system", None), self.name)
        return other

    def sample_params(self, key, ranges: dict, params: EnvParams | None = None) -> EnvParams:
        """params (default: the make-time ones) with the physical parameters of ``ranges`` ({name: (low, high)},
        as ``gym.make(id, randomize=ranges)`` takes them) drawn from the key as the numpy env draws them
        (`connenv.core.context.Range.draw`): uniform on [low, high], log-uniform for a scale with low > 0, the ends
        exact. The ranges are checked as ``randomize`` is, at make: the env made at every corner of their box
        (linked parameters: every draw is one the numpy env takes) and its spaces unchanged there; a static
        parameter (``JAX_STATIC``) cannot be drawn under jit and is refused. vmap over keys draws a batch."""
        params = self.default_params if params is None else params
        ranges = dict(ranges)
        fixed = sorted(set(ranges) & set(self.static))
        if fixed:
            raise ValueError(f"sample_params: {fixed} of {self.name} are static in connenv.jax (they set the spaces "
                             f"or the step's structure); traced: "
                             f"{[f.name for f in dataclasses.fields(self.model.params) if f.name not in self.static]}")
        written = tuple((name, tuple(bounds) if isinstance(bounds, (tuple, list)) else bounds)
                        for name, bounds in ranges.items())
        if written not in self._contexts:
            self._contexts[written] = Context(self.env, ranges, False).ranges
        keys = jax.random.split(key, max(len(ranges), 1))
        drawn = {}
        for k, (name, r) in zip(keys, self._contexts[written].items()):
            if r.log:
                value = jnp.exp(jax.random.uniform(k, (), float, jnp.log(r.low), jnp.log(r.high)))
            else:
                value = jax.random.uniform(k, (), float, r.low, r.high)
            drawn[name] = jnp.clip(value, r.low, r.high)
        return EnvParams(params.max_steps_in_episode, dataclasses.replace(params.physical, **drawn))

    def transition(self, x, action, params: EnvParams | None = None):
        """(x_next, reward, terminated, info, failed) of one state x (n,) under action: the numpy env's step."""
        env = self._for(params)
        return env._transition(x, action)

    def _transition(self, x, action):
        X_next, obs, reward, terminated, info, stalled = self._advance_rows(jnp.asarray(x, float)[None],
                                                                            jnp.asarray(action, float)[None])
        return jax.tree_util.tree_map(lambda v: v[0], (X_next, obs, reward, terminated, info, stalled))

    @under_tie_rule
    def _advance_rows(self, X, A):
        """(X_next, obs, reward, terminated, info, failed) of rows X (N, n) under actions A (N, *shape): the numpy
        vector env's path, each a row's; a row whose step failed is marked in ``failed``."""
        N = X.shape[0]
        a = jnp.asarray(A, float).reshape(N, *self._action_space.shape)
        a = jnp.minimum(jnp.maximum(a, self._low), self._high)
        before = self.state_of(X)
        with failures() as failed, stepping(self.env.dt):  # the segments' bound: loops of a fixed trip count
            after = self.env.advance(before, self.env.command(a), self.stepper, JAX_TASK)
            X_next = self.flatten(after)
        stalled = jnp.zeros(N, bool)
        for condition, _ in failed:
            condition = jnp.asarray(condition)
            per_row = condition.shape[:1] == (N,)
            stalled = stalled | (jnp.any(condition.reshape(N, -1), axis=-1) if per_row else jnp.any(condition))
        info = self.env.describe(after, JAX_TASK)
        reward = self.env.reward(before, after, info, JAX_TASK)
        terminated = self.env.terminated(after, info, JAX_TASK)
        obs = self.env.observe(after, JAX_TASK)
        rows = lambda v: jnp.broadcast_to(v, (N, *jnp.shape(v)[1:])) if jnp.ndim(v) > 0 else jnp.broadcast_to(v, (N,))  # noqa: E731
        info, obs = jax.tree_util.tree_map(rows, (info, obs))  # an observation: an array, or a dict (a goal env's)
        return X_next, obs, rows(reward), rows(terminated) & ~stalled, info, stalled

    def step_env(self, key, state: EnvState, action, params: EnvParams | None = None):
        """One step without autoreset: (obs, state, reward, terminated, truncated, info)."""
        params = self.default_params if params is None else params
        x_next, obs, reward, terminated, info, failed = self.transition(state.x, action, params)
        x_next = jnp.where(failed, state.x, x_next)  # a failed step holds the state
        time = state.time + 1
        truncated = (time >= params.max_steps_in_episode) | failed
        info = {**info, "stepper_failed": failed}
        return obs, EnvState(x_next, time), reward.astype(float), terminated, truncated & ~terminated, info

    @under_tie_rule
    def reset_env(self, key, params: EnvParams | None = None, options=None):
        """The starting state of the task's own distribution (its ``start``, drawing from the key): (obs, state).

        ``options`` are the numpy env's reset options (``{"state": {...}}`` and the task's others), whose values may
        be traced: a traced value has no number to check, and is taken as it is. Or a function ``options(task)`` of
        the task drawing from the key (``task.np_random``, as the numpy env's does), which gives them: a start
        distribution of one's own (agents.curriculum's start curricula), written once for both envs."""
        env = self._for(params).env
        task = copy.copy(env)
        task._np_random = KeyGenerator(key)
        options = {} if options is None else options(task) if callable(options) else options
        start = task.start(options, JAX_TASK)
        X = self.flatten(self._rows(start))
        obs = jax.tree_util.tree_map(lambda v: v[0], env.observe(self.state_of(X), JAX_TASK))
        return obs, EnvState(X[0], jnp.zeros((), jnp.int32))

    def _rows(self, state):
        """A State of one (its fields traced scalars and arrays) as a State of rows of one."""
        return type(state)(**{k: jnp.asarray(v, float)[None] for k, v in state.fields().items()})

    def reset(self, key, params: EnvParams | None = None, options=None):
        return self.reset_env(key, params, options)

    def step(self, key, state: EnvState, action, params: EnvParams | None = None):
        """step_env, then a reset from the key where the episode ended; info["final_observation"] and
        info["final_x"] hold the ended step's observation and state (gymnax's autoreset)."""
        key_step, key_reset = jax.random.split(key)
        obs, after, reward, terminated, truncated, info = self.step_env(key_step, state, action, params)
        obs_reset, fresh = self.reset_env(key_reset, params)
        done = terminated | truncated
        info = {**info, "final_observation": obs, "final_x": after.x}
        state = jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), fresh, after)
        obs = jax.tree_util.tree_map(lambda a, b: jnp.where(done, a, b), obs_reset, obs)
        return obs, state, reward, terminated, truncated, info

    # -- rows: the vector env's step, without vmap ------------------------------

    def reset_rows(self, key, n: int, params: EnvParams | None = None):
        """n starting states (obs (n, …), EnvState with x (n, n_x) and time (n,)) from one key."""
        return jax.vmap(self.reset_env, (0, None))(jax.random.split(key, n), params)

    def step_env_rows(self, key, state: EnvState, action, params: EnvParams | None = None):
        """``step_env`` of rows (state.x (N, n), action (N, …)) in one call, without autoreset: (obs, state, reward,
        terminated, truncated, info), a failed row's state held and its episode truncated. The key is unused (the
        step draws nothing), kept for gymnax's signature."""
        params = self.default_params if params is None else params
        X_next, obs, reward, terminated, info, failed = self._for(params)._advance_rows(state.x, action)
        X_next = jnp.where(failed[:, None], state.x, X_next)
        time = state.time + 1
        truncated = ((time >= params.max_steps_in_episode) | failed) & ~terminated
        info = {**info, "stepper_failed": failed}
        return obs, EnvState(X_next, time), reward.astype(float), terminated, truncated, info

    def step_rows(self, key, state: EnvState, action, params: EnvParams | None = None):
        """``step`` of rows (state.x (N, n), action (N, …)) in one call, as the numpy vector env steps its rows: the
        same numbers as ``jax.vmap(env.step)``, but a branch that no row takes (the exact step's numerical fallback)
        is skipped, which under vmap is computed for every row, and only the rows that are done are reset
        (`autoreset_rows`). (Under an outer vmap, over seeds say, those skips are lost too: step ``step_env_rows``
        on all rows at once and reset them with ``autoreset_rows`` and the seeds' keys.)"""
        obs, after, reward, terminated, truncated, info = self.step_env_rows(key, state, action, params)
        obs, state, info = self.autoreset_rows(key, obs, after, terminated | truncated, info, params)
        return obs, state, reward, terminated, truncated, info

    def autoreset_rows(self, key, obs, state: EnvState, done, info: dict, params: EnvParams | None = None):
        """gymnax's autoreset of rows: where done, the state and observation of a reset from the key;
        info["final_observation"] and info["final_x"] the ended step's. (obs, state, info). key: one key, whose
        resets are reset_rows(key, N)'s, or G keys for G groups of N/G rows (several seeds' rows in one batch), a
        group's those of reset_rows(its key, N/G). Only the done rows are reset (`_reset_where`): call it on all the
        rows at once rather than under vmap, which would compute every row's reset."""
        info = {**info, "final_observation": obs, "final_x": state.x}
        n = state.x.shape[0]
        one = jnp.ndim(key) == (0 if jax.dtypes.issubdtype(key.dtype, jax.dtypes.prng_key) else 1)  # typed or raw
        if one:
            keys = jax.random.split(key, n)
        else:  # a key per group
            keys = jax.vmap(lambda k: jax.random.split(k, n // key.shape[0]))(key)
            keys = keys.reshape(n, *keys.shape[2:])
        obs, state = self._reset_where(keys, done, obs, state, params)
        return obs, state, info

    def _reset_where(self, keys, done, obs, state, params):
        """(obs, state) with the rows where done replaced by reset_env(their key, params)'s: the done rows are
        gathered N / RESET_SHARE at a time, reset and written back, a chunk run only where some done row is left
        (``lax.cond`` in a loop of a fixed trip count: the reset traced once, reverse mode kept). Episodes end a few
        at a time, so a step usually resets one chunk, not N rows. A row's reset is the one reset_rows draws from
        its key, to an ulp: XLA's code for a batch of another size may round a product apart (measured: 4e-19 in an
        energy of 20 J)."""
        n = done.shape[0]
        few = max(1, n // RESET_SHARE)

        def chunk(i, carry):
            def reset_some(carry):
                obs, state, left = carry
                index = jnp.nonzero(left, size=few, fill_value=0)[0]  # the rows left, then row 0 (kept as it is)
                taken = left[index]
                fresh = jax.vmap(self.reset_env, (0, None))(keys[index], params)

                def put(a, b):
                    return a.at[index].set(jnp.where(taken.reshape(-1, *([1] * (jnp.ndim(a) - 1))), b, a[index]))

                obs, state = jax.tree_util.tree_map(put, (obs, state), fresh)
                return obs, state, left.at[index].set(False)

            return jax.lax.cond(jnp.any(carry[2]), reset_some, lambda carry: carry, carry)

        obs, state, _ = jax.lax.fori_loop(0, -(-n // few), chunk, (obs, state, done))
        return obs, state
