"""The steppers of the numpy envs, run on traced rows: the same arithmetic where it has no data-dependent branch,
and branch-free stand-ins where it has one, each named with how far it may differ from the numpy stepper.

- The explicit Runge–Kutta methods (Euler, RK4, RK8) are the numpy rows' own code (``compiled_substeps``): the
  control is evaluated at u + c h u̇ on every stage, which where u is held (u̇ = 0) is u itself. Semi-implicit Euler
  is its numpy code too (``SemiImplicitEuler.unchecked``).
- The exact step runs the system's closed form on every row; where the closed form declines (NaN: the swing's
  separatrix band) or where u moves under a system that has only a held flow, the numpy stepper calls scipy's
  adaptive DOP853, which does not trace: there the JAX step takes DOP853's eighth-order formula at FALLBACK_SUBSTEPS (8)
  fixed substeps instead, agreeing with it to the adaptive method's tolerance rather than to rounding.
- A non-finite state is a failure (``ops.fail``), not an exception.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from connenv.core.steppers import (
    ConnectionSystem,
    ExactFlow,
    ExactSegment,
    Exact,
    EnergyProjected,
    ExplicitRungeKutta,
    MAX_DOUBLINGS,
    RK8,
    SemiImplicitEuler,
    compiled_substep,
    compiled_substeps,
    conforms,
    project_onto_level,
)
from connenv.core.lie.magnus import Magnus, along, se2_body_flow
from connenv.jax.namespace import fail

FALLBACK_SUBSTEPS = 8  # RK8 substeps standing in for scipy's DOP853 (the exact step's fallback) on a segment; vmap
# computes both sides of the fallback's branch for every row, so its cost is paid on every step there


def _column(tau):
    """A segment length per row as a column (…, 1), as the numpy rows' ColumnTau hands it to a fixed-step method."""
    return tau if jnp.ndim(tau) == 0 else jnp.asarray(tau)[..., None]


def _finite(y, stepper):
    fail(~jnp.all(jnp.isfinite(y), axis=-1), f"{stepper} produced a non-finite value")
    return y


@dataclasses.dataclass(frozen=True)
class TracedRungeKutta:
    """An explicit Runge–Kutta method's numpy code on traced rows."""

    stepper: ExplicitRungeKutta

    def __call__(self, system, y, u, u_dot, tau):
        return _finite(self.unchecked(system, y, u, u_dot, tau), self.stepper)

    def unchecked(self, system, y, u, u_dot, tau):
        """The step without its check (inside a branch of lax.cond, whose failures the caller checks)."""
        tableau, n = self.stepper.tableau, self.stepper.substeps
        h = _column(tau) / n
        h_b = h / tableau.divisor
        if n == 1:
            return compiled_substeps(tableau, floats=False)(system.vector_field, y, u, u_dot, h, h_b, False, 1)
        substep = compiled_substep(tableau)
        return jax.lax.fori_loop(0, n, lambda i, y: substep(system.vector_field, y, u, u_dot, h, h_b, False, i), y)

    def __repr__(self):
        return repr(self.stepper)


@dataclasses.dataclass(frozen=True)
class TracedSemiImplicitEuler:
    """Semi-implicit Euler's numpy code (``SemiImplicitEuler.unchecked``) on traced rows, a segment length per row
    as a column."""

    stepper: SemiImplicitEuler

    def __call__(self, system, y, u, u_dot, tau):
        return _finite(self.stepper.unchecked(system, y, u, u_dot, _column(tau)), self.stepper)

    def __repr__(self):
        return repr(self.stepper)


@dataclasses.dataclass(frozen=True)
class TracedExact:
    """The system's closed-form step on every row (see the module), RK8 where it declines."""

    stepper: Exact
    fallback: TracedRungeKutta = TracedRungeKutta(RK8(FALLBACK_SUBSTEPS))

    def __call__(self, system, y, u, u_dot, tau):
        if conforms(system, ExactSegment):
            flow = system.exact_segment(y, u, u_dot, tau)
            declined = jnp.any(jnp.isnan(flow), axis=-1)
        else:
            flow = system.exact_flow(y, u, tau)
            declined = jnp.any(jnp.isnan(flow), axis=-1) | jnp.any(u_dot != 0.0, axis=-1)

        def fall_back(flow):
            numeric = self.fallback.unchecked(system, jnp.where(declined[..., None], y, jnp.zeros_like(y)), u, u_dot,
                                    jnp.where(declined, tau, 0.0))
            return jnp.where(declined[..., None], numeric, flow)

        # run only where some row declines: on rows under jit a real branch; under vmap JAX computes both
        flow = jax.lax.cond(jnp.any(declined), fall_back, lambda flow: flow, flow)
        return _finite(flow, self.stepper)

    def __repr__(self):
        return repr(self.stepper)


