"""The operations the physics is written against, so that each formula is written once for one state and for rows.

A system's function that runs on both takes its numbers as components along the last axis (``components``: a
Python float each for one state, an array over the rows for a batch) and ``ops``, the namespace of the operations
on them:

- ``FLOATS``: Python's math, for one state. numpy's per-call overhead on one state's few numbers costs several times
  the arithmetic, and the single env steps one state.
- ``ARRAYS``, numpy for arrays over rows (the vector env). numpy ≥ 2's main namespace follows the Array API
  standard, and the names here are the standard's (``atan2``, ``acos``, ``copysign``, ``maximum``, ``where``,
  ``round``, ``any``, ``isnan``), so an Array API namespace of another library (array_api_compat's torch or
  jax.numpy) fits the same slot.

``FLOATS`` gives those names their meaning on floats. ``ARRAYS`` is numpy's, but for the functions that are not
complex-analytic (atan2, hypot, maximum, …): on complex rows, those of the model's complex-step Jacobians
(`connenv.core.model`), each returns its value at the real parts, exactly as on real rows, with the imaginary part
carried by its derivative there (the one-sided one at a kink), so that Im f(x + ih)/h is f′(x). The task
namespaces SCALAR and BATCH (below; ``connenv.envs.base`` writes tasks on them) are these with the task's operations
added, and serve the systems' functions as well. Special functions outside the standard (scipy.special's Jacobi
elliptic functions) are chosen by the system beside ``ops``, or taken from the namespace where it has them (JAX's).
"""

from __future__ import annotations

import math
from types import ModuleType

import numpy as np


def operations(name: str, **functions) -> ModuleType:
    """A namespace of operations, held as a module object, as numpy's and math's are: the interpreter specializes a
    call through a module's attribute, and not one through a SimpleNamespace's (which then looks the name up in the
    type and in the instance's dict on every call, in physics called many times a step)."""
    namespace = ModuleType(name)
    vars(namespace).update(functions)
    return namespace


FLOATS = operations(
    "FLOATS",
    sin=math.sin,
    cos=math.cos,
    atan2=math.atan2,
    sqrt=math.sqrt,
    log=math.log,
    acos=math.acos,
    hypot=math.hypot,
    abs=abs,
    copysign=math.copysign,
    isnan=math.isnan,
    maximum=max,
    minimum=min,
    where=lambda condition, a, b: a if condition else b,
    round=round,  # half to even, as the standard's (an int on a float: exact in the arithmetic that follows)
    any=bool,
)
"""The Array API names used by connenv's physics, on Python floats."""

NAMES = tuple(name for name in vars(FLOATS) if not name.startswith("__"))  # a module's own: __name__, …


def is_complex(a) -> bool:
    """Whether a holds complex numbers (a Jacobian's rows), told by the dtype of an array or the type of a number:
    cheaper than np.iscomplexobj on the real rows and floats every step passes."""
    if type(a) is np.ndarray:
        return a.dtype.kind == "c"
    return not isinstance(a, (float, int)) and np.iscomplexobj(a)


def complex_step(real_function, derivative):
    """real_function on real arrays; on complex ones (x + ih), its value at the real parts plus i times the
    directional derivative ``derivative(real parts, imaginary parts)``."""

    def function(*args):
        if not any(map(is_complex, args)):
            return real_function(*args)
        re, im = [np.real(a) for a in args], [np.imag(a) for a in args]
        return real_function(*re) + 1j * derivative(re, im)

    function.__name__ = real_function.__name__
    return function


