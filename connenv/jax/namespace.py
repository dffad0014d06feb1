"""The third namespace: the operations of `connenv.core.backend` on JAX arrays, so that the physics and task code
written once for Python floats (FLOATS, SCALAR) and numpy rows (ARRAYS, BATCH) traces under jit, vmap and grad.

``JAX`` answers the physics' names (``connenv.core.backend.NAMES``, the Array API standard's) with jax.numpy's, and
the rows' seams that numpy code reached outside ``ops`` before: ``stack``, ``real_part`` (the real part a decision
reads; JAX differentiates by its own forward mode, so there are no complex rows and it is the value itself),
``any`` (whether a branch that only some rows take must be computed: always, as a trace cannot look at values; the
rows that do not take it are left by ``where``), ``branch`` (a branch computed only where some row takes it:
``lax.cond`` on rows stepped in one call, both sides under vmap), ``all``, ``sort``, ``concatenate``, ``full`` and
``ceil`` (the bounded segments' and the Kapitza pendulum's), ``broadcast_arrays`` and ``broadcast_to`` (the
connections'), ``maximum_one_sided``/``minimum_one_sided`` and ``sort`` with the derivative at a tie of the trace's
tie rule (``ties``: "linear", the second argument's, for forward and reverse mode; "one-sided", ARRAYS', as the
complex step takes it at a pivot's end stop, forward mode only), ``repeat`` (a loop to a trip count the numpy code
reads off the rows' values, at a fixed trip count where the step's ``longest_segment`` bounds it), ``sinc`` and
``nan_to_num`` (numpy's, which the falling cat's rows call), ``sinh`` and ``cosh`` (the bead's closed-form step),
``solve`` (numpy's linalg.solve, which the builders' Hamiltonian calls), ``atan2`` and ``hypot`` with ARRAYS'
derivative (0 at the origin, where they have none), ``ellipj``/``ellipk`` (traceable Jacobi elliptic functions,
below), ``single_precision`` (float32's values with derivative 1, the goals' rounding) and ``fail`` (a failure
reported as data, below). ``JAX_TASK`` adds the task's names (``connenv.envs.base``).

**Failures as data.** Traced code cannot raise on a value. Where the numpy env raises StepperError (a stepper's
non-finite state, an invariant past its bound), the JAX physics calls ``fail(condition, message)``, which records
the traced condition in the `failures` collector of the step being traced; `connenv.jax.env` turns them into
``info["stepper_failed"]``, holds the state and truncates the episode.
"""

from __future__ import annotations

import contextlib
import math

import jax
import jax.numpy as jnp

from connenv.core.backend import ANSWERED, NAMES, operations

MACHEP = 1.11022302462515654042e-16  # cephes' machine epsilon (2⁻⁵³), the AGM's stopping threshold
AGM_LEVELS = 8  # cephes' ellpj stops after 8 AGM levels; the fixed trip count here


def ellipj(u, m):
    """(sn, cn, dn, φ) of u at parameter m, scipy.special.ellipj's algorithm (cephes' ellpj: the arithmetic-geometric
    mean's descending Landen scale, DLMF 22.20(ii), with cephes' series for m < 1e-9 and m ≥ 1 − 1e-10) written
    branch-free with a fixed trip count: every AGM level is computed and the levels past cephes' stop (|c/a| ≤ MACHEP)
    are left out by ``where``, so that a converged row gets cephes' own arithmetic. Differentiable by JAX's forward
    and reverse modes through the recurrence."""
    u, m = jnp.asarray(u, float), jnp.asarray(m, float)
    # the AGM scale: levels 0..AGM_LEVELS, and the number of levels cephes takes (its loop's i at the end)
    a, b, c = [jnp.ones_like(m)], jnp.sqrt(1.0 - m), [jnp.sqrt(m)]
    taken = jnp.zeros(jnp.shape(m), int)
    going = jnp.abs(c[0] / a[0]) > MACHEP
    for _ in range(AGM_LEVELS):
        ai = a[-1]
        c.append((ai - b) / 2.0)
        t = jnp.sqrt(ai * b)
        a.append((ai + b) / 2.0)
        b = jnp.where(going, t, b)
        taken = taken + going
        going = going & (jnp.abs(c[-1] / a[-1]) > MACHEP)
    twon = 2.0 ** taken.astype(float)
    a_last = sum(jnp.where(taken == i, a[i], 0.0) for i in range(AGM_LEVELS + 1))
    phi = twon * a_last * u
    last = phi
    for i in range(AGM_LEVELS, 0, -1):  # the backward recurrence, over the levels taken
        use = i <= taken
        t = c[i] * jnp.sin(phi) / a[i]
        last = jnp.where(use, phi, last)
        phi = jnp.where(use, (jnp.arcsin(jnp.clip(t, -1.0, 1.0)) + phi) / 2.0, phi)
    sn, cn = jnp.sin(phi), jnp.cos(phi)
    dnfix = cn / jnp.cos(phi - last)
    # cephes takes dn = cn / cos(φ₁ − φ₀) unless it is small (DLMF 22.20.5's discussion); the quotient of two small
    # numbers near cn = 0 loses digits, where scipy's dn agrees with √(1 − m sn²): that is taken there too
    dn = jnp.where((jnp.abs(dnfix) < 0.1) | (jnp.abs(cn) < 0.1), jnp.sqrt(1.0 - m * sn * sn), dnfix)
    # cephes' series at the ends of [0, 1], computed where some row needs them (every row under vmap)
    is_small, is_one = m < 1e-9, m >= 0.9999999999
    agm = tuple(jnp.broadcast_arrays(sn, cn, dn, phi))
    small, near_one = branch(is_small | is_one, _end_series, lambda u, m: (agm, agm), u, m)
    return tuple(jnp.where(is_small, s, jnp.where(is_one, o, x)) for s, o, x in zip(small, near_one, agm))


