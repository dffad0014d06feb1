"""Surfaces z(x, y) for the rolling coin: the height and its gradient (z, z_x, z_y), over arrays or one point.

Built in:

- ``Plane(slope)``: z = sx x + sy y, slope = (sx, sy), a constant gradient (the coin's closed-form step);
- ``Bowl(radius)``: z = (x² + y²)/(2 ρ), the paraboloid of curvature 1/ρ at its bottom, the origin;
- ``Hill(slope, height, width, center)``: the plane with a Gaussian hill on it,
  z = sx x + sy y + H exp(−|(x, y) − c|²/(2 w²));
- ``Symbolic(expression, params)``: a sympy expression in x and y (or its text), differentiated symbolically;
  its other symbols take their values from ``params``, as the skier's symbolic trails do.

``make_surface`` builds one from an env's kwargs and checks it on the arena: finite height and gradient.
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from connenv.core.backend import floats, namespace, traced
from connenv.core.validation import MAGNITUDE_BOUND, check_keys, check_number, check_vector

GRID = 201  # samples per side of the arena for the checks and the bounds
LENGTH_MIN = 1e-3  # m: the least length of a surface (bowl radius, hill width) and of the coin's radius


class Surface:
    """Base class: subclasses define ``height(x, y) -> (z, z_x, z_y)`` on arrays, and on floats without array
    calls (one state, the env's hot path)."""

    def height(self, x, y):
        raise NotImplementedError

    def gradient_is_constant(self) -> bool:
        return False


class Plane(Surface):
    """z = sx x + sy y."""

    def __init__(self, slope=(0.0, -0.25)):
        self.slope = tuple(check_vector("slope", slope, 2, -10.0, 10.0))

    def height(self, x, y):
        sx, sy = self.slope
        return sx * x + sy * y, sx + 0.0 * x, sy + 0.0 * y

    def gradient_is_constant(self) -> bool:
        return True


class Bowl(Surface):
    """z = (x² + y²)/(2 ρ): curvature 1/ρ at the bottom (the origin)."""

    def __init__(self, radius: float = 5.0):
        self.radius = check_number("surface_params radius", radius, LENGTH_MIN, MAGNITUDE_BOUND)

    def height(self, x, y):
        k = 1.0 / self.radius
        return 0.5 * k * (x * x + y * y), k * x, k * y


class Hill(Surface):
    """z = sx x + sy y + H exp(−|(x, y) − c|²/(2 w²)): a Gaussian hill of height H and width w at c on a plane."""

    def __init__(self, slope=(0.0, -0.25), height: float = 1.0, width: float = 0.6, center=(0.0, 2.0)):
        self.slope = tuple(check_vector("slope", slope, 2, -10.0, 10.0))
        self.H = check_number("surface_params height", height, 0.0, MAGNITUDE_BOUND)
        self.width = check_number("surface_params width", width, LENGTH_MIN, MAGNITUDE_BOUND)
        self.center = tuple(check_vector("surface_params center", center, 2, -1e3, 1e3))

    def height(self, x, y):
        sx, sy = self.slope
        cx, cy = self.center
        dx, dy = x - cx, y - cy
        if isinstance(x, float) and isinstance(y, float):
            exp = math.exp
        else:  # numpy's, or JAX's on its rows (connenv.jax)
            exp = ops.exp if traced(ops := namespace(dx)) else np.exp
        bump = self.H * exp(-(dx * dx + dy * dy) / (2.0 * self.width**2))
        scale = bump / self.width**2
        return sx * x + sy * y + bump, sx - scale * dx, sy - scale * dy


class Symbolic(Surface):
    """A sympy expression in x and y (or its text); other symbols take their values from ``params``."""

    def __init__(self, expression, params: dict | None = None):
        import sympy

        self.expression, self.params = expression, dict(params or {})
        x, y = sympy.Symbol("x", real=True), sympy.Symbol("y", real=True)
        try:
            expr = sympy.sympify(expression, locals={"x": x, "y": y})
        except (sympy.SympifyError, TypeError) as e:
            raise ValueError(f"surface={expression!r} is not a sympy expression in x and y: {e}") from e
        if not isinstance(expr, sympy.Expr):
            raise ValueError(f"surface={expression!r} is not a sympy expression in x and y")
        free = {str(s) for s in expr.free_symbols} - {"x", "y"}
        check_keys(f"surface_params of surface={expression!r} (its symbols besides x and y)", self.params, free)
        if free - set(self.params):
            missing = sorted(free - set(self.params))
            raise ValueError(f"surface={expression!r} is not one of {sorted(BUILT_IN)}; as a sympy expression in x and "
                             f"y, give surface_params for its symbol(s) {missing}")
        values = {name: check_number(f"surface_params {name}", v, -MAGNITUDE_BOUND, MAGNITUDE_BOUND)
                  for name, v in self.params.items()}  # fmt: skip
        expr = expr.subs({sympy.Symbol(k, real=True): v for k, v in values.items()}).subs(values)
        if expr.has(sympy.I):
            raise ValueError(f"surface={expression!r} is complex (it has I): the height must be real")
        derivatives = (expr, expr.diff(x), expr.diff(y))
        self._symbols, self._derivatives, self._traced = (x, y), derivatives, None
        self._functions = [sympy.lambdify((x, y), e, "numpy") for e in derivatives]
        self._scalar = [sympy.lambdify((x, y), e, "math") for e in derivatives]  # one point: no array calls

    def height(self, x, y):
        if isinstance(x, float) and isinstance(y, float):
            return tuple(float(f(x, y)) for f in self._scalar)
        if traced(ops := namespace(x)) or traced(ops := namespace(y)):  # JAX's rows (connenv.jax)
            x, y = ops.broadcast_arrays(x * 1.0, y * 1.0)
            return tuple(ops.broadcast_to(f(x, y) * 1.0, x.shape) for f in self._jax_functions())
        # floats: complex on a Jacobian's rows, whose imaginary parts carry the derivatives
        x, y = np.broadcast_arrays(floats(x), floats(y))
        return tuple(np.broadcast_to(floats(f(x, y)), x.shape) for f in self._functions)

    def _jax_functions(self):
        """The height and its gradient lambdified for jax.numpy, made on the first traced call (``import connenv``
        imports no jax)."""
        if self._traced is None:
            import sympy

            self._traced = [sympy.lambdify(self._symbols, e, "jax") for e in self._derivatives]
        return self._traced

    def __getstate__(self):
        return {"expression": self.expression, "params": self.params}

    def __setstate__(self, state):
        self.__init__(state["expression"], state["params"])


BUILT_IN = {"plane": Plane, "bowl": Bowl, "hill": Hill}
TAKES_SLOPE = ("plane", "hill")


def make_surface(surface="hill", slope=None, surface_params: dict | None = None) -> Surface:
    """A Surface from the env's kwargs: "plane" (slope), "bowl", "hill" (slope and its surface_params), or a
    sympy expression in x and y (or its text), whose other symbols' values are the surface_params."""
    if surface_params is not None and not isinstance(surface_params, dict):
        raise ValueError(f"surface_params={surface_params!r} must be a dict or None")
    params = dict(surface_params or {})
    if slope is not None and surface not in TAKES_SLOPE:
        raise ValueError(f"slope={slope!r} is for surface='plane' or 'hill', not surface={surface!r}")
    if isinstance(surface, str) and surface in BUILT_IN:
        cls = BUILT_IN[surface]
        allowed = inspect.signature(cls.__init__).parameters.keys() - {"self", "slope"}
        check_keys(f"surface_params of surface={surface!r}", params, allowed)
        return cls(**({} if slope is None else {"slope": slope}), **params)
    if isinstance(surface, str) or type(surface).__module__.startswith("sympy"):
        return Symbolic(surface, params)
    raise ValueError(f"surface={surface!r} is not one of {sorted(BUILT_IN)} or a sympy expression in x and y")


def check_surface(surface: Surface, half_width: float):
    """(z_min, z_max, max |∇z|) over the arena |x|, |y| ≤ half_width; ValueError where z or ∇z is not finite
    there, naming the point."""
    side = np.linspace(-half_width, half_width, GRID)
    x, y = np.meshgrid(side, side)
    with np.errstate(all="ignore"):  # a non-finite value is reported below, by name and place
        values = surface.height(x, y)
    for name, v in zip(("z", "z_x", "z_y"), values):
        bad = ~np.isfinite(v)
        if bad.any():
            raise ValueError(
                f"surface {name}(x, y) is not finite at (x, y) = ({x[bad][0]:.6g}, {y[bad][0]:.6g}) in the arena "
                f"|x|, |y| ≤ {half_width}"
            )
    z, z_x, z_y = values
    return float(z.min()), float(z.max()), float(np.max(np.hypot(z_x, z_y)))
