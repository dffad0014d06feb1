"""The open challenges' page: JAX PPO's curves at the challenge budget, and where the runs stand.

    python -m agents.challenges [--runs runs/challenges] [--write docs/baselines/challenges.md]

reads the run folders of ``python train.py --backend jax --env ID --seeds 5 --hyperparams
agents/hyperparams/ppo_jax_challenges.yml --runs runs/challenges --eval-seed 100000`` for KapitzaSwingUp-v0 and
RollingBallPose-v0 — each seed's periodic evaluations (evaluations.npz: the deterministic policy on the JAX env),
its training curve (progress.csv: the training episodes' success, the wall time) and its results.json (the final
policy on the numpy env's unseen episodes, reset seeds 100000–100099, with the status: finished, or interrupted at
the steps it reached) — and writes the page and its chart (challenges.png beside it): success against steps and
against wall time, per seed. Beside them: the attempts of ATTEMPTS (their own run folders under --runs, their own
hyperparameters: a start curriculum for the swing-up), and the first-order result, SHAC through the differentiable
step beside PPO at the same budget, read from the run folders of ``python -m agents.exact_gradients``
(--first-order-runs; its guide, docs/guides/exact-gradients.md, has the step Jacobian's spectrum along the rollouts).
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
SUCCESS = 0.9  # learned: this share of the unseen episodes, on the seeds' mean
# (env id, run folders under --runs, hyperparameters, what was tried): attempts beside the budget's run
ATTEMPTS = (
    ("connenv/KapitzaSwingUp-v0", "curriculum", "agents/hyperparams/ppo_jax_curriculum.yml",
     "Wide starts (SuPLE, ICRA 2025): half of the training episodes released at rest from any angle up to inverted, "
     "cut at 2000 steps (agents/curriculum.py's kapitza_release); the evaluations start as the task does"),
    ("connenv/RollingBallPose-v0", "recurrent", "agents/hyperparams/ppo_jax_recurrent.yml",
     "A recurrent policy, for a controller that keeps a plan: a GRU of 64 units before the policy's and the value's "
     "MLPs, trained on whole rollouts of rows (agents/jax_ppo.py, recurrent)"),
)  # fmt: skip


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
    tenth = rows[-max(1, len(rows) // 10) :]  # the training episodes that ended in the last tenth of the updates
    episodes = sum(row.get("episodes", 0.0) for row in tenth)
    training = sum(row.get("success", 0.0) * row.get("episodes", 0.0) for row in tenth) / episodes if episodes else None
    if data is None:
        return {"steps": [], "success": [], "return": [], "seconds": [], "training_success": training}
    steps = data["timesteps"].tolist()
    return {"steps": steps, "success": data["successes"].mean(1).tolist(), "return": data["results"].mean(1).tolist(),
            "seconds": [seconds.get(s, np.nan) for s in steps], "training_success": training}  # fmt: skip


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


def unseen(folder: Path) -> dict:
    """The seed's own row of its results.json's evaluation on the numpy env's unseen episodes ({} if none)."""
    evaluation = (final(folder) or {}).get("evaluation") or {}
    return (evaluation.get("policies") or [{}])[0]


