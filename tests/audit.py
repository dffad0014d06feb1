"""Bad-input audit over every registered connenv id: make kwargs from the float64 edges to zero, stepper options,
reset states and options, and actions (subnormal, huge, non-finite, complex, of the wrong shape or type), by the
single env and the vector env.

Run it from the repository's root::

    python tests/audit.py [--quick] [--ids connenv/Swing-v0 ...] [--cases make_kwarg_cases ...] [--show N]

It prints every open case as it meets it (and every accepted case slower than SLOW s), then the totals by subject
and overall; it exits 1 if a case is open. The full sweep takes the powers of ten one by one (``--quick``: every
tenth). pytest does not collect it (its name does not start with ``test_``); tests/test_fuzz.py runs a sample of
its cases with few steps each.

Every case ends one of three ways:

- **error**: a ValueError or TypeError (or StepperError, the project's documented exception, where a case says
  so) whose message names the argument (``names``), with no warning before it; a refused step must leave the state
  as it was;
- **ran**: accepted, and every number that left the env (observations, rewards, infos) was finite, with no
  warning, within TIMEOUT s;
- **open**: anything else (another exception, an error that names nothing, a non-finite number, a warning, a
  refused step that had moved the state, a hang), listed by case.

The sweep is the list of case generators ``GENERATORS``: each is a function ``generator(ids, quick)`` that yields
``Case``s. Cases of another kind (the builders' hostile systems, the command lines) come from a generator appended
there: a ``Case`` is a subject, a description, the names its error must give, and a callable that raises or
returns the results whose numbers must be finite (a command line's: run it in a subprocess, raise on a traceback
or a zero exit, return nothing).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import dataclasses
import inspect
import math
import re
import signal
import sys
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run as a script from anywhere: this checkout's connenv

import connenv  # noqa: F401  (registers the envs)
from connenv.core.integrators import SUBSTEPS_MAX
from connenv.core.steppers import StepperError
from connenv.core.validation import init_parameters
from connenv.envs.spec import registry, spec

IDS = sorted(registry)  # every id with a spec
TIMEOUT = 10.0  # s a case may take before it counts as a hang
STEPS = 50  # random steps of a single env made with an edge kwarg (then a reset)
VECTOR_STEPS = 10  # of its vector env of VECTOR_ROWS rows
VECTOR_ROWS = 2
SLOW = 2.0  # s: an accepted case slower than this is listed (a step's work should stay well within TIMEOUT)

# -- the values ---------------------------------------------------------------------------------------------------

SUBNORMALS = (5e-324, 1e-310)


def edge_numbers(quick=False):
    """0, the subnormals and the powers of ten from 1e-308 to 1e308 (every tenth with quick, and both ends), each
    of both signs."""
    exponents = range(-308, 309, 10 if quick else 1)
    magnitudes = sorted({*SUBNORMALS, *(10.0**k for k in exponents), 1e-308, 1e308})
    return [0.0, *magnitudes, *(-m for m in magnitudes)]


MAGNITUDES = (*SUBNORMALS, 1e-300, 1e-30, 1e-3, 1.0, 1e3, 1e30, 1e300, 1.7e308)
STATE_NUMBERS = (0.0, *MAGNITUDES, *(-x for x in MAGNITUDES))  # in reset states and actions
NON_FINITE = (math.nan, math.inf, -math.inf)
NOT_NUMBERS = ("1.0", True, False, 1 + 0j, np.complex128(2 + 3j), [1.0], np.array([1.0]), b"1", object())
"""Values no numeric argument takes: a string, bools, complex numbers (of zero imaginary part too), a list, an
array, bytes, an object."""
INTEGERS = (0, 1, SUBSTEPS_MAX, SUBSTEPS_MAX + 1, 10**6, 10**9, 10**18, 2**63, -1, -(10**9), 2.0, 1.5)  # substeps

# -- the envs' arguments ----------------------------------------------------------------------------------------



class Declared(Mapping):
    """{id: read(id, env)} over the registered ids, each read on first use off the unwrapped env, made with its
    make kwargs: what the env declares (its reset state, `connenv.core.state`), a builder's sizes its example's."""

    def __init__(self, read):
        self.read, self.found = read, {}

    def __getitem__(self, env_id):
        if env_id not in registry:
            raise KeyError(env_id)
        if env_id not in self.found:
            self.found[env_id] = self.read(env_id, make(env_id).unwrapped)
        return self.found[env_id]

    def __iter__(self):
        return iter(registry)

    def __len__(self):
        return len(registry)


def numeric_keys(fields, env):
    """The numbers and vectors of declared reset keys (`connenv.core.state`): the number of entries of each (0: a
    number)."""
    shapes = fields.shapes(env)
    return {key: (shapes[key] or (0,))[0] for key, field in fields.fields.items() if field.kind in ("number", "vector")}


def rotations(env_id, env):
    """Reset arguments that take a rotation matrix, (path in the options, name in the message): the declared reset
    state's rotations, then the declared options'."""
    state = [(("state", key), f"state {key}") for key, field in env.STATE.fields.items() if field.kind == "rotation"]
    return state + [((key,), key) for key, field in env.OPTIONS.fields.items() if field.kind == "rotation"]


STATE_KEYS = Declared(lambda env_id, env: numeric_keys(env.STATE, env))
"""Reset state keys of each id (its env's declared state): the number of entries of each (0: a number)."""
OPTION_KEYS = Declared(lambda env_id, env: numeric_keys(env.OPTIONS, env))
"""Reset options beside "state" (its env's declared options), alike."""
ROTATIONS = Declared(rotations)
"""Reset arguments that take a rotation matrix: (path in the options, name in the message)."""


def randomized_ranges(env_id, env):
    """randomize for an id: each physical parameter within 10 % of its make value, but those that make refuses to
    vary (a parameter that sets the observation space: the swing's radii, the skier's h_max); {} without any."""
    if env.context is None:
        return {}
    ranges = {}
    for name, value in env.context.base.items():
        if isinstance(value, float) and value != 0.0:
            trial = {**ranges, name: tuple(sorted((0.9 * value, 1.1 * value)))}
            try:
                make(env_id, randomize=trial)
            except ValueError:
                continue
            ranges = trial
    return ranges


RANDOMIZED = Declared(randomized_ranges)
"""randomize of each id with physical parameters: every one that may vary, within 10 % of its make value."""
NOT_NUMERIC = {"render_mode", "system", "connection", "task", "draw", "trail", "trail_params", "group", "frame",
               "control", "integrator", "pivot", "vectorized", "surface", "surface_params", "measure_distance"}


def make_kwargs(env_id):
    """The kwargs env_id is made with: the builders' examples (its spec's), none for the others."""
    return spec(env_id).make_kwargs()


def env_class(env_id):
    module, name = gym.spec(env_id).entry_point.split(":")
    return getattr(__import__(module, fromlist=[name]), name)


def numeric_parameters(env_id):
    """The make kwargs of env_id that take a number (or None for a number): name -> default. The builders' bounds
    (u_low, shape_low, ...) take a number or a sequence and count as numbers."""
    cls = env_class(env_id)
    defaults = {}
    for klass in cls.__mro__:
        if "__init__" in vars(klass):
            for p in inspect.signature(klass.__init__).parameters.values():
                defaults.setdefault(p.name, p.default)
    given = make_kwargs(env_id)
    names = [n for n in init_parameters(cls) if n not in NOT_NUMERIC]
    return {n: given.get(n, defaults.get(n)) for n in names
            if isinstance(given.get(n, defaults.get(n)), (int, float, list, type(None)))}


def stepper_options(env_id):
    """{option: the integrator it is swept with}: each of substeps, rtol, atol under the env's default integrator
    if it takes it, else substeps under rk4 (and rtol, atol under dop853) where the env offers them."""
    found = {}
    for option, probe in (("substeps", 2), ("rtol", 1e-6), ("atol", 1e-8)):
        for integrator in (None, "rk4" if option == "substeps" else "dop853"):
            extra = {} if integrator is None else {"integrator": integrator}
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    gym.make(env_id, disable_env_checker=True, **make_kwargs(env_id), **extra, **{option: probe})
            except ValueError:
                continue
            found[option] = integrator
            break
    return found


# -- cases and their verdicts -----------------------------------------------------------------------------------


@dataclass
class Case:
    """One bad input: ``run()`` raises, or returns the results (observations, rewards, infos) whose numbers must
    be finite. A clear error names one of ``names``; ``documented`` lists further exceptions that count as
    clear errors here (StepperError, where a case expects it)."""

    where: str  # the env id, or another subject (a builder, a command line)
    what: str
    names: tuple[str, ...]
    run: Callable[[], object]
    documented: tuple[type, ...] = ()


@dataclass
class Verdict:
    kind: str  # "error", "ran" or "open"
    detail: str = ""


class Hang(Exception):
    """A case ran past TIMEOUT."""


class MovedState(Exception):
    """A refused step had changed the env's state."""


def numbers(tree):
    """Every number in an observation, reward, info or a tuple of them (strings left out)."""
    if isinstance(tree, dict):
        return [x for value in tree.values() for x in numbers(value)]
    if isinstance(tree, (tuple, list)) and any(isinstance(v, (dict, tuple, list, np.ndarray)) for v in tree):
        return [x for value in tree for x in numbers(value)]
    if tree is None or isinstance(tree, str):
        return []
    array = np.asarray(tree)
    if array.dtype.kind in "USO":  # strings (a vector env's info over rows): kept only where they are numbers
        return [float(x) for x in array.ravel() if isinstance(x, (int, float, np.number))]
    return list(np.ravel(array.astype(float)))


@contextlib.contextmanager
def time_limit(seconds):
    """Raise Hang in the main thread after `seconds` (None: no limit); a solver's Python loop is interrupted."""
    if seconds is None:
        yield
        return

    def alarm(signum, frame):
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def names(name: str, message: str) -> bool:
    """Whether an error message names the argument: as ``name=`` or ``name[`` (its value, or an entry's), or, for a
    name longer than a letter, as a word (a one-letter name, a or b, would match the article)."""
    pattern = rf"(?<![\w.]){re.escape(name)}(=|\[)" if len(name) == 1 else rf"(?<![\w.]){re.escape(name)}(?!\w)"
    return re.search(pattern, message) is not None


OUT_OF_DATE = r".*is out of date\. You should consider upgrading"
"""Gymnasium's notice on making an id of which a newer version is registered; the older versions are kept on purpose,
so it is no warning of the audit's (nor of the tests', pyproject.toml's filterwarnings)."""


def judge(case: Case, timeout: float | None = TIMEOUT) -> Verdict:
    """Run the case and say how it ended (see the module)."""
    start = time.perf_counter()
    try:
        with warnings.catch_warnings(record=True) as caught, time_limit(timeout):
            warnings.simplefilter("always")
            warnings.filterwarnings("ignore", OUT_OF_DATE, DeprecationWarning)
            results = case.run()
    except (ValueError, TypeError, *case.documented) as error:
        message = str(error)
        if not any(names(name, message) for name in case.names):
            return Verdict("open", f"{type(error).__name__} naming none of {case.names}: {message[:300]}")
        if caught:
            return Verdict("open", f"refused, but warned first: {caught[0].category.__name__}: {caught[0].message}")
        return Verdict("error", f"{type(error).__name__}: {message[:300]}")
    except Hang as error:
        return Verdict("open", f"hang: {error}")
    except Exception as error:  # noqa: BLE001  (every other outcome is what the audit reports)
        return Verdict("open", f"{type(error).__name__}: {str(error)[:300]}")
    values = np.array(numbers(results), float)
    if caught:
        return Verdict("open", f"warning: {caught[0].category.__name__}: {str(caught[0].message)[:200]}")
    if not np.all(np.isfinite(values)):
        return Verdict("open", f"a non-finite number left the env ({np.count_nonzero(~np.isfinite(values))} of them)")
    return Verdict("ran", f"{time.perf_counter() - start:.2f} s")


# -- running an env ---------------------------------------------------------------------------------------------


def make(env_id, **changed):
    return gym.make(env_id, disable_env_checker=True, **{**make_kwargs(env_id), **changed})


def make_vector(env_id, **changed):
    kwargs = {**make_kwargs(env_id), **changed}
    return gym.make_vec(env_id, VECTOR_ROWS, vectorization_mode="vector_entry_point", **kwargs)


def rollout(env, steps, seed=0, options=None):
    """reset(seed, options), `steps` random steps (resetting where an episode ends), a reset: every result."""
    results = [env.reset(seed=seed, options=options)]
    env.action_space.seed(seed)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        results.append((obs, reward, info))
        if np.ndim(terminated) == 0 and (terminated or truncated):  # a vector env resets its rows itself
            results.append(env.reset())
    results.append(env.reset())
    return results


def state_snapshot(env):
    """A copy of the env's state (single: the unwrapped env's; vector: its batch)."""
    return copy.deepcopy(env.unwrapped.state if hasattr(env, "unwrapped") else env.state)


def same_state(a, b):
    return all(np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True) for x, y in zip(
        a.fields().values(), b.fields().values()))


