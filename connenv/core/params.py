"""Declared arguments: an env's make kwargs written once, as data, each with its name, default, unit, valid range and
meaning. One declaration, `Args`, checks the kwargs (a ValueError naming the argument, its value and its range, as
`connenv.core.validation` words it), writes the Arguments table of the env's docstring (`document`) and lists the
physical parameters its errors report.

A range is one of four kinds: a *scale* (`scale`: `check_scale`'s span of SCALE_SPAN either way of the default,
down to 0 with low=0.0, at most high), an *interval* (`interval`: its ends), a set of *choices* (`choice`), or text
for an argument that another check owns (`given`, `integrator`, `options`: a trail, a stepper and its options). An
end may be set by an argument checked before it, by its name (a_max below length), or by a `Bound`, a function of
them (damping below 1e3 m l² √(g/l)).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable
from typing import Any

from connenv.core.backend import is_traced
from connenv.core.validation import DT_MIN, SCALE_SPAN, check_number, check_scale, check_stepper_options


@dataclasses.dataclass(frozen=True)
class Bound:
    """An end of a range that what is checked before it sets: ``value(args)`` (args a dict of them) for an argument,
    ``value(env, values)`` (the values checked before it) for a key of the reset state (`connenv.core.state`);
    written ``text`` in the table, and named by ``name`` in an argument's error (None: the number alone)."""

    value: Callable[[dict], float]
    text: str
    name: str | None = None


End = float | str | Bound  # a number, the name of an argument checked before, or a Bound


@dataclasses.dataclass(frozen=True)
class Param:
    """One make kwarg: its name, default, unit, range (see the module) and meaning. ``physical``: a parameter of the
    physics (a length, a mass, g), which errors report, rather than of the task (a tolerance, dt, a stepper).
    ``optional``: None is also valid (its meaning in ``default_text``)."""

    name: str
    default: Any
    unit: str = ""
    about: str = ""
    kind: str = "scale"
    low: End = -math.inf
    high: End = math.inf
    open_low: bool = False
    open_high: bool = False
    choices: tuple = ()
    physical: bool = True
    optional: bool = False
    default_text: str = ""
    range_text: str = ""
    typical: End | None = None  # a scale's centre of its span where the default is None

    def check(self, value, args: dict):
        """value checked against its range (args: the arguments checked before it), or ValueError. A traced value
        (a physical parameter that ``connenv.jax`` traces), or one whose range a traced argument sets, passes as it
        is: it has no number to check until it is drawn (``FunctionalEnv.sample_params`` draws within the ranges
        checked here at their corners)."""
        if is_traced(value) or any(map(is_traced, args.values())):
            return value
        if value is None and self.optional or self.kind in ("given", "options"):
            return value
        if self.kind == "choice":
            if value not in self.choices:
                raise ValueError(f"{self.name}={value!r} is not one of {list(self.choices)}")
            return value
        (low, low_name), (high, high_name) = end(self.low, args), end(self.high, args)
        if self.kind == "scale":
            typical = self.default if self.typical is None else end(self.typical, args)[0]
            value = check_scale(self.name, value, typical, high, zero=low == 0.0, open_high=self.open_high,
                                high_name=high_name)  # fmt: skip
            if low_name is not None and value <= low:
                raise ValueError(f"{self.name}={value!r} is out of range: must be above {low_name}={low!r}")
            return value
        return check_number(self.name, value, low, high, open_low=self.open_low, open_high=self.open_high,
                            low_name=low_name, high_name=high_name)  # fmt: skip

    def row(self) -> str:
        """The Arguments table's row: | name | default | range unit, about |."""
        default = self.default_text or (text(self.default) if isinstance(self.default, str) else
                                        NAMED.get(self.default, repr(self.default)))  # fmt: skip
        if self.kind in ("given", "options"):
            return cells(self.name, self.default_text if self.kind == "options" else default, self.range_text)
        return cells(self.name, default, self.span() + (f", {self.about}" if self.about else ""))

    def span(self) -> str:
        """The valid range as the Arguments table writes it, with the unit: [low, high] unit, or the choices."""
        if self.kind == "choice":
            return ", ".join(text(c) for c in self.choices)
        low, high = written(self.low), written(self.high)
        typical, is_open = self.default if self.typical is None else self.typical, self.open_low
        if self.kind == "scale":
            is_open = isinstance(self.low, str)
            low = "0" if self.low == 0.0 else low if is_open else scaled(typical, 1 / SCALE_SPAN)
            capped = isinstance(self.high, (str, Bound)) or self.high < math.inf and (
                isinstance(typical, Bound) or self.high < typical * SCALE_SPAN)
            high = high if capped else scaled(typical, SCALE_SPAN)
        brackets = "(" if is_open else "[", ")" if self.open_high else "]"
        span = f"{'None or ' if self.optional else ''}{brackets[0]}{low}, {high}{brackets[1]}"
        return span + (f" {self.unit}" if self.unit else "")


def cells(*texts: str) -> str:
    """A row of a markdown table, a | inside a cell escaped."""
    escaped = (t.replace("|", "\\|") for t in texts)
    return "|" + "|".join(f" {t} " if t else " " for t in escaped) + "|"


def written(value: End) -> str:
    """An end as the table writes it."""
    return value.text if isinstance(value, Bound) else value if isinstance(value, str) else text(value)


def end(value: End, args: dict) -> tuple[float, str | None]:
    """(the number, the name the error gives it) of an end."""
    if isinstance(value, Bound):
        return value.value(args), value.name
    if isinstance(value, str):
        return args[value], value
    return value, None


NAMED = {math.pi: "π", math.pi / 2: "π/2", 2 * math.pi / 3: "2π/3", 2 * math.pi: "2π", 4 * math.pi: "4π"}


