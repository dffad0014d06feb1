"""What the trained policies do in shape space, beside the analytic gait, for the connection envs.

    python -m agents.shape_space --envs ID ... --write docs/baselines/shape-space.md

For each env, the analytic controller and the shipped models (agents/pretrained/, each algorithm's best seed) run
the score's first unseen episode (reset seed agents.baselines.UNSEEN_SEED). Their shape paths are drawn over the
curvature map (agents.plots, beside the page as {name}.png), and each policy's loops are measured: the cycles of
its shape path (agents.plots.cycles: returns near where it was), their mean length in steps, the mean area they
enclose in the shape plane (signed: positive counterclockwise), the mean −∬F over each (the first-order prediction
of a cycle's net motion, connenv.geometry) and the mean net motion a cycle makes, in the directions the
connection moves.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from agents import plots
from agents.baselines import UNSEEN_SEED, short
from agents.evaluate import ENV_IDS, Trace, evaluate, expand_pretrained, make_policy
from connenv import cli, geometry

PROG = "python -m agents.shape_space"


def traces(env_id: str) -> dict:
    """label → (Trace, Episode) of the analytic controller and each shipped model on the first unseen episode."""
    found = {}
    for spec, algo in expand_pretrained(["analytic", "pretrained"], env_id, None):
        label, policy = make_policy(spec, env_id, UNSEEN_SEED, algo)
        trace = Trace()
        found[label] = trace, evaluate(env_id, policy, 1, UNSEEN_SEED, trace=trace)[0]
    return found


def area(loop) -> float:
    """The signed area a closed polygon (M, 2) encloses (shoelace): positive counterclockwise."""
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))


def loops(env, local, trace) -> dict:
    """The cycles of a policy's shape path and what they enclose and make (see the module)."""
    path = np.real(plots.fields(env, trace)[local.field]).reshape(len(trace.states), -1)
    found = plots.cycles(path)
    g = plots.group_path(env, trace)
    A = np.real(geometry.evaluate(local.connection, path))
    moving = [d for d in range(local.group.dim) if np.any(A[:, d])]
    if not found:
        return {"cycles": 0, "moving": moving}
    return {
        "cycles": len(found),
        "steps": float(np.mean([b - a for a, b in found])),
        "area": float(np.mean([area(plots.loop(path[a:b])) for a, b in found])),
        "predicted": np.mean([-geometry.enclosed(local, plots.loop(path[a:b])) for a, b in found], axis=0)[moving],
        "net": np.mean([plots.net_motion(local, g[a], g[b]) for a, b in found], axis=0)[moving],
        "moving": moving,
    }


def section(env_id: str, folder: Path) -> list[str]:
    """The env's part of the page: its figure and its table of loops."""
    import gymnasium as gym

    found = traces(env_id)
    picture = folder / f"{short(env_id)}.png"
    plots.draw(env_id, {label: trace for label, (trace, _) in found.items()}, picture)
    env = gym.make(env_id).unwrapped
    local = geometry.local_connection(env)
    names = geometry.DIRECTIONS[local.group.name]
    lines = [f"## {short(env_id)}", "", f"![{short(env_id)} in shape space]({folder.name}/{picture.name})", "",
             "| policy | success | steps | cycles | steps per cycle | area per cycle | −∬F per cycle | net per cycle |",
             "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for label, (trace, episode) in found.items():
        stats = loops(env, local, trace)
        cells = ["–"] * 4
        if stats["cycles"]:
            directions = [names[d] for d in stats["moving"]]
            vector = lambda v: ", ".join(f"{n} {x:+.3g}" for n, x in zip(directions, v))  # noqa: E731
            cells = [f"{stats['steps']:.1f}", f"{stats['area']:+.3g}", vector(stats["predicted"]), vector(stats["net"])]
        success = "yes" if episode.success else "no"
        lines.append(f"| {label} | {success} | {episode.length} | {stats['cycles']} | {' | '.join(cells)} |")
    env.close()
    return [*lines, ""]


def page(envs, folder: Path) -> str:
    lines = [
        "# What the policies do in shape space", "",
        f"Written by `{PROG} --envs {' '.join(envs)} --write docs/baselines/shape-space.md`: the analytic controller and the shipped models on "
        f"the score's first unseen episode (reset seed {UNSEEN_SEED}). The figures draw each policy's shape path over "
        "the curvature map (colour F, arrows −A) and the net motion beside its first-order prediction. The tables "
        "measure the loops: a cycle is a return of the shape near where it was; its area is signed (positive "
        "counterclockwise in the plot's axes), −∬F its predicted net motion and the last column the simulated one, "
        "per direction of the group the connection moves (x, y in the body frame, θ in rad; the ball's ω in rad).",
        "",
    ]  # fmt: skip
    for env_id in envs:
        lines += section(env_id, folder)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> str:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", nargs="+", required=True, choices=ENV_IDS, metavar="ID",
                        help="connection envs with shipped models")
    parser.add_argument("--write", type=cli.writable_file, required=True, help="the markdown page")
    args = parser.parse_args(argv)
    path = Path(args.write)
    folder = path.with_suffix("")
    folder.mkdir(parents=True, exist_ok=True)
    text = page(args.envs, folder)
    path.write_text(text)
    print(text)
    return text


if __name__ == "__main__":
    cli.run(main, PROG)