def step_from(env, action, steps=3, seed=0):
    """From reset(seed): step `action` `steps` times; a refused step must leave the state as it was."""
    results = [env.reset(seed=seed)]
    for _ in range(steps):
        before = state_snapshot(env)
        try:
            obs, reward, terminated, truncated, info = env.step(action)
        except (ValueError, TypeError):
            if not same_state(before, state_snapshot(env)):
                raise MovedState("a refused step changed the state") from None
            raise
        results.append((obs, reward, info))
        if np.any(terminated) or np.any(truncated):
            break
    return results


# -- the generators ---------------------------------------------------------------------------------------------


def make_kwarg_cases(ids, quick=False, values=None, steps=STEPS, vector_steps=VECTOR_STEPS):
    """Every numeric make kwarg at every value (default: the edge numbers, the non-finite ones, those that are no
    number, and None where the default is a number): single env (`steps` random steps and a reset) and vector env
    (`vector_steps`)."""
    for env_id in ids:
        for key, default in numeric_parameters(env_id).items():
            chosen = values
            if chosen is None:
                chosen = [*edge_numbers(quick), *NON_FINITE, *NOT_NUMBERS, *([None] if default is not None else [])]
            for value in chosen:
                yield Case(env_id, f"make {key}={value!r}", (key,),
                           lambda e=env_id, k=key, v=value: rollout(make(e, **{k: v}), steps))
                yield Case(env_id, f"make_vec {key}={value!r}", (key,),
                           lambda e=env_id, k=key, v=value: rollout(make_vector(e, **{k: v}), vector_steps))