def table(folders: list[Path], curves: list[dict]) -> list[str]:
    lines = ["| seed | status | steps trained | wall time (min) | training episodes' success, last tenth | success on "
             "the JAX env, last evaluation | success on unseen episodes (numpy env) | return on unseen episodes |",
             "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for folder, c in zip(folders, curves):
        result, row = final(folder) or {}, unseen(folder)
        success = f"{row['success_rate']:.0%}" if "success_rate" in row else "–"
        ret = f"{row['return_mean']:.4g}" if "return_mean" in row else "–"
        last = f"{c['success'][-1]:.0%}" if c["success"] else "–"
        training = "–" if c.get("training_success") is None else f"{c['training_success']:.1%}"
        minutes = f"{result.get('train_seconds', np.nan) / 60:.1f}" if result else "–"
        status = result.get("status", "stopped without results.json (killed): its curves to its last checkpoint")
        lines.append(f"| {folder.name.rsplit('_s', 1)[1]} | {status} | "
                     f"{result.get('timesteps', c['steps'][-1] if c['steps'] else 0):,} | {minutes} | {training} | {last} | "
                     f"{success} | {ret} |")  # fmt: skip
    return lines + [""]


def standing(env_id: str, folders: list[Path]) -> str:
    """One sentence from the figures: learned (the seeds' mean success on unseen episodes ≥ SUCCESS) or open."""
    rows = [unseen(f) for f in folders]
    rates = [r["success_rate"] for r in rows if "success_rate" in r]
    steps = min(((final(f) or {}).get("timesteps", 0) for f in folders), default=0)
    if not rates:
        return "No seed has been evaluated on the unseen episodes yet."
    mean = float(np.mean(rates))
    word = "**Learned**" if mean >= SUCCESS and steps >= 1e8 else "**Open**"
    text = (f"{word}: over {len(rates)} seeds at {steps:,} steps each, {mean:.0%} of the unseen episodes succeed "
            f"(seeds from {min(rates):.0%} to {max(rates):.0%}; learned means ≥ {SUCCESS:.0%} at ≥ 10⁸ steps), "
            f"mean return {np.mean([r['return_mean'] for r in rows if 'return_mean' in r]):.3g}")  # fmt: skip
    measures = [r["measures_mean"] for r in rows if r.get("measures_mean")]
    if measures:  # the task's own measures at the episodes' ends (info's), the seeds' mean
        text += ", " + ", ".join(f"{k} {np.mean([m[k] for m in measures]):.3g}" for k in measures[0])
    evaluation = (final(folders[0]) or {}).get("evaluation") or {}
    analytic = next((r for r in evaluation.get("policies", []) if r.get("policy") == "analytic"), None)
    if analytic is not None:
        text += (f"; the analytic controller on the same episodes: {analytic['success_rate']:.0%}, return "
                 f"{analytic['return_mean']:.3g}")  # fmt: skip
        text += "".join(f", {k} {v:.3g}" for k, v in (analytic.get("measures_mean") or {}).items())
    return text + "."


def first_order(runs: Path, env_id: str) -> list[str]:
    """SHAC and PPO at agents.exact_gradients' budget for this env, from its run folders (nothing where none)."""
    from agents import exact_gradients as eg

    if env_id not in eg.ENVS:
        return []
    steps, *_ = eg.ENVS[env_id]
    found = {algo: [eg.final(f) for f in eg.folders(runs, env_id, algo, 5)] for algo in eg.ALGOS}
    if not any(f for algo in found.values() for f in algo):
        return []
    lines = ["First-order result (`python -m agents.exact_gradients`, 5 seeds each at the same budget, the best "
             "policies on the numpy env's unseen episodes; the step Jacobian's spectrum along their rollouts is in "
             "[the exact-gradients guide](../guides/exact-gradients.md)):", "",
             "| method | steps per seed | success [min, max over seeds] | return | training s (per run of 5 seeds) |",
             "|---|---|---|---|---|"]  # fmt: skip
    for algo, results in found.items():
        done = [r for r in results if r is not None]
        lines.append(f"| {eg.NAMES[algo]} | {steps:.0e} | {eg.percent([r['success'] for r in done])} | "
                     f"{eg.mean_of([r['return'] for r in done])} | {eg.mean_of([r['train'] for r in done], '{:.0f}')} |")  # fmt: skip
    return lines + [""]


def page(runs: Path, path: Path, command: str, first_order_runs: Path) -> str:
    curves, lines = {}, []
    for env_id in CHALLENGES:
        folders = seeds_of(runs, env_id)
        curves[env_id] = [curve(f) for f in folders]
        lines += [f"## {env_id.split('/')[-1]}", "", standing(env_id, folders), "",
                  *table(folders, curves[env_id]), *first_order(first_order_runs, env_id)]  # fmt: skip
    attempts = [(env_id, sub, hyperparams, what) for env_id, sub, hyperparams, what in ATTEMPTS
                if seeds_of(runs / sub, env_id)]  # fmt: skip
    if attempts:
        lines += ["## What the literature suggests, tried", ""]
    for env_id, sub, hyperparams, what in attempts:
        folders = seeds_of(runs / sub, env_id)
        label = f"{env_id.split('/')[-1]}, {sub}"
        curves[label] = [curve(f) for f in folders]
        lines += [f"### {label}", "", f"{what}. `python train.py --backend jax --env {env_id} --seeds 5 "
                  f"--hyperparams {hyperparams} --runs {runs / sub} --eval-seed 100000`.", "",
                  standing(env_id, folders), "", *table(folders, curves[label])]  # fmt: skip
    chart(curves, path.with_suffix(".png"))
    head = [
        "# The open challenges at the field's budget",
        "",
        f"Generated by `{command}` from the run folders (agents/challenges.py says what it reads). The runs: `python "
        f"train.py --backend jax --env ID --seeds 5 --hyperparams {HYPERPARAMS} --eval-seed 100000` (PPO compiled "
        "with the env, 256 rows per seed; the hyperparameters' file says why each). A run stopped before its "
        "n_timesteps (Ctrl-C) is marked interrupted with the steps it reached; `--resume` continues it from its "
        "last checkpoint. A run that stopped short of its n_timesteps (the table's steps) shows the curves so far, "
        "not the budget's result. The measures after the return are the task's own at the episodes' ends, as "
        "agents.evaluate reports them (SI: angles in rad, lengths in m).",
        "",
        f"![success against steps and wall time, return against steps]({path.with_suffix('.png').name})",
        "",
    ]
    return "\n".join(head + lines)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", default="runs/challenges", help="the challenges' run folders")
    parser.add_argument("--write", type=cli.writable_file, default="docs/baselines/challenges.md")
    parser.add_argument("--first-order-runs", default="runs/exact-gradients",
                        help="python -m agents.exact_gradients' run folders (its --runs)")  # fmt: skip
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> str:
    args = parse_args(argv)
    runs = Path(args.runs)
    if not any(seeds_of(runs, env_id) for env_id in CHALLENGES):
        raise FileNotFoundError(f"{runs}: no run folder of {', '.join(CHALLENGES)}")
    command = f"{PROG} --runs {args.runs} --write {args.write} --first-order-runs {args.first_order_runs}"
    text = page(runs, Path(args.write), command, Path(args.first_order_runs))
    Path(args.write).write_text(text)
    print(text)
    return text


if __name__ == "__main__":
    cli.run(main, PROG)
