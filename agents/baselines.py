"""Reference results: SB3 baselines beside the analytic controllers, for every env (docs/guides/reference-results.md).

    python -m agents.baselines train     # 3 seeds per (env, algo) with train.py into runs/baselines/, on Ray
    python -m agents.baselines collect   # best model per (env, algo) into agents/pretrained/, curves into docs/
    python -m agents.baselines table     # the reference table, from agents/pretrained/ alone (offline, minutes)
    python -m agents.baselines unseen    # every seed's model on unseen episodes into docs/baselines/unseen.json
    python -m agents.baselines score     # normalized scores and their aggregates (agents.score), offline, seconds

``train`` trains once per (env, algo, seed) with train.py's ``train.main`` and the hyperparameters of
agents/hyperparams/, each run a Ray task of one CPU (``agents.cluster``): on a local Ray of ``--jobs`` CPUs by default,
on a running cluster with ``--address``. It skips runs that finished (their results.json says so). A run checkpoints
after each periodic evaluation, between rollouts; a run whose worker process dies is retried by Ray, from its last
checkpoint, and the other runs go on; a run folder that cannot be resumed (other hyperparameters, or no checkpoint
yet) is moved aside to {folder}.{date-time} and the run trained anew. PPO trains on the native vector envs
(``--vector-env``), SAC on one env.
``collect`` picks, for each (env, algo), the seed whose best model returns most on EPISODES selection episodes (reset
with seeds SELECTION_SEED + i), copies its best_model.zip with the VecNormalize statistics it was evaluated with to
agents/pretrained/{env}_{algo}/, records
the training steps and wall time of every seed in agents/pretrained/runs.json and writes the periodic evaluations
of all seeds to docs/baselines/curves.csv. ``table`` evaluates random, each analytic controller and each pretrained
model on the same 100 episodes (seeds 0..99) with agents.evaluate, writes docs/baselines/results.{json,md} and
draws docs/baselines/{env}.png: the learning curves (mean and range over seeds) with the analytic controller's mean
return as a horizontal line.
``unseen`` evaluates random, the analytic controller and the best model of every seed in `--runs` (with
``--pretrained``, the shipped models instead) on EPISODES episodes reset with seeds UNSEEN_SEED + i, which no
training, periodic evaluation, tuning, seed selection, table or diagnosis uses, and writes their returns and
successes into docs/baselines/unseen.json. ``score`` reads that file alone: agents.score.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import re
import shutil
from concurrent.futures import ProcessPoolExecutor
from contextlib import redirect_stderr, redirect_stdout
from functools import partial
from operator import attrgetter
from pathlib import Path

import numpy as np
import yaml

import connenv
from agents import cluster, score
from agents.controllers import CONTROLLERS
from agents.evaluate import PRETRAINED, compare, evaluate, load_model, make_policy, pretrained_models
from agents.progress import progress
from connenv import cli
from connenv.cli import positive_int
from connenv.envs.spec import registry

PROG = "python -m agents.baselines"
REPO = Path(__file__).resolve().parent.parent
HYPERPARAMS = Path(__file__).resolve().parent / "hyperparams"
DOCS = REPO / "docs" / "baselines"
RUNS = REPO / "runs" / "baselines"
SEEDS = (0, 1, 2)
ENVS = tuple(spec.id for spec in registry.values() if spec.measure and spec.controllers)
"""The reference table's envs: every id whose spec names a physical measure and an analytic controller."""
UNTRAINED = ()
"""Envs with hyperparameters and analytic controllers whose reference runs are still to be trained: ``train`` and
``collect`` take them; the table holds ENVS."""
ALGOS = ("ppo", "sac")  # SAC on a goal env is SAC + HER (its entry of agents/hyperparams/sac.yml)
JAX_ALGOS = ("ppo_jax",)  # train.py --backend jax's runs: trained by train.py --seeds, evaluated and scored here
EVALUATIONS = 10  # periodic evaluations per run, of train.PERIODIC_EVAL_EPISODES (10) episodes each
FINAL_EPISODES = 10  # train.py's own table at the end of a run; the results table is evaluated on EPISODES
EPISODES = 100
UNSEEN_SEED = 100_000
"""The score's episode i is reset with seed UNSEEN_SEED + i. Training resets with its seed plus the env's rank
(below 100), the periodic evaluation likewise, the table with 0..99, agents.imitate's diagnosis with 10 000..10 099
(evaluation) and 20 000 and up (demonstrations), collect's choice of the shipped seed with SELECTION_SEED + i."""
SELECTION_SEED = 50_000
"""collect ships the seed whose best model returns most on EPISODES episodes reset from here: a periodic evaluation's
10 episodes pick the best checkpoint of a seed, but are too few to rank seeds whose successes differ by a few
percent, and the table's and the score's episodes must not choose the model they report."""
UNSEEN = DOCS / "unseen.json"
LONG = "long"  # the key of an env's budget curve in agents/hyperparams/ppo.yml: the hyperparameters it overrides
BOOK = "hyperparams.yml"  # a budget curve's run folder holds the hyperparameters it trains with, for train.py