def stepper_cases(ids, quick=False, values=None):
    """substeps (integers, huge ones too; or `values`), rtol and atol at the edge numbers (or `values`), each also
    non-finite or no number, under the integrator that takes them. Under an integrator other than the env's
    default a StepperError (its documented divergence: RK4 drifts off SO(3), say) is a clear error."""
    for env_id in ids:
        for option, integrator in stepper_options(env_id).items():
            extra = {} if integrator is None else {"integrator": integrator}
            documented = () if integrator is None else (StepperError,)  # another integrator may diverge
            chosen = values.get(option) if values else (INTEGERS if option == "substeps" else edge_numbers(True))
            for value in (*chosen, *NOT_NUMBERS, *NON_FINITE):
                kwargs = {**extra, option: value}
                label = ", ".join(f"{k}={v!r}" for k, v in kwargs.items())
                yield Case(env_id, f"make {label}", (option,),
                           lambda e=env_id, kw=kwargs: rollout(make(e, **kw), 5), documented)


def entries(size, number):
    """Values of a reset argument of `size` entries (0: a number) with `number` in it: the number alone, or in the
    first entry of a sequence and of an array."""
    if size == 0:
        return [number]
    vector = [number] + [0.0] * (size - 1)
    try:
        return [vector, np.array(vector)]
    except ValueError:  # a ragged sequence: no array of it
        return [vector]