def _end_series(u, m):
    """cephes' series of (sn, cn, dn, φ) for m < 1e-9 and for m ≥ 1 − 1e-10 (ellipj's ends), each broadcast."""
    t, bb = jnp.sin(u), jnp.cos(u)
    ai = 0.25 * m * (u - t * bb)
    small = (t - ai * bb, bb + ai * t, 1.0 - 0.5 * m * t * t, u - ai)
    ai = 0.25 * (1.0 - m)
    bb, t = jnp.cosh(u), jnp.tanh(u)
    inverse, twon = 1.0 / bb, bb * jnp.sinh(u)
    aj = ai * t * inverse
    near_one = (t + ai * (twon - u) / (bb * bb), inverse - aj * (twon - u), inverse + aj * (twon + u),
                2.0 * jnp.arctan(jnp.exp(u)) - math.pi / 2 + ai * (twon - u) / bb)
    return tuple(jnp.broadcast_arrays(*small)), tuple(jnp.broadcast_arrays(*near_one))


def ellipk(m):
    """K(m), the complete elliptic integral of the first kind, as π / (2 AGM(1, √(1 − m))) at a fixed trip count
    (the AGM converges quadratically: six levels reach rounding for m ≤ 1 − 1e-12). Used where the numpy code rounds
    with scipy's ellipk (a rotation's whole turns), not where its value enters a state."""
    a, b = jnp.ones_like(m), jnp.sqrt(1.0 - m)
    for _ in range(10):
        a, b = (a + b) / 2.0, jnp.sqrt(a * b)
    return math.pi / (2.0 * a)


CARLSON_LEVELS = 12  # duplications of Carlson's R_F and R_D: each quarters the arguments' spread, 12 reach rounding


def _carlson(x, y, z):
    """(R_F(x, y, z), R_D(x, y, z)) by Carlson's duplication (DLMF 19.36.1–2) at a fixed trip count, for arguments
    within a factor of a few of each other (an elliptic integral's of moderate parameter)."""
    total = jnp.zeros_like(x)
    scale = jnp.ones_like(x)
    for _ in range(CARLSON_LEVELS):
        root_x, root_y, root_z = jnp.sqrt(x), jnp.sqrt(y), jnp.sqrt(z)
        lam = root_x * root_y + root_y * root_z + root_z * root_x
        total = total + scale / (root_z * (z + lam))
        scale = scale / 4.0
        x, y, z = (x + lam) / 4.0, (y + lam) / 4.0, (z + lam) / 4.0
    # R_F: the series in the deviations from the mean (DLMF 19.36.1)
    mean = (x + y + z) / 3.0
    dx, dy = 1.0 - x / mean, 1.0 - y / mean
    dz = -(dx + dy)
    e2, e3 = dx * dy - dz * dz, dx * dy * dz
    rf = (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / jnp.sqrt(mean)
    # R_D: its series (DLMF 19.36.2) at the last level, plus the duplications' sum
    mean = (x + y + 3.0 * z) / 5.0
    dx, dy = (mean - x) / mean, (mean - y) / mean
    dz = -(dx + dy) / 3.0
    e2 = dx * dy - 6.0 * dz * dz
    e3 = (3.0 * dx * dy - 8.0 * dz * dz) * dz
    e4 = 3.0 * (dx * dy - dz * dz) * dz * dz
    e5 = dx * dy * dz * dz * dz
    series = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0 - 9.0 * e2 * e3 / 52.0
              + 3.0 * e5 / 26.0)
    rd = 3.0 * total + scale * series / (mean * jnp.sqrt(mean))
    return rf, rd