def short(env_id: str) -> str:
    return env_id.split("/")[-1]


def hyperparams_file(algo: str) -> Path:
    return HYPERPARAMS / f"{algo}.yml"


def hyperparams(algo: str, env_id: str, book: str = "") -> dict:
    """The env's hyperparameters in agents/hyperparams/{algo}.yml as train.py takes them (without LONG); with book
    LONG, its budget curve's (LONG's over them)."""
    entry = yaml.safe_load(hyperparams_file(algo).read_text())[env_id]
    return {key: value for key, value in entry.items() if key != LONG} | (entry[book] if book else {})


def run_config(folder: Path, env_id: str) -> dict | None:
    """The hyperparameters a run folder was trained with (rl-zoo3's {env}/config.yml), or None."""
    path = folder / f"connenv-{short(env_id)}" / "config.yml"
    return dict(yaml.load(path.read_text(), Loader=yaml.UnsafeLoader)) if path.is_file() else None  # OrderedDict


def run_folder(env_id: str, algo: str, seed: int, runs: Path = RUNS) -> Path:
    return runs / f"{short(env_id)}_{algo}_s{seed}"


def finished(folder: Path) -> bool:
    """Whether a run folder holds a finished run: train.py's results.json, of status "finished" (or of none: written
    before an interrupted run was told apart), not "interrupted"."""
    results = folder / "results.json"
    return results.is_file() and json.loads(results.read_text()).get("status", "finished") == "finished"