def reset_values(size):
    values = [v for x in (*STATE_NUMBERS, *NON_FINITE) for v in entries(size, x)]
    values += [v for x in NOT_NUMBERS for v in entries(size, x)]
    if size == 0:
        return [*values, np.array(0.5 + 0j), np.array([0.5]), None]
    return [*values, np.zeros(size, complex), np.full(size, 2 + 3j), np.zeros(size + 1), np.zeros((size, 1)), None]


def reset_cases(ids, quick=False):
    """Every reset state key and option at the edge numbers, non-finite, complex, of the wrong shape or type;
    rotations given complex, subnormally off, or not rotations. Accepted: five random steps."""
    for env_id in ids:
        keys = {**{("state", k): n for k, n in STATE_KEYS.get(env_id, {}).items()},
                **{(k,): n for k, n in OPTION_KEYS.get(env_id, {}).items()}}
        for path, size in keys.items():
            name = " ".join(path)
            for value in reset_values(size):
                options = {path[0]: value} if len(path) == 1 else {path[0]: {path[1]: value}}
                yield Case(env_id, f"reset {options!r}", (name, path[-1]),
                           lambda e=env_id, o=options: rollout(make(e), 5, options=o))
        for path, name in ROTATIONS.get(env_id, []):
            tiny = np.eye(3)
            tiny[0, 1] = 1e-310
            for value in (np.eye(3) + 0j, np.eye(3) * (1 + 1e-3j), tiny, np.eye(3)[:2], np.full((3, 3), np.nan),
                          np.eye(3).astype(object), "I", np.eye(3).tolist()):
                options = {path[0]: value} if len(path) == 1 else {path[0]: {path[1]: value}}
                yield Case(env_id, f"reset {name}={value!r}", (name,),
                           lambda e=env_id, o=options: rollout(make(e), 5, options=o))


