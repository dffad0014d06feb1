"""Control paths cut into segments, and the one runner that steps a state across them.

A control segment is (u at its start, u̇, duration τ): the assigned coordinates move at constant velocity,
u(s) = u + s·u̇ for 0 ≤ s ≤ τ. A task's control over one step (a jump or a ramp to a commanded u; a commanded u̇
stopped at the end of its travel) is a short list of segments; `run_segments` steps a state across them with a
stepper and sums the change of a quantity each segment conserves, the stepper's error on it, which
`check_drift` bounds. The same runner serves one state (τ a float) and a batch of rows (τ one per row, rows
with τ = 0 skipped).

On the complex rows of a complex-step Jacobian (`connenv.envs.model`) the batch functions decide on the real parts
(which rows skip a segment, where a coordinate stops, the drift's bound), so that a complex row follows its real
row's branch and carries the derivative of that branch (a stop's time moves with u and u̇).
"""

from __future__ import annotations

import math

import numpy as np

from connenv.core.backend import ARRAYS, SCALAR, floats, namespace, traced
from connenv.core.steppers import StepperError


def run_segments(stepper, system, y, segments, conserved=None):
    """y after the control segments (u, u̇, τ), and the change of conserved(y, u, u̇) summed over them (0 without
    it). One state: every segment is stepped. A batch (τ an array over the rows): each row skips its segments of
    length 0."""
    change = 0.0
    if traced(namespace(y)):
        return _run_segments_traced(stepper, system, y, segments, conserved, namespace(y))
    for u, u_dot, tau in segments:
        if not isinstance(tau, np.ndarray) or tau.ndim == 0:  # one state; np.ndim(float) raises inside numpy: slow
            before = None if conserved is None else conserved(y, u, u_dot)
            y = stepper(system, y, u, u_dot, tau)
            if conserved is not None:
                change += conserved(y, u, u_dot) - before
            continue
        change = np.broadcast_to(change, np.shape(tau)) if np.ndim(change) == 0 else change
        rows = np.real(tau) > 0.0
        if np.all(rows):
            before = None if conserved is None else conserved(y, u, u_dot)
            y = stepper(system, y, u, u_dot, tau)
            if conserved is not None:
                change = change + (conserved(y, u, u_dot) - before)
        elif np.any(rows):
            y, u, u_dot, tau = y.copy(), u[rows], u_dot[rows], tau[rows]
            before = None if conserved is None else conserved(y[rows], u, u_dot)
            y[rows] = stepper(system, y[rows], u, u_dot, tau)
            if conserved is not None:
                increment = conserved(y[rows], u, u_dot) - before
                change = np.array(change, np.result_type(change, increment))
                change[rows] += increment
    return y, change


def _run_segments_traced(stepper, system, y, segments, conserved, ops):
    """run_segments on traced rows: every row is stepped across every segment, and a row whose segment has length 0
    keeps its y (and its change) by ``where``, the rows the numpy path skips."""
    change = 0.0
    for u, u_dot, tau in segments:
        if isinstance(tau, float):  # a length fixed by the task (dt), not by the rows
            if tau > 0.0:
                before = None if conserved is None else conserved(y, u, u_dot)
                y = stepper(system, y, u, u_dot, tau)
                change = change if conserved is None else change + (conserved(y, u, u_dot) - before)
            continue
        stepped = stepper(system, y, u, u_dot, tau)
        moving = ops.real_part(tau) > 0.0
        if conserved is not None:
            change = change + ops.where(moving, conserved(stepped, u, u_dot) - conserved(y, u, u_dot), 0.0)
        y = ops.where(moving[..., None], stepped, y)
    return y, change


