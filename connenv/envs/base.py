"""The task layer every connenv env stands on: one explicit state, task code as functions of it, one step loop.

A task has a *state*, a small dataclass (`State` subclass) holding what the step needs and nothing else: floats in
the single env, arrays over rows in the native vector env (`connenv.envs.vector`), with the same field names.
Its task code is functions of that state, written once for both with the operations ``ops`` (``SCALAR`` on
Python floats, ``BATCH`` on numpy arrays):

- ``command(action)``: what the action asks of the assigned coordinates;
- ``advance(state, command, stepper, ops)``: the next state, physics through ``connenv.core.segments.run_segments``:
  the single env's step with its stepper, and the vector env's with the batched stepper (row i stepped as the
  single state) and ops=BATCH;
- ``observe(state, ops)``, ``describe(state, ops)`` (the info), ``reward(before, after, info, ops)`` and
  ``terminated(state, info, ops)`` (default: ``info["is_success"]``).

``TaskEnv`` owns the Gymnasium API around them: ``reset`` calls ``start(options)`` for the state; ``step`` checks
the action, advances, and reports. Nothing in a task sets attributes on the side: what a step changes is the state.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace
from typing import ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding

from connenv.core.backend import SCALAR
from connenv.core.context import Context
from connenv.core.model import Model
from connenv.core.params import Args, document
from connenv.core.state import Fields, Options, document_state
from connenv.core.steppers import StepperError
from connenv.core.validation import check_action, check_keys, check_mapping


@dataclasses.dataclass
class State:
    """Base of the task states: a dataclass of numbers (floats, ints, bools, small arrays) in the single env, the
    same fields as arrays over rows in the vector env. ``components`` names the entries of an array field where
    the literature has names for them (the model's ``state_names``)."""

    components: ClassVar[dict] = {}
    phase: ClassVar[tuple[str, ...]] = ()
    """(q, p, u…): the names, among the model's ``state_names``, of a conjugate pair and the assigned coordinates
    that a phase portrait draws, where they are not y = (q, p) and u."""
    unmeasured: ClassVar[tuple[str, ...]] = ()
    """Fields that hold NaN for "not measured" (the ball's distance where it is not solved for): the model takes NaN
    there, and in no other entry."""

    def rows(self, n: int) -> State:
        """A state of n rows shaped and typed like this one's fields, zeroed."""
        return type(self)(**{k: np.zeros((n, *np.shape(v)), np.asarray(v).dtype) for k, v in self.fields().items()})

    def set_row(self, i: int, state: State) -> None:
        """Row i of this batch := the single state."""
        for key, value in state.fields().items():
            getattr(self, key)[i] = value

    def fields(self) -> dict:
        return {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}

    def replace(self, **changes) -> State:
        return dataclasses.replace(self, **changes)


def each_row(function, states, ops):
    """function(*states) of state dicts (as ``info["state"]``) on one state (ops=SCALAR); over a batch, function of
    each row's dicts (every value indexed by the row), stacked: a user's task code, written for one state, run by
    a vector env."""
    if ops is SCALAR:
        return function(*states)
    rows = range(len(states[0]["t"]))
    return np.stack([np.asarray(function(*({k: v[i] for k, v in d.items()} for d in states))) for i in rows])


class TaskEnv(gym.Env):
    """A single env of the task layer (see the module): ``self.state`` is its State; subclasses give ``start``,
    ``command``, ``advance``, ``observe``, ``describe``, ``reward`` and may override ``terminated``. It is drawn by its
    ``renderer`` (`connenv.rendering.Renderer`), made of the env on the first render: pygame loads then, as in
    classic control."""

    metadata: ClassVar[dict] = {"render_modes": ["human", "rgb_array"], "render_fps": 20}
    renderer: ClassVar[type]
    name: ClassVar[str] = "this env"
    """How errors name the env: its id without the namespace, or its versions' stem (`connenv.envs.spec.register`)."""
    ARGS: ClassVar[Args]
    """The make kwargs (`connenv.core.params`): their checks, the docstring's Arguments table, `parameters()`."""
    state: State
    STATE: ClassVar[Fields] = Fields()
    """The reset state's keys (`connenv.core.state`): their checks in ``start``, the docstring's table of them."""
    OPTIONS: ClassVar[Options] = Options()
    """The reset options beside "state" and "params" (a target), declared as the state is."""
    JAX_STATIC: ClassVar[tuple[str, ...]] = ()
    """Physical parameters that ``connenv.jax`` holds static (compiled anew for another value) rather than traced: those
    that set the spaces (which ``randomize`` refuses to vary too) or the step's structure (a count of pieces)."""
    context: Context | None = None
    """The episodes' physical parameters (`connenv.core.context`); None for an env without declared ones."""
    _model = None  # the model, made on first use
    trace: list
    """While rendering: the renderer's ``point(env)`` of each state since reset, the track drawn behind the body."""
    reports_params = False  # whether info carries "params" (and the observation them, if observed): where they vary,
    # or a reset set them

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        document(cls)
        document_state(cls)

    def check_args(self, kwargs: dict) -> tuple[SimpleNamespace, dict]:
        """(ARGS checked on the make kwargs, with their defaults, as attributes, kept as ``self.args``; the
        stepper's options). A bad one is a ValueError before anything is set."""
        randomize, observe_params = kwargs.pop("randomize", None), kwargs.pop("observe_params", False)
        args, options = self.ARGS.check(self.name, type(self), kwargs)
        self.args, self.kwargs = SimpleNamespace(**args), dict(kwargs)
        self.context = Context(self, randomize, observe_params)
        return self.args, options

    def parameters(self) -> dict:
        """The physical parameters of ARGS, as a stepper's error reports them (none where there are no ARGS)."""
        return self.ARGS.physical(vars(self.args)) if hasattr(self, "args") else {}

    def __init__(self, render_mode: str | None, dt: float):
        """dt: the control step, s (checked by the subclass); it sets the render frame rate."""
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode={render_mode!r} is not one of {self.metadata['render_modes']} or None")
        self.render_mode = render_mode
        self.dt = dt
        self.metadata = {**self.metadata, "render_fps": round(1.0 / dt)}
        self._renderer, self.trace = None, []

    def render(self):
        if self.render_mode is None:
            gym.logger.warn('render() without render_mode; pass render_mode="rgb_array" or "human" to make().')
            return None
        if self._renderer is None:
            self._renderer = self.renderer(self)
        if not self.trace and self.renderer.point is not None:  # a render before the first reset or step
            self.trace.append(self.renderer.point(self))
        return self._renderer.draw(self)

    def __getstate__(self):
        """The env without its renderer (a pygame window or surface, which cannot be pickled or copied): a copy
        or an unpickled env makes its own on its first render."""
        return {**self.__dict__, "_renderer": None, "_model": None}

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _stepper_error(self, error: StepperError, t: float) -> StepperError:
        """`error` (a stepper's, or the env's own invariant check) with the env, the time t, dt and the physical
        parameters (the subclass's ``parameters()``) added."""
        values = ", ".join(f"{key} = {value!r}" for key, value in self.parameters().items())
        where = f"{type(self).__name__} in the step from t = {t:.6g} s, dt = {self.dt}"
        return StepperError(f"{error} [{where}, {values}]")

    def reset(self, *, seed=None, options=None):
        """Gymnasium's reset. Everything is checked before anything of the env changes: the options, the
        parameters (drawn and given) and the state are checked on a copy of the generator (and, where the parameters
        change, on the env made with them), and taken only when all are good. A reset that raises leaves the env as
        it was, its generator included (a seed is taken with the reset; draws from the generator are put back)."""
        check_mapping("reset options", options or {})
        options = dict(options or {})
        given, context = options.pop("params", None), self.context
        if given is not None:
            if context is None:
                raise ValueError(f'reset option "params": {self.name} declares no physical parameters')
            given = context.check_given(given)
        own = self._np_random
        if seed is not None or own is None:
            rng, rng_seed, drawn = *seeding.np_random(seed), None
        else:  # drawn from in place, its state put back if the reset raises: a vector env's row keeps its own
            rng, rng_seed, drawn = own, None, own.bit_generator.state
        env, values = self, None
        try:
            if context is not None and (given is not None or context.varies or context.moved):
                values = context.checked(self, context.draw(rng, given))
                if values != context.current:
                    env = self.made_with(values)
            env._np_random = rng
            state = env.start(options)
        except BaseException:
            if drawn is not None:
                rng.bit_generator.state = drawn
            raise
        finally:
            self._np_random = own
        if env is not self:
            self.take(env, values)
        if rng is not own:
            self._np_random, self._np_random_seed = rng, rng_seed
        self.reports_params = given is not None or (context is not None and context.varies)
        self.state = state
        if self.render_mode is not None:
            self.trace = []
            self.rendered()
        return self.observation(self.state), self.report(self.describe(self.state))

    def step(self, action):
        command = self.command(self.check_action(action))
        before = self.state
        try:
            self.state = self.advance(before, command, self.stepper)
        except StepperError as error:
            raise self._stepper_error(error, before.t) from error
        info = self.describe(self.state)
        reward = self.reward(before, self.state, info)
        terminated = self.terminated(self.state, info)
        if self.render_mode is not None:
            self.rendered()
        if self.reports_params:  # checked here, not in calls, as the step of fixed parameters is the common one
            return self.observation(self.state), reward, terminated, False, self.report(info)
        return self.observe(self.state), reward, terminated, False, info

    _observed_space = None  # the observation space with the observed parameters', made on first use

    @property
    def observation_space(self):
        """The task's observation space, with the observed parameters' appended (``observe_params``): one object
        for the env's life, so that a user's seed of it holds."""
        space = self._observation_space  # not self.__dict__: an instance whose dict is read loses its fast attributes
        if self.context is None or not self.context.observe:
            return space
        if self._observed_space is None:
            self._observed_space = self.context.observation_space(space)
        return self._observed_space

    @observation_space.setter
    def observation_space(self, space):
        self._observation_space = space

    def observation(self, state, ops=SCALAR):
        """observe(state), with the observed parameters appended (of each row, over a batch)."""
        obs = self.observe(state, ops)
        if self.context is None or not self.context.observe:
            return obs
        params = self.context.observed
        if isinstance(obs, dict):  # a goal env's: the parameters as a key of their own
            rows = next(iter(obs.values())).shape[:-1]
            return {**obs, "params": np.broadcast_to(params, (*rows, params.size)).copy()}
        return np.concatenate([obs, np.broadcast_to(params, (*obs.shape[:-1], params.size))], axis=-1)

    def report(self, info: dict) -> dict:
        """info, with this episode's physical parameters as "params" where they may differ from the make kwargs."""
        if self.reports_params:
            info["params"] = dict(self.context.current)
        return info

    def set_params(self, values: dict):
        """Take these physical parameter values: the env's make kwargs with them, checked (ValueError naming one
        out of range) and built anew before anything of this env changes; its generator, spaces, context and spec
        kept."""
        values = self.context.checked(self, values)
        if values != self.context.current:
            self.take(self.made_with(values), values)

    KEPT = ("_np_random", "_np_random_seed", "context", "spec", "render_mode", "_renderer", "action_space",
            "_observation_space", "_observed_space")
    """What a parameter change keeps of the env: its generator, its spaces (a user may have seeded them; make fixed
    them), its context, its spec and its renderer's settings."""

    def made_with(self, values: dict) -> TaskEnv:
        """The env made with these (checked) parameter values, its spaces those of this env, else ValueError."""
        fresh = type(self)(**{**self.context.kwargs, **values})
        for space in ("_observation_space", "action_space"):
            if getattr(fresh, space) != getattr(self, space):
                raise ValueError(f"params {values} change {self.name}'s {space.strip('_').replace('_', ' ')}, "
                                 "which must stay fixed")
        return fresh

    def take(self, fresh: TaskEnv, values: dict):
        """fresh's parameters and what follows from them (its system, its constants), the rest kept (``KEPT``)."""
        self.close()
        for key, value in vars(fresh).items():
            if key not in self.KEPT:
                setattr(self, key, value)
        self._model = None
        self.context.take(values)

    def rendered(self):
        """While rendering, after a reset or a step: the state's point on the trace (if the renderer draws one), and
        in human mode the frame shown, as in classic control."""
        if self.renderer.point is not None:
            self.trace.append(self.renderer.point(self))
        if self.render_mode == "human":
            self.render()

    def reset_values(self, options: dict, defaults: dict | None = None) -> dict:
        """The values of the reset state's keys and of the other options (`STATE`, `OPTIONS`): those given checked,
        the others their defaults (``defaults``, else the fields'). A bad key or value is a ValueError naming it,
        before anything is set."""
        check_keys("reset options", options, {"state", *self.OPTIONS.names})
        values = self.STATE.check(self, options.get("state", {}), defaults)
        if self.OPTIONS.fields:
            others = {key: value for key, value in options.items() if key != "state"}
            values |= self.OPTIONS.check(self, others, defaults, "reset options")
        return values

    def check_action(self, action):
        """The action as a finite float array of the space's shape, clipped into the space (else ValueError)."""
        return check_action(action, self.action_space)

    @property
    def model(self):
        """The env's step as a pure function of a flat state, with its Jacobians (`connenv.core.model.Model`),
        for the env's current parameters."""
        if self._model is None:
            self._model = Model(self)
        return self._model

    def terminated(self, state, info, ops=SCALAR):
        """Whether the task ends the episode: on success, unless the task says otherwise."""
        return info["is_success"]

    def start(self, options: dict) -> State:
        raise NotImplementedError

    def command(self, action):
        raise NotImplementedError

    def advance(self, state, command, stepper, ops=SCALAR) -> State:
        raise NotImplementedError

    def observe(self, state, ops=SCALAR):
        raise NotImplementedError

    def describe(self, state, ops=SCALAR) -> dict:
        raise NotImplementedError

    def reward(self, before, after, info, ops=SCALAR):
        raise NotImplementedError
