"""Figures of evaluated episodes, ``python -m agents.evaluate --env ID --policy ... --plot FILE.png``: each policy's
first episode (an `agents.evaluate.Trace`), all policies in one figure on shared axes.

* An env with a mechanical connection (`connenv.geometry.local_connection` finds one): the shape path of each policy,
  a colour per policy, over the curvature map, one panel per group direction that moves (colour the curvature F₁₂,
  arrows the shape velocity −A of that direction; a 1-D shape space has no curvature, so its panels draw the group
  coordinate against the shape, arrows the direction (1, −A) that the connection moves them along). Beside them
  the simulated net motion per cycle and its first-order prediction −∬F over the cycle, where the shape returns
  near where it was a quarter into the episode (`cycles`); else the net motion of the episode and −∫A ds along its
  path.
* An active-constraint env: the phase portrait (q, p) of each policy, a column per policy on shared axes, coloured
  by the assigned coordinate u, and below them the energy (or the env's own measure) against time, every policy on
  one axis; the events of u (its jumps and the turns of its rate) are marked on both.

What to draw is read from the env's model (``state_names``, the fields of its state) and ``info``; a state's
``phase`` names q, p and u where its fields ``y`` = (q, p) and ``u`` do not.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import gymnasium as gym
import matplotlib
import numpy as np
from matplotlib import patheffects
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from scipy.spatial.transform import Rotation

from connenv import geometry
from connenv.core import mechanics

DPI = 100
PANEL = (4.2, 3.8)  # inches per panel
POINTS = 31  # grid nodes per shape direction of the curvature map
GROUP_FIELDS = ("g", "pose", "R")  # the state's field that holds the group element, by the envs' names for it
RETURN = 0.08  # a cycle ends where the shape comes this close (a fraction of the path's extent) to its start
EXCURSION = 0.3  # ... after having gone at least this far from it
JUMP = 0.25  # a step of u larger than this fraction of u's range is a jump
MARKS = 30  # events past this many (a random policy's, nearly every step) are counted, not marked
LOOP_POINTS = 120  # a cycle's loop is thinned to at most this many points for the area integral
OUTLINE = [patheffects.withStroke(linewidth=3, foreground="white")]  # paths stay visible on any colour
"""q, p (a state name each) and the candidates for u (state names; the one that moves most is drawn) where the
state's field y = (q, p) and its field u do not give them."""


def draw(env_id: str, traces: dict, path, env_kwargs: dict | None = None, seed=None, episodes=None):
    """The figure of the traces (label → Trace) of an env, written to path (PNG): `connection_figure` where the
    env has a mechanical connection, else `active_figure`; its title says which episode is drawn (reset `seed`, the
    first of `episodes`). Returns its size in pixels (width, height)."""
    env = gym.make(env_id, **(env_kwargs or {}))
    try:
        local = geometry.local_connection(env)
    except ValueError:
        local = None
    traces = {label: trace for label, trace in traces.items() if trace.states}
    figure = (connection_figure if local else active_figure)(env.unwrapped, local, traces)
    env.close()
    which = "" if seed is None else f" (reset seed {seed}" + ("" if episodes is None else f", of {episodes} evaluated") + ")"
    figure.suptitle(f"{env_id}: each policy's first episode{which}")
    Path(path).parent.mkdir(parents=True, exist_ok=True)  # --plot's check allows missing folders
    figure.savefig(path, dpi=DPI)  # a Figure without pyplot: Agg's canvas, no global state to close
    return tuple(round(float(inches) * DPI) for inches in figure.get_size_inches())


def colours(labels) -> dict:
    """A colour per policy, the same in every panel."""
    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    return {label: cycle[i % len(cycle)] for i, label in enumerate(labels)}


def fields(env, trace) -> dict:
    """The task state's fields over the episode: arrays (T + 1, ...) by field name."""
    return env.model.unpack(np.stack(trace.states))


def column(env, trace, name: str) -> np.ndarray:
    """One named entry of the packed state (``model.state_names``) over the episode."""
    return np.stack(trace.states)[:, env.model.state_names.index(name)]


def times(env, trace) -> np.ndarray:
    return column(env, trace, "t")


# -- connection envs -------------------------------------------------------------------------------------------