def selected(choose):
    """maximum or minimum over complex rows: the argument whose real part choose(a, b) picks, imaginary part and all
    (a NaN propagating, as in numpy's). Where the real parts tie, the one whose imaginary part choose picks: the
    derivative along the step's direction (+ih), which at a kink of max or min is the larger or the smaller of the
    two (a ramp toward a command u meets: its stop is the command, its length |u_cmd − u|/speed grows)."""

    def function(a, b):
        if not (is_complex(a) or is_complex(b)):
            return choose(a, b)
        re_a, re_b, im_a = np.real(a), np.real(b), np.imag(a)
        first = np.where(re_a == re_b, choose(im_a, np.imag(b)) == im_a, choose(re_a, re_b) == re_a)
        return np.where(first | np.isnan(re_a), a, b)

    function.__name__ = choose.__name__
    return function


def quotient(numerator, denominator):
    """numerator / denominator, 0 where the denominator is 0: the derivative taken at the origin of atan2 and
    hypot, where they have none (a cone's apex), is 0, which the branch the real parts take there keeps finite."""
    numerator, denominator = np.broadcast_arrays(numerator, denominator)
    return np.divide(numerator, denominator, out=np.zeros(numerator.shape), where=denominator != 0.0)


def _copysign(a, b):
    """|a| with b's sign: a itself, or −a, whole, by the signs of the real parts."""
    if not (is_complex(a) or is_complex(b)):
        return np.copysign(a, b)
    return np.where(np.signbit(np.real(a)) == np.signbit(np.real(b)), a, -a)


ARRAYS = operations(
    "ARRAYS",
    **{name: getattr(np, name) for name in NAMES},
)
vars(ARRAYS).update(
    atan2=complex_step(np.atan2, lambda re, im: quotient(re[1] * im[0] - re[0] * im[1], re[0] ** 2 + re[1] ** 2)),
    hypot=complex_step(np.hypot, lambda re, im: quotient(re[0] * im[0] + re[1] * im[1], np.hypot(re[0], re[1]))),
    copysign=_copysign,
    maximum=selected(np.maximum),
    minimum=selected(np.minimum),
    round=complex_step(np.round, lambda re, im: 0.0 * re[0]),
    isnan=lambda x: np.isnan(np.real(x)),
    abs=complex_step(np.abs, lambda re, im: np.sign(re[0]) * im[0]),
    stack=np.stack,
    zeros_like=np.zeros_like,
    real_part=np.real,
    all=np.all,
    sort=np.sort,
    maximum_one_sided=selected(np.maximum),
    minimum_one_sided=selected(np.minimum),
    concatenate=np.concatenate,
    full=np.full,
    ceil=np.ceil,
    broadcast_arrays=np.broadcast_arrays,
    broadcast_to=np.broadcast_to,
    sinh=np.sinh,
    cosh=np.cosh,
    traced=False,
)
"""numpy under the Array API names of FLOATS, safe on the complex rows of a complex-step Jacobian (see the module)."""


def floats(a) -> np.ndarray:
    """a as an array of floats, or of complex numbers on the complex rows of a Jacobian (which a cast to float would
    strip of their derivatives). A JAX array stays one (float64, as numpy's: a float32 one is cast), as the traced
    rows need it."""
    if type(a) is not np.ndarray and traced(namespace(a)):
        return a if a.dtype.char == "d" else a.astype(float)
    a = np.asarray(a)
    if a.dtype.char in "dD":  # float64 or complex128 already: no conversion (the common case, kept cheap)
        return a
    return a.astype(complex if a.dtype.kind == "c" else float)


def namespace(x):
    """The operations for x, as array_api_compat's array_namespace asks an array for its own: FLOATS for a Python
    float (one state), ARRAYS for numpy's arrays over rows, and ``connenv.jax.namespace.JAX`` for a JAX array or
    tracer (imported only then: ``import connenv`` does not import jax)."""
    if isinstance(x, float):
        return FLOATS
    if type(x) is np.ndarray or "jax" not in type(x).__module__:
        return ARRAYS
    if "jax" not in ANSWERED:
        raise TypeError(f"connenv's physics on a JAX array ({type(x).__name__}) needs connenv.jax imported, which "
                        "adds its namespace")
    return ANSWERED["jax"]


