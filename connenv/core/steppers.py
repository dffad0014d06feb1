"""Steppers: advance a state over one control segment.

A control segment is a stretch of time of length ``tau`` on which the assigned
coordinates move at constant velocity: u(s) = u + s·u̇ for 0 ≤ s ≤ tau. A
stepper is called as ``stepper(system, y, u, u_dot, tau) -> y`` and uses the
system's ``vector_field(y, u, u_dot)``; the exact stepper uses its
``exact_segment(y, u, u_dot, tau)`` (a closed-form step for any constant u̇)
or else its ``exact_flow(y, u, tau)`` where u̇ = 0. All of them broadcast over
leading batch axes of y.

Which one an env uses is a make kwarg: ``integrator="exact"`` (closed-form flow), ``"magnus"`` (the Lie-group
step of a system with a connection, ``connenv.core.lie.Magnus``), ``"euler"``, ``"semi_implicit_euler"``,
``"rk4"``, ``"rk8"`` (DOP853's formula at a fixed step), ``"rk8_energy"`` (the same, projected onto the energy
level where u is held) or ``"gauss6"`` (Gauss–Legendre, order 6) with ``substeps`` (1 to SUBSTEPS_MAX = 1000), or
one of scipy's ``"dop853"``, ``"rk45"``, ``"lsoda"``, ``"radau"`` with ``rtol`` (RTOL_MIN = 100 ε to 1) and
``atol`` (1e-100 to 1e100); ``connenv.core.integrators.make_stepper`` builds one by name and refuses an option
outside its range, at make rather than at a step that stalls or diverges. The two Euler methods are Gymnasium
classic control's integrators (its ``kinematics_integrator``), there to compare against: they are first order, and
written here because scipy has no fixed-step methods; so is RK8, which takes scipy's tableau.

As in scipy's ``RungeKutta``, an explicit Runge–Kutta method is its Butcher tableau (`Tableau`, data) on one generic
step (`ExplicitRungeKutta`): Euler, RK4 and RK8 differ in their tableaus alone. Gauss6 keeps its tableau as data too,
but its implicit stages take a step of their own.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np
from scipy.integrate import DOP853, solve_ivp

from connenv.core.backend import concat, floats, namespace, traced


@runtime_checkable
class SteppedSystem(Protocol):
    """What every stepper needs of a system: ẏ = vector_field(y, u, u̇), broadcasting over leading axes of y."""

    def vector_field(self, y, u, u_dot): ...


@runtime_checkable
class OneStateField(Protocol):
    """A system whose vector field also takes one state as Python floats: ``vector_field_one(y, u, u̇)``, y a list,
    is ``vector_field``'s ẏ on that state as a list, by the same arithmetic (an explicit Runge–Kutta step of one
    state then runs on floats throughout)."""

    def vector_field_one(self, y, u, u_dot): ...


@runtime_checkable
class ExactSegment(Protocol):
    """A system with a closed-form step over any segment at constant u̇ (the Exact stepper uses it throughout)."""

    def exact_segment(self, y, u, u_dot, tau): ...


@runtime_checkable
class ExactFlow(Protocol):
    """A system with a closed-form flow where u is held (the Exact stepper falls back to scipy where u moves)."""

    def exact_flow(self, y, u, tau): ...


@runtime_checkable
class CanonicalSystem(Protocol):
    """A system whose state is y = (q, p) with n free coordinates q and their momenta p (semi-implicit Euler
    splits it there); a kinematic model (no p) has no n."""

    n: int


@runtime_checkable
class ConnectionSystem(Protocol):
    """A system moved by a mechanical connection (``connenv.core.lie``): its state is the coordinates of g in
    ``group`` ("SO2", "SE2", "SO3", "R2"), its assigned coordinates the shape s, and ξ = −A(s) ṡ with
    ``connection(s)`` = A(s) of shape (…, dim 𝔤, dim S) moves g in ``frame`` ("body": ġ = g ξ^, "space":
    ġ = ξ^ g). It may give ``group_velocity(s, ṡ)``, ξ as components, in closed form (the Magnus stepper's fast
    path), and with it ``segment_velocity(s, ṡ, t)``, ξ at s + t ṡ over a batch at the nodes t
    (``lie.se2_body_flow``)."""

    group: str
    frame: str

    def connection(self, s): ...


STEPPER_OPTIONS = ("substeps", "rtol", "atol")  # the make kwargs of a stepper (connenv.core.integrators)


class StepperError(ArithmeticError):
    """A stepper produced a non-finite state or could not meet its tolerance (or an env's invariant left its
    documented bound)."""


@dataclass(frozen=True)
class Tableau:
    """A Runge–Kutta method's Butcher tableau as data, sparse: ``stages``, each (c, ((j, a), …)), its node c and
    the nonzero entries a = A[i, j] of its row, and ``weights``, ((j, b), …), the nonzero b over a common
    ``divisor``. A step of length h then adds h/divisor · Σ b_j k_j, summed in the order of the weights (RK4's
    h/6 (k₁ + 2 k₂ + 2 k₃ + k₄) as it is written by hand)."""

    stages: tuple
    weights: tuple
    divisor: float = 1.0

    @classmethod
    def of_scipy(cls, method) -> Tableau:
        """The tableau of one of scipy's explicit Runge–Kutta classes (its A, B, C; no error estimator)."""
        A, C = method.A[: method.n_stages, : method.n_stages], method.C[: method.n_stages]
        stages = tuple((float(C[i]), tuple((j, float(a)) for j, a in enumerate(A[i, :i]) if a != 0.0)) for i in
                       range(len(C)))  # fmt: skip
        return cls(stages, tuple((j, float(b)) for j, b in enumerate(method.B) if b != 0.0))