def check_drift(stepper, quantity: str, drift, bound: float, unit: str = "", norm=None):
    """StepperError if |drift| (of any row of a batch) passes bound: the stepper has diverged on a quantity the
    flow conserves (the energy at held u, the spatial momentum). With norm (the quantity's norm, per row), the
    bound is relative: a row fails where |drift| > bound · norm, and the error names the first such row's. A
    Jacobian's complex rows are checked on their real parts. Traced rows (JAX's) report the failure as data
    (``ops.fail``) instead of raising."""
    ops = namespace(drift)
    if traced(ops):
        limit = bound if norm is None else bound * ops.abs(norm)
        ops.fail(~(ops.abs(drift) <= limit), f"{stepper} diverged: {quantity} past its bound")
        return
    if type(drift) is not float:  # one state's drift is a Python float; rows (complex on a Jacobian's) an array
        drift = np.real(drift)
    if norm is not None:
        drift, norm = np.atleast_1d(np.abs(drift)), np.atleast_1d(np.real(norm))
        failed = np.flatnonzero(~(drift <= bound * norm))
        if failed.size:
            i = failed[0]
            raise StepperError(
                f"{stepper} diverged: {quantity} moved by {drift[i]:.3g}{unit}, more than {bound} of its norm "
                f"{norm[i]:.3g}{unit}"
            )
        return
    worst = abs(drift) if isinstance(drift, float) or np.ndim(drift) == 0 else np.max(np.abs(drift))
    if not worst <= bound:
        raise StepperError(f"{stepper} diverged: |{quantity}| = {worst:.3g}{unit} > {bound:.3g}{unit}")


def control_segments(u: float, u_cmd: float, dt: float, max_speed: float | None = None):
    """Control segments (u at the start, u̇, duration) covering one step of length dt toward the command u_cmd.

    Without max_speed, u jumps to the command: one segment held at u_cmd. With it,
    u ramps toward the command at that speed, then holds where it got to.
    """
    if max_speed is None:
        return [(u_cmd, 0.0, dt)]
    distance = u_cmd - u
    ramp = min(dt, abs(distance) / max_speed)
    u_dot = math.copysign(max_speed, distance)
    u_after = u_cmd if ramp < dt else u + u_dot * ramp
    return [s for s in [(u, u_dot, ramp), (u_after, 0.0, dt - ramp)] if s[2] > 0.0]


def control_segments_batch(u, u_cmd, dt: float, max_speed: float | None = None):
    """control_segments over a batch of commands (arrays of one shape): the ramp and the hold, each as
    (u at the start, u̇, duration) with arrays of that shape, a duration 0 where a row has no such segment; and u at
    the end of the step. Without max_speed, one segment held at the command for dt."""
    ops = namespace(u_cmd)
    if max_speed is None:
        return [(u_cmd, ops.zeros_like(u_cmd), dt)], u_cmd
    distance = u_cmd - u
    ramp = ops.minimum(dt, ops.abs(distance) / max_speed)
    u_dot = ops.copysign(max_speed, distance)
    u_after = ops.where(ops.real_part(ramp) < dt, u_cmd, u + u_dot * ramp)  # where the step ends, the hold or not
    return [(u, u_dot, ramp), (u_after, ops.zeros_like(u_dot), dt - ramp)], u_after


def bounded_segments(u, u_dot_cmd, low, high, dt: float):
    """Control segments (u at the start, u̇, duration) covering a step of length dt in which u moves at the
    commanded velocity until a coordinate meets its bound (low below, high above, a number or one per coordinate;
    ±inf: never), where that coordinate rests for the rest of the step; and (u, u̇) at the end of the step.

    The Kapitza pendulum's pivot (bounds ±travel) and a connection's shape stop at their bounds so. Stopping is a
    jump of u̇, admissible where only u̇ enters the equations: p is continuous across it and u never leaves its
    bounds nor jumps. A ramp toward a command stops there: low = min(u, u_cmd), high = max(u, u_cmd).

    One state's few coordinates run as Python floats, where numpy's per-call overhead would dominate; max(0.0, x)
    and the comparisons take numpy's choices, so a row of bounded_segments_batch gets the same numbers."""
    u, u_dot = np.asarray(u, float).tolist(), np.asarray(u_dot_cmd, float).tolist()
    low, high = _per_coordinate(low, len(u)), _per_coordinate(high, len(u))
    u_end = [a + v * dt for a, v in zip(u, u_dot)]
    if all(lo <= end <= hi for end, lo, hi in zip(u_end, low, high)):  # no stop within the step
        u_dot = np.array(u_dot)
        return [(np.array(u), u_dot, dt)], np.array(u_end), u_dot
    stops = [hi if v > 0.0 else lo for v, lo, hi in zip(u_dot, low, high)]
    reach = [max(0.0, (stop - a) / v) if v != 0.0 else math.inf for stop, a, v in zip(stops, u, u_dot)]
    segments, start = [], 0.0
    for end in sorted({r for r in reach if r < dt} | {dt}):
        if end > start:
            segments.append((np.array(u), np.array(u_dot), end - start))
            u = [a + v * (end - start) for a, v in zip(u, u_dot)]
        u = [stop if r <= end else a for stop, r, a in zip(stops, reach, u)]
        u_dot = [0.0 if r <= end else v for r, v in zip(reach, u_dot)]
        start = end
    return segments, np.array(u), np.array(u_dot)