def text(value) -> str:
    """A default, an end or a choice as the tables write it: 9.81e-6, 1e6, π, "exact"."""
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float) and value in NAMED:
        return NAMED[value]
    if isinstance(value, float) and math.isfinite(value) and (abs(value) >= 1e3 or 0 < abs(value) < 1e-3):
        mantissa, _, exponent = f"{value:.12e}".partition("e")
        return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"
    return f"{value:.12g}" if isinstance(value, float) else str(value)


def scaled(default: float | Bound, factor: float) -> str:
    """default · factor as the tables write it: 2.5e-7, or 2π·1e-6 for a named default or a Bound."""
    if isinstance(default, Bound) or default in NAMED:
        return f"{default.text if isinstance(default, Bound) else NAMED[default]}·{text(factor)}"
    return text(float(f"{default * factor:.12g}"))


def scale(name, default, unit="", about="", **fields) -> Param:
    """A physical scale: within SCALE_SPAN of its default (of typical where the default is None) either way, down to 0
    with low=0.0, above another argument with low its name, at most high."""
    return Param(name, default, unit, about, kind="scale", **fields)


def interval(name, default, unit, low, high, about="", **fields) -> Param:
    """A number in [low, high] (open ends with open_low, open_high)."""
    return Param(name, default, unit, about, kind="interval", low=low, high=high, **fields)


def choice(name, default, choices, about="", **fields) -> Param:
    """One of the choices."""
    return Param(name, default, about=about, kind="choice", choices=tuple(choices), **{"physical": False, **fields})


def given(name, default, range_text, default_text="", **fields) -> Param:
    """An argument another check owns (a stepper, a builder), documented here: its range as text."""
    return Param(name, default, kind="given", range_text=range_text, default_text=default_text, physical=False,
                 **fields)  # fmt: skip


def step(default: float, dt_max: float) -> Param:
    """The control step dt, s, in [DT_MIN, dt_max]."""
    return interval("dt", default, "s", DT_MIN, dt_max, physical=False)


def integrator(default, *choices, default_text="", about="") -> Param:
    """The stepper's name (`connenv.core.integrators.make_stepper` checks it): its default and the env's choices."""
    span = ", ".join(text(c) for c in choices)
    return given("integrator", default, span + (f"; {about}" if about else ""), default_text)


def options(default_text="", names="substeps / rtol, atol") -> Param:
    """The stepper's options, checked by the stepper (the table's last row)."""
    return Param(names, None, kind="options", range_text="the stepper's", default_text=default_text,
                 physical=False)  # fmt: skip


class Args:
    """An env's declared make kwargs, in order: a later one's range may refer to an earlier one."""

    def __init__(self, *params: Param):
        self.params = {p.name: p for p in params if p.kind != "options"}
        self.rows = params

    def __add__(self, more: tuple[Param, ...]) -> Args:
        """These arguments and more (a subclass's), a parameter of the same name replaced in place."""
        replaced, rows = {p.name: p for p in more}, [p for p in self.rows if p.kind != "options"]
        extra = [p for p in more if p.name not in self.params]
        return Args(*(replaced.get(p.name, p) for p in rows), *extra, *(p for p in self.rows if p.kind == "options"))

    def check(self, env_name: str, env_cls: type, given: dict) -> tuple[dict, dict]:
        """(the declared arguments, checked, with defaults; the stepper's options): unknown kwargs that are no
        stepper option are a ValueError naming the env (`check_stepper_options`)."""
        options = {k: v for k, v in given.items() if k not in self.params}
        check_stepper_options(env_name, options, env_cls)
        args = {}
        for name, param in self.params.items():
            args[name] = param.check(given.get(name, param.default), args)
        return args, options

    def physical(self, args: dict) -> dict:
        """The physical parameters among the checked arguments."""
        return {name: args[name] for name, p in self.params.items() if p.physical}

    def table(self) -> list[str]:
        return ["| kwarg | default | range |", "|---|---|---|", *(p.row() for p in self.rows)]

    def signature(self) -> inspect.Signature:
        """__init__'s: (self, render_mode=None, *, each argument=its default, **stepper_options)."""
        P = inspect.Parameter
        return inspect.Signature([
            P("self", P.POSITIONAL_OR_KEYWORD), P("render_mode", P.POSITIONAL_OR_KEYWORD, default=None),
            *(P(name, P.KEYWORD_ONLY, default=p.default) for name, p in self.params.items()),
            P("stepper_options", P.VAR_KEYWORD),
        ])  # fmt: skip


def document(cls: type) -> None:
    """Declare cls's own ``ARGS`` (if it has them): its Arguments table goes under the docstring's "## Arguments"
    heading (a section of its own at the end where there is none), and its __init__'s signature lists them."""
    args = cls.__dict__.get("ARGS")
    if args is None:
        return
    if "__init__" in cls.__dict__:
        cls.__init__.__signature__ = args.signature()
    lines = (cls.__dict__.get("__doc__") or "").split("\n")
    heading = next((i for i, line in enumerate(lines) if line.strip() == "## Arguments"), None)
    if heading is None:
        indent = " " * min((len(s) - len(s.lstrip()) for s in lines[1:] if s.strip()), default=0)
        lines[-1:] = ["", f"{indent}## Arguments", lines[-1]]
        heading = len(lines) - 2
    indent = lines[heading][: len(lines[heading]) - len(lines[heading].lstrip())]
    after = lines[heading + 2:] if heading + 1 < len(lines) and not lines[heading + 1].strip() else lines[heading + 1:]
    table = [indent + row for row in args.table()]
    cls.__doc__ = "\n".join([*lines[: heading + 1], "", *table, *([""] if any(s.strip() for s in after) else []),
                             *after])  # fmt: skip
