"""Checks at the boundary: every bad input names the parameter, its value and the valid range."""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping

import numpy as np

from connenv.core.backend import is_traced
from connenv.core.steppers import SMALL, STEPPER_OPTIONS


def check_number(
    name: str,
    value,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    open_low=False,
    open_high=False,
    low_name: str | None = None,
    high_name: str | None = None,
):
    """Return value as a float if it is a finite real in the interval, else raise ValueError; low_name and
    high_name name the parameters that set a bound, if any."""
    ends = [low if low_name is None else f"{low_name}={low}", high if high_name is None else f"{high_name}={high}"]
    interval = f"{'(' if open_low else '['}{ends[0]}, {ends[1]}{')' if open_high else ']'}"
    if is_traced(value):  # a physical parameter connenv.jax traces: checked where it is drawn, not here
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name}={value!r} must be a real number in {interval}")
    value = float(value)
    below = value <= low if open_low else value < low
    above = value >= high if open_high else value > high
    if not math.isfinite(value) or below or above:
        raise ValueError(f"{name}={value!r} is out of range: must be finite and in {interval}")
    return value


SCALE_SPAN = 1e6  # a physical scale may lie within this factor of its default, either way


def check_scale(name: str, value, default: float, high: float = math.inf, *, zero=False, open_high=False,
                high_name: str | None = None) -> float:
    """A physical scale (a length, mass, inertia, density, g, a speed or rate bound, a tolerance), a finite real
    within SCALE_SPAN of its default either way, [default/SCALE_SPAN, default·SCALE_SPAN], and at most high if given
    (below it with open_high; high_name names the parameter that sets it). With zero, the low end is 0 (a scale that
    may vanish: a fluid's density, an offset). The span reaches from a toy to a ship, and keeps the products of a
    few such scales an env forms (energies, momenta, rates, the observation's bounds and the reward) far inside
    float64 and its float32 observation, where the whole positive axis would overflow or divide by zero."""
    low, top = (0.0 if zero else decimal(default / SCALE_SPAN)), decimal(default * SCALE_SPAN)
    if high < top:
        return check_number(name, value, low, high, open_high=open_high, high_name=high_name)
    return check_number(name, value, low, top)


def decimal(x: float) -> float:
    """x rounded to 12 significant digits: a bound as the docstrings write it (0.1/1e6 is 1.0000000000000001e-07 in
    floats, and 1e-7 would be refused)."""
    return float(f"{x:.12g}")


ANGLE_BOUND = 2.0 * math.pi  # |an angle| given at reset: every configuration lies within it
MAGNITUDE_BOUND = 1e3  # |a coordinate or momentum of a user's system| given at reset, or a finite bound of one


def check_angle(name: str, value) -> float:
    """An angle given at reset, rad: a finite real in [−2π, 2π] (every configuration lies within it)."""
    return check_number(name, value, -ANGLE_BOUND, ANGLE_BOUND)


DT_MIN = 1e-12  # s: the shortest control step an env takes (1/dt, the render frame rate, stays finite); the
# physics tests isolate a jump of u with steps of 1e-12 to 1e-9 s


def check_dt(dt, high: float) -> float:
    """The control step dt, s: a finite real in [DT_MIN, high], high the env's measured limit."""
    return check_number("dt", dt, DT_MIN, high)


def check_mapping(name: str, given):
    """Raise ValueError if ``given`` is not a mapping (a dict of named values)."""
    if not isinstance(given, Mapping):
        raise ValueError(f"{name}={given!r} must be a mapping (a dict of named values)")


def check_keys(name: str, given, allowed):
    """Raise ValueError if ``given`` is not a mapping or has keys outside ``allowed``."""
    check_mapping(name, given)
    unknown = set(given) - set(allowed)
    if unknown:
        raise ValueError(f"unknown key(s) {sorted(unknown)} in {name}; valid keys: {sorted(allowed)}")


def init_parameters(env_cls) -> list[str]:
    """The named parameters of env_cls.__init__, and of its bases' where it passes ``**kwargs`` on to them (the
    first ``__init__`` whose ``**`` collects the stepper options ends the chain)."""
    names = []
    for cls in env_cls.__mro__:
        if "__init__" not in vars(cls):
            continue
        params = inspect.signature(cls.__init__).parameters.values()
        names += [p.name for p in params if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL) and p.name != "self"]
        if not any(p.kind is p.VAR_KEYWORD and p.name != "stepper_options" for p in params):
            break
    return list(dict.fromkeys(names))