@dataclasses.dataclass(frozen=True)
class TracedMagnus:
    """The Lie-group step with its fixed rule (``Magnus.pieces``, chosen at the env's construction: the swimmers')
    on SE(2) in the body frame: the numpy rows' quadrature, its pieces and Gauss points fixed, so the same count on
    every row. A system without a connection (a swimmer's full model) goes to the numpy stepper's fallback, scipy's
    DOP853, which does not trace: RK8 at FALLBACK_SUBSTEPS fixed substeps stands in for it (the adaptive method's
    tolerance apart, not rounding)."""

    stepper: Magnus
    fallback: TracedRungeKutta = TracedRungeKutta(RK8(FALLBACK_SUBSTEPS))

    def __call__(self, system, y, u, u_dot, tau):
        if not conforms(system, ConnectionSystem):
            return _finite(self.fallback.unchecked(system, y, u, u_dot, tau), self.stepper)
        if self.stepper.pieces is None or (system.group, system.frame) != ("SE2", "body"):
            raise TypeError(f"{self.stepper!r} on {system.group} ({system.frame} frame) has no JAX version yet: "
                            "connenv.jax runs the Lie-group step with a fixed rule on SE(2) in the body frame")
        g = tuple(y[..., i] for i in range(y.shape[-1]))
        tau = tau if jnp.ndim(tau) == 0 else jnp.reshape(tau, -1)
        g = se2_body_flow(along(system), g, u, u_dot, tau, self.stepper.pieces, self.stepper.points)
        return _finite(jnp.stack(g, -1), self.stepper)


@dataclasses.dataclass(frozen=True)
class TracedEnergyProjected:
    """EnergyProjected's step on traced rows: RK8 at its substeps, then its Newton step onto the energy level
    (``project_onto_level``, the numpy rows' own code) where u is held. The numpy stepper retakes a row whose energy
    error passes atol at twice the substeps, up to MAX_DOUBLINGS times; here each doubling is a level of a fixed
    depth (MAX_DOUBLINGS + 1 levels, a static recursion): a level runs under lax.cond only where some row asks for it
    (on rows under jit a real branch; under vmap JAX computes every level, 2^7 − 1 times the substeps of the first),
    and a row takes the deeper level's projected state by ``where`` exactly where numpy's would recurse. So the
    decisions and the arithmetic are numpy's: a row differs from it by XLA's rounding, and by a doubling more or
    less only where its energy error sits within rounding of atol. Where u moves the step is RK8's alone, per row.
    Reverse mode differentiates it (lax.cond), as forward mode does."""

    stepper: EnergyProjected

    def __call__(self, system, y, u, u_dot, tau):
        substeps = self.stepper.substeps
        y_new = TracedRungeKutta(RK8(substeps)).unchecked(system, y, u, u_dot, tau)
        moving = jnp.any(u_dot != 0.0, axis=-1)
        projected = self._held(system, y, u, u_dot, tau, substeps, y_new, ~moving)
        return _finite(jnp.where(moving[..., None], y_new, projected), self.stepper)

    def _held(self, system, y, u, u_dot, tau, substeps, y_new, active):
        """EnergyProjected._held's rows: y_new the RK8 step at substeps; active the rows that may ask to redo."""
        excess = system.hamiltonian(y_new, u) - system.hamiltonian(y, u)
        if substeps < self.stepper.substeps << MAX_DOUBLINGS:
            redo = active & ~(jnp.abs(excess) <= self.stepper.atol)

            def deeper(y_new):
                finer = TracedRungeKutta(RK8(2 * substeps)).unchecked(system, y, u, u_dot, tau)
                return self._held(system, y, u, u_dot, tau, 2 * substeps, finer, redo)

            y_new = jnp.where(redo[..., None], jax.lax.cond(jnp.any(redo), deeper, lambda y_new: y_new, y_new), y_new)
            excess = jnp.where(redo, 0.0, excess)  # those rows are projected already
        return project_onto_level(system, y_new, u, u_dot, excess)

    def __repr__(self):
        return repr(self.stepper)


def traced_stepper(stepper, system, name: str):
    """The traced stepper of a numpy env's stepper, or a TypeError naming what is missing. system: the env's one
    system, or None for an env that steps several (the swimmers' full and reduced models): the stepper then takes
    each as it comes."""
    if isinstance(stepper, ExplicitRungeKutta):
        return TracedRungeKutta(stepper)
    if isinstance(stepper, SemiImplicitEuler):
        return TracedSemiImplicitEuler(stepper)
    if isinstance(stepper, Magnus) and stepper.pieces is not None:
        return TracedMagnus(stepper)
    if isinstance(stepper, EnergyProjected):
        return TracedEnergyProjected(stepper)
    if isinstance(stepper, Exact) and (conforms(system, ExactFlow) or conforms(system, ExactSegment)):
        return TracedExact(stepper)
    raise TypeError(
        f"{name}'s stepper {stepper!r} has no JAX version (scipy's adaptive step-size control does not trace; "
        "connenv.jax runs the exact step, the Lie-group step with a fixed rule, the energy-projected RK8, the "
        "fixed-step Runge–Kutta methods and semi-implicit Euler: make it with integrator='exact', 'euler', "
        "'semi_implicit_euler', 'rk4' or 'rk8')"
    )
