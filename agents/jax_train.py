"""``python train.py --backend jax``: PPO on connenv.jax (agents.jax_ppo), several seeds at once.

    python train.py --backend jax --env connenv/Swing-v0 --seeds 16

trains seeds --seed, --seed + 1, …, --seed + --seeds − 1 in one compiled program (vmap over the seeds; seed s draws
from jax.random.key(s), so a seed's run does not depend on which others train beside it, up to the rounding of
XLA's batched kernels). Hyperparameters come from agents/hyperparams/ppo_jax.yml (rl-zoo3's layout; the keys are
agents.jax_ppo.Config's, SB3's names) or --hyperparams PATH; --timesteps overrides n_timesteps.

Each seed has its run folder, runs/{env}_ppo_jax_s{seed}/, laid out as train.py's SB3 runs are where the tools read
them: connenv-{env}/config.yml (the hyperparameters used), evaluations.npz (SB3's EvalCallback's keys: timesteps,
results, successes, ep_lengths; the periodic deterministic evaluations on the JAX env), progress.csv (per update:
the training episodes' mean return and success, the losses), policy.npz (the final policy) and best_policy.npz
(the best periodic evaluation's; agents.jax_policy: numpy runs them), and results.json: the final evaluation of
agents.evaluate on the numpy env, the policy beside the analytic controller and random, on the same episodes
(where the numpy env diverges under them, a cheap stepper's StepperError, "evaluation" is null and
"evaluation_error" says why: the trained policies are kept).

Checkpoints (--checkpoint-freq N: the training state of every seed, at the first evaluation past every N steps and
at the end), --resume, --overwrite, Ctrl-C (the policies so far saved, results.json "interrupted", exit 130) and
errors in one line behave as train.py's do. A --resume continues all the seeds' runs from their common checkpoint.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
import yaml

import agents
from agents import evaluate, jax_policy
from agents.controllers import CONTROLLERS
from connenv.core.steppers import StepperError

HYPERPARAMS = Path(agents.__file__).parent / "hyperparams" / "ppo_jax.yml"
ALGO = "ppo_jax"


def hyperparams_entry(path: Path, env_id: str) -> dict:
    loaded = yaml.safe_load(Path(path).read_text())
    if env_id not in loaded and "default" not in loaded:  # train.py's hyperparams_fault has checked the rest
        raise ValueError(f"--hyperparams {path}: no entry for {env_id} (nor default)")
    return dict(loaded.get(env_id, loaded.get("default")))


def run_folder(runs: Path, env_id: str, seed: int) -> Path:
    return Path(runs) / f"{env_id.split('/')[-1]}_{ALGO}_s{seed}"


def config_path(folder: Path, env_id: str) -> Path:
    """rl-zoo3's place of the hyperparameters used (agents.baselines.run_config reads it)."""
    return folder / f"connenv-{env_id.split('/')[-1]}" / "config.yml"


# -- checkpoints ------------------------------------------------------------------------------------------------


def save_checkpoint(folder: Path, runner, steps: int):
    """The vmapped training state (all seeds) as its leaves, the keys as their raw data; named in checkpoints/latest
    once complete, the one before deleted (as train.py's Checkpoints)."""
    import jax

    path = folder / "checkpoints"
    path.mkdir(parents=True, exist_ok=True)
    leaves = jax.tree_util.tree_leaves(runner)
    arrays = {f"leaf{i}": np.asarray(jax.random.key_data(v) if _is_key(v) else v) for i, v in enumerate(leaves)}
    tmp = path / f"runner_{steps}.tmp.npz"
    np.savez(tmp, **arrays)
    tmp.replace(path / f"runner_{steps}.npz")
    before = _latest(folder)
    (path / "latest.tmp").write_text(str(steps))
    os.replace(path / "latest.tmp", path / "latest")
    if before is not None and before != steps:
        (path / f"runner_{before}.npz").unlink(missing_ok=True)


def load_checkpoint(folder: Path, template, steps: int):
    """The training state saved at `steps`, in the structure of `template` (a fresh one of the same run)."""
    import jax

    leaves, treedef = jax.tree_util.tree_flatten(template)
    with np.load(folder / "checkpoints" / f"runner_{steps}.npz") as data:
        loaded = [data[f"leaf{i}"] for i in range(len(leaves))]
    restored = [jax.random.wrap_key_data(v) if _is_key(t) else jax.numpy.asarray(v, t.dtype)
                for v, t in zip(loaded, leaves)]  # fmt: skip
    for v, t in zip(restored, leaves):
        if v.shape != t.shape:
            raise ValueError(f"{folder}: its checkpoint holds another run's state ({v.shape} where {t.shape})")
    return jax.tree_util.tree_unflatten(treedef, restored)


