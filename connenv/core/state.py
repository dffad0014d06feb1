"""Declared reset state: the keys of an env's ``reset(options={"state": {...}})`` written once, as data, each with
its name, size, unit, valid range and meaning. One declaration, `Fields`, checks the given state (a ValueError
naming the key, its value and its range, as `connenv.core.validation` words it, before anything is set), writes the
table of the docstring's "## Starting State" (`document_state`) and names the keys with their shapes in one fixed
order, the order they are checked in (`names`, `shapes`). The reset options beside "state" (a target) are declared
the same way, as the env's ``OPTIONS``: checked, tabled and named alike.

A field is a number (`number`, `angle`), a vector (`vector`: n entries, n a number or the name of an env attribute),
a rotation matrix (`rotation`) or a key its env checks (`given`: a method of the env). A range is an interval (its
ends ``low`` and ``high``, or ``bound`` for ±bound), an end a number, the name of an env attribute (a_max), or a
`connenv.core.params.Bound` whose value is a function of the env and the values checked before it (|θ̇| ≤ the
observed bound; p bounded through θ̇ at the given θ). ``either`` names alternatives, of which a state gives one at
most (theta_dot or p); where it gives none, the first takes its default.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from connenv.core.params import Bound, End, cells, text, written
from connenv.core.validation import ANGLE_BOUND, check_keys, check_number, check_rotation, check_vector

Size = int | str | tuple  # 0 a number, n a vector of n, a shape, or the name of an env attribute holding one of them


@dataclasses.dataclass(frozen=True)
class Field:
    """One key of the reset state: its name, size, unit, range (see the module) and meaning. ``note``: words after
    an entry's name in its range error, of the env (why its bound is what it is); ``scalar``: a vector of one entry
    may be given as a number; ``check_with``: a given key's checking method of the env (value -> the value);
    ``range_text``: the table's range where the ends do not say it."""

    name: str
    size: Size = 0
    unit: str = ""
    about: str = ""
    kind: str = "number"
    low: End = -math.inf
    high: End = math.inf
    bound: End | None = None
    note: Callable | None = None
    scalar: bool = False
    check_with: str = ""
    range_text: str = ""

    def shape(self, env) -> tuple:
        """() for a number, (n,) for a vector, (3, 3) for a rotation, the env's for a given key."""
        size = getattr(env, self.size) if isinstance(self.size, str) else self.size
        return tuple(size) if isinstance(size, tuple) else (size,) if size else ()

    def default(self, env):
        """The value where the state does not give it and the env passes none: zero, the identity; a given key has
        none (the env's own start)."""
        if self.kind == "given":
            return None
        return np.eye(3) if self.kind == "rotation" else np.zeros(self.shape(env)) if self.size else 0.0

    def ends(self, env, values: dict):
        """(low, high): numbers, or arrays of one per entry."""
        if self.bound is not None:
            bound = end(self.bound, env, values)
            return -bound, bound
        return end(self.low, env, values), end(self.high, env, values)

    def check(self, value, env, values: dict, prefix: str = "state "):
        """value checked against its range (values: those checked before it), or ValueError naming prefix + name."""
        name = prefix + self.name
        if self.kind == "given":
            return getattr(env, self.check_with)(value)
        if self.kind == "rotation":
            return check_rotation(name, value)
        low, high = self.ends(env, values)
        if self.kind == "number":
            return check_number(name, value, low, high)
        if self.scalar and np.ndim(value) == 0:
            value = np.ravel(value)
        note = self.note(env) if self.note else ""
        return check_vector(name, value, self.shape(env)[0], low, high, note=note)

    def row(self) -> str:
        """The table's row: | key | shape | unit | range, about |."""
        size = self.size if isinstance(self.size, (str, tuple)) else (self.size,) if self.size else ()
        shape = "number" if size == () else size if isinstance(size, str) else " × ".join(map(str, size))
        if self.range_text:
            span = self.range_text
        elif self.bound is not None:
            span = f"±{written(self.bound)}"
        else:
            span = f"[{written(self.low)}, {written(self.high)}]"
        return cells(f"`{self.name}`", shape, self.unit, span + (f"; {self.about}" if self.about else ""))


def end(value: End, env, values: dict):
    """The number (or array) of an end: itself, the env's attribute of that name, or a Bound's value."""
    if isinstance(value, Bound):
        return value.value(env, values)
    return getattr(env, value) if isinstance(value, str) else value


def number(name, unit="", about="", **fields) -> Field:
    """A number in [low, high], or within ±bound."""
    return Field(name, 0, unit, about, **fields)


def angle(name, about="", **fields) -> Field:
    """An angle, rad, in [−2π, 2π] (every configuration lies within it)."""
    return Field(name, 0, "rad", about, bound=ANGLE_BOUND, **fields)


