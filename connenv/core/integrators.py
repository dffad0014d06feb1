"""Steppers by name: ``make_stepper(integrator, system, **options)`` builds the stepper of an env's make kwargs
``integrator=`` and its options, each checked against its range.

It stands above what it builds from, the steppers (``connenv.core.steppers``), the Lie-group step
(``connenv.core.lie``) and the checks (``connenv.core.validation``), so that none of those imports another to
build a stepper.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from connenv.core.lie import Magnus
from connenv.core.steppers import (
    RK4,
    RK8,
    CanonicalSystem,
    EnergyProjected,
    Euler,
    Exact,
    ExactFlow,
    ExactSegment,
    Gauss6,
    HamiltonianSystem,
    Scipy,
    SemiImplicitEuler,
    SteppedSystem,
)
from connenv.core.validation import check_number

SUBSTEPS_MAX = 1000  # a fixed-step segment's substeps: with RK8's 12 stages a segment's evaluations stay within
# MAX_EVALUATIONS, the adaptive steppers' budget, so that a step ends as theirs do instead of stalling
RTOL_MIN = 100 * np.finfo(float).eps  # scipy's floor: below it solve_ivp raises rtol to it itself, with a warning
ATOL_RANGE = (1e-100, 1e100)  # an absolute tolerance, in the state's units: scipy's error norm squares y/atol and
# err/atol, which past these leave float64 (a first step of NaN, or none at all)
MAGNUS_ATOL_MIN = 1e-15  # the Lie-group step's error estimate on coordinates of g of order 1 is rounding below it


@dataclass(frozen=True)
class Method:
    """An integrator as make_stepper builds it: ``build(**options)``, after each option is checked against its
    range in ``options`` (a ``range`` for an integer, (low, high) for a real number), on a system that is one of
    ``needs`` (protocols; any system if empty), else a ValueError that ``refusal`` words ({system}: its type)."""

    build: Callable
    options: dict
    needs: tuple = ()
    refusal: str = ""


SUBSTEPS = {"substeps": range(1, SUBSTEPS_MAX + 1)}
TOLERANCES = {"rtol": (RTOL_MIN, 1.0), "atol": ATOL_RANGE}


def exact(**tolerances):
    """The closed-form step, scipy's DOP853 at these tolerances where the system has none."""
    return Exact(Scipy(**tolerances))


def magnus(**tolerances):
    """The Lie-group step at its atol, DOP853 at these tolerances for a system without a connection."""
    return Magnus(tolerances.get("atol", Magnus.atol), Scipy(**tolerances))


SCIPY_METHODS = {"dop853": "DOP853", "rk45": "RK45", "lsoda": "LSODA", "radau": "Radau"}
METHODS = {
    "exact": Method(
        exact,
        TOLERANCES,
        (ExactFlow, ExactSegment),
        "integrator='exact' needs a closed-form flow, which {system} has not",
    ),
    "magnus": Method(magnus, {**TOLERANCES, "atol": (MAGNUS_ATOL_MIN, ATOL_RANGE[1])}),
    "euler": Method(Euler, SUBSTEPS),
    "semi_implicit_euler": Method(
        SemiImplicitEuler,
        SUBSTEPS,
        (CanonicalSystem,),
        "integrator='semi_implicit_euler' needs a state (q, p) split by the system's n, which {system} has not (a "
        "kinematic model); 'euler' is what the method reduces to there",
    ),
    "rk4": Method(RK4, SUBSTEPS),
    "rk8": Method(RK8, SUBSTEPS),
    "gauss6": Method(Gauss6, SUBSTEPS),
    "rk8_energy": Method(
        EnergyProjected,
        {**SUBSTEPS, "atol": ATOL_RANGE},
        (HamiltonianSystem,),
        "integrator='rk8_energy' projects onto the level of the system's hamiltonian(y, u), which {system} has not; "
        "'rk8' is the step without the projection",
    ),
    **{name: Method(functools.partial(Scipy, method), TOLERANCES) for name, method in SCIPY_METHODS.items()},
}
INTEGRATORS = tuple(METHODS)


def make_stepper(integrator: str, system: SteppedSystem | None = None, **options):
    """Build a stepper by name (METHODS), checking its options and that the system has what the method needs.

    euler, semi_implicit_euler, rk4, rk8, rk8_energy and gauss6 take ``substeps`` (an integer in [1, SUBSTEPS_MAX]),
    rk8_energy also ``atol``, its energy error per segment past which it doubles the substeps (default 1e-8, in H's
    units); the scipy methods take ``rtol`` (in [RTOL_MIN, 1]: 100 times the spacing of floats at 1, up to an error
    the size of the state) and ``atol`` (in ATOL_RANGE); exact takes the scipy options for the segments where u
    moves; magnus takes ``atol``, its error bound per segment on the coordinates of g (default 1e-10, at least
    MAGNUS_ATOL_MIN), and hands ``rtol`` and ``atol`` to DOP853 for systems without a connection (the shell's full
    model). Each option out of its range is a ValueError naming it, its value and the range.
    """
    method = METHODS.get(integrator)
    if method is None:
        raise ValueError(f"integrator={integrator!r} is not one of {INTEGRATORS}")
    unknown = set(options) - set(method.options)
    if unknown:
        raise ValueError(
            f"unknown option(s) {sorted(unknown)} for integrator={integrator!r}; it takes {sorted(method.options)}"
        )
    checked = {name: checked_option(name, value, method.options[name]) for name, value in options.items()}
    if system is not None and method.needs and not isinstance(system, method.needs):
        raise ValueError(method.refusal.format(system=type(system).__name__))
    return method.build(**checked)


def checked_option(name: str, value, bounds):
    """value if it lies within bounds (a range of integers, or (low, high) for a real number), else ValueError."""
    if isinstance(bounds, range):
        integer = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
        if not (integer and bounds.start <= value < bounds.stop):
            raise ValueError(f"{name}={value!r} must be an integer in [{bounds.start}, {bounds.stop - 1}]")
        return int(value)
    return check_number(name, value, *bounds)
