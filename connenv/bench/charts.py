"""What the charts share: a work–precision case and its Pareto front, a stability map, and their CSV files and
figures. ``connenv.bench.precision`` and ``connenv.bench.stability`` chart the envs with them, and
``connenv.bench.rigid_body`` the free rigid body, a system without an env, in the same format."""

from __future__ import annotations

import csv
import dataclasses
import math

DIVERGED = math.inf  # the error and drift of a stepper that raised StepperError


@dataclasses.dataclass(frozen=True)
class Episode:
    label: str
    reset: dict  # reset options
    actions: object  # (steps, rng) -> array of actions
    steps: int


@dataclasses.dataclass(frozen=True)
class Case:
    env_id: str
    reference: tuple  # (integrator, options) of the reference stepper
    episodes: tuple  # the first one is timed
    error: object  # (env, reference env) -> state error at the end
    invariant: str  # what the drift measures, as printed
    drift: object  # (env, info, start) -> the invariant's drift at this step; start: the env's state at reset
    error_unit: str
    kwargs: dict = dataclasses.field(default_factory=dict)  # make kwargs of every env of the case
    steppers: tuple = ()  # (integrator, options) charted besides the common candidates


TIME_NOISE = 0.05  # relative differences of the median step time below this are within the timing's noise


def pareto(rows):
    """Mark each row on the front of (ratio, error): it did not diverge, and no other row is at least as fast and
    at least as accurate, and strictly better in one. Times within TIME_NOISE of each other count as equal, so
    that two steppers doing the same work (a rule that meets several tolerances) do not oust each other by noise."""
    for row in rows:
        row["pareto"] = not row["diverged"] and not any(
            o is not row
            and not o["diverged"]
            and o["ratio"] <= row["ratio"] * (1 + TIME_NOISE)
            and o["error"] <= row["error"]
            and (o["ratio"] < row["ratio"] * (1 - TIME_NOISE) or o["error"] < row["error"])
            for o in rows
        )


def write_precision_csv(name, case, rows, folder):
    """<name>_precision.csv in folder: a row per stepper (time, errors, drift, Pareto, default, diverged)."""
    path = folder / f"{name}_precision.csv"
    labels = [e.label for e in case.episodes]
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(
            ["integrator", "options", "us_per_step", "ratio_to_pendulum"]
            + [f"state_error_{label} ({case.error_unit})" for label in labels]
            + [f"drift ({case.invariant})", "pareto", "default", "diverged"]
        )
        for row in rows:
            writer.writerow(
                [row["integrator"], row["options"], f"{row['us_per_step']:.1f}", f"{row['ratio']:.2f}"]
                + [f"{row['errors'][label]:.3e}" for label in labels]
                + [f"{row['drift']:.3e}", row["pareto"], row["default"], row["diverged"]]
            )
    return path


STYLE = {
    "exact": ("k", "*"),
    "euler": ("tab:red", "v"),
    "semi_implicit_euler": ("tab:orange", "^"),
    "rk4": ("tab:blue", "o"),
    "dop853": ("tab:green", "s"),
    "lsoda": ("tab:purple", "D"),
    "radau": ("tab:brown", "P"),
    "magnus": ("tab:cyan", "X"),
    "splitting": ("tab:olive", "h"),
    "rk8": ("tab:pink", "p"),
    "rk8_energy": ("tab:gray", "H"),
    "gauss6": ("gold", "d"),
}


