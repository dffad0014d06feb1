"""Steppers by name: ``make_stepper(integrator, system, **options)`` builds the stepper of an env's make kwargs
``integrator=`` and its options, each checked against its range.

It stands above what it builds from, the steppers (``connenv.core.steppers``), the Lie-group step
(``connenv.core.lie``) and the checks (``connenv.core.validation``), so that none of those imports another to
build a stepper.
"""

from __future__ import annotations

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

SCIPY_METHODS = {"dop853": "DOP853", "rk45": "RK45", "lsoda": "LSODA", "radau": "Radau"}
FIXED_STEP = {
    "euler": Euler,
    "semi_implicit_euler": SemiImplicitEuler,
    "rk4": RK4,
    "rk8": RK8,
    "gauss6": Gauss6,
    "rk8_energy": EnergyProjected,
}
INTEGRATORS = ("exact", "magnus", *FIXED_STEP, *SCIPY_METHODS)


SUBSTEPS_MAX = 1000  # a fixed-step segment's substeps: with RK8's 12 stages a segment's evaluations stay within
# MAX_EVALUATIONS, the adaptive steppers' budget, so that a step ends as theirs do instead of stalling
RTOL_MIN = 100 * np.finfo(float).eps  # scipy's floor: below it solve_ivp raises rtol to it itself, with a warning
ATOL_RANGE = (1e-100, 1e100)  # an absolute tolerance, in the state's units: scipy's error norm squares y/atol and
# err/atol, which past these leave float64 (a first step of NaN, or none at all)
MAGNUS_ATOL_MIN = 1e-15  # the Lie-group step's error estimate on coordinates of g of order 1 is rounding below it


def make_stepper(integrator: str, system: SteppedSystem | None = None, **options):
    """Build a stepper by name, validating its options (and, for "exact", that the system has a flow).

    euler, semi_implicit_euler, rk4, rk8, rk8_energy and gauss6 take ``substeps`` (an integer in [1, SUBSTEPS_MAX]),
    rk8_energy also ``atol``, its energy error per segment past which it doubles the substeps (default 1e-8, in H's
    units); the scipy methods take ``rtol`` (in [RTOL_MIN, 1]: 100 times the spacing of floats at 1, up to an error
    the size of the state) and ``atol`` (in ATOL_RANGE); exact takes the scipy options for the segments where u
    moves; magnus takes ``atol``, its error bound per segment on the coordinates of g (default 1e-10, at least
    MAGNUS_ATOL_MIN), and hands ``rtol`` and ``atol`` to DOP853 for systems without a connection (the shell's full
    model). Each option out of its range is a ValueError naming it, its value and the range.
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator={integrator!r} is not one of {INTEGRATORS}")
    allowed = {"substeps"} if integrator in FIXED_STEP else {"rtol", "atol"}
    allowed |= {"atol"} if integrator == "rk8_energy" else set()
    unknown = set(options) - allowed
    if unknown:
        raise ValueError(
            f"unknown option(s) {sorted(unknown)} for integrator={integrator!r}; it takes {sorted(allowed)}"
        )
    if integrator in FIXED_STEP:
        substeps = options.get("substeps", 1)
        integer = isinstance(substeps, (int, np.integer)) and not isinstance(substeps, bool)
        if not (integer and 1 <= substeps <= SUBSTEPS_MAX):
            raise ValueError(f"substeps={substeps!r} must be an integer in [1, {SUBSTEPS_MAX}]")
        if integrator == "semi_implicit_euler" and system is not None and not isinstance(system, CanonicalSystem):
            raise ValueError(
                f"integrator='semi_implicit_euler' needs a state (q, p) split by the system's n, which "
                f"{type(system).__name__} has not (a kinematic model); 'euler' is what the method reduces to there"
            )
        if integrator == "rk8_energy" and system is not None and not isinstance(system, HamiltonianSystem):
            raise ValueError(
                f"integrator='rk8_energy' projects onto the level of the system's hamiltonian(y, u), which "
                f"{type(system).__name__} has not; 'rk8' is the step without the projection"
            )
        if integrator == "rk8_energy":
            atol = check_number("atol", options.get("atol", EnergyProjected.atol), *ATOL_RANGE)
            return EnergyProjected(int(substeps), atol)
        return FIXED_STEP[integrator](int(substeps))
    for name, low, high in (("rtol", RTOL_MIN, 1.0), ("atol", *ATOL_RANGE)):
        if name in options:
            check_number(name, options[name], low, high)
    if integrator == "magnus":
        check_number("atol", options.get("atol", Magnus.atol), MAGNUS_ATOL_MIN, ATOL_RANGE[1])
        return Magnus(options.get("atol", Magnus.atol), Scipy(**options))
    if integrator == "exact":
        if system is not None and not isinstance(system, (ExactFlow, ExactSegment)):
            raise ValueError(f"integrator='exact' needs a closed-form flow, which {type(system).__name__} has not")
        return Exact(Scipy(**options))
    return Scipy(SCIPY_METHODS[integrator], **options)