EULER_TABLEAU = Tableau(((0.0, ()),), ((0, 1.0),))
RK4_TABLEAU = Tableau(
    ((0.0, ()), (0.5, ((0, 0.5),)), (0.5, ((1, 0.5),)), (1.0, ((2, 1.0),))),
    ((0, 1.0), (1, 2.0), (2, 2.0), (3, 1.0)),
    6.0,
)
DOP853_TABLEAU = Tableau.of_scipy(DOP853)
_ROOT15 = math.sqrt(15.0)
GAUSS6_TABLEAU = Tableau(
    (
        (0.5 - _ROOT15 / 10, ((0, 5 / 36), (1, 2 / 9 - _ROOT15 / 15), (2, 5 / 36 - _ROOT15 / 30))),
        (0.5, ((0, 5 / 36 + _ROOT15 / 24), (1, 2 / 9), (2, 5 / 36 - _ROOT15 / 24))),
        (0.5 + _ROOT15 / 10, ((0, 5 / 36 + _ROOT15 / 30), (1, 2 / 9 + _ROOT15 / 15), (2, 5 / 36))),
    ),
    ((0, 5 / 18), (1, 4 / 9), (2, 5 / 18)),
)


@dataclass(frozen=True)
class ExplicitRungeKutta:
    """An explicit Runge–Kutta method at ``substeps`` equal steps per segment, its ``tableau`` the subclass's (as
    scipy's ``RungeKutta`` takes C, A and B from its subclasses): stage i evaluates the vector field at
    y + h Σ_j a_ij k_j and u + (t + c_i h) u̇, the step adds h/divisor · Σ_j b_j k_j, each sum in the tableau's
    order, with the control held (u itself) where u̇ = 0. The tableau is run as the straight-line code it stands
    for (`compiled_substeps`). A single state runs on Python floats where the system gives its field on one
    state (`OneStateField`), or with ``floats_for_one_state`` (RK8's twelve stages) through an array, since a
    stage sum of a few numbers costs less than numpy's per-call overhead; a row of a batch gets the same
    arithmetic either way."""

    substeps: int = 1
    tableau: ClassVar[Tableau]
    floats_for_one_state: ClassVar[bool] = False

    def __call__(self, system, y, u, u_dot, tau):
        held = not _moving(u_dot)
        h = tau / self.substeps
        h_b = h / self.tableau.divisor  # the weights' factor
        one = type(y) is np.ndarray and y.ndim == 1 and (type(tau) is not np.ndarray or tau.ndim == 0)
        if one and (self.floats_for_one_state or conforms(system, OneStateField)):
            substeps = compiled_substeps(self.tableau, floats=True)
            y = substeps(_one_state_field(system), y.tolist(), u, u_dot, h, h_b, held, self.substeps)
            return check_finite(np.array(y), self)
        substeps = compiled_substeps(self.tableau, floats=False)
        return check_finite(substeps(system.vector_field, y, u, u_dot, h, h_b, held, self.substeps), self)


