"""Steppers for a batch of independent states, each row stepped as the single-state stepper would step it.

RK4 and the closed-form flows broadcast over leading axes already: row i of a batch gets the arithmetic a
single state gets. scipy's adaptive ``solve_ivp`` does not: on a flattened batch it takes one step size for all
rows, chosen by the error of the whole vector, so row i would not follow the path of the same state stepped
alone. ``EmbeddedRK`` is scipy's explicit Runge–Kutta driver (``scipy.integrate._ivp.rk``: the initial step of
Hairer, Nørsett & Wanner II.4, the error norm and the step-size control with its SAFETY, MIN_FACTOR and
MAX_FACTOR) rewritten over a batch with one step size, accept/reject decision and clock per row, using scipy's own
DOP853 and RK45 tableaus: for a single row it makes the decisions solve_ivp makes, and agrees with it to
rounding (tests). Like the Scipy stepper, it raises StepperError for a row whose step size falls below the
spacing of floats or that exceeds MAX_EVALUATIONS evaluations of the vector field in one segment. The implicit
and multistep methods (LSODA, Radau) are not rewritten; ``batched`` runs them one row at a time.

On the complex rows of a complex-step Jacobian (`connenv.envs.model`), EmbeddedRK's decisions (the initial step, the
error norm, acceptance, the next step size, the end of the segment) read the real parts alone: a complex row takes
exactly the steps of its real row, so that its imaginary part is the derivative of that same discrete map, and a
segment's length that carries a derivative (a stop's time) carries it through the last step, which ends there.
RowByRow (LSODA, Radau) refuses complex rows.

A batch may take one segment length tau per row (shape of the batch), where the rows' control segments differ
(ramps, the Kapitza pivot's end stops); the steppers here take it, and ``batched`` hands it to the others (RK4,
the Euler steppers) as a column.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.integrate import DOP853, RK45

from connenv.core.backend import ARRAYS, floats
from connenv.core.lie import Magnus
from connenv.core.steppers import MAX_EVALUATIONS, Exact, Scipy, StepperError

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # scipy.integrate._ivp.rk's step-size control
TABLEAUS = {"DOP853": DOP853, "RK45": RK45}


@dataclass(frozen=True)
class EmbeddedRK:
    """scipy's DOP853 or RK45 with per-row adaptive steps over a batch of states (..., n)."""

    method: str = "DOP853"
    rtol: float = 1e-10
    atol: float = 1e-12

    def __call__(self, system, y, u, u_dot, tau):
        y = floats(y)
        n = y.shape[-1]
        rows = y.reshape(-1, n).copy()
        lead = y.shape[:-1]
        u = np.broadcast_to(u, (*lead, np.shape(u)[-1])).reshape(len(rows), -1)
        u_dot = np.broadcast_to(u_dot, u.shape[:-1] + (np.shape(u_dot)[-1],)).reshape(len(rows), -1)

        evaluations = np.zeros(len(rows), int)  # per row, with Scipy's budget per segment (the system's, if it has one)
        budget = getattr(system, "max_evaluations", MAX_EVALUATIONS)

        def rhs(s, states, idx):
            """ẏ at times s of the rows idx (a slice or an index array)."""
            evaluations[idx] += 1
            if evaluations.max() > budget:
                over = np.flatnonzero(evaluations > budget)
                raise StepperError(
                    f"{self} cannot meet its tolerance: {budget} evaluations of the vector field brought "
                    f"rows {over.tolist()} to s = {np.atleast_1d(s)[0]:.9g} of segments of {tau[over].tolist()} s"
                )
            u_rows, u_dot_rows = u[idx], u_dot[idx]
            f = system.vector_field(states, u_rows + s[:, None] * u_dot_rows, u_dot_rows)
            if not np.all(np.isfinite(f.real)):
                raise StepperError(f"{self} produced a non-finite derivative {f[~np.isfinite(f.real).all(-1)]}")
            return f

        everyone = slice(None)
        tau = np.broadcast_to(np.reshape(tau, (-1,) if np.ndim(tau) else ()), (len(rows),))  # one per row
        t = np.zeros(len(rows), tau.dtype if tau.dtype.kind == "c" else float)
        f = rhs(t, rows, everyone)
        h_abs = self._initial_step(rhs, rows, f, tau.real, everyone)
        rejected = np.zeros(len(rows), bool)
        active = np.arange(len(rows))
        while active.size:
            idx = everyone if active.size == len(rows) else active  # a slice, cheaper than fancy indexing
            active = active[self._attempt(rhs, idx, t, rows, f, h_abs, rejected, tau)]
        return rows.reshape(y.shape)

    def _initial_step(self, rhs, y0, f0, tau, idx):
        """scipy.integrate._ivp.common.select_initial_step, per row."""
        order = TABLEAUS[self.method].error_estimator_order
        y0, f0 = y0.real, f0.real
        scale = self.atol + np.abs(y0) * self.rtol
        d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
        with np.errstate(divide="ignore", invalid="ignore"):
            h0 = np.where((d0 < 1e-5) | (d1 < 1e-5), 1e-6, 0.01 * d0 / d1)
        h0 = np.minimum(h0, tau)
        f1 = rhs(h0, y0 + h0[:, None] * f0, idx)
        d2 = _rms((f1.real - f0) / scale) / h0
        with np.errstate(divide="ignore"):
            h1 = np.where(
                (d1 <= 1e-15) & (d2 <= 1e-15),
                np.maximum(1e-6, h0 * 1e-3),
                (0.01 / np.maximum(d1, d2)) ** (1.0 / (order + 1)),
            )
        return np.minimum(np.minimum(100 * h0, h1), tau)

    def _attempt(self, rhs, idx, t, y, f, h_abs, rejected, tau):
        """One step attempt for the rows idx (scipy's RungeKutta._step_impl, one pass of its loop); updates the
        per-row arrays in place and returns the mask, over idx, of the rows that have not reached tau."""
        tableau = TABLEAUS[self.method]
        t0, y0, f0, tau = t[idx], y[idx], f[idx], tau[idx]
        min_step = 10 * np.abs(np.nextafter(t0.real, np.inf) - t0.real)
        h = np.where(rejected[idx], h_abs[idx], np.maximum(h_abs[idx], min_step))
        if np.any(h < min_step):
            bad = np.arange(len(t))[idx][h < min_step]
            raise StepperError(
                f"{self}: required step size is less than spacing between numbers at rows {bad.tolist()} "
                f"(t = {t[bad].tolist()} of segments of {tau[h < min_step].tolist()} s)"
            )
        t_new = ARRAYS.minimum(t0 + h, tau)
        h = t_new - t0
        K = [f0]
        for s in range(1, tableau.n_stages):
            K.append(rhs(t0 + tableau.C[s] * h, y0 + _combine(tableau.A[s, :s], K) * h[:, None], idx))
        y_new = y0 + h[:, None] * _combine(tableau.B, K)
        f_new = rhs(t0 + h, y_new, idx)
        K.append(f_new)
        scale = self.atol + np.maximum(np.abs(y0.real), np.abs(y_new.real)) * self.rtol
        error = self._error_norm(tableau, K, h.real, scale)
        with np.errstate(divide="ignore"):
            growth = SAFETY * error ** (-1.0 / (tableau.error_estimator_order + 1))
        accept = error < 1
        factor = np.where(error == 0, MAX_FACTOR, np.minimum(MAX_FACTOR, growth))
        factor = np.where(rejected[idx], np.minimum(1.0, factor), factor)
        h_abs[idx] = np.where(accept, h.real * factor, h.real * np.maximum(MIN_FACTOR, growth))
        rejected[idx] = ~accept
        t[idx] = np.where(accept, t_new, t0)
        y[idx] = np.where(accept[:, None], y_new, y0)
        f[idx] = np.where(accept[:, None], f_new, f0)
        return ~accept | (t_new.real < tau.real)

    def _error_norm(self, tableau, K, h, scale):
        """scipy's error norm of the step, on the real parts."""
        n = scale.shape[-1]
        if self.method == "RK45":
            return np.sqrt(np.sum((_combine(tableau.E, K).real * h[:, None] / scale) ** 2, axis=-1) / n)
        err5 = np.sum((_combine(tableau.E5, K).real / scale) ** 2, axis=-1)
        err3 = np.sum((_combine(tableau.E3, K).real / scale) ** 2, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            error = np.abs(h) * err5 / np.sqrt((err5 + 0.01 * err3) * n)
        return np.where((err5 == 0) & (err3 == 0), 0.0, error)


@dataclass(frozen=True)
class ColumnTau:
    """A fixed-step stepper (RK4, ...) given one segment length per row: tau as a column (..., 1), so that it
    broadcasts against the states (..., n) as a scalar does."""

    stepper: object

    def __call__(self, system, y, u, u_dot, tau):
        return self.stepper(system, y, u, u_dot, tau if np.ndim(tau) == 0 else np.asarray(tau)[..., None])

    def __repr__(self):
        return repr(self.stepper)


@dataclass(frozen=True)
class RowByRow:
    """A stepper applied to one row of the batch at a time (for LSODA and Radau, whose step control is not
    rewritten here): slow, but row i is exactly the single state's step."""

    stepper: Scipy

    def __call__(self, system, y, u, u_dot, tau):
        if any(np.iscomplexobj(a) for a in (y, u, u_dot, tau)):
            raise TypeError(
                f"{self.stepper} cannot step complex rows (a complex-step Jacobian's): scipy's {self.stepper.method} "
                "is not rewritten over rows; use an explicit method (dop853, rk45, rk4, rk8) or the exact step"
            )
        y = np.asarray(y, float)
        u = np.broadcast_to(u, (*y.shape[:-1], np.shape(u)[-1]))
        u_dot = np.broadcast_to(u_dot, u.shape)
        tau = np.broadcast_to(tau, y.shape[:-1])
        out = np.empty_like(y)
        for i in np.ndindex(y.shape[:-1]):
            out[i] = self.stepper(system, y[i], u[i], u_dot[i], float(tau[i]))
        return out


def batched(stepper):
    """The stepper to use on a batch so that row i follows the single-state stepper's path (see the module)."""
    if isinstance(stepper, Scipy):
        if stepper.method in TABLEAUS:
            return EmbeddedRK(stepper.method, stepper.rtol, stepper.atol)
        return RowByRow(stepper)
    if isinstance(stepper, (Exact, Magnus)):  # Magnus steps a batch row by row already, with per-row substeps
        return dataclasses.replace(stepper, fallback=batched(stepper.fallback))
    return ColumnTau(stepper)


def _combine(weights, K):
    """Σ_j weights[j] K[j] over the nonzero weights, elementwise: no BLAS call, whose threads stall on a busy
    machine, and the same arithmetic for a row whatever the batch around it."""
    terms = [w * k for w, k in zip(weights, K) if w != 0.0]
    total = terms[0]
    for term in terms[1:]:
        total = total + term
    return total


def _rms(x):
    """The RMS norm of each row, scipy's ``norm`` of ``_ivp.common``."""
    return np.sqrt(np.sum(x * x, axis=-1) / x.shape[-1])
