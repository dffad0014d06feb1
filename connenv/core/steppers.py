"""Steppers: advance a state over one control segment.

A control segment is a stretch of time of length ``tau`` on which the assigned
coordinates move at constant velocity: u(s) = u + s·u̇ for 0 ≤ s ≤ tau. A
stepper is called as ``stepper(system, y, u, u_dot, tau) -> y`` and uses the
system's ``vector_field(y, u, u_dot)``; the exact stepper uses its
``exact_segment(y, u, u_dot, tau)`` (a closed-form step for any constant u̇)
or else its ``exact_flow(y, u, tau)`` where u̇ = 0. All of them broadcast over
leading batch axes of y.

Which one an env uses is a make kwarg: ``integrator="exact"`` (closed-form
flow), ``"magnus"`` (the fourth-order Lie-group step of a system with a
connection, ``connenv.core.lie.Magnus``), ``"euler"``, ``"semi_implicit_euler"`` or ``"rk4"`` with ``substeps``, or
one of scipy's ``"dop853"``, ``"rk45"``, ``"lsoda"``, ``"radau"`` with ``rtol``
and ``atol``. The two Euler methods are Gymnasium classic control's
integrators (its ``kinematics_integrator``), there to compare against: they are
first order, and written here because scipy has no fixed-step methods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from scipy.integrate import solve_ivp


@runtime_checkable
class SteppedSystem(Protocol):
    """What every stepper needs of a system: ẏ = vector_field(y, u, u̇), broadcasting over leading axes of y."""

    def vector_field(self, y, u, u_dot): ...


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


class StepperError(ArithmeticError):
    """A stepper produced a non-finite state or could not meet its tolerance (or an env's invariant left its
    documented bound)."""


@dataclass(frozen=True)
class RK4:
    """Classic fourth-order Runge–Kutta with ``substeps`` equal steps per segment."""

    substeps: int = 1

    def __call__(self, system, y, u, u_dot, tau):
        h = tau / self.substeps
        held = not np.any(u_dot)  # then u(s) = u throughout: skip the control's array arithmetic
        for i in range(self.substeps):
            s = i * h
            u0, u_half, u1 = (u, u, u) if held else (u + s * u_dot, u + (s + 0.5 * h) * u_dot, u + (s + h) * u_dot)
            k1 = system.vector_field(y, u0, u_dot)
            k2 = system.vector_field(y + 0.5 * h * k1, u_half, u_dot)
            k3 = system.vector_field(y + 0.5 * h * k2, u_half, u_dot)
            k4 = system.vector_field(y + h * k3, u1, u_dot)
            y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return _finite(y, self)


@dataclass(frozen=True)
class Euler:
    """Explicit Euler with ``substeps`` equal steps per segment: y ← y + h f(y)."""

    substeps: int = 1

    def __call__(self, system, y, u, u_dot, tau):
        h = tau / self.substeps
        for i in range(self.substeps):
            y = y + h * system.vector_field(y, u + i * h * u_dot, u_dot)
        return _finite(y, self)


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
        h, n = tau / self.substeps, system.n
        for i in range(self.substeps):
            u_i = u + i * h * u_dot
            p = y[..., n:] + h * system.vector_field(y, u_i, u_dot)[..., n:]
            y = np.concatenate([y[..., :n], p], axis=-1)
            y = np.concatenate([y[..., :n] + h * system.vector_field(y, u_i, u_dot)[..., :n], p], axis=-1)
        return _finite(y, self)


MAX_EVALUATIONS = 100_000  # of the vector field per segment: past it an adaptive stepper has failed (about 1 s)


@dataclass(frozen=True)
class Scipy:
    """One of scipy.integrate.solve_ivp's methods (DOP853, RK45, LSODA, Radau), adaptive. It raises StepperError
    when scipy gives up (a step below the spacing of floats) or after MAX_EVALUATIONS evaluations of the vector
    field in one segment, which a segment needing ever smaller steps reaches."""

    method: str = "DOP853"
    rtol: float = 1e-10
    atol: float = 1e-12

    def __call__(self, system, y, u, u_dot, tau):
        shape, evaluations = np.shape(y), 0

        def rhs(s, flat):
            nonlocal evaluations
            evaluations += 1
            if evaluations > MAX_EVALUATIONS:  # LSODA creeps on toward a singularity instead of failing
                raise StepperError(
                    f"{self} cannot meet its tolerance: {MAX_EVALUATIONS} evaluations of the vector field brought "
                    f"it to s = {s:.9g} of a segment of {tau} s"
                )
            return _finite(system.vector_field(flat.reshape(shape), u + s * u_dot, u_dot).ravel(), self)

        sol = solve_ivp(rhs, (0.0, tau), np.ravel(y), method=self.method, rtol=self.rtol, atol=self.atol)
        if not sol.success:
            raise StepperError(f"{self}: {sol.message} over a segment of {tau} s")
        return _finite(sol.y[:, -1].reshape(shape), self)


@dataclass(frozen=True)
class Exact:
    """The system's closed-form step: ``exact_segment`` on every segment where the system has one; else
    ``exact_flow`` on segments where u is held, and ``fallback`` where it moves. States for which the closed
    form answers NaN (outside its accurate domain) go to ``fallback`` too."""

    fallback: Scipy = Scipy()

    def __call__(self, system, y, u, u_dot, tau):
        if conforms(system, ExactSegment):
            flow = system.exact_segment(y, u, u_dot, tau)
        elif np.any(u_dot != 0.0):
            return self.fallback(system, y, u, u_dot, tau)
        else:
            flow = system.exact_flow(y, u, tau)
        if math.isfinite(flow.sum()):  # the common case, in one reduction: no NaN (nor ±inf) anywhere
            return flow
        outside = np.isnan(flow).any(axis=-1)
        if np.any(outside):
            y = np.asarray(y, float)
            u, u_dot = (np.broadcast_to(a, (*y.shape[:-1], np.shape(a)[-1])) for a in (u, u_dot))
            flow = np.array(flow)
            tau = tau if np.ndim(tau) == 0 else np.broadcast_to(tau, outside.shape)[outside]  # one per row
            flow[outside] = self.fallback(system, y[outside], u[outside], u_dot[outside], tau)
        return _finite(flow, self)


SCIPY_METHODS = {"dop853": "DOP853", "rk45": "RK45", "lsoda": "LSODA", "radau": "Radau"}
FIXED_STEP = {"euler": Euler, "semi_implicit_euler": SemiImplicitEuler, "rk4": RK4}
INTEGRATORS = ("exact", "magnus", *FIXED_STEP, *SCIPY_METHODS)
STEPPER_OPTIONS = ("substeps", "rtol", "atol")


def make_stepper(integrator: str, system: SteppedSystem | None = None, **options):
    """Build a stepper by name, validating its options (and, for "exact", that the system has a flow).

    euler, semi_implicit_euler and rk4 take ``substeps`` (int ≥ 1); the scipy
    methods take ``rtol`` and ``atol`` (> 0); exact takes the scipy options for
    the segments where u moves; magnus takes ``atol``, its error bound per
    segment on the coordinates of g (default 1e-10), and hands ``rtol`` and
    ``atol`` to DOP853 for systems without a connection (the shell's full model).
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator={integrator!r} is not one of {INTEGRATORS}")
    allowed = {"substeps"} if integrator in FIXED_STEP else {"rtol", "atol"}
    unknown = set(options) - allowed
    if unknown:
        raise ValueError(
            f"unknown option(s) {sorted(unknown)} for integrator={integrator!r}; it takes {sorted(allowed)}"
        )
    if integrator in FIXED_STEP:
        substeps = options.get("substeps", 1)
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
            raise ValueError(f"substeps={substeps!r} must be an integer ≥ 1")
        if integrator == "semi_implicit_euler" and system is not None and not isinstance(system, CanonicalSystem):
            raise ValueError(
                f"integrator='semi_implicit_euler' needs a state (q, p) split by the system's n, which "
                f"{type(system).__name__} has not (a kinematic model); 'euler' is what the method reduces to there"
            )
        return FIXED_STEP[integrator](int(substeps))
    for name in ("rtol", "atol"):
        value = options.get(name, 1.0)
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
            raise ValueError(f"{name}={value!r} must be a finite number > 0")
    if integrator == "magnus":
        from connenv.core.lie import Magnus  # lie builds on this module

        return Magnus(options.get("atol", Magnus.atol), Scipy(**options))
    if integrator == "exact":
        if system is not None and not isinstance(system, (ExactFlow, ExactSegment)):
            raise ValueError(f"integrator='exact' needs a closed-form flow, which {type(system).__name__} has not")
        return Exact(Scipy(**options))
    return Scipy(SCIPY_METHODS[integrator], **options)


_CONFORMS: dict = {}


def conforms(system, protocol) -> bool:
    """isinstance(system, protocol), decided once per (type of system, protocol): a Protocol's isinstance is slow
    for a step's hot path."""
    key = (type(system), protocol)
    if key not in _CONFORMS:
        _CONFORMS[key] = isinstance(system, protocol)
    return _CONFORMS[key]


def _finite(y, stepper):
    """y, unless it holds a non-finite number (state or derivative), which raises StepperError."""
    if not np.all(np.isfinite(y)):
        raise StepperError(f"{stepper} produced a non-finite value {y}")
    return y