def action_values(shape):
    """Actions of the space's shape with one entry (or all) at an edge number, non-finite or complex; arrays of the
    wrong shape; values that are no number."""
    size = shape[0]
    values = []
    for x in (*STATE_NUMBERS, *NON_FINITE):
        one = np.zeros(size)
        one[0] = x
        values += [one, np.full(size, x)]
    values += [np.full(size, 0.5 + 1j), np.zeros(size, complex), np.zeros(size + 1), np.zeros((size, 1)),
               np.zeros(0), [0.0] * size, ["0.5"] * size, np.zeros(size, bool), "0.5", None, 0.5]
    return values


def action_cases(ids, quick=False):
    """Every action value (action_values) from reset(seed=0), stepped three times, by the single env and by the
    vector env (the same action on every row)."""
    for env_id in ids:
        single, vector = make(env_id), make_vector(env_id)
        for action in action_values(single.action_space.shape):
            yield Case(env_id, f"step {action!r}", ("action",), lambda e=single, a=action: step_from(e, a))
            given = isinstance(action, np.ndarray)
            rows = np.broadcast_to(action, (VECTOR_ROWS, *np.shape(action))) if given else action
            yield Case(env_id, f"vector step {action!r}", ("action",), lambda e=vector, a=rows: step_from(e, a))


MODEL_NUMBERS = (math.nan, math.inf, -math.inf, 1e300, -1e300, 0.5)
"""Values put into one entry of a model's x at a time (0.5: a flag's or a counter's)."""


def finite_part(model, x_next):
    """x_next without its unmeasured entries (the ball's distance, NaN by declaration): what must be finite."""
    return np.asarray(x_next)[..., ~model.nan_allowed]