def _per_coordinate(bound, n: int) -> list:
    """A bound (a number or one per coordinate) as n Python floats."""
    return [bound] * n if isinstance(bound, float) else np.broadcast_to(np.asarray(bound, float), (n,)).tolist()


def bounded_segments_batch(u, u_dot_cmd, low, high, dt: float, axes=None):
    """bounded_segments over a batch (..., m): a list of m + 1 segments (u at the start (..., m), u̇ (..., m),
    durations (...)), a duration 0 where a row has fewer, and (u, u̇) at the end of the step. A segment ends where a
    coordinate reaches its bound or at dt; row i's segments of nonzero length are bounded_segments' for row i. Written
    branch-free in the rows' namespace, so that JAX traces it (connenv.jax). axes: the coordinates whose u̇ may be
    nonzero (the actuated ones; the others' u̇ must be 0), whose stops alone end segments: len(axes) + 1 segments,
    the same ones less those of length 0 that a coordinate at rest adds at dt (traced rows step every segment, the
    numpy rows skip those)."""
    ops = namespace(u_dot_cmd)
    u, u_dot = (u, u_dot_cmd) if traced(ops) else (np.array(floats(u)), np.array(floats(u_dot_cmd)))  # JAX's: immutable
    real = ops.real_part
    u_end = u + u_dot * dt
    free = ops.all((real(low) <= real(u_end)) & (real(u_end) <= real(high)), axis=-1, keepdims=True)  # no stop
    stops = ops.where(real(u_dot) > 0.0, high, low)
    moving = (real(u_dot) != 0.0) & ~free
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a subnormal u̇ never reaches: inf
        # u̇ = 1 where it is 0 or free: the rows where leaves it out are finite, for a trace's derivatives
        reach = (stops - u) / ops.where(moving, u_dot, 1.0)
        reach = ops.where(moving, ops.maximum_one_sided(reach, 0.0), math.inf)
    ending = reach if axes is None else ops.stack([reach[..., k] for k in axes], axis=-1)
    ends = ops.concatenate([ops.sort(ops.minimum_one_sided(ending, dt), axis=-1), ops.full(free.shape, dt)], axis=-1)
    segments, start = [], 0.0
    for k in range(ends.shape[-1]):
        end = ends[..., k]
        duration = end - start
        segments.append((u, u_dot, duration))
        u = ops.where(real(duration)[..., None] > 0.0, u + u_dot * duration[..., None], u)
        stopped = real(reach) <= real(end)[..., None]
        u, u_dot = ops.where(stopped, stops, u), ops.where(stopped, 0.0, u_dot)
        start = end
    return segments, u, u_dot


def control_path(u, u_cmd, dt: float, max_speed: float | None, ops=SCALAR):
    """One assigned coordinate's control segments over a step toward the command u_cmd (`control_segments`: a jump
    to it, or with max_speed a ramp and a hold), with u and u̇ as columns (…, 1), as a system takes them; and
    u at the end of the step. One state (floats) or rows (arrays over them, ops=BATCH)."""
    if ops is SCALAR:
        cuts = control_segments(u, u_cmd, dt, max_speed)
        u, u_dot, tau = cuts[-1]
        return [(np.array([a]), np.array([v]), duration) for a, v, duration in cuts], u + u_dot * tau
    cuts, u_end = control_segments_batch(u, u_cmd, dt, max_speed)
    return [(a[:, None], v[:, None], duration) for a, v, duration in cuts], u_end