def compiled_substeps(tableau: Tableau, floats: bool):
    """The tableau's substeps as a Python function, compiled once: ``substeps(field, y, u, u̇, h, h_b, held, n)``
    takes n steps of length h (h_b = h/divisor) from y, an array (one state or rows), or with ``floats`` a list of
    one state's floats, each sum then taken component by component. Its code is `substeps_source`'s, the tableau's
    sums written out, because a loop over the stages costs more than their arithmetic on a small state (a list of
    stages, a call per sum, a product by each weight of 1)."""
    return _compiled(tableau, floats)["substeps"]


def compiled_substep(tableau: Tableau):
    """Substep i alone on arrays, ``substep(field, y, u, u̇, h, h_b, held, i)``: the body of `compiled_substeps`'
    loop, the same arithmetic, for a loop primitive (JAX's fori_loop) to run n times."""
    return _compiled(tableau, False)["substep"]


@functools.cache
def _compiled(tableau: Tableau, floats: bool) -> dict:
    namespace = {}
    code = compile(substeps_source(tableau, floats), "<Runge-Kutta substeps>", "exec")
    exec(code, namespace)  # noqa: S102 (code made here from a tableau of numbers, not from input)
    return namespace


def substeps_source(tableau: Tableau, floats: bool) -> str:
    """The code of `compiled_substeps`: per substep the control u_m at each distinct node c (once for the stages
    that share it), then for stage s ``k{s} = field(y + h * (a k_j + …), u_m, u_dot)`` and finally
    ``y = y + h_b * (b k_j + …)``, each sum left to right in the tableau's order, as `_weighted` sums, a weight of 1
    without its product (1·k = k exactly). A sum of one term whose weight is a power of two is taken as (h·a)·k, as
    RK4 is written by hand (½h·k): h·a is exact, so both are h a k rounded once, unless a·k falls below the normal
    floats. With ``floats`` each sum runs over zip(y, k_j, …)."""
    suffix = "_" if floats else ""  # a component of k_j (floats), or k_j itself

    def combined(factor, row):
        if len(row) == 1 and math.frexp(row[0][1])[0] == 0.5:  # one term, a power of two
            ((j, a),) = row
            factor, terms = (factor if a == 1.0 else f"({factor} * {a!r})"), f"k{j}{suffix}"
        else:
            terms = "(" + " + ".join(f"k{j}{suffix}" if a == 1.0 else f"{a!r} * k{j}{suffix}" for j, a in row) + ")"
        if not floats:
            return f"y + {factor} * {terms}"
        names, stages = ", ".join(f"k{j}_" for j, _ in row), ", ".join(f"k{j}" for j, _ in row)
        return f"[y_ + {factor} * {terms} for y_, {names} in zip(y, {stages})]"

    nodes = list(dict.fromkeys(c for c, _ in tableau.stages))  # the distinct c: stages at one node share its u
    body = [f"        u{m} = u if held else u + (i * h + {c!r} * h) * u_dot" for m, c in enumerate(nodes)]
    for s, (c, row) in enumerate(tableau.stages):
        body.append(f"        k{s} = field({combined('h', row) if row else 'y'}, u{nodes.index(c)}, u_dot)")
    body.append(f"        y = {combined('h_b', tableau.weights)}")
    lines = ["def substeps(field, y, u, u_dot, h, h_b, held, n):", "    for i in range(n):", *body, "    return y"]
    if not floats:  # the loop's body alone, substep i (compiled_substep)
        lines += ["", "def substep(field, y, u, u_dot, h, h_b, held, i):", *(line[4:] for line in body), "    return y"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Euler(ExplicitRungeKutta):
    """Explicit Euler with ``substeps`` equal steps per segment: y ← y + h f(y)."""

    tableau = EULER_TABLEAU


@dataclass(frozen=True)
class RK4(ExplicitRungeKutta):
    """Classic fourth-order Runge–Kutta with ``substeps`` equal steps per segment."""

    tableau = RK4_TABLEAU


@dataclass(frozen=True)
class RK8(ExplicitRungeKutta):
    """DOP853's eighth-order formula (Dormand & Prince; scipy's 12-stage tableau) at ``substeps`` equal steps per
    segment, without its step-size control: the adaptive method's work with none of its decisions, and with no
    solve_ivp around one state, which runs on Python floats (scipy's own fixed-step methods are none)."""

    tableau = DOP853_TABLEAU
    floats_for_one_state = True


@dataclass(frozen=True)
class SemiImplicitEuler:
    """Semi-implicit (symplectic) Euler with ``substeps`` equal steps per segment: with y = (q, p), q the first
    ``system.n`` entries, p ← p + h ṗ(q, p), then q ← q + h q̇(q, p_new).

    Symplectic where H separates (q̇ depends on p only, ṗ on q only: the swing), so the energy error stays
    bounded; elsewhere (the skier, whose ṗ depends on p; the Kapitza pendulum, whose q̇ depends on q through the
    pivot's velocity) it is Gymnasium's semi-implicit Euler, first order and not symplectic. A state with no p
    (y of n entries: the shell's reduced model, whose momentum is identically 0) has no update of p, and the step
    is explicit Euler's, which is the method on the full model restricted to p = 0. A system without ``n`` (the
    rolling ball, kinematic: R is neither q nor p) is refused by make_stepper.
    """

    substeps: int = 1

    def __call__(self, system, y, u, u_dot, tau):
        return check_finite(self.unchecked(system, y, u, u_dot, tau), self)

    def unchecked(self, system, y, u, u_dot, tau):
        """The step without its check of finite values (numpy's arrays, or JAX's: connenv.jax checks them)."""
        h, n = tau / self.substeps, system.n
        for i in range(self.substeps):
            u_i = u + i * h * u_dot
            p = y[..., n:] + h * system.vector_field(y, u_i, u_dot)[..., n:]
            y = concat([y[..., :n], p], axis=-1)
            y = concat([y[..., :n] + h * system.vector_field(y, u_i, u_dot)[..., :n], p], axis=-1)
        return y


@dataclass(frozen=True)
class Gauss6:
    """The three-stage Gauss–Legendre collocation method (order 6, symplectic and symmetric) at ``substeps`` equal
    steps per segment. Its tableau (GAUSS6_TABLEAU) is data as the explicit methods' are, but its A is full: each
    stage depends on all three, itself included, so the stages are not evaluated one after the other as
    ExplicitRungeKutta's are but solved together, by fixed-point iteration from K = f(y), to rounding (an
    increment below 1e-15 of the state) or StepperError after MAX_ITERATIONS sweeps, which a step too long for the
    system's fastest motion reaches. Written here because scipy has no implicit fixed-step collocation method."""

    substeps: int = 1
    tableau: ClassVar[Tableau] = GAUSS6_TABLEAU
    MAX_ITERATIONS = 100

    def __call__(self, system, y, u, u_dot, tau):
        stages, weights, divisor = self.tableau.stages, self.tableau.weights, self.tableau.divisor
        h = tau / self.substeps
        for i in range(self.substeps):
            controls = [u + (i * h + c * h) * u_dot for c, _ in stages]
            K = [system.vector_field(y, controls[0], u_dot)] * len(stages)
            for _ in range(self.MAX_ITERATIONS):
                new = [
                    system.vector_field(y + h * _weighted(row, K), control, u_dot)
                    for (_, row), control in zip(stages, controls)
                ]
                change = max(float(np.max(np.abs(np.real(h * (a - b))))) for a, b in zip(new, K))
                K = new
                if change <= 1e-15 * (1.0 + float(np.max(np.abs(np.real(y))))):  # the real parts' sweeps
                    break
            else:
                raise StepperError(f"{self}: the stages did not converge in {self.MAX_ITERATIONS} sweeps (step {h} s)")
            y = y + h / divisor * _weighted(weights, K)
        return check_finite(y, self)


@dataclass(frozen=True)
class EnergyProjected:
    """RK8 at ``substeps``, then one Newton step back onto the energy level the segment started on, where u is
    held: y ← y − (H(y) − H₀) ∇H / |∇H|², with ∇H = (−ṗ, q̇) read off Hamilton's equations (y = (q, p)). The flow
    conserves H there, so the projection removes the step's energy error, and what is left is the error of the
    phase along the level, which the method's order keeps small. The energy error the projection removes is
    also the step's error estimate: past ``atol`` (in the units of H), the segment is stepped again at twice
    the substeps, up to MAX_DOUBLINGS times. Past them the projected step is taken as it is: where the vector
    field jumps (a trail's f‴ at the end of its domain) the error is first order in the substep and doubling
    stops paying, while the projection still lands on the level; a diverged step, which the projection cannot
    bring back, leaves its energy error for the env's check (and a non-finite state raises StepperError).
    Where u moves H is not conserved, and the step is RK8's alone. The system gives ``hamiltonian(y, u)`` and
    ``n`` (HamiltonianSystem). A batch decides per row, as each row's single state would."""

    substeps: int = 1
    atol: float = 1e-8

    def __call__(self, system, y, u, u_dot, tau):
        if _moving(u_dot):
            return RK8(self.substeps)(system, y, u, u_dot, tau)
        return self._held(system, y, u, u_dot, tau, self.substeps)

    def _held(self, system, y, u, u_dot, tau, substeps):
        y_new = RK8(substeps)(system, y, u, u_dot, tau)
        excess = system.hamiltonian(y_new, u) - system.hamiltonian(y, u)
        if y_new.ndim == 1:  # one state, on Python floats (numpy's per-call overhead would double the step)
            if not abs(excess) <= self.atol and substeps < self.substeps << MAX_DOUBLINGS:
                return self._held(system, y, u, u_dot, tau, 2 * substeps)
            f = _one_state_field(system)(y_new.tolist(), u, u_dot)
            gradient = [-v for v in f[system.n :]] + f[: system.n]
            norm = sum(v * v for v in gradient)
            shift = float(excess) / norm if norm > 0.0 else 0.0
            return check_finite(np.array([y_k - shift * g_k for y_k, g_k in zip(y_new.tolist(), gradient)]), self)
        redo = ~(np.abs(np.real(excess)) <= self.atol) & (substeps < self.substeps << MAX_DOUBLINGS)
        if redo.any():
            rows = lambda a: a[redo] if np.ndim(a) else a
            y_new, excess = y_new.copy(), excess.copy()
            y_new[redo] = self._held(system, y[redo], rows(u), rows(u_dot), rows(tau), 2 * substeps)
            excess[redo] = 0.0  # those rows are projected already
        return check_finite(project_onto_level(system, y_new, u, u_dot, excess), self)


def project_onto_level(system, y_new, u, u_dot, excess):
    """EnergyProjected's Newton step on rows: y − (H(y) − H₀) ∇H / |∇H|², ∇H = (−ṗ, q̇), no shift where ∇H = 0;
    in the rows' namespace (numpy's, or JAX's for connenv.jax's traced stepper)."""
    ops = namespace(y_new)
    f = system.vector_field(y_new, u, u_dot)
    gradient = ops.concatenate([-f[..., system.n :], f[..., : system.n]], axis=-1)
    norm = (gradient * gradient).sum(axis=-1)
    positive = ops.real_part(norm) > 0.0
    shift = ops.where(positive, excess / ops.where(positive, norm, 1.0), 0.0)
    return y_new - shift[..., None] * gradient


MAX_DOUBLINGS = 6  # of EnergyProjected's substeps on one segment


@runtime_checkable
class HamiltonianSystem(Protocol):
    """A system with a state y = (q, p), n = dim q, and its Hamiltonian H(y, u) (EnergyProjected's level)."""

    n: int

    def hamiltonian(self, y, u): ...


def _one_state_field(system):
    """The system's vector field on one state as a list of floats: its vector_field_one, or vector_field through
    an array."""
    if conforms(system, OneStateField):
        return system.vector_field_one
    return lambda y, u, u_dot: system.vector_field(np.array(y), u, u_dot).tolist()


def _weighted(row, K):
    """Σ a K[j] over the (j, a) of row, left to right (for floats and arrays alike)."""
    (j, a), *rest = row
    total = a * K[j]
    for j, a in rest:
        total = total + a * K[j]
    return total


MAX_EVALUATIONS = 100_000  # of a closed-form vector field per segment: past it an adaptive stepper has failed


def evaluation_budget(system) -> int:
    """The evaluations of the system's vector field an adaptive stepper may spend on one segment: the system's own
    ``max_evaluations`` if it sets one, else MAX_EVALUATIONS. A system whose vector field is dear (a numerical
    gradient: connenv.core.mechanics' MetricField) sets a smaller budget, so that a step that cannot
    succeed ends as soon as on a closed-form field, and a stall is an error rather than minutes of work."""
    return getattr(system, "max_evaluations", MAX_EVALUATIONS)


@dataclass(frozen=True)
class Scipy:
    """One of scipy.integrate.solve_ivp's methods (DOP853, RK45, LSODA, Radau), adaptive. It raises StepperError
    when scipy gives up (a step below the spacing of floats) or after the system's evaluation budget
    (`evaluation_budget`) of the vector field in one segment, which a segment needing ever smaller steps reaches."""

    method: str = "DOP853"
    rtol: float = 1e-10
    atol: float = 1e-12

    def __call__(self, system, y, u, u_dot, tau):
        shape, evaluations, budget = np.shape(y), 0, evaluation_budget(system)

        def rhs(s, flat):
            nonlocal evaluations
            evaluations += 1
            if evaluations > budget:  # LSODA creeps on toward a singularity instead of failing
                raise StepperError(
                    f"{self} cannot meet its tolerance: {budget} evaluations of {type(system).__name__}'s vector "
                    f"field brought it to s = {s:.9g} of a segment of {tau} s"
                )
            return check_finite(system.vector_field(flat.reshape(shape), u + s * u_dot, u_dot).ravel(), self)

        sol = solve_ivp(rhs, (0.0, tau), np.ravel(y), method=self.method, rtol=self.rtol, atol=self.atol)
        if not sol.success:
            raise StepperError(f"{self}: {sol.message} over a segment of {tau} s")
        return check_finite(sol.y[:, -1].reshape(shape), self)


@dataclass(frozen=True)
class Exact:
    """The system's closed-form step: ``exact_segment`` on every segment where the system has one; else
    ``exact_flow`` on segments where u is held, and ``fallback`` where it moves. States for which the closed
    form answers NaN (outside its accurate domain) go to ``fallback`` too."""

    fallback: Scipy = Scipy()

    def __call__(self, system, y, u, u_dot, tau):
        if conforms(system, ExactSegment):
            flow = system.exact_segment(y, u, u_dot, tau)
        elif _moving(u_dot):
            return self.fallback(system, y, u, u_dot, tau)
        else:
            flow = system.exact_flow(y, u, tau)
        if (
            type(flow) is not np.ndarray
            or flow.dtype.kind != "f" and not _complex_rows(flow, y)
            or flow.shape != y.shape
        ):
            _wrong_flow(system, flow, y)
        if _all_finite(flow):  # the common case: no NaN (nor ±inf) anywhere
            return flow
        outside = np.isnan(flow.real).any(axis=-1)
        if np.any(outside):
            y = floats(y)
            u, u_dot = (np.broadcast_to(a, (*y.shape[:-1], np.shape(a)[-1])) for a in (u, u_dot))
            flow = np.array(flow, np.result_type(flow, y))  # complex where y is (a Jacobian's rows)
            tau = tau if np.ndim(tau) == 0 else np.broadcast_to(tau, outside.shape)[outside]  # one per row
            flow[outside] = self.fallback(system, y[outside], u[outside], u_dot[outside], tau)
        return check_finite(flow, self)


def _complex_rows(flow, y) -> bool:
    """Whether flow is complex because y is: the rows of a complex-step Jacobian (`connenv.envs.model`)."""
    return flow.dtype.kind == "c" and np.iscomplexobj(y)


def _wrong_flow(system, flow, y):
    """ValueError for a closed-form flow (a user's exact_segment or exact_flow) that is not a real array of the
    state's shape: written into the state, it would corrupt it."""
    method = "exact_segment" if conforms(system, ExactSegment) else "exact_flow"
    shape = np.shape(flow) if isinstance(flow, np.ndarray) else type(flow).__name__
    raise ValueError(
        f"{type(system).__name__}.{method} returned {shape} {_shown(flow)}; it must return the state after the "
        f"segment, a real array of the state's shape {np.shape(y)}"
    )


_CONFORMS: dict = {}


def conforms(system, protocol) -> bool:
    """isinstance(system, protocol), decided once per (type of system, protocol): a Protocol's isinstance is slow
    for a step's hot path."""
    key = (type(system), protocol)
    if key not in _CONFORMS:
        _CONFORMS[key] = isinstance(system, protocol)
    return _CONFORMS[key]


SMALL = 16  # numbers up to which a check on Python floats costs less than numpy's per-call overhead


def _moving(u_dot) -> bool:
    """Whether any assigned coordinate moves (u̇ ≠ 0); on Python floats for a few numbers, where numpy's reduction
    costs more than the test."""
    if type(u_dot) is not np.ndarray:
        return u_dot != 0.0
    return any(u_dot.ravel().tolist()) if u_dot.size <= SMALL else bool(u_dot.any())


def _all_finite(y) -> bool:
    """No NaN nor ±inf in y (its real parts, on a Jacobian's complex rows): on Python floats for a few numbers, else
    in one reduction."""
    y = y.real
    return all(map(math.isfinite, y.ravel().tolist())) if y.size <= SMALL else math.isfinite(y.sum())


def check_finite(y, stepper):
    """y, unless it holds a non-finite number (state or derivative; the real parts of a Jacobian's complex rows),
    which raises StepperError."""
    values = y.real
    if not (all(map(math.isfinite, values.ravel().tolist())) if values.size <= SMALL else np.isfinite(values).all()):
        raise StepperError(f"{stepper} produced a non-finite value {y}")
    return y


FLOAT32_MAX = float(np.finfo(np.float32).max)  # observations are float32: a state beyond it is observed as ±inf


def check_observable(name: str, value):
    """StepperError if an entry of value (a state's array, one state or a batch) lies beyond ±FLOAT32_MAX, where the
    float32 observation of a finite state would be ±inf. A few numbers are compared as Python floats. Traced rows
    (JAX's, connenv.jax) report it as a failure (``ops.fail``)."""
    if type(value) is not np.ndarray and traced(ops := namespace(value)):
        ops.fail(~ops.all(ops.abs(value) <= FLOAT32_MAX, axis=-1),
                 f"{name} has left float32's range ±{FLOAT32_MAX:.4g}")
        return
    value = np.real(value)
    worst = max(map(abs, value.ravel().tolist()), default=0.0) if value.size <= SMALL else np.max(np.abs(value))
    if not worst <= FLOAT32_MAX:
        raise StepperError(
            f"{name} = {_shown(value)} has left float32's range ±{FLOAT32_MAX:.4g}, in which it is observed"
        )


def _shown(value) -> str:
    """value for a message, on one line: a few numbers as a list, a larger array as its shape and extremes."""
    if not isinstance(value, np.ndarray):
        return repr(value)
    if value.size <= SMALL:
        return repr(value.tolist())
    if value.dtype.kind not in "biuf":
        return f"array {value.shape} of {value.dtype}"
    return f"array {value.shape} in [{np.min(value):.4g}, {np.max(value):.4g}]"