def check_stepper_options(env_name: str, options, env_cls):
    """Raise ValueError for make kwargs that are neither the env's parameters nor stepper options."""
    unknown = set(options) - set(STEPPER_OPTIONS)
    if unknown:
        params = init_parameters(env_cls)
        valid = params + list(STEPPER_OPTIONS)
        raise ValueError(f"unknown parameter(s) {sorted(unknown)} for {env_name}; valid: {valid}")


def ndim(x) -> int:
    """np.ndim(x), at an attribute's cost for an array or a float (np.ndim's dispatch costs a step's microsecond)."""
    if isinstance(x, float):
        return 0
    return x.ndim if type(x) is np.ndarray else np.ndim(x)


def check_action(action, space):
    """The action as a float array of the space's shape, finite, clipped into the space."""
    return np.minimum(np.maximum(finite_action(action, space), space.low), space.high)


def dtype_kind(value) -> str:
    """numpy's dtype kind of value ("f", "c", "U", ...), "O" for a ragged sequence."""
    try:
        return np.asarray(value).dtype.kind
    except (TypeError, ValueError):
        return "O"


def finite_action(action, space):
    """The action as a float array of the space's shape, finite, else ValueError; not clipped."""
    if type(action) is np.ndarray and action.dtype.kind == "f" and action.shape == space.shape:  # a policy's action
        a = action.astype(np.float64)
        if a.size <= SMALL and all(map(math.isfinite, a.flat)):  # Python floats: cheaper than numpy on a few numbers
            return a
        if a.size > SMALL and np.isfinite(a).all():
            return a
    kind = dtype_kind(action)
    if kind == "c":
        raise ValueError(f"action={action!r} is complex; expected real numbers in [{space.low}, {space.high}]")
    if kind not in "biuf":
        expected = f"real numbers in [{space.low}, {space.high}] of shape {space.shape}"
        raise ValueError(f"action={action!r} must be {expected}")
    a = np.asarray(action, dtype=np.float64)
    if a.shape != space.shape:
        raise ValueError(f"action has shape {a.shape}; expected {space.shape} (action={action!r})")
    if not np.isfinite(a).all():
        raise ValueError(f"action={action!r} is not finite; expected values in [{space.low}, {space.high}]")
    return a


def real_array(name: str, value, expected: str) -> np.ndarray:
    """value as a float64 array if every entry is a real number (an int or a float: a numeric array, or numbers
    nested in sequences), else ValueError naming it and what is ``expected``. numpy's own cast would take a complex
    number's real part (with only a ComplexWarning), a bool as 0 or 1 and a numeric string as its number."""
    if isinstance(value, np.ndarray):
        real, complex_ = value.dtype.kind in "iuf", value.dtype.kind == "c"
    else:
        try:
            entries = np.array(value, dtype=object).ravel().tolist()
        except (TypeError, ValueError):  # a ragged sequence
            entries = [None]
        real = all(isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) for x in entries)
        complex_ = any(isinstance(x, (complex, np.complexfloating)) for x in entries)
    if complex_:
        raise ValueError(f"{name}={value!r} is complex; expected {expected}")
    if not real:
        raise ValueError(f"{name}={value!r} must be {expected}")
    return np.array(value, dtype=np.float64)


def check_vector(name: str, value, size: int, low=-math.inf, high=math.inf, note=""):
    """value as a float array of shape (size,), every entry a finite real within [low, high] (bounds a number or
    one per entry), else ValueError naming it, the entry (followed by ``note``, why its bound is what it is) and the
    range."""
    expected = f"a sequence of {size} finite real numbers"
    vector = real_array(name, value, expected)
    if vector.shape != (size,) or not np.all(np.isfinite(vector)):
        raise ValueError(f"{name}={value!r} must be a sequence of {size} finite real numbers")
    low, high = np.broadcast_to(low, (size,)), np.broadcast_to(high, (size,))
    for i in np.flatnonzero((vector < low) | (vector > high)):
        interval = f"[{float(low[i])}, {float(high[i])}]"
        raise ValueError(f"{name}[{i}]{note}={float(vector[i])!r} is out of range: must be in {interval}")
    return vector


