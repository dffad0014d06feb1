"""Trails for the skier: height profiles y = f(x) in a vertical plane, with f′, f″, f‴.

A trail is defined on a domain [lo, hi]. Beyond it, it continues as the
parabola that osculates it at the end (f, f′, f″ continuous, f‴ = 0), so that
the one step in which a skier leaves the domain stays finite. The built-in
trails have rims at both ends of the domain.

σ = √(1 + f′²) is the length element (ds = σ dx), κ = f″/σ³ the curvature,
tan φ = f′ the slope angle. The arc length s is measured from the trail's
origin: x = 0 if the domain holds it, else lo.
"""

from __future__ import annotations

import inspect
import math
from functools import cached_property

import numpy as np
from scipy.differentiate import derivative
from scipy.integrate import cumulative_simpson
from scipy.interpolate import CubicSpline
from scipy.special import ellipeinc

from connenv.core.backend import namespace, traced
from connenv.core.validation import check_keys, check_number

GRID = 4001  # samples of the domain for the checks and the tabulated arc length


class Trail:
    """Base class: subclasses set ``lo``, ``hi``, ``rims`` and define ``profile(x) -> (f, f′, f″, f‴)`` on the domain."""

    lo: float
    hi: float
    rims: bool = False

    def profile(self, x):
        raise NotImplementedError

    def derivatives(self, x):
        """(f, f′, f″, f‴) at x, on the domain and on its osculating-parabola continuation."""
        if isinstance(x, float):  # a single state (numpy scalars too), the env's hot path: no array calls
            b = min(max(x, self.lo), self.hi)
            if b == x:
                return self.profile(x)
            f, f1, f2, _ = self.profile(b)
            d = x - b
            return f + d * (f1 + 0.5 * d * f2), f1 + d * f2, f2, 0.0
        ops = namespace(x)  # numpy's rows, or JAX's (connenv.jax)
        b = self._clip(x, ops)
        f, f1, f2, f3 = self.profile(b)
        d = x - b
        return f + d * (f1 + 0.5 * d * f2), f1 + d * f2, f2 + 0.0 * d, ops.where(d == 0.0, f3, 0.0)

    def _clip(self, x, ops):
        """x clipped to the domain: numpy's clip on numpy's rows, the namespace's maximum and minimum on traced ones."""
        return ops.minimum(ops.maximum(x, self.lo), self.hi) if traced(ops) else np.clip(x, self.lo, self.hi)

    def grid(self):
        return np.linspace(self.lo, self.hi, GRID)

    @property
    def origin(self):
        return 0.0 if self.lo <= 0.0 <= self.hi else self.lo

    def arc_length(self, x):
        """s(x) = ∫ σ dx from the origin; continued in closed form along the parabola beyond the domain."""
        if isinstance(x, float) and self.lo <= x <= self.hi:  # a single state on the domain: no array calls
            return float(self.arc_length_on_domain(x) - self._origin_arc) + 0.0  # + the parabola's 0, as below
        b = self._clip(x, namespace(x))
        _, f1, f2, _ = self.profile(b)
        return self.arc_length_on_domain(b) - self._origin_arc + _parabola_arc(f1, f2, x - b)

    @cached_property
    def _origin_arc(self):
        """The primitive of σ at the origin, where s = 0."""
        return self.arc_length_on_domain(self.origin)

    def arc_length_on_domain(self, x):
        """A primitive of σ on the domain: tabulated (Simpson on GRID points) and splined, unless a subclass knows it."""
        if not hasattr(self, "_arc_spline"):
            xs = self.grid()
            sigma = np.sqrt(1.0 + self.profile(xs)[1] ** 2)
            self._arc_spline = CubicSpline(xs, cumulative_simpson(sigma, x=xs, initial=0.0))
        return self._arc_spline(x)

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_")}


def _ufuncs(x):
    """numpy itself (its ufuncs on numpy's rows and scalars alike, under the Array API names sqrt, asin, asinh, where),
    or the namespace of traced rows (connenv.jax)."""
    ops = namespace(x)
    return ops if traced(ops) else np