def _is_key(value) -> bool:
    import jax

    return hasattr(value, "dtype") and jax.dtypes.issubdtype(value.dtype, jax.dtypes.prng_key)


def _latest(folder: Path) -> int | None:
    latest = folder / "checkpoints" / "latest"
    return int(latest.read_text()) if latest.is_file() else None


# -- the run ----------------------------------------------------------------------------------------------------


def claim(folders: list[Path], resume: bool, overwrite: bool) -> int | None:
    """The step all seeds resume from, or None: agents.run_folders.claim_run_folder of each folder, which must
    agree."""
    from agents.run_folders import claim_run_folder

    steps = {claim_run_folder(folder, resume, overwrite) for folder in folders}
    if len(steps) > 1:
        raise FileExistsError(f"the seeds' run folders hold checkpoints at different steps {sorted(steps, key=str)}: "
                              "resume them one --seed at a time, or --overwrite")  # fmt: skip
    return steps.pop()


def write_progress(folder: Path, rows: list[dict]):
    with open(folder / "progress.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def read_progress(folder: Path) -> list[dict]:
    path = folder / "progress.csv"
    if not path.is_file():
        return []
    with open(path) as file:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(file)]


PPO_LOSSES = ("policy_loss", "value_loss", "entropy", "approx_kl", "clip_fraction", "stepper_failures")


def record_chunk(trainer, runner, seeds, folders, evaluations: dict, progress: dict, best: dict, meta: dict,
                 metrics: dict, evaluation: dict, updates: int, wall: float, losses: tuple[str, ...],
                 eval_means: bool = False):  # fmt: skip
    """After a chunk of updates (numpy metrics (S, updates) and evaluation (S, episodes)): each seed's evaluation
    and per-update progress rows appended (with eval_means, the evaluation's mean return and success in each row), and
    best_policy.npz saved where the evaluation's mean return is the seed's best so far. Shared by the trainers on
    connenv.jax (PPO here, agents.jax_shac)."""
    config = trainer.config
    for i, (seed, folder) in enumerate(zip(seeds, folders)):
        returns, successes = evaluation["return"][i], evaluation["success"][i]
        record = evaluations[seed]
        record["timesteps"].append(updates * config.rollout)
        record["results"].append(returns.tolist())
        record["successes"].append(successes.tolist())
        means = {"eval_return": float(np.mean(returns)), "eval_success": float(np.mean(successes))} if eval_means else {}
        for u in range(config.updates_per_eval):
            episodes = int(metrics["episodes"][i, u])
            progress[seed].append({
                "timesteps": (updates - config.updates_per_eval + u + 1) * config.rollout,
                "seconds": wall,
                "episodes": episodes,
                "episode_return": metrics["episode_return"][i, u] / max(episodes, 1),
                "success": metrics["successes"][i, u] / max(episodes, 1),
                **means,
                **{k: float(metrics[k][i, u]) for k in losses},
            })  # fmt: skip
        if np.mean(returns) > best[seed]:
            best[seed] = float(np.mean(returns))
            jax_policy.save(folder / "best_policy.npz", *trainer.policy_arrays(runner, i), meta)


def wait(tree, poll: float = 0.05):
    """Until every array of the tree is computed, in short sleeps rather than one blocking call, so that Ctrl-C
    interrupts at once (Python handles a signal between its own steps, not inside XLA's wait)."""
    import jax

    leaves = [leaf for leaf in jax.tree_util.tree_leaves(tree) if hasattr(leaf, "is_ready")]
    while not all(leaf.is_ready() for leaf in leaves):
        time.sleep(poll)


def write_records(seeds: list[int], folders: list[Path], evaluations: dict, progress: dict):
    """Each seed's evaluations.npz (SB3's EvalCallback's keys) and progress.csv, as far as the run has come."""
    for seed, folder in zip(seeds, folders):
        record = evaluations[seed]
        if record["timesteps"]:
            np.savez(folder / "evaluations.npz", timesteps=np.array(record["timesteps"]),
                     results=np.array(record["results"]), successes=np.array(record["successes"]),
                     ep_lengths=np.zeros_like(np.array(record["results"])))  # fmt: skip
        if progress[seed]:
            write_progress(folder, progress[seed])