def check_bounds(low_name: str, low, high_name: str, high, size: int | None = None):
    """(low, high) as float arrays of one shape (k,), k ≥ 1 (with size, a number broadcasts to (size,)), low < high
    in every coordinate, finite ones within ±MAGNITUDE_BOUND, ±inf allowed for no bound, NaN not; else ValueError
    naming both as given."""
    given = f"{low_name}={low!r}, {high_name}={high!r}"
    count = "one number per coordinate" if size is None else f"a number or {size} of them"
    expected = f"real numbers, {count}, ±inf for no bound"
    lows, highs = real_array(low_name, low, expected), real_array(high_name, high, expected)
    try:
        if size is not None:
            lows, highs = (np.broadcast_to(v, (size,)).copy() for v in (lows, highs))
    except ValueError as error:
        raise ValueError(f"{given} must be {expected}") from error
    if lows.ndim != 1 or lows.shape != highs.shape or lows.size == 0:
        raise ValueError(f"{given} must have one shape (k,), k ≥ 1")
    if np.isnan(lows).any() or np.isnan(highs).any():
        raise ValueError(f"{given} hold NaN; give numbers (±inf for no bound)")
    if not np.all(lows < highs):
        raise ValueError(f"{low_name}={low!r} must be below {high_name}={high!r} in every coordinate")
    finite = np.concatenate([lows, highs])
    if np.any(np.abs(finite[np.isfinite(finite)]) > MAGNITUDE_BOUND):
        raise ValueError(f"{given}: a finite bound must lie within ±{MAGNITUDE_BOUND} (±inf for no bound)")
    return lows, highs


ORTHONORMAL_TOL = 1e-9  # ‖RᵀR − I‖ and |det R − 1| allowed in a given rotation


def check_rotation(name: str, value) -> np.ndarray:
    """value as a 3×3 rotation matrix (float64), or ValueError: never re-orthonormalized."""
    R = real_array(name, value, "a 3×3 rotation matrix of real numbers")
    if R.shape != (3, 3):
        raise ValueError(f"{name} has shape {np.shape(value)}; expected a 3×3 rotation matrix")
    if not np.isfinite(R).all():
        raise ValueError(f"{name}={R.tolist()} is not finite")
    drift = float(np.linalg.norm(R.T @ R - np.eye(3)))
    det = float(np.linalg.det(R))
    if drift > ORTHONORMAL_TOL or abs(det - 1.0) > ORTHONORMAL_TOL:
        raise ValueError(
            f"{name}={R.tolist()} is not a rotation: ‖RᵀR − I‖ = {drift:.3g}, det R = {det:.12g}; "
            f"both must be within {ORTHONORMAL_TOL} of 0 and 1"
        )
    return R


def check_returned(name: str, value, shape: tuple | None = None, expected: str = "") -> np.ndarray:
    """What a user's function returned, as a float64 array: TypeError unless it is real numbers (None, a string,
    an object), ValueError if it is complex, of another shape than ``shape`` (when given) or not finite. ``name``
    says which function at which arguments, ``expected`` what it must return; both go into the message."""
    kind = dtype_kind(value)
    if kind == "c":
        raise ValueError(f"{name} returned complex values {value!r}; expected {expected or 'real numbers'}")
    if kind not in "biuf":
        raise TypeError(f"{name} returned {value!r}; expected {expected or 'real numbers'}")
    array = np.asarray(value, dtype=float)
    if shape is not None and array.shape != tuple(shape):
        raise ValueError(f"{name} returned shape {array.shape}; expected {expected or f'shape {tuple(shape)}'}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} returned non-finite values {value!r}; expected {expected or 'finite numbers'}")
    return array


def probe(name: str, function, *args):
    """function(*args) for a check at construction, or ValueError naming the function (``name``, with the
    arguments) and what it raised: a user's function that fails on a valid input fails at construction, under its
    own name, not inside a step."""
    try:
        return function(*args)
    except Exception as error:  # any failure of a user's function is reported under its name
        raise ValueError(f"{name} raised {type(error).__name__}: {error}") from error