def _parabola_arc(c, k, d):
    """∫₀ᵈ √(1 + (c + k t)²) dt, the arc length along y′ = c + k t."""
    ops = _ufuncs(d)
    primitive = lambda v: 0.5 * (v * ops.sqrt(1.0 + v * v) + ops.asinh(v))  # noqa: E731
    with np.errstate(divide="ignore", invalid="ignore"):
        curved = (primitive(c + k * d) - primitive(c)) / k
    return ops.where(k * d == 0.0, ops.sqrt(1.0 + c * c) * d, curved)


class Valley(Trail):
    """f = H (1 − cos(2πx/L))/2 on |x| ≤ L/2: a valley of depth H between two flat rims."""

    rims = True

    def __init__(self, H: float = 3.0, L: float = 12.0):
        self.H = check_number("trail_params H", H, 0.0, open_low=True)
        self.L = check_number("trail_params L", L, 0.0, open_low=True)
        self.lo, self.hi = -self.L / 2, self.L / 2

    def profile(self, x):
        k, a = 2.0 * math.pi / self.L, 0.5 * self.H
        ops = namespace(x)
        c, s = ops.cos(k * x), ops.sin(k * x)
        return a * (1.0 - c), a * k * s, a * k * k * c, -a * k**3 * s

    def arc_length_on_domain(self, x):
        """∫₀ˣ √(1 + (ak)² sin² kx) dx = E(kx | −(ak)²)/k, Legendre's incomplete integral of the second kind."""
        k = 2.0 * math.pi / self.L
        ops = namespace(x)
        return (ops.ellipeinc if traced(ops) else ellipeinc)(k * x, -((0.5 * self.H * k) ** 2)) / k


class Halfpipe(Trail):
    """An exact circular arc of radius R: f = R − √(R² − x²) on |x| ≤ R sin(max_angle); the lips are the rims."""

    rims = True

    def __init__(self, radius: float = 5.0, max_angle: float = 1.4):
        self.radius = check_number("trail_params radius", radius, 0.0, open_low=True)
        self.max_angle = check_number("trail_params max_angle", max_angle, 0.0, math.pi / 2, open_low=True, open_high=True)
        self.hi = self.radius * math.sin(self.max_angle)
        self.lo = -self.hi

    def profile(self, x):
        R2 = self.radius**2
        root = (R2 - x * x) ** 0.5
        return self.radius - root, x / root, R2 / root**3, 3.0 * R2 * x / root**5

    def arc_length_on_domain(self, x):
        return self.radius * _ufuncs(x).asin(x / self.radius)


class Callables(Trail):
    """A user trail from four callables (f, f′, f″, f‴) of an array x, on the domain (lo, hi)."""

    def __init__(self, functions, domain):
        if len(functions) != 4 or not all(callable(fn) for fn in functions):
            raise ValueError(f"trail={functions!r}: give four callables (f, f', f'', f''') of x")
        self.functions = tuple(functions)
        self.lo, self.hi = _domain(domain)

    def profile(self, x):
        x = np.asarray(x, float)
        return tuple(np.broadcast_to(fn(x), x.shape).astype(float) for fn in self.functions)