def connection_figure(env, local, traces):
    """Panels of the shape paths over the curvature map, one per moving group direction, and the net motions."""
    paths = {label: np.real(fields(env, trace)[local.field]).reshape(len(trace.states), -1)
             for label, trace in traces.items()}  # fmt: skip
    k = next(iter(paths.values())).shape[1]
    if k not in (1, 2):
        raise ValueError(f"{env.name}'s shape space is {k}-D: the plot draws 1-D and 2-D shape spaces")
    groups = {label: group_path(env, trace) for label, trace in traces.items()}
    low, high = geometry.window(local, np.concatenate(list(paths.values())))
    axes = [np.linspace(lo, hi, POINTS) for lo, hi in zip(low, high)]
    shapes = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, k)
    A = np.real(geometry.evaluate(local.connection, shapes))
    F = geometry.curvature(local, shapes).F[:, :, 0, 1] if k == 2 else np.zeros(A.shape[:2])
    moving = [d for d in range(local.group.dim) if np.any(F[:, d] != 0.0) or np.any(A[:, d] != 0.0)]
    figure = Figure(figsize=(PANEL[0] * (len(moving) + 1), PANEL[1] + 0.6), layout="constrained")
    panels = figure.subplots(1, len(moving) + 1, squeeze=False)
    colour = colours(traces)
    names = geometry.DIRECTIONS[local.group.name]
    for panel, d in zip(panels[0], moving):
        if k == 2:
            curvature_panel(figure, panel, axes, shapes, F[:, d], -A[:, d], paths, colour)
        else:
            line_panel(panel, axes[0], -A[:, d, 0], paths, {label: g[:, d] for label, g in groups.items()}, colour)
        colour_key = "F = 0" if k == 1 or not np.any(F[:, d]) else "curvature F"
        arrows = "−A" if k == 2 else "(1, −A)"
        ylabel = shape_name(env, local, 1) if k == 2 else f"Δ{names[d]}"
        panel.set(title=f"{names[d]}: {colour_key}, arrows {arrows}", xlabel=shape_name(env, local, 0), ylabel=ylabel)
    drawn = net_panel(panels[0][-1], local, paths, groups, moving, colour)
    handles = [Line2D([], [], color=c, lw=2, label=f"{label}: net {drawn[label]}") for label, c in colour.items()]
    figure.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), len(moving) + 1), frameon=False)
    return figure


def shape_name(env, local, i: int) -> str:
    """The name of shape coordinate i: its component's name in the state (``State.components``), else field[i]."""
    names = env.model.components.get(local.field, ())
    return names[i] if i < len(names) else f"{local.field}[{i}]"


