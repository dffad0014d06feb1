"""Agents trained on randomized physical parameters against agents trained on fixed ones, on both kinds of episode.

    python -m agents.randomized --env ID --randomize '{"NAME": [LOW, HIGH]}' --runs runs/randomized \\
        --write docs/baselines/randomized.md

Every seed's best model in --runs (trained by ``train.py --env-kwargs '{"randomize": ...}'``) and the shipped
pretrained models (trained on the make kwargs' values) are evaluated on the score's unseen episodes (reset seeds
from agents.baselines.UNSEEN_SEED), once with the parameters fixed at their defaults and once drawn per episode
from the ranges. Success is the mean over seeds, with a 95% bootstrap interval over them (one seed: its own).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import gymnasium as gym
import numpy as np

from agents.baselines import ALGOS, EPISODES, PRETRAINED, UNSEEN_SEED, run_seeds, short
from agents.evaluate import ENV_IDS, evaluate, make_policy
from agents.imitate import bootstrap_interval
from connenv import cli

PROG = "python -m agents.randomized"


def success(env_id: str, model: Path, algo: str, env_kwargs: dict) -> float:
    _, policy = make_policy(str(model), env_id, UNSEEN_SEED, algo, env_kwargs)
    return float(np.mean([e.success for e in evaluate(env_id, policy, EPISODES, UNSEEN_SEED, env_kwargs=env_kwargs)]))


def rows(env_id: str, algo: str, randomize: dict, runs: Path) -> list[dict]:
    """Per policy (the runs' seeds, the shipped model): success on fixed and on randomized parameters."""
    groups = {
        f"{algo}, trained on randomized {', '.join(randomize)}": [
            runs / f"{short(env_id)}_{algo}_s{seed}" / "best_model.zip" for seed in run_seeds(env_id, algo, runs)
        ],
        f"{algo}, trained on fixed (shipped model)": [PRETRAINED / f"{short(env_id)}_{algo}" / "best_model.zip"],
    }
    table = []
    for label, models in groups.items():
        fixed = [success(env_id, m, algo, {}) for m in models]
        drawn = [success(env_id, m, algo, {"randomize": randomize}) for m in models]
        table.append({"policy": label, "seeds": len(models), "fixed": fixed, "randomized": drawn})
    return table


def markdown(env_id: str, randomize: dict, table: list[dict]) -> str:
    def cell(values):
        low, high = bootstrap_interval(values, method="percentile")
        return f"{100 * np.mean(values):.0f}% [{100 * low:.0f}, {100 * high:.0f}]"

    lines = [
        f"# Randomized parameters: {short(env_id)}", "",
        f"Written by `{PROG} --env {env_id} --randomize '{json.dumps(randomize)}'`. Success on {EPISODES} unseen "
        f"episodes (reset seeds {UNSEEN_SEED} and up), mean over seeds with a 95% bootstrap interval; fixed: the "
        f"make kwargs' values, randomized: each episode draws {json.dumps(randomize)} (log-uniform for a scale).", "",
        "| policy | seeds | fixed parameters | randomized parameters |", "|---|---|---|---|",
        *(f"| {r['policy']} | {r['seeds']} | {cell(r['fixed'])} | {cell(r['randomized'])} |" for r in table), "",
    ]  # fmt: skip
    return "\n".join(lines)


def ranges(text: str) -> dict:
    """argparse type: a JSON object {name: [low, high]} of numbers."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        value = None
    pair = lambda v: isinstance(v, list) and len(v) == 2 and all(  # noqa: E731
        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v
    )
    if not isinstance(value, dict) or not value or not all(pair(v) for v in value.values()):
        raise argparse.ArgumentTypeError(f"{text!r} is not a JSON object {{name: [low, high]}} of numbers")
    return value


def check(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """What the evaluations need, checked before the first: the env takes the ranges, --runs holds the env's
    randomized runs, and the shipped model exists."""
    try:
        gym.make(args.env, randomize=args.randomize).close()
    except ValueError as error:
        parser.error(f"argument --randomize: {error}")
    if not args.runs.is_dir():
        parser.error(f"argument --runs: {str(args.runs)!r} is no folder")
    runs = [args.runs / f"{short(args.env)}_{args.algo}_s{seed}" for seed in run_seeds(args.env, args.algo, args.runs)]
    if not runs:
        parser.error(f"argument --runs: {str(args.runs)!r} has no run folder {short(args.env)}_{args.algo}_s<SEED>")
    shipped = PRETRAINED / f"{short(args.env)}_{args.algo}" / "best_model.zip"
    for path in [*(run / "best_model.zip" for run in runs), shipped]:
        if not path.is_file():
            parser.error(f"argument --runs: no model {str(path)!r}")


def main(argv: list[str] | None = None) -> str:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", required=True, choices=ENV_IDS)
    parser.add_argument("--algo", default="ppo", choices=ALGOS)
    parser.add_argument("--randomize", required=True, type=ranges, help="a JSON object {name: [low, high]}")
    parser.add_argument("--runs", required=True, type=Path, help="the folder of the randomized runs")
    parser.add_argument("--write", type=cli.writable_file, help="the markdown page to write")
    args = parser.parse_args(argv)
    check(parser, args)
    text = markdown(args.env, args.randomize, rows(args.env, args.algo, args.randomize, args.runs))
    if args.write:
        Path(args.write).write_text(text)
    print(text)
    return text


if __name__ == "__main__":
    cli.run(main, PROG)