def run(args: argparse.Namespace) -> dict:
    """Train args.seeds seeds of PPO on the JAX env, evaluate them on the numpy env, write the run folders."""
    import jax

    jax.config.update("jax_enable_x64", True)  # connenv.jax computes the physics in float64 (an application may set it)
    # XLA's compiled programs kept between runs (JAX's persistent cache): a second run of the same env and
    # hyperparameters starts at once; JAX_COMPILATION_CACHE_DIR moves it, an empty one turns it off
    cache = os.environ.get("JAX_COMPILATION_CACHE_DIR", str(Path.home() / ".cache" / "connenv" / "jax"))
    if cache:
        jax.config.update("jax_compilation_cache_dir", cache)
    import connenv.jax
    from agents.jax_ppo import Config, Trainer

    if args.algo != "ppo":
        raise ValueError(f"--backend jax trains ppo; --algo {args.algo} runs on --backend sb3")
    hyperparams_file = Path(args.hyperparams)
    entry = hyperparams_entry(hyperparams_file, args.env)
    config = Config.from_hyperparams(entry, args.timesteps)
    if args.eval_freq is not None:
        config = Config.from_hyperparams({**entry, "eval_freq": max(args.eval_freq, 0)}, args.timesteps)
    env_kwargs = evaluate.make_kwargs(args.env, args.env_kwargs)
    env, env_params = connenv.jax.make(args.env, **env_kwargs)
    seeds = list(range(args.seed, args.seed + args.seeds))
    folders = [run_folder(Path(args.runs), args.env, seed) for seed in seeds]
    try:
        steps = claim(folders, args.resume, args.overwrite)
    except FileExistsError as error:
        raise SystemExit(f"train.py: error: {error}") from None

    start = time.perf_counter()
    trainer = Trainer(env, env_params, config)
    runner = trainer.init(jax.numpy.stack([jax.random.key(seed) for seed in seeds]))
    compiled = trainer.run.lower(runner).compile()
    compile_seconds = time.perf_counter() - start
    print(f"{args.env}: PPO on JAX, {len(seeds)} seeds × {config.n_timesteps} steps, {config.n_envs} envs each; "
          f"compiled in {compile_seconds:.1f} s", flush=True)  # fmt: skip
    for folder in folders:
        config_path(folder, args.env).parent.mkdir(parents=True, exist_ok=True)
        config_path(folder, args.env).write_text(yaml.safe_dump(entry | {"n_timesteps": config.n_timesteps}))
    evaluations = {seed: {"timesteps": [], "results": [], "successes": []} for seed in seeds}
    progress = {seed: [] for seed in seeds}
    updates = 0
    if steps is not None:
        runner = load_checkpoint(folders[0], runner, steps)
        updates = int(np.asarray(runner["update"])[0])
        for seed, folder in zip(seeds, folders):
            if (folder / "evaluations.npz").is_file():
                with np.load(folder / "evaluations.npz") as data:
                    kept = data["timesteps"] <= steps
                    evaluations[seed] = {k: data[k][kept].tolist() for k in ("timesteps", "results", "successes")}
            progress[seed] = [row for row in read_progress(folder) if row["timesteps"] <= steps]
        print(f"resumed from the checkpoint at {steps} steps", flush=True)
    best = {seed: max((np.mean(r) for r in evaluations[seed]["results"]), default=-math.inf) for seed in seeds}
    # a resumed run's wall time goes on from its checkpoint's: the curves against wall time and train_seconds count
    # the training of every kept step, not only this process's
    earlier = max((rows[-1]["seconds"] for rows in progress.values() if rows), default=0.0)
    meta = trainer.meta(args.env)
    saved_steps = steps or 0
    interrupted, pending = False, False
    train_start = time.perf_counter()
    try:
        while updates < config.n_updates:
            previous, pending = runner, True
            runner, metrics, evaluation = compiled(runner)
            wait(runner)
            pending = False
            updates += config.updates_per_eval
            timesteps = updates * config.rollout
            wall = earlier + time.perf_counter() - train_start
            metrics, evaluation = jax.tree_util.tree_map(np.asarray, (metrics, evaluation))
            record_chunk(trainer, runner, seeds, folders, evaluations, progress, best, meta, metrics, evaluation,
                         updates, wall, PPO_LOSSES)  # fmt: skip
            mean_success = np.mean(evaluation["success"])
            print(f"{timesteps:>10} steps  {wall:7.1f} s  evaluation: return {np.mean(evaluation['return']):.4g}, "
                  f"success {mean_success:.0%} (mean of {len(seeds)} seeds)", flush=True)  # fmt: skip
            due = args.checkpoint_freq > 0 and timesteps // args.checkpoint_freq > saved_steps // args.checkpoint_freq
            if due or (args.checkpoint_freq > 0 and updates >= config.n_updates):
                write_records(seeds, folders, evaluations, progress)  # the curves so far, with their checkpoint
                save_checkpoint(folders[0], runner, timesteps)
                for folder in folders[1:]:  # every seed's folder names the common checkpoint
                    (folder / "checkpoints").mkdir(parents=True, exist_ok=True)
                    (folder / "checkpoints" / "latest").write_text(str(timesteps))
                    (folder / "checkpoints" / "in").write_text(str(folders[0].resolve()))
                saved_steps = timesteps
    except KeyboardInterrupt:  # a chunk of updates under way is dropped: the state before it is kept
        interrupted, runner = True, previous if pending else runner
    train_seconds = earlier + time.perf_counter() - train_start
    timesteps = int(np.asarray(runner["update"])[0]) * config.rollout
    write_records(seeds, folders, evaluations, progress)
    for i, (seed, folder) in enumerate(zip(seeds, folders)):
        jax_policy.save(folder / "policy.npz", *trainer.policy_arrays(runner, i), meta)
        if not (folder / "best_policy.npz").is_file():
            jax_policy.save(folder / "best_policy.npz", *trainer.policy_arrays(runner, i), meta)
    common = {"algo": ALGO, "backend": "jax", "timesteps": timesteps, "train_seconds": train_seconds,
              "compile_seconds": compile_seconds, "seeds_trained_together": seeds,
              "hyperparams": str(hyperparams_file), "jax_devices": [str(d) for d in jax.devices()]}  # fmt: skip
    if interrupted:
        for seed, folder in zip(seeds, folders):
            results = {"status": "interrupted", "seed": seed, **common, "model": str(folder / "policy.npz"),
                       "evaluation": None}  # fmt: skip
            evaluate.write_json(results, folder / "results.json")
        latest = _latest(folders[0])
        resume = "" if latest is None else f"; --resume continues it from its checkpoint at step {latest}"
        print(f"training interrupted at step {timesteps}; the policies so far are in {folders[0]} …; results.json "
              f"marks the runs interrupted{resume}", file=sys.stderr)  # fmt: skip
        raise SystemExit(130)
    print(f"trained {len(seeds)} seeds × {timesteps} timesteps in {train_seconds:.1f} s (+ {compile_seconds:.1f} s "
          "compiling)", flush=True)  # fmt: skip
    specs = [f"jax:{folder / 'best_policy.npz'}" for folder in folders]
    specs += [*(["analytic"] if args.env in CONTROLLERS else []), "random"]
    try:
        report = evaluate.compare(args.env, specs, args.eval_episodes, args.eval_seed, env_kwargs=env_kwargs)
    except StepperError as error:  # the numpy env diverged under a policy (a cheap stepper): the runs are kept
        print(f"the final evaluation on the numpy env diverged: {error}", file=sys.stderr)
        for seed, folder in zip(seeds, folders):
            results = {"status": "finished", "seed": seed, **common, "model": str(folder / "best_policy.npz"),
                       "evaluation": None, "evaluation_error": f"StepperError: {error}"}  # fmt: skip
            evaluate.write_json(results, folder / "results.json")
        return {"env": args.env, "evaluation_error": str(error)}
    print(evaluate.format_table(report))
    for seed, folder, spec in zip(seeds, folders, specs):
        own = _own_report(report, spec)
        results = {"status": "finished", "seed": seed, **common, "model": str(folder / "best_policy.npz"),
                   "evaluation": own}  # fmt: skip
        evaluate.write_json(results, folder / "results.json")
    return report


def _own_report(report: dict, spec: str) -> dict:
    """The compare report with only this seed's policy among the learned ones (the references kept)."""
    label = evaluate.jax_label(spec.removeprefix("jax:"))
    rows = [row for row in report["policies"] if not row["policy"].startswith(f"{ALGO}:") or row["policy"] == label]
    return {**report, "policies": rows}