def curvature_panel(figure, panel, axes, shapes, F, field, paths, colour):
    """The curvature of one direction (colour, symmetric about 0, with its colour bar), its −A (arrows) and the
    policies' shape paths, each starting at a dot."""
    scale = np.max(np.abs(F))
    if scale > 0.0:  # a flat direction has no colours to scale
        image = panel.pcolormesh(*axes, F.reshape(POINTS, POINTS).T, cmap="RdBu_r", vmin=-scale, vmax=scale,
                                 shading="auto")  # fmt: skip
        figure.colorbar(image, ax=panel, shrink=0.9)
    every = max(1, POINTS // 10)
    grid = shapes.reshape(POINTS, POINTS, 2)[::every, ::every].reshape(-1, 2)
    arrows = field.reshape(POINTS, POINTS, 2)[::every, ::every].reshape(-1, 2)
    if np.any(arrows):
        panel.quiver(grid[:, 0], grid[:, 1], arrows[:, 0], arrows[:, 1], color="0.35", alpha=0.7)
    for rank, (label, path) in enumerate(paths.items()):  # the first policy (the reference) on top
        panel.plot(path[:, 0], path[:, 1], color=colour[label], lw=1.5, path_effects=OUTLINE, zorder=3 - rank / 10)
        panel.plot(*path[0], "o", color=colour[label], ms=5, path_effects=OUTLINE, zorder=4)
    panel.set_xlim(axes[0][0], axes[0][-1])
    panel.set_ylim(axes[1][0], axes[1][-1])


def line_panel(panel, s, slope, paths, coordinate, colour):
    """A 1-D shape space: the group coordinate's change against the shape, arrows (1, −A) of unit length."""
    changes = np.concatenate([c - c[0] for c in coordinate.values()])
    g = np.linspace(min(changes.min(), -0.5), max(changes.max(), 0.5), 9)
    S, G = np.meshgrid(s[:: max(1, POINTS // 12)], g)
    dg = np.interp(S, s, slope)
    length = np.hypot(1.0, dg)
    panel.quiver(S, G, 1.0 / length, dg / length, color="0.35", alpha=0.7, angles="xy")
    for label, path in paths.items():
        panel.plot(path[:, 0], coordinate[label] - coordinate[label][0], color=colour[label], lw=1.5)
        panel.plot(path[0, 0], 0.0, "o", color=colour[label], ms=5)


def group_path(env, trace) -> np.ndarray:
    """The group element's coordinates over the episode (T + 1, size): the state's field among GROUP_FIELDS."""
    state = fields(env, trace)
    name = next(name for name in GROUP_FIELDS if name in state)
    return np.real(state[name]).reshape(len(trace.states), -1)


def net_motion(local, g0, g1) -> np.ndarray:
    """g₀⁻¹ g₁ (body frame; g₁ g₀⁻¹ in the space frame) in the algebra's coordinates, as `geometry.Holonomy.net`."""
    group = local.group
    m0, m1 = group.matrix(g0), group.matrix(g1)
    if group.name == "R2":
        return m1 - m0
    if group.name == "SO2":
        return np.array([g1[0] - g0[0]])
    inverse = np.linalg.inv(m0)
    m = inverse @ m1 if local.connection.frame == "body" else m1 @ inverse
    if group.name == "SO3":
        return Rotation.from_matrix(m).as_rotvec()
    return np.asarray(group.coordinates(m))


def cycles(path) -> list[tuple[int, int]]:
    """(start, end) index pairs of the cycles of a shape path (T, k): the returns nearest its shape at its start, or
    a quarter into the episode (past the transient from reset), each after an excursion of EXCURSION of the path's
    extent and within RETURN of it, or (a 2-D path) its turns about its centre past that quarter, which a loop that
    drifts as it repeats makes without returning; whichever gives most. None where the path does not come back."""
    extent = np.max(np.ptp(path, axis=0))
    if extent == 0.0 or len(path) < 8:
        return []
    found = [returns(path, start, extent) for start in (0, len(path) // 4)]
    return max(found + ([turns(path, len(path) // 4)] if path.shape[1] == 2 else []), key=len)


def turns(path, start: int) -> list[tuple[int, int]]:
    """The cycles of a 2-D path from index start: each full turn (2π of its unwrapped angle about the centre of the
    path from there) ends one."""
    relative = path[start:] - path[start:].mean(axis=0)
    angle = np.unwrap(np.arctan2(relative[:, 1], relative[:, 0]))
    turned = np.floor(np.abs(angle - angle[0]) / (2 * math.pi))
    ends = [start, *(start + 1 + np.flatnonzero(np.diff(turned) > 0)).tolist()]
    return list(itertools.pairwise(ends))


def returns(path, start: int, extent: float) -> list[tuple[int, int]]:
    """The cycles of `cycles` from the shape at index start."""
    distance = np.max(np.abs(path - path[start]), axis=1) / extent
    ends, away = [start], False
    for i in range(start + 1, len(path) - 1):
        away = away or distance[i] > EXCURSION
        if away and distance[i] < RETURN and distance[i] <= distance[i - 1] and distance[i] <= distance[i + 1]:
            ends.append(i)
            away = False
    return list(itertools.pairwise(ends))


def predictions(local, path, g, moving) -> tuple[np.ndarray, np.ndarray, str]:
    """(net, predicted, what): the mean net motion per cycle beside the mean of −∬F over each cycle's loop (its end
    moved onto its start); without cycles, the episode's net motion beside −∬F over its path closed by the chord
    from its end to its start, plus −∫A ds along that chord from start to end (on a 1-D shape space, where F = 0,
    −∫A ds along the path). These are the connection's alone: an env's momentum (the beanie's) drifts apart."""
    found = cycles(path) if path.shape[1] == 2 else []
    if found:
        net = np.mean([net_motion(local, g[a], g[b]) for a, b in found], axis=0)
        predicted = np.mean([-geometry.enclosed(local, loop(path[a:b])) for a, b in found], axis=0)
        return net[moving], predicted[moving], f"per cycle (n = {len(found)})"
    predicted = line_integral(local, path)
    if path.shape[1] == 2:
        predicted = line_integral(local, path[[0, -1]]) - geometry.enclosed(local, loop(path))
    return net_motion(local, g[0], g[-1])[moving], predicted[moving], "of the episode"


def line_integral(local, path, pieces: int = 16) -> np.ndarray:
    """−∫A ds along a polygon (M, k), each edge cut in `pieces` (midpoint rule)."""
    fractions = (np.arange(pieces) + 0.5) / pieces
    steps = np.diff(path, axis=0)
    points = (path[:-1, None, :] + fractions[:, None] * steps[:, None, :]).reshape(-1, path.shape[1])
    A = np.real(geometry.evaluate(local.connection, points)).reshape(len(steps), pieces, -1, path.shape[1])
    return -np.einsum("npdk,nk->d", A, steps) / pieces


def loop(segment) -> np.ndarray:
    """A path's shapes thinned to at most LOOP_POINTS, closed by returning to its first."""
    closed = segment[:: max(1, math.ceil(len(segment) / LOOP_POINTS))]
    return np.vstack([closed, closed[:1]])


def net_panel(panel, local, paths, groups, moving, colour) -> dict:
    """Bars of the simulated net motion (filled) and its prediction (hatched) per moving direction, per policy;
    returns what each policy's bars are (`predictions`), by label."""
    names = geometry.DIRECTIONS[local.group.name]
    width = 0.8 / (2 * len(paths))
    drawn = {}
    for i, (label, path) in enumerate(paths.items()):
        net, predicted, drawn[label] = predictions(local, path, groups[label], moving)
        x = np.arange(len(moving)) + (2 * i - len(paths)) * width + width / 2
        panel.bar(x, net, width, color=colour[label])
        panel.bar(x + width, predicted, width, color="none", edgecolor=colour[label], hatch="///")
    panel.axhline(0.0, color="0.5", lw=0.8)
    panel.set_xticks(np.arange(len(moving)), [names[d] for d in moving])
    net = "g₀⁻¹g₁" if local.connection.frame == "body" else "g₁g₀⁻¹"
    panel.set(title="net motion: simulated (filled),\npredicted −∬F (hatched)", ylabel=f"{net} (algebra coordinates)")
    return drawn


# -- active-constraint envs -------------------------------------------------------------------------------------


def active_figure(env, local, traces):
    """A phase portrait per policy (shared axes, one colour scale of u) over the energy against time."""
    n = len(traces)
    figure = Figure(figsize=(max(PANEL[0] * n, 7.0), 2 * PANEL[1]), layout="constrained")
    grid = figure.add_gridspec(2, n, height_ratios=(1.4, 1))
    portraits = [figure.add_subplot(grid[0, 0])]
    portraits += [figure.add_subplot(grid[0, i], sharex=portraits[0], sharey=portraits[0]) for i in range(1, n)]
    energy = figure.add_subplot(grid[1, :])
    q, p, u_names = roles(env)
    u = {label: assigned(env, trace, u_names) for label, trace in traces.items()}
    u_name = max(u_names, key=lambda name: max(np.ptp(column(env, t, name)) for t in traces.values()))
    low, high = min(v.min() for v in u.values()), max(v.max() for v in u.values())
    norm = matplotlib.colors.Normalize(low, high if high > low else low + 1.0)
    colour = colours(traces)
    for panel, (label, trace) in zip(portraits, traces.items()):
        image = portrait(panel, column(env, trace, q), column(env, trace, p), u[label], norm)
        panel.set_title(label, color=colour[label])
        panel.set(xlabel=with_unit(env, q), ylabel=with_unit(env, p) if panel is portraits[0] else None)
    figure.colorbar(image, ax=portraits, label=f"u = {with_unit(env, u_name)}", shrink=0.9)
    measure_panel(energy, env, traces, u, colour)
    return figure


UNITS = {"t": "s", "energy": "J", "energy E": "J"}  # names not in an env's reset state: the time, the energy


def with_unit(env, name: str) -> str:
    """name with its unit, "theta (rad)": the unit the env's reset state declares for it (its STATE), else the
    time's or the energy's; the name alone where none is known (a dimensionless quantity)."""
    field = env.STATE.fields.get(name)
    unit = field.unit if field is not None and field.unit else UNITS.get(name, "")
    return f"{name} ({unit})" if unit else name


def roles(env) -> tuple[str, str, tuple[str, ...]]:
    """The state names of q, p and the candidates for u: the state's ``phase`` where it declares one, else the
    fields y = (q, p) and u."""
    components, phase = env.model.components, type(env.state).phase
    names = env.model.state_names
    y = [name for name in names if name in components.get("y", ()) or name.startswith("y[")]
    u = tuple(name for name in names if name in components.get("u", ()) or name.startswith("u["))
    return (phase[0], phase[1], phase[2:]) if phase else (y[0], y[1], u)


def assigned(env, trace, names) -> np.ndarray:
    """u over the episode: of the candidates, the one that moves most."""
    return max((column(env, trace, name) for name in names), key=np.ptp)


def events(u) -> tuple[np.ndarray, np.ndarray]:
    """(jumps, turns): the steps i → i + 1 where u jumps (by more than JUMP of its range), and the states i where its
    rate changes sign (zero rates skipped), each excluding the other."""
    du = np.diff(u)
    span = np.ptp(u)
    jumps = np.flatnonzero(np.abs(du) > JUMP * span) if span > 0 else np.array([], int)
    moving = np.flatnonzero(du != 0.0)
    signs = np.sign(du[moving])
    return jumps, np.setdiff1d(moving[1:][signs[1:] != signs[:-1]], np.concatenate([jumps, jumps + 1]))


def shown(marks) -> np.ndarray:
    """The events to mark: none past MARKS of them (they would hide the path; the legend counts them)."""
    return marks if len(marks) <= MARKS else marks[:0]


def portrait(panel, q, p, u, norm):
    """The path (q, p), its segments coloured by u, a dot at its start, the jumps (triangles) and the turns of u's
    rate (crosses)."""
    points = np.stack([q, p], -1)
    lines = LineCollection(np.stack([points[:-1], points[1:]], 1), cmap="viridis", norm=norm, lw=1.5)
    lines.set_array(0.5 * (u[:-1] + u[1:]))
    panel.add_collection(lines)
    panel.autoscale_view()
    panel.plot(q[0], p[0], "o", color="k", ms=5)
    jumps, turns = map(shown, events(u))
    panel.plot(q[jumps], p[jumps], "^", color="crimson", ms=5, ls="none")
    panel.plot(q[turns], p[turns], "x", color="k", ms=4, ls="none")
    return lines


def measure(env, trace) -> tuple[np.ndarray, str]:
    """(values, name) over the episode: info's energy, else the Hamiltonian E = H_u at u̇ = 0 where the env's
    system has one, else the first of the env's measures, else the first number of info."""
    infos = trace.infos
    if "energy" in infos[0]:
        return np.array([info["energy"] for info in infos], float), "energy"
    system, state = getattr(env, "system", None), fields(env, trace)
    if hasattr(system, "metric") and hasattr(system, "potential") and "y" in state and "u" in state:
        y, u = np.real(state["y"]), np.real(state["u"]).reshape(len(trace.states), -1)
        n = y.shape[1] // 2
        return np.asarray(mechanics.hamiltonian(system, y[:, :n], y[:, n:], u, np.zeros_like(u)), float), "energy E"
    keys = [*env.metadata.get("measures", ()), *(k for k, v in infos[0].items() if np.ndim(v) == 0)]
    key = next(k for k in keys if k != "is_success")
    return np.array([info[key] for info in infos], float), key


def measure_panel(panel, env, traces, u, colour):
    """The energy (or the env's measure) of every policy against time, its jumps and turns of u marked."""
    name, drawn = None, {"^": 0, "x": 0}
    for label, trace in traces.items():
        values, name = measure(env, trace)
        t = times(env, trace)
        jumps, turns = events(u[label])
        panel.plot(t, values, color=colour[label], lw=1.3, label=f"{label} ({len(jumps)} jumps, {len(turns)} turns)")
        jumps, turns = shown(jumps), shown(turns)
        panel.plot(t[jumps], values[jumps], "^", color=colour[label], ms=5, ls="none")
        panel.plot(t[turns], values[turns], "x", color=colour[label], ms=4, ls="none")
        drawn["^"], drawn["x"] = drawn["^"] + len(jumps), drawn["x"] + len(turns)
    marks = [Line2D([], [], marker=marker, color="0.3", ls="none", label=text)
             for marker, text in (("^", "u jumps"), ("x", "u̇ changes sign")) if drawn[marker]]  # fmt: skip
    handles = [*panel.get_legend_handles_labels()[0], *marks]  # only the marks drawn
    panel.figure.legend(
        handles=handles, fontsize=8, loc="outside lower center", ncols=min(len(handles), 3), frameon=False
    )  # below the figure: a legend beside the axes would narrow the portraits too
    panel.set(xlabel="t (s)", ylabel=with_unit(env, name), title=f"{name} against time")