def held_energy(energy, y, u, u_dot):
    """energy(y, u) where the one assigned coordinate u is held (u̇ = 0, where E is conserved), 0 where it moves: one
    state on Python floats, or rows. `run_segments`' energy as ``functools.partial(held_energy, system.energy)``."""
    if y.ndim == 1:
        (u,), (u_dot,) = u.tolist(), u_dot.tolist()
        return energy(y, u) if u_dot == 0.0 else 0.0
    return namespace(y).where(u_dot[..., 0] == 0.0, energy(y, u[..., 0]), 0.0)


def straight_path(s, s_cmd, dt: float, max_speed: float):
    """(ṡ, the duration of the motion, s at the end) of a step of several assigned coordinates s (a swimmer's joints)
    toward s_cmd: along the straight segment, the fastest coordinate at max_speed, held at s_cmd once there; over a
    batch (rows on axis 0) a duration per row, 0 with ṡ = 0 for a row that does not move. A move so small that
    max_speed / its length overflows (a subnormal command from rest) is none: s takes the command, ṡ = 0, duration 0
    (the body would not move in floats)."""
    if np.ndim(s) == 1:  # one state on floats, the same arithmetic: several times faster than numpy on two numbers
        return _straight_path_floats(s.tolist(), s_cmd.tolist(), dt, max_speed)
    if type(s) is not np.ndarray and traced(ops := namespace(s)):
        return _straight_path_traced(s, s_cmd, dt, max_speed, ops)
    delta = s_cmd - s
    largest = _largest(delta)
    reach = largest / max_speed
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # invalid: 0/0 on a Jacobian's complex rows
        scale = max_speed / largest
    moves = np.real(scale) < math.inf  # a move, resolved: largest > 0 and max_speed / largest finite
    s_dot = np.where(moves[..., None], delta * np.where(moves, scale, 0.0)[..., None], 0.0)
    ramp = np.where(moves, ARRAYS.minimum(reach, dt), 0.0)
    end = np.where((np.real(reach) <= dt)[..., None], s_cmd, s + s_dot * dt)
    return s_dot, ramp, end


def _straight_path_traced(s, s_cmd, dt, max_speed, ops):
    """straight_path on traced rows (connenv.jax): the same arithmetic, the largest |δ_k| the first one at a tie (as
    numpy's argmax on a Jacobian's complex rows)."""
    delta = s_cmd - s
    largest = ops.abs(delta[..., 0])
    for k in range(1, delta.shape[-1]):
        magnitude = ops.abs(delta[..., k])
        largest = ops.where(magnitude > largest, magnitude, largest)
    reach = largest / max_speed
    moves = largest > 0.0
    scale = max_speed / ops.where(moves, largest, 1.0)
    moves = moves & (scale < math.inf)
    s_dot = ops.where(moves[..., None], delta * ops.where(moves, scale, 0.0)[..., None], 0.0)
    ramp = ops.where(moves, ops.minimum_one_sided(reach, dt), 0.0)
    end = ops.where((reach <= dt)[..., None], s_cmd, s + s_dot * dt)
    return s_dot, ramp, end


def _largest(delta):
    """max |δ_k| on the last axis; on complex rows (a Jacobian's) the entry the real parts pick, with its derivative."""
    if not np.iscomplexobj(delta):
        return np.max(np.abs(delta), axis=-1)
    magnitude = ARRAYS.abs(delta)
    return np.take_along_axis(magnitude, np.argmax(np.real(magnitude), axis=-1)[..., None], axis=-1)[..., 0]


def _straight_path_floats(s, s_cmd, dt, max_speed):
    """straight_path of one state, its coordinates as lists of floats."""
    delta = [b - a for a, b in zip(s, s_cmd)]
    largest = max(abs(d) for d in delta)
    reach = largest / max_speed
    scale = max_speed / largest if largest > 0.0 else math.inf
    if scale == math.inf:  # no move, or one below what floats resolve (see straight_path)
        return np.zeros(len(s)), 0.0, np.array(s_cmd)
    s_dot = [d * scale for d in delta]
    end = s_cmd if reach <= dt else [a + d * dt for a, d in zip(s, s_dot)]
    return np.array(s_dot), min(reach, dt), np.array(end)