def ellipeinc(phi, m):
    """E(φ | m), Legendre's incomplete elliptic integral of the second kind (scipy.special.ellipeinc's), for m < 1
    and moderate |m|: sin φ R_F − (m/3) sin³ φ R_D of (cos² φ, 1 − m sin² φ, 1) on |φ| ≤ π/2 (DLMF 19.25.9), and
    E(φ + jπ) = E(φ) + 2j E(m) beyond. A few ulp from scipy's, differentiable in both modes. Used where a numpy
    value is read out (a trail's arc length in info), not where it enters a state."""
    phi, m = jnp.asarray(phi, float), jnp.asarray(m, float)
    turns = jnp.round(phi / math.pi)
    reduced = phi - turns * math.pi
    s, c = jnp.sin(reduced), jnp.cos(reduced)
    rf, rd = _carlson(c * c, 1.0 - m * s * s, jnp.ones_like(reduced))
    rf_whole, rd_whole = _carlson(jnp.zeros_like(m), 1.0 - m, jnp.ones_like(m))
    complete = rf_whole - m / 3.0 * rd_whole
    return s * rf - m / 3.0 * s * s * s * rd + 2.0 * turns * complete


_collectors: list[list] = []


@contextlib.contextmanager
def failures():
    """Collect the failures ``fail`` records while a step is traced: the list of (condition, message)."""
    _collectors.append([])
    try:
        yield _collectors[-1]
    finally:
        _collectors.pop()


def fail(condition, message: str):
    """Record that the step has failed where condition holds (an array over rows; traced). Outside a step being
    traced by connenv.jax, where no one would read it, a RuntimeError."""
    if not _collectors:
        raise RuntimeError(f"{message}: a failure of connenv physics traced outside connenv.jax's step, which carries "
                           "it out as info['stepper_failed']; trace the physics through connenv.jax.make's env")
    _collectors[-1].append((jnp.asarray(condition), message))


_step_lengths: list[float] = []


@contextlib.contextmanager
def stepping(dt: float):
    """The step being traced is dt long: every control segment within it lasts at most dt, which bounds the trip
    count of a loop whose count the numpy code takes from a segment's length (``longest_segment``, ``repeat``)."""
    _step_lengths.append(float(dt))
    try:
        yield
    finally:
        _step_lengths.pop()


def longest_segment():
    """The longest a control segment of the step being traced can last (its dt, a Python float), or None outside
    connenv.jax's step."""
    return _step_lengths[-1] if _step_lengths else None


def repeat(counts, body, carry, most=None):
    """body(i, carry) for i = 0, 1, … up to the largest of counts (an array over rows; traced); body holds a row past
    its own count by ``where``, so that every further trip leaves the rows as they are. With most (a static bound on
    the counts, a Python int) the loop runs most trips, a fixed trip count that JAX's reverse mode differentiates as
    well as its forward mode, and a row whose count passes it is a failure (``fail``); without it, a while_loop to the
    largest count (forward mode only)."""
    if most is None:
        return jax.lax.fori_loop(0, jnp.max(counts).astype(int), body, carry)
    fail(counts > most, f"a loop of more than {most} trips (its static bound)")
    return jax.lax.fori_loop(0, int(most), body, carry)


TIES = ("linear", "one-sided")
"""The derivative rules of max, min and sort at a tie of their values (a kink: a pivot at its end stop), chosen per
functional env (``connenv.jax.make(id, ties=...)``). "linear", the default: the second argument's derivative (the
command, a ramp's stop: see `connenv.core.backend.selected`), a stable sort's order of the tangents; a rule linear in
the tangents, so that reverse mode (grad, vjp) transposes it and agrees with forward mode. "one-sided": the one-sided
derivative along the tangent, ARRAYS' (the complex step's: ``model.jacobians``), which is not linear in the tangent
at a tie: forward mode only (jvp, jacfwd). Away from ties both are the derivative of the side the values pick."""

_tie_rules: list[str] = []


def check_ties(rule: str) -> str:
    """rule, if it is one of TIES; else a ValueError naming them."""
    if rule not in TIES:
        raise ValueError(f"ties={rule!r}: the tie rule of connenv.jax's max, min and sort is one of {list(TIES)}")
    return rule


