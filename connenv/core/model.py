"""The model behind an env: its step as a pure function of a flat state vector, with exact Jacobians, for
planners, system identification and learned models. ``env.unwrapped.model`` is one (`Model`).

The state vector x is the env's task state (``env.unwrapped.state``, a `connenv.envs.base.State`) flattened: its
fields in the dataclass's order, every entry a float64 (a flag as 0 or 1, a counter as its count), named by
``model.state_names``. It holds everything the step reads: the coordinates and momenta, the assigned coordinates,
the time, and the task's own state (a target, the side the episode started on, a hold counter), so that the next
state is a function of x and the action alone. It is more than ``info["state"]``, which reports the physical
coordinates in SI, and is read back from x by ``model.info(x)``.

``model.step`` runs the env's own ``advance``: on one state (x of shape (n,)) the single env's path on Python
floats, on rows ((N, n)) the native vector env's on numpy arrays. From the same state and action it gives the next
state of ``env.step`` (single) and of the vector env's step (rows) to the bit.

Jacobians are by complex step (Squire & Trapp, SIAM Rev. 1998; Martins, Sturdza & Alonso, ACM TOMS 2003): an input
entry moved by i·h (h = 1e-150) through the rows' path gives Im(x_next)/h, its column, exact to rounding since no
difference cancels. h lies far below any entry a state holds: an entry near 0 (a segment a planner's action makes
1e-45 s long) keeps the step analytic within i·h of it, which h = 1e-20, common elsewhere, would not. It
differentiates the step's own arithmetic: substeps, closed-form flows, projections and all.
Where the step is not differentiable (a clip, an end stop, a switching surface), the branch the real part takes
is followed, which is the one-sided derivative; a flag or counter does not move under a small change, so its
column and row are 0, and so is the column of an action entry the action space clips. An entry the env rounds to
float32 (a goal env's goals) is differentiated through the rounding, whose derivative is 1.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping, Sequence
from types import SimpleNamespace

import numpy as np
from gymnasium.vector.utils import batch_space

from connenv.core.backend import BATCH, SCALAR
from connenv.core.batched import batched
from connenv.core.context import is_real, physical_params
from connenv.core.steppers import StepperError
from connenv.core.validation import check_mapping, dtype_kind, real_array

STEP = 1e-150  # far below any entry a state holds (a step's series converges within |entry|), far above 1e-308
CACHED_MODELS = 64  # models of other parameter values kept by with_params


@dataclasses.dataclass(frozen=True)
class Entry:
    """A field of the task state in x: its name, shape, where it lies (offset), how the single env holds it
    (``container``: ndarray, tuple, list or a number type) and its dtype (float32 where the env rounds to it: a goal
    env's goals)."""

    name: str
    shape: tuple[int, ...]
    offset: int
    container: type
    dtype: np.dtype

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    @property
    def columns(self) -> slice:
        return slice(self.offset, self.offset + self.size)

    @property
    def real(self) -> bool:
        """Whether the entry is a real number that moves continuously (not a flag or a counter)."""
        return self.dtype.kind == "f"

    def names(self, components: dict) -> list[str]:
        """The entries' names: the field's own, its components' (``State.components``), or name[i, …]."""
        if not self.shape:
            return [self.name]
        if len(components.get(self.name, ())) == self.size:
            return list(components[self.name])
        return [f"{self.name}[{','.join(map(str, i))}]" for i in np.ndindex(*self.shape)]

    def single(self, x: np.ndarray):
        """The entry of one state, as the single env holds it."""
        values = x[self.columns]
        if self.container is np.ndarray:
            return values.reshape(self.shape).astype(self.dtype)
        if self.container in (tuple, list):
            return self.container(values.tolist())
        return self.container(values[0])

    def rows(self, x: np.ndarray) -> np.ndarray:
        """The entry over rows x (N, n), as the vector env holds it: complex rows stay complex."""
        values = x[:, self.columns].reshape(len(x), *self.shape)
        return values if self.real and np.iscomplexobj(values) else values.real.astype(self.dtype)


def layout(state) -> list[Entry]:
    """The entries of a task state, in the order of its fields."""
    entries, offset = [], 0
    for name, value in state.fields().items():
        array = np.asarray(value)
        container = type(value)
        if isinstance(value, (np.floating, np.integer, np.bool_)):  # a numpy scalar: the Python number it stands for
            container = {"f": float, "i": int, "u": int, "b": bool}[array.dtype.kind]
        entries.append(Entry(name, array.shape, offset, container, array.dtype))
        offset += array.size
    return entries


def flatten(fields: dict, entries: list[Entry]) -> np.ndarray:
    """The entries of a task state's fields in one float64 vector (n,), or rows (N, n) where the time is one per
    row (complex on a Jacobian's rows)."""
    values = [fields[e.name] for e in entries]
    if np.ndim(fields["t"]) == 1:
        rows = [np.asarray(v).reshape(len(v), -1) for v in values]
        return np.concatenate(rows, axis=1).astype(np.result_type(float, *rows))
    return np.concatenate([np.asarray(v, float).ravel() for v in values])


def params_type(env) -> type:
    """A frozen dataclass of the env's physical parameters (its ARGS' numbers marked physical), named after it."""
    declared = list(physical_params(env).values())
    rows = "\n".join(f"    {p.row()}" for p in declared)
    fields = tuple((p.name, p.optional) for p in declared)
    return params_class(type(env).__name__.removesuffix("Env") + "Params", fields,
                        f"The physical parameters of {env.name}: name, default, valid range and unit.\n\n{rows}")


PARAMS_TYPES: dict[tuple, type] = {}  # one class per name and fields, so that pickle's copy is an instance of it


def params_class(name: str, fields: tuple[tuple[str, bool], ...], doc: str = "") -> type:
    """The frozen dataclass ``name`` of the fields (name, optional), made once. It pickles by value (`params_of`):
    the class is made at run time, so a process that unpickles it finds it by its name and fields, not by import."""
    key = (name, fields)
    if key not in PARAMS_TYPES:
        declared = [(field, float | None if optional else float) for field, optional in fields]
        cls = dataclasses.make_dataclass(name, declared, frozen=True)
        cls.__module__ = __name__
        cls.__doc__ = doc
        cls.__reduce__ = lambda self: (params_of, (name, fields, dataclasses.astuple(self)))
        PARAMS_TYPES[key] = cls
    return PARAMS_TYPES[key]


def params_of(name: str, fields: tuple, values: tuple):
    """An instance of `params_class(name, fields)`: how a pickled Params is read back."""
    return params_class(name, fields)(*values)


class Model:
    """The pure step of an env (see the module): ``state_names``, ``params``, ``pack``/``unpack``, ``step``,
    ``jacobians``, ``reward``, ``terminated`` and ``info``, on one state (n,) or rows (N, n).

    Built on a private copy of the env, so that nothing the user's env does later (a reset with other parameters)
    changes it; ``with_params`` gives the model of other parameter values."""

    def __init__(self, env):
        self.env = copy.deepcopy(env)
        self.env.close()
        self.row_stepper = batched(self.env.stepper)
        self.entries = layout(self.env.state)
        self.components = {**getattr(self.env, "components", {}), **type(self.env.state).components}
        self.state_names = tuple(name for entry in self.entries for name in entry.names(self.components))
        self.n = len(self.state_names)
        self.m = int(np.prod(self.env.action_space.shape))
        Params = params_type(self.env)
        self.params = Params(**{f.name: getattr(self.env.args, f.name) for f in dataclasses.fields(Params)})
        self._models = {self.key(self.params): self}
        unmeasured = type(self.env.state).unmeasured
        self.nan_allowed = np.array([e.name in unmeasured for e in self.entries for _ in range(e.size)])

    def __repr__(self):
        return f"Model({self.env.name}, n={self.n}, m={self.m}, {self.params})"

    # -- state vector ----------------------------------------------------------

    def pack(self, state) -> np.ndarray:
        """x of a task state (a State, or a dict of its fields as ``unpack`` gives): (n,) for one state, (N, n)
        for rows (the vector env's ``state``)."""
        names = [e.name for e in self.entries]
        if isinstance(state, type(self.env.state)):
            fields = state.fields()
        elif isinstance(state, dict):
            fields = state
        else:
            raise TypeError(f"state={state!r} must be a {type(self.env.state).__name__} of {self.env.name} or a dict "
                            f"of its fields {names}")
        if set(fields) != set(names):
            raise ValueError(f"state has the fields {sorted(fields)}; expected those of {self.env.name}'s "
                             f"{type(self.env.state).__name__}: {names}")
        try:
            return flatten(fields, self.entries)
        except (TypeError, ValueError) as error:
            raise ValueError(f"state fields of {self.env.name} must be numbers or arrays of them, one shape per "
                             f"field (as unpack gives them): {error}") from error

    def unpack(self, x) -> dict:
        """The task state's fields of x: as the single env holds them for (n,), arrays over rows for (N, n)."""
        return self._unpack(self._check_state(x))

    def state(self, x):
        """The env's State of x (one state or rows)."""
        return self._state(self._check_state(x))

    def info(self, x) -> dict:
        """The env's info at x (``info["state"]`` among it): one state, or rows as the vector env reports them."""
        x = self._check_state(x)
        return self.env.describe(self._state(x), SCALAR if x.ndim == 1 else BATCH)

    def _unpack(self, x) -> dict:
        if x.ndim == 1:
            return {e.name: e.single(x) for e in self.entries}
        return {e.name: e.rows(x) for e in self.entries}

    def _state(self, x):
        """The State of x, checked before (or a Jacobian's complex rows)."""
        return type(self.env.state)(**self._unpack(x))

    # -- dynamics --------------------------------------------------------------

    def step(self, x, a, params=None) -> np.ndarray:
        """x_next: the env's step from x under action a (the policy's units, clipped as the env clips it); x (n,)
        with a of the action space's shape, or rows (N, n) with a (N, *shape). ``params``: a dict (or Params) of
        parameter values for all rows (the model ``with_params(params)``), or a sequence of them, one per row: such
        rows step as the vector env steps rows whose parameters are their own (``randomize``, or a reset's
        "params"), each on the single env's path with its own values, to the bit.

        Bad input is refused before the step (ValueError or TypeError naming it): x, a or params that are not real
        numbers (complex ones too) or not finite (NaN only in a task's "not measured" entry, ``State.unmeasured``),
        of another shape, an empty batch (N = 0), a flag or counter that is not a whole number. A step that the
        stepper cannot take (it diverges, or overflows) raises `StepperError`, one state or rows."""
        if params is not None and not (isinstance(params, Mapping) or dataclasses.is_dataclass(params)):
            return self._step_rows_of_their_own(params, x, a)
        if params is not None:
            return self.with_params(params).step(x, a)
        x = self._check_state(x)
        if x.ndim == 1:
            command = self.env.command(self.env.check_action(self._check_action(a, None)))
            x_next = self.pack(self._advance(self._state(x), command, self.env.stepper, SCALAR, x))
        else:
            command = self.env.command(self._check_actions(self._check_action(a, len(x)), len(x)))
            x_next = self.pack(self._advance(self._state(x), command, self.row_stepper, BATCH, x))
        lost = ~np.isfinite(x_next) & ~(np.isnan(x_next) & np.isnan(x))
        if lost.any():  # a state far outside the env's (an attitude of 1e300) that the step's checks do not see
            j = int(np.argwhere(lost)[0][-1])
            raise self.env._stepper_error(StepperError(
                f"the step from a finite x gave {self.state_names[j]} = {float(x_next[..., j].ravel()[0])!r}"),
                float(np.min(x[..., self.t_column])))
        return x_next

    def jacobians(self, x, a, params=None) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) = (∂x_next/∂x, ∂x_next/∂a) at (x, a), by complex step (see the module): (n, n) and (n, m) for one
        state, (N, n, n) and (N, n, m) for rows. x and a are checked as ``step`` checks them."""
        if params is not None:
            return self._per_params(params, x, a, lambda model, x, a: model.jacobians(x, a), pair=True)
        x = self._check_state(x)
        X = np.atleast_2d(x)
        N = len(X)
        raw = self._check_action(a, None if x.ndim == 1 else N).reshape(N, *self.env.action_space.shape)
        actions = self._check_actions(raw, N).reshape(N, self.m)
        free = actions == raw.reshape(N, self.m)  # entries the space does not clip
        moving = [i for e in self.entries if e.real for i in range(e.columns.start, e.columns.stop)]
        k = len(moving) + self.m
        Xc = np.repeat(X, k, axis=0).astype(complex)
        Ac = np.repeat(actions, k, axis=0).astype(complex)
        rows = np.arange(N * k).reshape(N, k)
        Xc[rows[:, : len(moving)], moving] += 1j * STEP
        Ac[rows[:, len(moving):], np.arange(self.m)] += 1j * STEP
        command = self.env.command(Ac.reshape(N * k, *self.env.action_space.shape))
        after = self.pack(self._advance(self._state(Xc), command, self.row_stepper, BATCH, Xc))
        D = (np.asarray(after).imag / STEP).reshape(N, k, self.n).transpose(0, 2, 1)
        A = np.zeros((N, self.n, self.n))
        A[:, :, moving] = D[:, :, : len(moving)]
        B = D[:, :, len(moving):] * free[:, None, :]
        real = np.array([e.real for e in self.entries for _ in range(e.size)])
        A[:, ~real], B[:, ~real] = 0.0, 0.0
        return (A[0], B[0]) if x.ndim == 1 else (A, B)

    # -- task ------------------------------------------------------------------

    def reward(self, x, a, x_next):
        """The env's reward of the step from x to x_next. ``a`` completes a planner's signature: the rewards read the
        states alone (x_next holds what the action did)."""
        x, x_next = self._check_state(x), self._check_state(x_next, "x_next")
        if x.shape != x_next.shape:
            raise ValueError(f"state x of shape {x.shape} and state x_next of shape {x_next.shape}: expected one "
                             "state each, or the same number of rows")
        ops = SCALAR if x.ndim == 1 else BATCH
        after = self._state(x_next)
        return self.env.reward(self._state(x), after, self.env.describe(after, ops), ops)

    def terminated(self, x):
        """Whether the task ends the episode at x (success, or a failure the task ends on)."""
        x = self._check_state(x)
        ops = SCALAR if x.ndim == 1 else BATCH
        s = self._state(x)
        return self.env.terminated(s, self.env.describe(s, ops), ops)

    # -- parameters ------------------------------------------------------------

    def with_params(self, params) -> Model:
        """The model of the same env with other parameter values (a dict or Params; unnamed ones kept), each a real
        number (None where the parameter is optional) in the range the env's make takes (ValueError naming one that
        is not)."""
        known = {f.name: f for f in dataclasses.fields(self.params)}
        if dataclasses.is_dataclass(params) and not isinstance(params, type):
            given = dataclasses.asdict(params)
        elif isinstance(params, Mapping):
            given = dict(params)
        else:
            raise TypeError(f"params={params!r} must be a dict of parameter values (or a Params) of {self.env.name}; "
                            f"its parameters: {list(known)}")
        check_mapping("params", given)
        unknown = [name for name in given if name not in known]
        if unknown:
            raise ValueError(f"params {unknown} are not physical parameters of {self.env.name}; known: {list(known)}")
        declared = physical_params(self.env)
        for name, value in given.items():
            if value is None and declared[name].optional:
                continue
            if not (is_real(value) and math.isfinite(value)):
                none = " (or None)" if declared[name].optional else ""
                raise ValueError(f"params: {name}={value!r} must be a real number in {declared[name].span()}{none}")
        values = {**dataclasses.asdict(self.params), **given}
        key = self.key(values)
        if key not in self._models:
            env = type(self.env)(**{**self.env.kwargs, **values})
            env.state = self.env.state
            model = Model(env)
            model._models = self._models
            if len(self._models) >= CACHED_MODELS:  # a fit tries many values: keep the latest
                del self._models[next(k for k in self._models if self._models[k] is not self)]
            self._models[key] = model
        return self._models[key]

    @staticmethod
    def key(params) -> tuple:
        values = dataclasses.asdict(params) if dataclasses.is_dataclass(params) else params
        return tuple(sorted(values.items()))

    def _per_params(self, params, x, a, function, pair=False):
        """function(model, x, a) with the model of params: one set for all, or grouped by row where they differ."""
        if isinstance(params, Mapping) or dataclasses.is_dataclass(params):
            return function(self.with_params(params), x, a)
        x, a, models = self._rows_of(params, x, a)
        groups = {}
        for i, model in enumerate(models):
            groups.setdefault(id(model), (model, []))[1].append(i)
        out = None
        for model, rows in groups.values():
            result = function(model, x[rows], a[rows])
            parts = result if pair else (result,)
            if out is None:
                out = tuple(np.empty((len(x), *p.shape[1:]), p.dtype) for p in parts)
            for o, p in zip(out, parts):
                o[rows] = p
        return out if pair else out[0]

    def _rows_of(self, params, x, a) -> tuple[np.ndarray, np.ndarray, list[Model]]:
        """(x, a, the model of each row's params) of per-row params, checked."""
        if isinstance(params, (str, bytes)) or not isinstance(params, Sequence):
            raise TypeError(f"params={params!r} must be a dict of parameter values (or a Params) for all rows, or a "
                            "sequence of them, one per row")
        x = self._check_state(x)
        if x.ndim != 2 or len(params) != len(x):
            raise ValueError(f"per-row params ({len(params)} of them) need rows x of shape (N, {self.n}) with N "
                             f"equal to it; x has shape {x.shape}")
        a = self._check_action(a, len(x))
        return x, a, [self.with_params(p) for p in params]

    def _step_rows_of_their_own(self, params, x, a) -> np.ndarray:
        """Rows with their own params stepped as the vector env steps them (`connenv.envs.vector`): the actions
        checked over the batch, then each row on the single env's path by the model of its params."""
        x, a, models = self._rows_of(params, x, a)
        actions = self._check_actions(a, len(x))
        rows = []
        for model, row, action in zip(models, x, actions):
            command = model.env.command(action)
            rows.append(model.pack(model._advance(model._state(row), command, model.env.stepper, SCALAR, row)))
        return np.stack(rows)

    # -- checks ----------------------------------------------------------------

    def _advance(self, state, command, stepper, ops, x):
        """The env's advance; an overflow, which Python floats raise (OverflowError) and numpy's rows are made to
        raise here (FloatingPointError, not a warning and inf), is a StepperError as a diverged step is."""
        try:
            with np.errstate(over="raise"):
                return self.env.advance(state, command, stepper, ops)
        except StepperError as error:
            raise self.env._stepper_error(error, float(np.min(np.real(x[..., self.t_column])))) from error
        except (OverflowError, FloatingPointError, ZeroDivisionError) as error:  # a state far outside the env's
            raise self.env._stepper_error(StepperError(f"the step overflowed ({error})"),
                                          float(np.min(np.real(x[..., self.t_column])))) from error

    @property
    def t_column(self) -> int:
        return next(e.offset for e in self.entries if e.name == "t")

    def _check_state(self, x, name="x") -> np.ndarray:
        """x as float64, (n,) or (N ≥ 1, n): real, finite (NaN only in an unmeasured entry), its flags 0 or 1 and
        its counters whole; else ValueError naming the entry."""
        expected = (f"real numbers of shape ({self.n},) or (N ≥ 1, {self.n}), the entries {self.state_names} of "
                    f"{self.env.name}")
        if not isinstance(x, np.ndarray) and dtype_kind(x) not in "iuf":
            x = real_array(f"state {name}", x, expected)  # names the value (a complex number, a string, None)
        if not (isinstance(x, np.ndarray) and x.dtype.kind in "iuf" and x.ndim in (1, 2) and x.shape[-1] == self.n
                and x.size):
            kind = dtype_kind(x)
            what = "complex" if kind == "c" else f"of shape {np.shape(x)}, dtype {np.asarray(x).dtype}"
            raise ValueError(f"state {name} {what}: expected {expected}")
        x = np.asarray(x, np.float64)
        bad = ~np.isfinite(x) & ~(np.isnan(x) & self.nan_allowed)
        if bad.any():
            self._refuse(name, x, bad, "is not finite: every entry must be finite" + (
                f" (NaN allowed only in {[n for n, ok in zip(self.state_names, self.nan_allowed) if ok]})"
                if self.nan_allowed.any() else ""))
        for e in self.entries:
            if e.dtype != np.float64:  # a float32 copy (a goal), a counter or a flag: a value its type holds
                top = float(np.finfo(e.dtype).max if e.real else np.iinfo(np.int64).max)
                values = x[..., e.columns]
                if (np.abs(values) > top).any():
                    columns = np.zeros(x.shape, bool)
                    columns[..., e.columns] = np.abs(values) > top
                    self._refuse(name, x, columns, f"does not fit its {e.dtype} (|value| ≤ {top:.6g})")
            if e.real:
                continue
            values = x[..., e.columns]
            wrong = values != np.round(values) if e.dtype.kind != "b" else (values != 0) & (values != 1)
            if wrong.any():
                columns = np.zeros(x.shape, bool)
                columns[..., e.columns] = wrong
                self._refuse(name, x, columns, "must be 0 or 1 (a flag)" if e.dtype.kind == "b" else
                             "must be a whole number (a counter)")
        return x

    def _refuse(self, name, x, bad, why):
        """ValueError naming the first bad entry of x (by its state name, and its row)."""
        index = np.argwhere(bad)[0]
        j = int(index[-1])
        row = f" (row {int(index[0])})" if x.ndim == 2 else ""
        raise ValueError(f"state {name}[{j}] ({self.state_names[j]}) = {float(x[tuple(index)])!r}{row} {why}, "
                         f"on {self.env.name}")

    def _check_action(self, a, N) -> np.ndarray:
        """a as float64 of the action space's shape (N None: one state) or (N, *shape): real numbers, else
        ValueError naming it (finiteness and the clip are the env's check, after this)."""
        shape = self.env.action_space.shape if N is None else (N, *self.env.action_space.shape)
        expected = f"real numbers of shape {shape}, the action space's {self.env.action_space}"
        kind = dtype_kind(a)
        if kind == "c":
            raise ValueError(f"action a={a!r} is complex; expected {expected}")
        if kind not in "iuf":
            raise ValueError(f"action a={a!r} must be {expected}")
        a = np.asarray(a, np.float64)
        if a.shape != shape:
            raise ValueError(f"action a has shape {a.shape}; expected {expected}")
        if not np.isfinite(a).all():
            raise ValueError(f"action a={a!r} is not finite; expected {expected}")
        return a

    def _check_actions(self, a, N) -> np.ndarray:
        """Rows of actions checked (and clipped) as the vector env checks them."""
        space = SimpleNamespace(action_space=batch_space(self.env.action_space, N))
        return type(self.env).check_action(space, np.asarray(a))