class Symbolic(Trail):
    """A user trail from a sympy expression in x (or its text), differentiated symbolically; other symbols
    take their values from ``params``."""

    def __init__(self, expression, params: dict, domain):
        try:
            import sympy
        except ImportError as e:  # sympy comes with torch, so with the "train" extra
            raise ImportError("a symbolic trail needs sympy: pip install sympy") from e
        self.expression, self.params = expression, dict(params)
        self.lo, self.hi = _domain(domain)
        x = sympy.Symbol("x", real=True)
        try:
            expr = sympy.sympify(expression, locals={"x": x})
        except (sympy.SympifyError, TypeError) as e:
            raise ValueError(f"trail={expression!r} is not a sympy expression in x: {e}") from e
        free = {str(s) for s in expr.free_symbols} - {"x"}
        check_keys(f"trail_params of trail={expression!r} (its symbols besides x)", self.params, free)
        if free - set(self.params):
            raise ValueError(f"trail={expression!r}: give trail_params for its symbol(s) {sorted(free - set(self.params))}")
        expr = expr.subs({sympy.Symbol(k, real=True): v for k, v in self.params.items()}).subs(self.params)
        self._functions = [sympy.lambdify(x, sympy.diff(expr, x, n), "numpy") for n in range(4)]

    def profile(self, x):
        x = np.asarray(x, float)
        return tuple(np.broadcast_to(np.asarray(fn(x), float), x.shape) for fn in self._functions)

    def __setstate__(self, state):
        self.__init__(state["expression"], state["params"], (state["lo"], state["hi"]))


def _domain(domain):
    if domain is None or len(domain) != 2:
        raise ValueError(f"domain={domain!r}: a user trail needs trail_params['domain'] = (lo, hi) with lo < hi")
    lo = check_number("trail_params domain lo", domain[0])
    hi = check_number("trail_params domain hi", domain[1], lo, open_low=True)
    return lo, hi


BUILT_IN = {"valley": Valley, "halfpipe": Halfpipe}


def make_trail(trail="valley", trail_params: dict | None = None) -> Trail:
    """A Trail from the env's kwargs: a built-in name, a sympy expression (or its text) in x, or four callables.

    For a built-in, trail_params are its parameters (valley: H, L; halfpipe: radius,
    max_angle). For a user trail, trail_params holds ``domain`` = (lo, hi) and the
    values of the expression's other symbols. The profile is then checked.
    """
    params = dict(trail_params or {})
    if isinstance(trail, str) and trail in BUILT_IN:
        cls = BUILT_IN[trail]
        check_keys(f"trail_params of trail={trail!r}", params, inspect.signature(cls.__init__).parameters.keys() - {"self"})
        made = cls(**params)
    elif isinstance(trail, (tuple, list)):
        check_keys("trail_params of a callable trail", params, {"domain"})
        made = Callables(trail, params.get("domain"))
    elif (isinstance(trail, str) and not (trail.isidentifier() and trail != "x")) or type(trail).__module__.startswith(
        "sympy"
    ):
        domain = params.pop("domain", None)
        made = Symbolic(trail, params, domain)
    else:
        raise ValueError(
            f"trail={trail!r} is not one of {sorted(BUILT_IN)}, a sympy expression in x, or four callables"
        )
    check_profile(made)
    return made


def check_profile(trail: Trail):
    """Raise ValueError if the profile is not finite on the domain or a derivative disagrees with the one before."""
    xs, names = trail.grid(), ("f", "f'", "f''", "f'''")
    with np.errstate(all="ignore"):  # a non-finite value is reported below, by name and place
        values = trail.profile(xs)
    for name, v in zip(names, values):
        bad = ~np.isfinite(v)
        if bad.any():
            raise ValueError(f"trail {name}(x) is not finite at x={xs[bad][0]:.6g} (domain [{trail.lo}, {trail.hi}])")
    probe = np.linspace(trail.lo, trail.hi, 9)[1:-1]
    length = trail.hi - trail.lo
    for n in range(3):
        numeric = derivative(lambda x: trail.profile(x)[n], probe, initial_step=1e-3 * length).df
        given = trail.profile(probe)[n + 1]
        scale = np.max(np.abs(given)) + np.max(np.abs(numeric)) + np.max(np.abs(values[n])) / length
        worst = np.argmax(np.abs(numeric - given))
        if abs(numeric[worst] - given[worst]) > 1e-5 * scale:
            raise ValueError(
                f"trail {names[n + 1]} disagrees with the derivative of {names[n]} at x={probe[worst]:.6g}: "
                f"{given[worst]:.6g} given, {numeric[worst]:.6g} numerically"
            )