@contextlib.contextmanager
def ties(rule: str):
    """Trace max, min and sort with this tie rule (one of TIES) within: read where they are called, so that the rule
    of a traced function is the one its trace saw, whenever JAX differentiates it later."""
    _tie_rules.append(check_ties(rule))
    try:
        yield
    finally:
        _tie_rules.pop()


def tie_rule() -> str:
    """The tie rule of the code being traced: the innermost ``ties`` context's, "linear" outside any."""
    return _tie_rules[-1] if _tie_rules else TIES[0]


def branch(taken, compute, otherwise, *operands):
    """compute(*operands) where some row takes the branch (taken: a flag per row; traced), else otherwise(*operands)
    (of the same shapes): ``lax.cond`` on jnp.any(taken), so that rows stepped in one call under jit (``step_rows``)
    skip work no row needs, while under vmap JAX computes both (the same numbers: the caller keeps each row's by
    ``where``). The failures ``compute`` records (``fail``) are carried out of the branch as its outputs and recorded
    here, false where it is not taken. Differentiable in both modes."""
    messages = []

    def run(*operands):
        with failures() as failed:
            result = compute(*operands)
        messages[:] = [message for _, message in failed]
        return result, [jnp.asarray(condition) for condition, _ in failed]

    shapes = jax.eval_shape(run, *operands)[1]

    def skip(*operands):
        return otherwise(*operands), [jnp.zeros(shape.shape, bool) for shape in shapes]

    result, conditions = jax.lax.cond(jnp.any(taken), run, skip, *operands)
    for condition, message in zip(conditions, messages):
        fail(condition, message)
    return result


def _selection(choose, first, name: str):
    """maximum or minimum (choose) whose derivative is the first argument's where first(a, b, ṫa, ṫb, out) holds,
    the second's elsewhere."""

    @jax.custom_jvp
    def function(a, b):
        return choose(a, b)

    @function.defjvp
    def derivative(primals, tangents):
        (a, b), (ta, tb) = primals, tangents
        out = choose(a, b)
        return out, jnp.broadcast_to(jnp.where(first(a, b, ta, tb, out), ta, tb), jnp.shape(out)).astype(out.dtype)

    function.__name__ = f"{name}_{choose.__name__}"
    return function


def one_sided(choose):
    """maximum or minimum (choose) whose forward-mode derivative at a tie is the one-sided one along the tangent,
    choose(ṫa, ṫb): ARRAYS' convention on a Jacobian's complex rows (`connenv.core.backend.selected`), where a row sits
    on the kink (the pivot at its end stop). Its tangent is not linear there: forward mode only (jvp, jacfwd)."""
    return _selection(choose, lambda a, b, ta, tb, out: jnp.where(a == b, choose(ta, tb) == ta, out == a)
                      | jnp.isnan(a), "one_sided")


def second_at_ties(choose):
    """maximum or minimum (choose) whose derivative is the side's the values pick, at a tie the second argument's (a
    NaN's where one is): a selection by the values alone, linear in the tangents (forward and reverse mode)."""
    return _selection(choose, lambda a, b, ta, tb, out: ((a != b) & (out == a)) | jnp.isnan(a), "second_at_ties")


def by_tie_rule(rules: dict):
    """The function of the tie rule being traced (``tie_rule``), picked where it is called."""

    def function(*args, **kwargs):
        return rules[tie_rule()](*args, **kwargs)

    function.__name__ = rules[TIES[0]].__name__
    return function


def sort(a, axis=-1):
    """jnp.sort on the last axis, its tangents ordered by the tie rule (``ties``): "linear", a stable sort's order of
    the values (ties in their order); "one-sided", as numpy's sort orders a Jacobian's complex rows: ties of the values
    by their tangents (the one-sided derivative; forward mode only)."""
    if axis != -1:
        raise ValueError("connenv.jax's sort sorts the last axis")
    return (_sort_last if tie_rule() == "one-sided" else _stable_sort_last)(a)


@jax.custom_jvp
def _sort_last(a):
    return jnp.sort(a, axis=-1)


@_sort_last.defjvp
def _sort_jvp(primals, tangents):
    (a,), (ta,) = primals, tangents
    order = jnp.lexsort((ta, a), axis=-1)
    return jnp.sort(a, axis=-1), jnp.take_along_axis(ta, order, axis=-1)  # the values: ties are equal


@jax.custom_jvp
def _stable_sort_last(a):
    return jnp.sort(a, axis=-1)


@_stable_sort_last.defjvp
def _stable_sort_jvp(primals, tangents):
    (a,), (ta,) = primals, tangents
    order = jnp.argsort(a, axis=-1, stable=True)
    return jnp.sort(a, axis=-1), jnp.take_along_axis(ta, order, axis=-1)