def model_cases(ids, quick=False):
    """``env.unwrapped.model``: each entry of x (one state and rows) non-finite, huge or fractional; x complex, of
    strings, None, of the wrong shape, an empty batch; actions and params that are no real numbers or of the wrong
    shape, per-row params of the wrong length; ``pack``, ``reward``, ``terminated``, ``info``, ``with_params`` and
    ``jacobians`` given the same. A huge entry may run (its result finite) or raise StepperError."""
    for env_id in ids:
        env = make(env_id).unwrapped
        env.reset(seed=0)
        model = env.model
        x, a = model.pack(env.state), np.zeros(env.action_space.shape)
        X, A = np.repeat(x[None], VECTOR_ROWS, axis=0), np.zeros((VECTOR_ROWS, *env.action_space.shape))
        name = next((f.name for f in dataclasses.fields(model.params)), "g")  # an env without any: an unknown name
        step = lambda y, b, m=model, **kw: finite_part(m, m.step(y, b, **kw))  # noqa: E731
        for j, entry in enumerate(model.state_names):
            for value in MODEL_NUMBERS if not quick or j % 3 == 0 else MODEL_NUMBERS[:2]:
                y, Y = x.copy(), X.copy()
                y[j], Y[-1, j] = value, value
                for label, args in (("step", (y, a)), ("rows step", (Y, A))):
                    yield Case(env_id, f"model {label} x[{entry}]={value!r}", ("state x", "step"),
                               lambda args=args, f=step: f(*args), (StepperError,))
                yield Case(env_id, f"model jacobians x[{entry}]={value!r}", ("state x", "step"),
                           lambda m=model, Y=Y: m.jacobians(Y, A), (StepperError,))
        states = [x + 1e-3j, X + 1e-3j, x.astype(str), x.tolist()[:-1] + ["0"], None, "x", x[:-1], X[:0], X[..., None],
                  x.astype(bool), np.zeros((0, model.n)), [[]]]
        for value in states:
            for call, label in ((lambda m, v: step(v, a if np.ndim(v) < 2 else A), "step"),
                                (lambda m, v: m.jacobians(v, a if np.ndim(v) < 2 else A), "jacobians"),
                                (lambda m, v: m.terminated(v), "terminated"), (lambda m, v: m.info(v), "info"),
                                (lambda m, v: m.unpack(v), "unpack"),
                                (lambda m, v: m.reward(x, a, v), "reward x_next")):
                yield Case(env_id, f"model {label} x={value!r}"[:200], ("state x", "state x_next"),
                           lambda m=model, v=value, c=call: c(m, v))
        actions = [None, "0.5", a + 1j, a.astype(str), np.zeros(a.size + 1), A, [], math.nan, np.full(a.shape, math.nan)]
        for value in actions:
            yield Case(env_id, f"model step a={value!r}", ("action",), lambda v=value: step(x, v))
            yield Case(env_id, f"model jacobians a={value!r}", ("action",), lambda m=model, v=value: m.jacobians(x, v))
            rows = value if not isinstance(value, np.ndarray) or value.shape == A.shape else np.broadcast_to(
                value, (VECTOR_ROWS, *np.shape(value)))
            yield Case(env_id, f"model rows step a={rows!r}"[:200], ("action",), lambda v=rows: step(X, v))
        params = [5, "g", None if False else [], [{}], [{}] * (VECTOR_ROWS + 1), {"bogus": 1.0}, {name: [1, 2]},
                  {name: "1"}, {name: math.nan}, {name: math.inf}, {name: True}, {name: 1 + 0j}, {name: None},
                  [{name: "1"}, {}], [5, {}], {name: -1.0}, {name: 1e300}]
        for value in params:
            yield Case(env_id, f"model rows step params={value!r}", ("params", name),
                       lambda v=value: step(X, A, params=v))
            yield Case(env_id, f"model jacobians params={value!r}", ("params", name),
                       lambda m=model, v=value: m.jacobians(X, A, params=v))
            if not isinstance(value, list):
                yield Case(env_id, f"model with_params({value!r})", ("params", name),
                           lambda m=model, v=value: m.with_params(v).params)
        fields = model.unpack(x)
        for value in ({}, "abc", None, 5, {**fields, "bogus": 1.0}, {k: v for k, v in list(fields.items())[1:]},
                      {**fields, "t": "0"}):
            yield Case(env_id, f"model pack({value!r})"[:200], ("state",), lambda m=model, v=value: m.pack(v))
        yield Case(env_id, "model reward (x, rows)", ("state x",), lambda m=model: m.reward(x, a, X))
        yield Case(env_id, "model reward (rows, x)", ("state x",), lambda m=model: m.reward(X, A, x))