ANSWERED: dict = {}
"""The namespaces of other array libraries, by name, added by the package that runs the physics on them
(``connenv.jax`` adds "jax"), so that this module imports none of them."""


def traced(ops) -> bool:
    """Whether ops is a tracing namespace (JAX's), which computes every branch and reports failures as data."""
    return getattr(ops, "traced", False)


def is_traced(x) -> bool:
    """Whether x is a JAX array or tracer (a physical parameter traced by ``connenv.jax``), told without importing
    jax: a number, numpy's array or None is not."""
    return not isinstance(x, (float, int, np.ndarray, type(None))) and "jax" in type(x).__module__


def vector(*entries):
    """One state's entries as an array: numpy's float64 array, or JAX's stack where an entry is traced (a reset traced
    by ``connenv.jax``)."""
    for entry in entries:
        if not isinstance(entry, float) and traced(ops := namespace(entry)):
            return ops.stack(entries).astype(float)
    return np.array(entries, float)


def concat(parts, axis: int = -1):
    """np.concatenate of arrays, or the namespace's where a part is traced (``connenv.jax``)."""
    for part in parts:
        if type(part) is not np.ndarray and traced(namespace(part)):
            return namespace(part).concat(parts, axis=axis)
    return np.concatenate(parts, axis=axis)


def components(a):
    """The components along the last axis: Python floats of one state (a 1-D array), arrays over the rows of a
    batch."""
    try:
        one = a.ndim == 1
    except AttributeError:  # a sequence: its array (an array goes without a call, as this is called often)
        a = np.asarray(a, float)
        one = a.ndim == 1
    return a.tolist() if one else [a[..., i] for i in range(a.shape[-1])]


def _clip(x, low, high):
    """x clipped to [low, high], on Python floats; a traced number (connenv.jax's traced parameters, in the state
    an env's constructor builds of them) by its own namespace."""
    try:
        return min(max(x, low), high)
    except TypeError:  # JAX's concretization errors are TypeErrors; a float never raises here
        ops = namespace(x)
        return ops.minimum(ops.maximum(x, low), high)


def _real(x):
    """float(x); a traced number (as in `_clip`) as it is."""
    try:
        return float(x)
    except TypeError:
        if is_traced(x):
            return x
        raise


SCALAR = operations(
    "SCALAR",
    **{name: getattr(FLOATS, name) for name in NAMES},
    clip=_clip,
    column=lambda x: x,
    pack=lambda parts: np.array(parts, np.float32),
    real=_real,
    flag=bool,
    vector=lambda a: tuple(np.asarray(a, float).tolist()),
    components=lambda a: a.tolist(),
    traced=False,  # read on the single env's path (a task's traced(ops)): an attribute, not getattr's miss
)
"""Operations on one state, as Python floats (the single env's): the physics' (``connenv.core.backend.FLOATS``)
and the task's. Several times faster than numpy on one state."""

BATCH = operations(
    "BATCH",
    **{name: value for name, value in vars(ARRAYS).items() if not name.startswith("__")},  # physics' and rows' names
    clip=lambda x, low, high: ARRAYS.minimum(ARRAYS.maximum(x, low), high),
    column=lambda x: x[..., None],
    pack=lambda parts: np.stack(np.broadcast_arrays(*parts), axis=-1).astype(np.float32),
    real=lambda x: np.asarray(x, np.result_type(x, np.float64)),  # float64, or complex on a Jacobian's rows
    flag=lambda x: np.asarray(np.real(x), bool),
    vector=lambda a: BATCH.real(np.array(a)),
    components=lambda a: [a[..., i] for i in range(a.shape[-1])],
)
"""The same operations on arrays over a batch (the vector env's): numpy's under FLOATS' Array API names (``ARRAYS``,
safe on the complex rows of the model's Jacobians), and the task's. ``components`` splits the last axis: Python floats
of one state, arrays over the rows of a batch."""