def train_argv(
    env_id: str,
    algo: str,
    seed: int,
    runs: Path,
    timesteps: int | None = None,
    evaluations: int = EVALUATIONS,
    book: str = "",
    episodes: tuple[int, int] | None = None,
) -> list[str]:
    """train.py's arguments for a run: a periodic evaluation and a checkpoint `evaluations` times, resumed from its
    last checkpoint if it has one; the hyperparameters of `book`, written into the run folder (BOOK) for train.py;
    `episodes`: (each periodic evaluation's, the final table's) episodes, (10, FINAL_EPISODES) by default."""
    timesteps = timesteps or int(float(hyperparams(algo, env_id, book)["n_timesteps"]))
    argv = ["--env", env_id, "--algo", algo, "--seed", str(seed), "--runs", str(runs), "--timesteps", str(timesteps)]
    if book:
        path = run_folder(env_id, algo, seed, runs) / BOOK
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(yaml.safe_dump({env_id: hyperparams(algo, env_id, book)}))
        argv += ["--hyperparams", str(path)]
    frequency = str(max(timesteps // evaluations, 1))
    periodic, final = episodes or (None, FINAL_EPISODES)
    argv += ["--eval-freq", frequency, "--checkpoint-freq", frequency, "--eval-episodes", str(final)]
    argv += ["--periodic-episodes", str(periodic)] if periodic else []
    return argv + ["--resume"] + (["--vector-env"] if algo == "ppo" else [])


def train_one(env_id: str, algo: str, seed: int, runs: Path = RUNS, **options) -> str:
    """Train one run in this process, a Ray task's worker, unless it finished with the current hyperparameters. An
    unfinished run with them resumes from its last checkpoint; a folder with none, or with other hyperparameters, is
    moved aside (train.py's --overwrite, done here so that the logs below start in the new folder) and the run
    trained anew. Each attempt adds a line to the run's attempts.log: the process, the step it starts from and the
    Ray node. options: train_argv's timesteps, evaluations, book and episodes."""
    import ray

    from agents import train

    folder = run_folder(env_id, algo, seed, runs)
    same = run_config(folder, env_id) == hyperparams(algo, env_id, options.get("book", ""))
    if same and finished(folder):
        return f"{folder.name}: done before"
    if folder.exists() and (not same or train.latest_checkpoint(folder) is None):
        train.move_aside(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "attempts.log", "a") as log:
        start, node = train.latest_checkpoint(folder) or 0, ray.get_runtime_context().get_node_id()
        print(f"pid {os.getpid()} from step {start} on node {node}", file=log, flush=True)
    with open(folder / "train.log", "a") as log, redirect_stdout(log), redirect_stderr(log):
        results = train.main(train_argv(env_id, algo, seed, runs, **options))
    return f"{folder.name}: {results['timesteps']} steps in {results['train_seconds']:.0f} s"


def train_all(
    envs: list[str], algos: list[str], jobs: int, address: str | None = None, seeds=SEEDS, **options
) -> list[str]:
    """Every (env, algo, seed) run as a Ray task of one CPU, retried from its checkpoint if its worker dies; print
    each run's outcome as it ends. options: train_one's runs, timesteps, evaluations, book and episodes."""
    ray = cluster.connect(address, jobs)
    task = ray.remote(num_cpus=1, max_retries=cluster.MAX_RETRIES)(train_one)
    pending = {task.remote(env_id, algo, seed, **options): (env_id, algo, seed)
               for env_id in envs for algo in algos for seed in seeds}  # fmt: skip
    outcomes = []
    while pending:
        (done,), _ = ray.wait(list(pending))
        env_id, algo, seed = pending.pop(done)
        try:
            outcomes.append(ray.get(done))
        except ray.exceptions.RayError as error:  # the run failed in train.py, or beyond its retries
            outcomes.append(f"{run_folder(env_id, algo, seed).name}: FAILED ({type(error).__name__}: {error})")
        print(outcomes[-1], flush=True)
    return outcomes


def evaluations(folder: Path) -> dict[str, np.ndarray]:
    """A run's periodic evaluations: timesteps, mean return and success rate."""
    data = np.load(folder / "evaluations.npz")
    return {
        "timesteps": data["timesteps"],
        "return": data["results"].mean(axis=1),
        "success": data["successes"].mean(axis=1),
    }


def copy_best_model(folder: Path, target: Path, env_id: str, algo: str):
    """Copy a run's best model, without its optimizers' moment estimates (only further training reads them; the
    policy is unchanged and a SAC zip halves), with the run files agents.evaluate reads beside it."""
    params = target / f"connenv-{short(env_id)}"
    if run_config(folder, env_id).get("normalize") and not (folder / params.name / "best_vecnormalize.pkl").is_file():
        raise FileNotFoundError(f"{folder}: normalized, but no {params.name}/best_vecnormalize.pkl; retrain it")
    shutil.rmtree(target, ignore_errors=True)
    params.mkdir(parents=True)
    for name in ("args.yml", "config.yml", "best_vecnormalize.pkl"):
        if (folder / params.name / name).is_file():
            shutil.copy(folder / params.name / name, params / name)
    policy = load_model(folder / "best_model.zip", env_id, algo)
    model = getattr(policy, "model", policy)  # the SB3 model behind its VecNormalize statistics
    for name in model._get_torch_save_params()[0]:
        if name.endswith("optimizer"):
            attrgetter(name)(model).state.clear()
    model.save(target / "best_model.zip")


def seed_record(folder: Path, env_id: str, algo: str) -> tuple[dict, list[dict]]:
    """A finished run's steps, wall time, best periodic return and its best model's mean return on the selection
    episodes, and its curve as CSV rows."""
    results = json.loads((folder / "results.json").read_text())
    curve = evaluations(folder)
    selection = episodes_record(env_id, str(folder / "best_model.zip"), algo, SELECTION_SEED)
    record = {
        "timesteps": results["timesteps"],
        "train_seconds": round(results["train_seconds"], 1),
        "best_periodic_return": float(curve["return"].max()),
        "selection_return": round(float(np.mean(selection["returns"])), 6),
    }
    rows = [
        {"seed": results["seed"], "timesteps": int(t), "return": f"{r:.6g}", "success": f"{s:.2f}"}
        for t, r, s in zip(curve["timesteps"], curve["return"], curve["success"], strict=True)
    ]
    return record, rows


def check_finished(env_id: str, algo: str, runs: Path, seeds) -> list[Path]:
    """The run folders of an (env, algo), each finished with the current hyperparameters, else FileNotFoundError."""
    folders = [run_folder(env_id, algo, seed, runs) for seed in seeds]
    for folder in folders:
        if not finished(folder) or run_config(folder, env_id) != hyperparams(algo, env_id):
            raise FileNotFoundError(f"{folder}: not finished with the current hyperparameters; run train first")
    return folders


def collect_pair(env_id: str, algo: str, entry: dict | None, runs: Path = RUNS, seeds=SEEDS) -> tuple[dict, list[dict]]:
    """The runs.json entry and curve rows of an (env, algo) whose seeds (in runs) finished with the current
    hyperparameters; its best model copied to agents/pretrained/ unless the same file is there already."""
    folders = check_finished(env_id, algo, runs, seeds)
    records, rows = {}, []
    for seed, folder in zip(seeds, folders, strict=True):
        records[seed], seed_rows = seed_record(folder, env_id, algo)
        rows += [{"env": env_id, "algo": algo, **row} for row in seed_rows]
    best = max(records, key=lambda seed: records[seed]["selection_return"])
    digest = hashlib.sha256((run_folder(env_id, algo, best, runs) / "best_model.zip").read_bytes()).hexdigest()
    target = PRETRAINED / f"{short(env_id)}_{algo}"
    mark_shipped(env_id, algo, best)
    if entry is None or entry.get("source_sha256") != digest or not (target / "best_model.zip").is_file():
        copy_best_model(run_folder(env_id, algo, best, runs), target, env_id, algo)
    return {"pretrained_seed": best, "source_sha256": digest, "seeds": records}, rows


def mark_shipped(env_id: str, algo: str, seed: int):
    """unseen.json's "shipped" flags of an (env, algo)'s runs, once collect has chosen the seed it ships."""
    if UNSEEN.is_file():
        data = json.loads(UNSEEN.read_text())
        for record in data["envs"].get(env_id, {}).get("runs", []):
            if record["algo"] == algo:
                record["shipped"] = record["seed"] == seed
        UNSEEN.write_text(unseen_text(data))


def collect(envs: list[str], algos: list[str], runs: Path = RUNS, seeds=SEEDS):
    """Best seed's best model per (env, algo) (its runs in `runs`) into agents/pretrained/, the training steps and
    wall time of every seed into agents/pretrained/runs.json, every seed's periodic evaluations into
    docs/baselines/curves.csv."""
    record_path, curves_path = PRETRAINED / "runs.json", DOCS / "curves.csv"
    shipped = json.loads(record_path.read_text()) if record_path.is_file() else {}
    collected = {}
    pairs = [(env_id, algo) for env_id in envs for algo in algos]
    for env_id, algo in pairs:  # every pair before the first evaluation, which takes minutes
        check_finished(env_id, algo, runs, seeds)
    for env_id, algo in progress(pairs, len(pairs), "pairs", "collect"):
        collected[env_id, algo] = collect_pair(env_id, algo, shipped.get(env_id, {}).get(algo), runs, seeds)
        print(f"{short(env_id)} {algo}: pretrained seed {collected[env_id, algo][0]['pretrained_seed']}", flush=True)
    # read again after the evaluations, which take minutes: another collect may have written meanwhile
    record, rows = json.loads(record_path.read_text()) if record_path.is_file() else {}, []
    if curves_path.is_file():
        with curves_path.open() as file:
            rows = list(csv.DictReader(file))
    for (env_id, algo), (entry, pair_rows) in collected.items():
        record.setdefault(env_id, {})[algo] = entry
        rows = [row for row in rows if (row["env"], row["algo"]) != (env_id, algo)] + pair_rows
    record_path.write_text(json.dumps(record, indent=1, sort_keys=True))
    DOCS.mkdir(parents=True, exist_ok=True)
    with curves_path.open("w", newline="") as file:
        writer = csv.DictWriter(file, ["env", "algo", "seed", "timesteps", "return", "success"])
        writer.writeheader()
        writer.writerows(sorted(rows, key=lambda r: (r["env"], r["algo"], int(r["seed"]), int(r["timesteps"]))))


def collect_long(envs: list[str], runs: Path):
    """The budget curves' periodic evaluations (one seed of PPO at 10x each, as far as they have run) into
    docs/baselines/long.csv, and docs/baselines/long.png: success against training steps, the budget of the
    0.3.0 ppo.yml marked on each."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows, envs = [], [env_id for env_id in envs if run_seeds(env_id, "ppo", runs)]  # the curves trained so far
    fig, axes = plt.subplots(1, len(envs), figsize=(3 * len(envs), 2.8), sharey=True, squeeze=False)
    for ax, env_id in zip(axes[0], envs, strict=True):
        seeds = run_seeds(env_id, "ppo", runs)
        for seed in seeds:
            folder = run_folder(env_id, "ppo", seed, runs)
            if run_config(folder, env_id) != hyperparams("ppo", env_id, LONG):
                raise FileNotFoundError(f"{folder}: not trained with the hyperparameters of its budget curve")
            curve = evaluations(folder)
            rows += [{"env": env_id, "seed": seed, "timesteps": int(t), "return": f"{r:.6g}", "success": f"{s:.2f}"}
                     for t, r, s in zip(curve["timesteps"], curve["return"], curve["success"], strict=True)]  # fmt: skip
            ax.plot(curve["timesteps"], 100 * curve["success"], marker=".", label=f"seed {seed}")
        budget = float(hyperparams("ppo", env_id, LONG)["n_timesteps"]) / 10
        ax.axvline(budget, ls="--", color="k", lw=1, label="0.3.0 budget (a tenth)")
        ax.set(title=short(env_id), xlabel="training steps", xlim=(0, None))
    axes[0][0].set(ylabel="success, periodic evaluation (%)")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(DOCS / "long.png", dpi=100)
    plt.close(fig)
    with (DOCS / "long.csv").open("w", newline="") as file:
        writer = csv.DictWriter(file, ["env", "seed", "timesteps", "return", "success"])
        writer.writeheader()
        writer.writerows(rows)


def steps_to_target(row: dict) -> float | None:
    lengths = [episode["length"] for episode in row["episodes"] if episode["success"]]
    return float(np.mean(lengths)) if lengths else None


def statistic(name: str):
    """How a Measure's statistic is read off an agents.evaluate summary row (connenv.envs.spec.Measure)."""
    if name == "time_to_success":
        return lambda row: row["time_to_success_mean"]
    if name == "steps_to_target":
        return steps_to_target
    return lambda row: row["measures_mean"][name]


# The physical measure of each env's row: its name and unit, and how to read it off an agents.evaluate summary.
MEASURES = {
    spec.id: (spec.measure.label, spec.measure.unit, statistic(spec.measure.statistic))
    for spec in registry.values()
    if spec.id in ENVS
}


def pretrained_label(model: Path) -> str:
    """PPO, SAC or SAC + HER, from a pretrained model's folder ({env}_{algo}) and the config.yml beside it."""
    config = next(model.parent.glob("*/config.yml")).read_text()
    return model.parent.name.rsplit("_", 1)[1].upper() + (" + HER" if "HerReplayBuffer" in config else "")


def evaluate_env(env_id: str) -> dict:
    """agents.evaluate's report for random, the env's controllers and its pretrained models, on EPISODES episodes
    (seeds 0..99), each row with its physical measure, the episodes themselves left out, and the models' training
    (their runs.json entries)."""
    import torch

    torch.set_num_threads(1)
    models = pretrained_models(env_id)
    controllers = list(CONTROLLERS[env_id])  # the first is the analytic reference
    report = compare(env_id, ["random", *controllers, *map(str, models)], EPISODES, 0)
    name, unit, measure = MEASURES[env_id]
    labels = ["random", *(f"{c} (analytic)" if i == 0 else c for i, c in enumerate(controllers))]
    labels += [pretrained_label(model) for model in models]
    for label, row in zip(labels, report["policies"], strict=True):
        row.update(label=label, measure=measure(row), measure_name=name, measure_unit=unit)
        del row["episodes"]
    report["training"] = json.loads((PRETRAINED / "runs.json").read_text())[env_id]
    return report


def training_cell(entry: dict) -> str:
    """Steps and mean wall time of a seed, from a runs.json entry."""
    (steps,) = {run["timesteps"] for run in entry["seeds"].values()}  # every seed trains the same budget
    minutes = np.mean([run["train_seconds"] for run in entry["seeds"].values()]) / 60
    return f"{steps / 1000:.0f}k steps, {minutes:.1f} min × {len(entry['seeds'])} seeds"


def format_results(reports: list[dict]) -> str:
    """One markdown table: per env, random, the analytic controllers and the pretrained models (each the best seed
    of its pair on the selection episodes)."""
    lines = [
        "| env | policy | training (per seed) | success | return | physical measure |",
        "|---|---|---|---|---|---|",
    ]
    for report in reports:
        env_id = report["env"]
        for i, row in enumerate(report["policies"]):
            algo = row["policy"].split(":")[0]
            training = training_cell(report["training"][algo]) if algo in ALGOS else "–"
            value = row["measure"]
            measure = "–" if value is None else f"{value:.4g} {row['measure_unit']}".strip()
            env = f"{short(env_id)}: {row['measure_name']}" if i == 0 else ""
            label = f"{row['label']}, best seed" if algo in ALGOS else row["label"]  # the shipped model
            lines.append(
                f"| {env} | {label} | {training} | {100 * row['success_rate']:.0f}% "
                f"| {row['return_mean']:.3f} ± {row['return_std']:.3f} | {measure} |"
            )
    return "\n".join(lines)


def plot_curves(report: dict, path: Path):
    """Periodic-evaluation return against training steps, mean and range over seeds for each algorithm, with the
    analytic controller's and the random policy's mean returns on the table's episodes as horizontal lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env_id = report["env"]
    with (DOCS / "curves.csv").open() as file:
        rows = [row for row in csv.DictReader(file) if row["env"] == env_id]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for row in report["policies"]:
        algo = row["policy"].split(":")[0]
        if algo not in ALGOS:
            continue
        runs = {}
        for r in rows:
            if r["algo"] == algo:
                runs.setdefault(int(r["seed"]), []).append((int(r["timesteps"]), float(r["return"])))
        (steps,) = {tuple(t for t, _ in points) for points in runs.values()}  # every seed evaluated at the same steps
        returns = np.array([[ret for _, ret in points] for points in runs.values()])
        (line,) = ax.plot(steps, returns.mean(axis=0), label=f"{row['label']} ({len(runs)} seeds)")
        ax.fill_between(steps, returns.min(axis=0), returns.max(axis=0), color=line.get_color(), alpha=0.25)
    analytic = next(row for row in report["policies"] if row["label"].endswith("(analytic)"))
    random = next(row for row in report["policies"] if row["label"] == "random")
    for row, style in ((analytic, "--"), (random, ":")):
        ax.axhline(row["return_mean"], ls=style, color="k", lw=1, label=f"{row['label']}, {EPISODES} episodes")
    ax.set(xlabel="training steps", ylabel="return (10 evaluation episodes)", title=short(env_id))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def table(jobs: int, envs: list[str]) -> str:
    """Evaluate the envs' policies (one env per process), update docs/baselines/results.{json,md} with them, draw
    their learning curves, return the markdown table of all envs evaluated so far."""
    with ProcessPoolExecutor(jobs) as pool:
        fresh = list(pool.map(evaluate_env, envs))
    DOCS.mkdir(parents=True, exist_ok=True)
    results_path = DOCS / "results.json"
    reports = (
        {report["env"]: report for report in json.loads(results_path.read_text())} if results_path.is_file() else {}
    )
    reports.update((report["env"], report) for report in fresh)  # the other envs' rows stay as they were
    reports = [reports[env_id] for env_id in ENVS if env_id in reports]
    text = format_results(reports)
    results_path.write_text(json.dumps(reports, indent=1))
    (DOCS / "results.md").write_text(text + "\n")
    guide = REPO / "docs" / "guides" / "reference-results.md"  # holds the same table
    table_lines = re.compile(r"^\| env \| policy \|.*?\n(?!\|)", re.MULTILINE | re.DOTALL)
    guide.write_text(table_lines.sub(lambda _: text + "\n", guide.read_text(), count=1))
    for report in reports:
        plot_curves(report, DOCS / f"{short(report['env'])}.png")
    return text


def run_seeds(env_id: str, algo: str, runs: Path) -> list[int]:
    """The seeds of an (env, algo)'s run folders in runs, in order (folders moved aside left out)."""
    pattern = re.compile(rf"{re.escape(short(env_id))}_{algo}_s(\d+)")
    return sorted(int(match[1]) for folder in runs.glob("*") if (match := pattern.fullmatch(folder.name)))


def episodes_record(env_id: str, spec: str, algo: str | None = None, first_seed: int = UNSEEN_SEED) -> dict:
    """The returns and successes of a policy (agents.evaluate's spec) on EPISODES episodes from first_seed on: by
    default the score's unseen episodes."""
    import torch

    torch.set_num_threads(1)
    _, policy = make_policy(spec, env_id, first_seed, algo)
    episodes = evaluate(env_id, policy, EPISODES, first_seed)
    returns = [float(f"{episode.ret:.10g}") for episode in episodes]  # enough for any score, short in the file
    return {"returns": returns, "successes": [episode.success for episode in episodes]}


def shipped_records(env_id: str, algos: list[str]) -> list[dict]:
    """The unseen episodes of the shipped pretrained models, each with the seed it is the best of."""
    record = json.loads((PRETRAINED / "runs.json").read_text())[env_id]
    return [
        {"algo": algo, "seed": record[algo]["pretrained_seed"], "of_seeds": len(record[algo]["seeds"]),
         **episodes_record(env_id, str(PRETRAINED / f"{short(env_id)}_{algo}" / "best_model.zip"), algo)}
        for algo in algos if algo in record
    ]  # fmt: skip


def run_records(env_id: str, algos: list[str], runs: Path) -> list[dict]:
    """The unseen episodes of the best model of every run in `runs` that finished with the current hyperparameters,
    "shipped" if it is the pretrained model."""
    record, records = json.loads((PRETRAINED / "runs.json").read_text()).get(env_id, {}), []
    for algo in algos:
        for seed in run_seeds(env_id, algo, runs):
            folder = run_folder(env_id, algo, seed, runs)
            if finished(folder) and run_config(folder, env_id) == hyperparams(algo, env_id):
                timesteps = json.loads((folder / "results.json").read_text())["timesteps"]
                if algo in JAX_ALGOS:
                    spec, shipped = f"jax:{folder / 'best_policy.npz'}", False
                else:
                    model = folder / "best_model.zip"
                    digest = hashlib.sha256(model.read_bytes()).hexdigest()
                    spec, shipped = str(model), digest == record.get(algo, {}).get("source_sha256")
                records.append({"algo": algo, "seed": seed, "timesteps": timesteps, "shipped": shipped,
                                **episodes_record(env_id, spec, None if algo in JAX_ALGOS else algo)})  # fmt: skip
    return records


def unseen_env(env_id: str, algos: list[str], runs: Path, pretrained: bool) -> dict:
    """unseen.json's entry of an env: random's and the analytic controller's episodes, and the algorithms' runs
    (under "runs") or shipped models (under "pretrained {version}", the release that shipped them)."""
    analytic = next(iter(CONTROLLERS[env_id]))
    entry = {
        "random": episodes_record(env_id, "random"),
        "analytic": {"name": analytic, **episodes_record(env_id, analytic)},
    }
    if pretrained:
        entry[f"pretrained {connenv.__version__}"] = shipped_records(env_id, algos)
    else:
        entry["runs"] = run_records(env_id, algos, runs)
    return entry


def unseen(envs: list[str], algos: list[str], jobs: int, runs: Path, pretrained: bool):
    """Evaluate the envs on the unseen episodes (one env per process) and merge them into docs/baselines/unseen.json:
    the records of the algorithms evaluated replace theirs, the others' stay."""
    with ProcessPoolExecutor(jobs) as pool:
        fresh = dict(zip(envs, pool.map(partial(unseen_env, algos=algos, runs=runs, pretrained=pretrained), envs)))
    data = json.loads(UNSEEN.read_text()) if UNSEEN.is_file() else {"first_seed": UNSEEN_SEED, "envs": {}}
    for env_id, entry in fresh.items():
        old = data["envs"].setdefault(env_id, {})
        for key, records in entry.items():
            if isinstance(records, list):
                records = [r for r in old.get(key, []) if r["algo"] not in algos] + records
            old[key] = records
        print(f"{short(env_id)}: {sum(len(v) for v in entry.values() if isinstance(v, list))} models", flush=True)
    UNSEEN.write_text(unseen_text(data))


def unseen_text(data: dict) -> str:
    """unseen.json's text: a line per record, so that a change of one run is a change of one line."""
    envs = [
        f"  {json.dumps(env_id)}: {{\n" + ",\n".join(
            f"   {json.dumps(key)}: " + (
                "[\n" + ",\n".join(f"    {json.dumps(r)}" for r in value) + "\n   ]" if isinstance(value, list)
                else json.dumps(value)
            )
            for key, value in entry.items()
        ) + "\n  }"
        for env_id, entry in data["envs"].items()
    ]  # fmt: skip
    return f'{{\n "first_seed": {data["first_seed"]},\n "envs": {{\n' + ",\n".join(envs) + "\n }\n}\n"


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("command", choices=("train", "collect", "table", "unseen", "score"))
    parser.add_argument(
        "--jobs", type=positive_int, default=os.cpu_count(), help="CPUs of a local Ray / table's processes"
    )
    parser.add_argument("--env", nargs="+", default=list(ENVS), choices=ENVS + UNTRAINED)
    parser.add_argument(
        "--algo", nargs="+", default=list(ALGOS), choices=ALGOS + JAX_ALGOS, help="ppo_jax: unseen and score only"
    )
    parser.add_argument(
        "--address", type=cluster.address, help="train: join the Ray cluster at ADDR (default: start a local Ray)"
    )
    parser.add_argument("--runs", type=cli.writable_dir, default=RUNS, help="train, collect: folder of the run folders")
    parser.add_argument("--timesteps", type=positive_int, help="train: steps per run (default: the hyperparameters')")
    parser.add_argument(
        "--seeds", nargs="+", type=cli.seed_int, default=list(SEEDS), help="train, collect: the seeds of each pair"
    )
    parser.add_argument("--pretrained", action="store_true", help="unseen: the shipped models, not the runs'")
    parser.add_argument(
        "--long",
        action="store_true",
        help="train, collect: the budget curves (PPO at 10x, the `long` keys of agents/hyperparams/ppo.yml; default "
        "envs: those that have one, seeds: 0, runs: runs/long), collected into docs/baselines/long.{csv,png}",
    )
    args = parser.parse_args(argv)
    if args.command in ("train", "collect", "table") and set(args.algo) & set(JAX_ALGOS):
        parser.error("argument --algo: ppo_jax runs are trained by python train.py --backend jax --seeds N; "
                     "unseen and score take them")  # fmt: skip
    if args.long:
        defaults = parser.parse_args([args.command])
        entries = yaml.safe_load(hyperparams_file("ppo").read_text())
        long_envs = [env_id for env_id in ENVS if LONG in entries[env_id]]
        args.env = long_envs if args.env == defaults.env else args.env
        args.seeds = [0] if args.seeds == defaults.seeds else args.seeds
        args.runs = RUNS.parent / "long" if args.runs == defaults.runs else args.runs
        args.algo = ["ppo"]
    return args


def main(argv: list[str] | None = None):
    args = parse_args(argv)
    if not (REPO / "train.py").is_file():
        raise SystemExit(f"python -m agents.baselines works in a clone of the repository; {REPO} is not one")
    if args.command == "train":
        options = {"runs": Path(args.runs), "timesteps": args.timesteps, "book": LONG if args.long else ""}
        outcomes = train_all(args.env, args.algo, args.jobs, args.address, args.seeds, **options)
        if any("FAILED" in outcome for outcome in outcomes):
            raise SystemExit("some runs failed; their train.log says why")
    elif args.command == "collect" and args.long:
        collect_long(args.env, Path(args.runs))
    elif args.command == "collect":
        collect(args.env, args.algo, Path(args.runs), args.seeds)
    elif args.command == "unseen":
        unseen(args.env, args.algo, args.jobs, Path(args.runs), args.pretrained)
    elif args.command == "score":
        print(score.write(score.load(UNSEEN), DOCS, score.latest(list(ENVS + UNTRAINED)), ALGOS + JAX_ALGOS))
    else:
        print(table(args.jobs, args.env))


if __name__ == "__main__":
    cli.run(main, PROG)