def geometry_cases(ids, quick=False):
    """``connenv.geometry`` on each id with a connection: shapes, loops and apexes non-finite, complex, of strings,
    of another number of coordinates, empty; a period that is no positive number; minimum_perturbation's grid out
    of its range or no whole number. An id without a connection is a ValueError that says so."""
    from connenv import geometry

    for env_id in ids:
        try:
            local = geometry.local_connection(env_id)
        except ValueError:
            yield Case(env_id, "geometry curvature of an env without a connection", ("connection",),
                       lambda e=env_id: geometry.curvature(e, [0.0]))
            continue
        k = len(local.low)
        s = np.full(k, 0.1)
        square = np.array([s, s + np.eye(k)[0] * 0.1, s + 0.1, s + np.eye(k)[-1] * 0.1, s]) if k > 1 else (
            np.array([[0.1], [0.2], [0.1]]))
        bad_shapes = [np.where(np.arange(k) == 0, v, s) for v in NON_FINITE] + [
            s + 1e-3j, s.astype(str), None, np.zeros(k + 1), np.zeros((0, k)), np.zeros((1, k, 1)), "s",
            np.zeros(max(k - 1, 0))]
        for value in bad_shapes:
            yield Case(env_id, f"geometry curvature s={value!r}", ("s",),
                       lambda e=env_id, v=value: geometry.curvature(e, v).F)
        for v in (*NON_FINITE, 1 + 1j):
            loop = square.astype(complex if isinstance(v, complex) else float)
            loop[1, 0] = v
            yield Case(env_id, f"geometry enclosed loop with {v!r}", ("loop",),
                       lambda e=env_id, lp=loop: geometry.enclosed(e, lp))
            yield Case(env_id, f"geometry loop_holonomy loop with {v!r}", ("loop",),
                       lambda e=env_id, lp=loop: geometry.loop_holonomy(e, lp).net)
            yield Case(env_id, f"geometry enclosed apex {v!r}", ("apex",),
                       lambda e=env_id, a=np.where(np.arange(k) == 0, v, s): geometry.enclosed(e, square, apex=a))
        for loop in (square[:2], square[:, :0], square[..., None], "loop", None, np.zeros((4, k + 1))):
            yield Case(env_id, f"geometry loop_holonomy loop={loop!r}"[:200], ("loop",),
                       lambda e=env_id, lp=loop: geometry.loop_holonomy(e, lp).net)
        for period in (math.nan, 0.0, -1.0, "2", 1j):
            yield Case(env_id, f"geometry loop_holonomy period={period!r}", ("period",),
                       lambda e=env_id, p=period: geometry.loop_holonomy(e, square, period=p).net)
        if local.connection.group == "SE2":
            for grid in (0, 1, 2, 5.5, True, "33", 10**9, -3, None):
                yield Case(env_id, f"geometry minimum_perturbation grid={grid!r}", ("grid",),
                           lambda e=env_id, g=grid: geometry.minimum_perturbation(e, g).beta)


CONTEXT_VALUES = ["79", {"low": 1.0}, (True, 2.0), (1 + 0j, 2.0), (math.nan, 1.0), (1.0, math.inf), (2.0, 1.0),
                  (1e-300, 1e300), (1.0, 2.0, 3.0), None, 5]
"""randomize ranges that are no pair of real numbers, are reversed, or leave the parameter's range."""
PARAM_VALUES = [True, 1 + 0j, "1", math.nan, math.inf, -1.0, 1e300, None, [1.0, 2.0], {"a": 1.0}]
"""A reset's parameter values that are no real number or lie outside every parameter's range."""


def context_cases(ids, quick=False):
    """Parameters as context: ``randomize`` of each physical parameter (and of an unknown name) given a bad range,
    at make and make_vec; ``reset(options={"params": ...})`` given a bad value, a bad mapping, an unknown name, on
    the single env (afterwards it must step as a copy taken before: the failed reset changed nothing) and the vector
    env; ``observe_params`` given a non-bool."""
    for env_id in ids:
        env = make(env_id).unwrapped
        declared = [f.name for f in dataclasses.fields(env.model.params)]
        for name in (declared[:1] if quick else declared) + ["bogus"]:
            for value in CONTEXT_VALUES:
                for how, maker in (("make", make), ("make_vec", make_vector)):
                    yield Case(env_id, f"{how} randomize={{{name!r}: {value!r}}}", ("randomize", name),
                               lambda m=maker, n=name, v=value: m(env_id, randomize={n: v}).reset(seed=0))
            for value in PARAM_VALUES:
                yield Case(env_id, f"reset params {name}={value!r}", ("params", name),
                           lambda n=name, v=value: unchanged_after_failed_reset(env_id, {n: v}))
                yield Case(env_id, f"vector reset params {name}={value!r}", ("params", name),
                           lambda n=name, v=value: make_vector(env_id).reset(seed=0, options={"params": {n: v}}))
        for value in (5, "g", [("g", 1.0)]):
            yield Case(env_id, f"reset params={value!r}", ("params", "options['params']"),
                       lambda v=value: unchanged_after_failed_reset(env_id, v))
        for value in ("yes", 2, None):
            yield Case(env_id, f"make observe_params={value!r}", ("observe_params",),
                       lambda v=value: make(env_id, observe_params=v).reset(seed=0))


