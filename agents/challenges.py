"""The open challenges' page: JAX PPO's curves at the challenge budget, and where the runs stand.

    python -m agents.challenges [--runs runs/challenges] [--write docs/baselines/challenges.md]

reads the run folders of ``python train.py --backend jax --env ID --seeds 5 --hyperparams
agents/hyperparams/ppo_jax_challenges.yml --runs runs/challenges --eval-seed 100000`` for KapitzaSwingUp-v0 and
RollingBallPose-v0 — each seed's periodic evaluations (evaluations.npz: the deterministic policy on the JAX env),
its training curve (progress.csv: the training episodes' success, the wall time) and its results.json (the final
policy on the numpy env's unseen episodes, reset seeds 100000–100099, with the status: finished, or interrupted at
the steps it reached) — and writes the page and its chart (challenges.png beside it): success against steps and
against wall time, per seed.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

from connenv import cli

PROG = "python -m agents.challenges"
CHALLENGES = ("connenv/KapitzaSwingUp-v0", "connenv/RollingBallPose-v0")
HYPERPARAMS = "agents/hyperparams/ppo_jax_challenges.yml"


def seeds_of(runs: Path, env_id: str) -> list[Path]:
    short = env_id.split("/")[-1]
    return sorted((p for p in runs.glob(f"{short}_ppo_jax_s*") if p.name.rsplit("_s", 1)[1].isdigit()),
                  key=lambda p: int(p.name.rsplit("_s", 1)[1]))  # fmt: skip


def curve(folder: Path) -> dict:
    """A seed's periodic evaluations (steps, mean success, mean return) and its wall time at each."""
    data = np.load(folder / "evaluations.npz") if (folder / "evaluations.npz").is_file() else None
    rows = []
    if (folder / "progress.csv").is_file():
        with open(folder / "progress.csv") as file:
            rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(file)]
    seconds = {int(row["timesteps"]): row["seconds"] for row in rows}
    if data is None:
        return {"steps": [], "success": [], "return": [], "seconds": []}
    steps = data["timesteps"].tolist()
    return {"steps": steps, "success": data["successes"].mean(1).tolist(), "return": data["results"].mean(1).tolist(),
            "seconds": [seconds.get(s, np.nan) for s in steps]}  # fmt: skip


def final(folder: Path) -> dict | None:
    path = folder / "results.json"
    return json.loads(path.read_text()) if path.is_file() else None


def chart(curves: dict[str, list[dict]], path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(curves), 3, figsize=(14, 3.4 * len(curves)), squeeze=False)
    for row, (env_id, seeds) in enumerate(curves.items()):
        for i, c in enumerate(seeds):
            axes[row, 0].plot(c["steps"], c["success"], lw=1, label=f"seed {i}")
            axes[row, 1].plot(np.asarray(c["seconds"]) / 60, c["success"], lw=1)
            axes[row, 2].plot(c["steps"], c["return"], lw=1)
        for ax, x in zip(axes[row], ("environment steps per seed", "wall time of the run (min)")):
            ax.set(xlabel=x, ylabel="success (deterministic, JAX env)", ylim=(-0.02, 1.02),
                   title=env_id.split("/")[-1])  # fmt: skip
        axes[row, 2].set(xlabel="environment steps per seed", ylabel="return (deterministic, JAX env)",
                         title=env_id.split("/")[-1])  # fmt: skip
        axes[row, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def page(runs: Path, path: Path, command: str) -> str:
    curves, lines = {}, []
    for env_id in CHALLENGES:
        folders = seeds_of(runs, env_id)
        curves[env_id] = [curve(f) for f in folders]
        lines += [f"## {env_id.split('/')[-1]}", "",
                  "| seed | status | steps trained | wall time (min) | success on the JAX env, last evaluation | "
                  "success on unseen episodes (numpy env) | return on unseen episodes |",
                  "|---|---|---|---|---|---|---|"]  # fmt: skip
        for folder, c in zip(folders, curves[env_id]):
            result = final(folder) or {}
            evaluation = result.get("evaluation") or {}
            policies = evaluation.get("policies") or [{}]
            unseen = policies[0]
            success = f"{unseen['success_rate']:.0%}" if "success_rate" in unseen else "–"
            ret = f"{unseen['return_mean']:.4g}" if "return_mean" in unseen else "–"
            last = f"{c['success'][-1]:.0%}" if c["success"] else "–"
            minutes = f"{result.get('train_seconds', np.nan) / 60:.1f}" if result else "–"
            status = result.get("status", "stopped without results.json (killed): its curves to its last checkpoint")
            lines.append(f"| {folder.name.rsplit('_s', 1)[1]} | {status} | "
                         f"{result.get('timesteps', c['steps'][-1] if c['steps'] else 0):,} | {minutes} | {last} | "
                         f"{success} | {ret} |")  # fmt: skip
        lines.append("")
    chart(curves, path.with_suffix(".png"))
    head = [
        "# The open challenges at the field's budget",
        "",
        f"Generated by `{command}` from the run folders (agents/challenges.py says what it reads). The runs: `python "
        f"train.py --backend jax --env ID --seeds 5 --hyperparams {HYPERPARAMS} --eval-seed 100000` (PPO compiled "
        "with the env, 256 rows per seed; the hyperparameters' file says why each). A run stopped before its "
        "n_timesteps (Ctrl-C) is marked interrupted with the steps it reached; `--resume` continues it from its "
        "last checkpoint. A run that stopped short of its n_timesteps (the table's steps) shows the curves so far, "
        "not the budget's result.",
        "",
        f"![success against steps and wall time, return against steps]({path.with_suffix('.png').name})",
        "",
    ]
    return "\n".join(head + lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", default="runs/challenges", help="the challenges' run folders")
    parser.add_argument("--write", type=cli.writable_file, default="docs/baselines/challenges.md")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> str:
    args = parse_args(argv)
    runs = Path(args.runs)
    if not any(seeds_of(runs, env_id) for env_id in CHALLENGES):
        raise FileNotFoundError(f"{runs}: no run folder of {', '.join(CHALLENGES)}")
    text = page(runs, Path(args.write), f"{PROG} --runs {args.runs} --write {args.write}")
    Path(args.write).write_text(text)
    print(text)
    return text


if __name__ == "__main__":
    cli.run(main, PROG)