def vector(name, size, unit="", about="", **fields) -> Field:
    """A vector of ``size`` entries (a number, or an env attribute's name), each in [low, high] or within ±bound."""
    return Field(name, size, unit, about, kind="vector", **fields)


def within(low: str, high: str, limit: float, names: tuple[str, str] | None = None) -> dict:
    """The ends of a vector's range: the env's attributes ``low`` and ``high`` (a number or one per entry, ±inf for
    none) cut to ±limit; ``names``: theirs in the table (the make kwargs that set them)."""
    low_name, high_name = names or (low, high)
    return {
        "low": Bound(lambda env, values: np.maximum(getattr(env, low), -limit), f"max({low_name}, −{text(limit)})"),
        "high": Bound(lambda env, values: np.minimum(getattr(env, high), limit), f"min({high_name}, {text(limit)})"),
    }


def rotation(name, about="", **fields) -> Field:
    """A rotation matrix, to 1e-9 (‖RᵀR − I‖, |det R − 1|), never re-orthonormalized (`check_rotation`)."""
    span = "a rotation matrix to 1e-9 (‖RᵀR − I‖, |det R − 1|), never re-orthonormalized"
    return Field(name, (3, 3), about=about, kind="rotation", range_text=span, **fields)


def given(name, size, check_with, range_text, about="") -> Field:
    """A key the env's method ``check_with`` checks (value -> the value), its range written as text."""
    return Field(name, size, about=about, kind="given", check_with=check_with, range_text=range_text)


class Fields:
    """An env's declared reset state, in order: a later field's range may refer to an earlier one's value."""

    prefix = "state "  # what errors put before a key: "state x"
    column = "key"  # the table's first column

    def __init__(self, *fields: Field, either: tuple[tuple[str, ...], ...] = ()):
        self.fields = {f.name: f for f in fields}
        self.either = either
        self.group = {key: group for group in either for key in group}  # each alternative's group

    @property
    def names(self) -> tuple[str, ...]:
        """The keys, in the declared order."""
        return tuple(self.fields)

    def shapes(self, env) -> dict[str, tuple]:
        """Each key's shape for this env (a builder's sizes are its own), in the declared order."""
        return {name: f.shape(env) for name, f in self.fields.items()}

    def check(self, env, state, defaults: dict | None = None, name: str = "options['state']") -> dict:
        """The state's values, in the declared order: the given keys checked, the others their defaults (those the
        env passes, else the fields'); of alternatives only the one given, or the first. A bad key or value (and
        two alternatives given) is a ValueError naming it, before anything is set."""
        check_keys(name, state, self.fields)
        for group in self.either:
            both = [key for key in group if key in state]
            if len(both) > 1:
                raise ValueError(f"{name} gives both {both[0]} and {both[1]}; give one of them")
        defaults, values = defaults or {}, {}
        for key, field in self.fields.items():
            if key in state:
                values[key] = field.check(state[key], env, values, self.prefix)
            elif not self.left_out(key, state):
                default = defaults[key] if key in defaults else field.default(env)
                if default is not None:
                    values[key] = default
        return values

    def left_out(self, key: str, state) -> bool:
        """Whether an alternative key takes no default: another of its group is given, or it is not the first."""
        group = self.group.get(key)
        return group is not None and (key != group[0] or any(k in state for k in group))

    def table(self) -> list[str]:
        """The Starting State's table of the keys, then a line per group of alternatives."""
        rows = [f"| {self.column} | shape | unit | range |", "|---|---|---|---|"]
        rows += [f.row() for f in self.fields.values()]
        for group in self.either:
            rows += ["", f"{' or '.join(f'`{k}`' for k in group)}, not both."]
        return rows


class Options(Fields):
    """An env's declared reset options beside "state" (a target): checked and tabled as the state's keys, errors
    naming them alone ("target")."""

    prefix = ""
    column = "option"


def document_state(cls: type) -> None:
    """cls's ``STATE`` and ``OPTIONS``, where it declares either: their tables end the docstring's "## Starting State"
    section."""
    if "STATE" not in cls.__dict__ and "OPTIONS" not in cls.__dict__:
        return
    doc = cls.__dict__.get("__doc__") or ""
    lines = doc.split("\n")
    heading = next((i for i, line in enumerate(lines) if line.strip() == "## Starting State"), None)
    if heading is None:
        return
    indent = lines[heading][: len(lines[heading]) - len(lines[heading].lstrip())]
    after = next((i for i in range(heading + 1, len(lines)) if lines[i].strip().startswith("## ")), len(lines))
    last = max(i for i in range(heading, after) if lines[i].strip())
    rows = cls.STATE.table() + (["", *cls.OPTIONS.table()] if cls.OPTIONS.fields else [])
    table = [indent + row if row else "" for row in rows]
    cls.__doc__ = "\n".join([*lines[: last + 1], "", *table, *lines[last + 1:]])