def unchanged_after_failed_reset(env_id, params):
    """A reset with these params, after a first one; if it raises, the env must step as a copy taken before it
    (else an AssertionError, which the audit reports as open)."""
    env = make(env_id)
    env.reset(seed=0)
    before = copy.deepcopy(env)
    try:
        return env.reset(seed=1, options={"params": params})
    except (ValueError, TypeError):
        action = np.zeros(env.action_space.shape, env.action_space.dtype)
        env.step(action), before.step(action)
        mine, theirs = env.unwrapped, before.unwrapped
        assert np.array_equal(mine.model.pack(mine.state), theirs.model.pack(theirs.state), equal_nan=True), (
            "a failed reset changed the env")
        raise


GENERATORS: list[Callable[[Iterable[str], bool], Iterable[Case]]] = [
    make_kwarg_cases,
    stepper_cases,
    reset_cases,
    action_cases,
    model_cases,
    geometry_cases,
    context_cases,
]
"""The case generators the audit runs, in order: append one to add cases."""


# -- the command line -------------------------------------------------------------------------------------------


def audit(ids, quick=False, timeout=TIMEOUT, report=None, generators=None):
    """Judge every case of every generator (or of those named): [(case, verdict)]; report(case, verdict, count)
    after each."""
    verdicts = []
    for generator in GENERATORS if generators is None else [g for g in GENERATORS if g.__name__ in generators]:
        for case in generator(ids, quick):
            verdicts.append((case, judge(case, timeout)))
            if report is not None:
                report(*verdicts[-1], len(verdicts))
    return verdicts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], prog="python tests/audit.py")
    parser.add_argument("--ids", nargs="+", default=IDS, help="the ids to audit (default: every registered one)")
    parser.add_argument("--quick", action="store_true", help="every tenth power of ten only")
    parser.add_argument("--cases", nargs="+", choices=[g.__name__ for g in GENERATORS],
                        help="the generators to run (default: all)")
    parser.add_argument("--show", type=int, default=200, help="open cases listed at most (default 200)")
    args = parser.parse_args(argv)
    unknown = set(args.ids) - set(IDS)
    if unknown:
        parser.error(f"unknown id(s) {sorted(unknown)}; registered: {IDS}")
    start, shown = time.perf_counter(), []

    def report(case, verdict, count):
        if verdict.kind == "ran" and float(verdict.detail.split()[0]) > SLOW:
            print(f"SLOW {case.where}: {case.what[:160]}\n     {verdict.detail}", flush=True)
        if verdict.kind == "open" and len(shown) < args.show:
            shown.append(case)
            print(f"OPEN {case.where}: {case.what[:160]}\n     {verdict.detail}", flush=True)
        if count % 1000 == 0:
            print(f"{count} cases, {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)

    verdicts = audit(args.ids, args.quick, report=report, generators=args.cases)
    totals = Counter(verdict.kind for _, verdict in verdicts)
    by_where = Counter(case.where for case, verdict in verdicts if verdict.kind == "open")
    for where, count in sorted(by_where.items()):
        print(f"open in {where}: {count}")
    print(f"cases: {len(verdicts)}, clear errors: {totals['error']}, accepted and ran finite: {totals['ran']}, "
          f"open: {totals['open']} ({time.perf_counter() - start:.0f} s)")
    return 1 if totals["open"] else 0


if __name__ == "__main__":
    sys.exit(main())