@jax.custom_jvp
def hypot(x, y):
    """jnp.hypot, its derivative ARRAYS' (the complex step's): (x ẋ + y ẏ)/hypot, 0 at the origin (a cone's apex,
    where it has none; jnp's is not 0 there). Linear in the tangents: forward and reverse mode."""
    return jnp.hypot(x, y)


@hypot.defjvp
def _hypot_jvp(primals, tangents):
    (x, y), (tx, ty) = primals, tangents
    h = jnp.hypot(x, y)
    apex = h == 0.0
    return h, jnp.where(apex, 0.0, (x * tx + y * ty) / jnp.where(apex, 1.0, h))


@jax.custom_jvp
def atan2(y, x):
    """jnp.arctan2, its derivative ARRAYS' (the complex step's): (x ẏ − y ẋ)/(x² + y²), 0 at the origin."""
    return jnp.arctan2(y, x)


@atan2.defjvp
def _atan2_jvp(primals, tangents):
    (y, x), (ty, tx) = primals, tangents
    square = y**2 + x**2
    apex = square == 0.0
    return jnp.arctan2(y, x), jnp.where(apex, 0.0, (x * ty - y * tx) / jnp.where(apex, 1.0, square))


def single_precision(x):
    """x rounded to float32's values, held in float64 with derivative 1: the complex step's convention on the goals'
    rounding (its real part rounded, its imaginary part kept; `connenv.envs.rolling_ball.single_precision`), where
    JAX's own astype(float32) would round the tangent to float32 too. x + (round(x) − x) is round(x) exactly (the
    difference is exact, by Sterbenz's lemma)."""
    x = jnp.asarray(x, float)
    return x + jax.lax.stop_gradient(x.astype(jnp.float32).astype(float) - x)


def _where(condition, a, b):
    return jnp.where(condition, a, b)


JAX = operations(
    "JAX",
    sin=jnp.sin,
    cos=jnp.cos,
    atan2=atan2,
    sqrt=jnp.sqrt,
    log=jnp.log,
    acos=jnp.arccos,
    hypot=hypot,
    abs=jnp.abs,
    copysign=jnp.copysign,
    isnan=jnp.isnan,
    maximum=jnp.maximum,
    minimum=jnp.minimum,
    where=_where,
    round=jnp.round,
    any=lambda x: True,  # see the module: a trace computes the branch, where keeps the rows that take it
    stack=jnp.stack,
    zeros_like=jnp.zeros_like,
    concat=jnp.concatenate,
    real_part=lambda x: x,
    all=jnp.all,
    sort=sort,
    maximum_one_sided=by_tie_rule({"linear": second_at_ties(jnp.maximum), "one-sided": one_sided(jnp.maximum)}),
    minimum_one_sided=by_tie_rule({"linear": second_at_ties(jnp.minimum), "one-sided": one_sided(jnp.minimum)}),
    concatenate=jnp.concatenate,
    full=jnp.full,
    ceil=jnp.ceil,
    exp=jnp.exp,
    broadcast_arrays=jnp.broadcast_arrays,
    broadcast_to=jnp.broadcast_to,
    repeat=repeat,
    longest_segment=longest_segment,
    branch=branch,
    ellipj=ellipj,
    ellipk=ellipk,
    ellipeinc=ellipeinc,
    asin=jnp.arcsin,
    asinh=jnp.arcsinh,
    fail=fail,
    sinc=jnp.sinc,
    nan_to_num=jnp.nan_to_num,
    sinh=jnp.sinh,
    cosh=jnp.cosh,
    single_precision=single_precision,
    solve=jnp.linalg.solve,
    traced=True,
)
"""The physics' operations on JAX arrays (see the module)."""

assert set(NAMES) <= set(vars(JAX)), "JAX must answer every name of FLOATS"
ANSWERED["jax"] = JAX

JAX_TASK = operations(
    "JAX_TASK",
    **{name: value for name, value in vars(JAX).items() if not name.startswith("__")},
    clip=lambda x, low, high: jnp.minimum(jnp.maximum(x, low), high),
    column=lambda x: x[..., None],
    pack=lambda parts: jnp.stack(jnp.broadcast_arrays(*parts), axis=-1).astype(jnp.float32),
    real=lambda x: jnp.asarray(x, float),
    flag=lambda x: jnp.asarray(x, bool),
    vector=lambda a: jnp.asarray(a, float),
    components=lambda a: [a[..., i] for i in range(a.shape[-1])],
)
"""The task's operations on JAX rows (BATCH's names), beside the physics'."""


def is_jax(x) -> bool:
    """Whether x is a JAX array or tracer."""
    return isinstance(x, jax.Array)