def plot_precision(name, case, rows, folder, fraction=1.0):
    """<name>_precision.png in folder: state error and drift against the time ratio, a curve per integrator."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    finite = [r[key] for r in rows for key in ("error", "drift") if 0 < r[key] < math.inf]
    top = 10 ** math.ceil(math.log10(max(finite))) * 10 if finite else 1.0
    floor = 1e-17
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    panels = [("error", f"state error at the end of the episode ({case.error_unit})"), ("drift", case.invariant)]
    for ax, (key, label) in zip(axes, panels):
        for integrator, (color, marker) in STYLE.items():
            family = [r for r in rows if r["integrator"] == integrator]
            if not family:
                continue
            xs = [r["ratio"] for r in family]
            ys = [min(max(r[key], floor), top) for r in family]
            ax.plot(xs, ys, color=color, marker=marker, ls="-", lw=0.8, label=integrator)
            for r, x, y in zip(family, xs, ys):
                if r["diverged"]:
                    ax.plot(x, y, color="red", marker="x", ms=12, mew=2, ls="")
        default = next(r for r in rows if r["default"])
        ax.plot(default["ratio"], max(default[key], floor), "o", ms=16, mfc="none", mec="k", mew=1.5)
        ax.annotate("default", (default["ratio"], max(default[key], floor)), textcoords="offset points", xytext=(8, 8))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per env step / Pendulum-v1's (same run)")
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].axhline(top, color="red", lw=0.5, ls=":")
    axes[0].text(
        axes[0].get_xlim()[1], top, "diverged (StepperError) × ", color="red", va="bottom", ha="right", fontsize=8
    )
    axes[0].legend(fontsize=8, loc="lower left")
    episodes = "; ".join(f"{e.label}, {max(round(e.steps * fraction), 1)} steps" for e in case.episodes)
    fig.suptitle(f"{case.env_id}: work–precision ({episodes}); python -m connenv.bench precision", fontsize=10)
    fig.tight_layout()
    path = folder / f"{name}_precision.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


# -- stability maps --------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class StabilityMap:
    env_id: str
    parameter: str  # as labelled
    values: tuple
    make: object  # value -> make kwargs
    reset: object  # value -> reset options
    action: object  # (value, t, dt, rng) -> action
    steps: object  # (value, dt) -> number of steps
    unbounded: object  # (env, info, start) -> True once the invariant has left its bound
    methods: tuple  # (integrator, options)
    largest: object = lambda value: 1.0  # the top of the dt grid, s


def top_of(stability_map, value, grid):
    """The largest dt tried at this parameter value."""
    return next(dt for dt in grid if dt <= stability_map.largest(value))


def cell(dt, top, grid):
    if dt == top:
        return f"≥ {dt:.2g}"
    return f"{dt:.2g}" if dt > 0 else f"< {grid[-1]:.0e}"


def write_stability_csv(name, stability_map, rows, grid, folder):
    """<name>_stability.csv in folder: the largest stable dt of each method at each value of the parameter."""
    path = folder / f"{name}_stability.csv"
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        header_row = ["method", stability_map.parameter, "largest_stable_dt_s (0: none on the grid)", "top_of_grid_s"]
        writer.writerow([*header_row, "smallest_s"])
        for method, by_value in rows.items():
            for value, dt in by_value.items():
                top = top_of(stability_map, value, grid)
                writer.writerow([method, value, f"{dt:.4g}", f"{top:.4g}", f"{grid[-1]:.0e}"])
    return path


def plot_stability(name, stability_map, rows, grid, folder):
    """<name>_stability.png in folder: the largest stable dt against the parameter, a curve per method."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.8))
    markers = "vo^sDP*"
    for k, ((method, by_value), marker) in enumerate(zip(rows.items(), markers)):
        xs = list(by_value)
        ys = [dt if dt > 0 else grid[-1] / 2 for dt in by_value.values()]
        ax.plot(xs, ys, marker=marker, ms=13 - 2 * k, mfc="none", mew=1.5, lw=1.5, label=method)  # overlaps show
    values = list(next(iter(rows.values())))
    tops = [top_of(stability_map, v, grid) for v in values]
    ax.plot(values, tops, color="grey", lw=3, alpha=0.3, label="top of the dt grid")
    ax.axhline(grid[-1] / 2, color="red", lw=0.5, ls=":")
    ax.text(0.01, grid[-1] / 2, f"none stable ≥ {grid[-1]:.0e} s", color="red", va="bottom", fontsize=8,
            transform=ax.get_yaxis_transform())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(stability_map.parameter)
    ax.set_ylabel("largest stable dt (s)")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{stability_map.env_id}: stability map\npython -m connenv.bench stability", fontsize=10)
    fig.tight_layout()
    path = folder / f"{name}_stability.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
