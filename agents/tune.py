"""Hyperparameter sweeps on Ray Tune: Optuna proposes, ASHA stops the trials that trail at the periodic evaluations.

    python -m agents.tune --env ID --algo sac --samples 16 --timesteps 40000 [--address ADDR]  # --help lists the ids

Each trial is one train.py run of ``--timesteps`` steps (one CPU), with the env's hyperparameters from
agents/hyperparams/{algo}.yml where rl-zoo3's search space replaces what it samples: rl-zoo3's own samplers
(``rl_zoo3.hyperparams_opt``), so the ranges are those of ``rl_zoo3.train --optimize``; SAC with HER (the goal env)
also samples n_sampled_goal and the goal-selection strategy. A trial reports the mean return of each of its
``--evaluations`` periodic evaluations; ASHA stops, at each rung, the trials below the top third, from the first
quarter of the evaluations on. Optuna's sampler (TPE) learns from the reported returns.

Results, run folders and checkpoints go under runs/tune/{env}_{algo}/. The same command again resumes an interrupted
sweep: Tune restores it, and an unfinished trial resumes from its run's last checkpoint (one stopped before its first
starts anew, its run moved aside). At the end it writes runs/tune/{env}_{algo}/best.yml: the hyperparameters of the
trial with the best periodic return in rl-zoo3's YAML form, the env id as key, ready for
agents/hyperparams/{algo}.yml, and prints every trial's best return.
"""

from __future__ import annotations

import argparse
import functools
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import gymnasium as gym
import optuna
import yaml
from rl_zoo3.hyperparams_opt import HYPERPARAMS_SAMPLER
from stable_baselines3.common.callbacks import BaseCallback

from agents import baselines, cluster
from agents.evaluate import ENV_IDS
from connenv import cli
from connenv.cli import positive_int

PROG = "python -m agents.tune"
RUNS = baselines.REPO / "runs" / "tune"
ALGOS = ("ppo", "sac")
METRIC = "return"


def base_hyperparams(env_id: str, algo: str) -> dict:
    """The env's hyperparameters in agents/hyperparams/{algo}.yml: what the sampler does not set stays as there."""
    return baselines.hyperparams(algo, env_id)


def sampler_arguments(env_id: str, algo: str) -> tuple[int, int, dict]:
    """rl-zoo3's sampler arguments: the action size, n_envs, and whether the replay buffer is HER's (with its kwargs)."""
    base = base_hyperparams(env_id, algo)
    her = base.get("replay_buffer_class") == "HerReplayBuffer"
    her_kwargs = eval(base.get("replay_buffer_kwargs", "dict()")) if her else {}  # rl-zoo3's YAML form: a dict(...)
    env = gym.make(env_id)
    n_actions = env.action_space.shape[0]
    env.close()
    return n_actions, base.get("n_envs", 1), {"using_her_replay_buffer": her, "her_kwargs": her_kwargs}


def sample(trial: optuna.Trial, algo: str, arguments: tuple) -> None:
    """The search space, define-by-run: rl-zoo3's sampler asks the Optuna trial for its parameters."""
    HYPERPARAMS_SAMPLER[algo](trial, *arguments)


def literal(value) -> str | int | float | bool:
    """A sampled value in rl-zoo3's YAML form: numbers as they are, dicts as 'dict(...)', torch modules as 'nn.X'."""
    if isinstance(value, dict):
        return "dict(" + ", ".join(f"{key}={literal_text(item)}" for key, item in value.items()) + ")"
    if isinstance(value, type):
        return f"nn.{value.__name__}"
    return value


def literal_text(value) -> str:
    value = literal(value)
    return value if isinstance(value, str) and value.startswith(("dict(", "nn.")) else repr(value)


def hyperparameters(env_id: str, algo: str, config: dict) -> dict:
    """The env's hyperparameters with the sampled ones of config (Optuna's raw parameters) in rl-zoo3's YAML form."""
    sampled = HYPERPARAMS_SAMPLER[algo](optuna.trial.FixedTrial(config), *sampler_arguments(env_id, algo))
    return {**base_hyperparams(env_id, algo), **{key: literal(value) for key, value in sampled.items()}}


class Report(BaseCallback):
    """After each periodic evaluation (the EvalCallback is its parent): report the mean return and the success rate
    to Tune."""

    def _on_step(self) -> bool:
        from ray import tune

        successes = self.parent._is_success_buffer  # SB3's, filled from info["is_success"] by the evaluation
        success = sum(successes) / len(successes) if successes else float("nan")
        tune.report({METRIC: float(self.parent.last_mean_reward), "success": success, "timesteps": self.num_timesteps})
        return True


def run_trial(
    config: dict,
    env_id: str,
    algo: str,
    timesteps: int,
    evaluations: int,
    seed: int,
    sweep_path: str,
    episodes: int = 10,
):
    """One trial: train.py with the sampled hyperparameters in {sweep_path}/trials/{trial id}/ (where a restored trial
    finds its checkpoint), its output in train.log there."""
    from ray import tune

    from agents import train

    folder = Path(sweep_path) / "trials" / tune.get_context().get_trial_id()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "hyperparams.yml"
    path.write_text(yaml.safe_dump({env_id: hyperparameters(env_id, algo, config)}))
    frequency = str(max(timesteps // evaluations, 1))
    argv = ["--env", env_id, "--algo", algo, "--seed", str(seed), "--hyperparams", str(path), "--runs", str(folder)]
    argv += ["--timesteps", str(timesteps), "--eval-freq", frequency, "--checkpoint-freq", frequency]
    argv += ["--periodic-episodes", str(episodes)]
    argv += ["--resume", "--overwrite"]  # a restored trial resumes from its checkpoint, or starts anew if it has none
    args = train.parse_args(argv + (["--vector-env"] if algo == "ppo" else []))
    with open(folder / "train.log", "a") as log, redirect_stdout(log), redirect_stderr(log):
        train.train(args, after_eval=Report())


def sweep(env_id, algo, samples, timesteps, evaluations=10, seed=0, address=None, runs=RUNS, jobs=None, episodes=10):
    """Run (or resume) the sweep; return Tune's ResultGrid."""
    cluster.connect(address, jobs)
    from ray import tune
    from ray.tune.schedulers import ASHAScheduler
    from ray.tune.search.optuna import OptunaSearch

    name = f"{baselines.short(env_id)}_{algo}"
    path = Path(runs).resolve() / name
    trial = functools.partial(
        run_trial,
        env_id=env_id,
        algo=algo,
        timesteps=timesteps,
        evaluations=evaluations,
        seed=seed,
        sweep_path=path,
        episodes=episodes,
    )
    trainable = tune.with_resources(trial, {"cpu": 1})
    if tune.Tuner.can_restore(str(path)):
        print(f"resuming the sweep in {path}", flush=True)
        return tune.Tuner.restore(str(path), trainable, resume_errored=True).fit()
    space = functools.partial(sample, algo=algo, arguments=sampler_arguments(env_id, algo))  # picklable: Tune saves it
    search = OptunaSearch(space, metric=METRIC, mode="max", seed=seed)
    asha = ASHAScheduler(max_t=evaluations, grace_period=max(1, evaluations // 4), reduction_factor=3)
    tuner = tune.Tuner(
        trainable,
        tune_config=tune.TuneConfig(metric=METRIC, mode="max", search_alg=search, scheduler=asha, num_samples=samples),
        run_config=tune.RunConfig(name=name, storage_path=str(path.parent), verbose=0),
    )
    return tuner.fit()


def write_best(results, env_id: str, algo: str, path: Path) -> dict:
    """best.yml: the hyperparameters of the trial with the best periodic return, in rl-zoo3's form."""
    best = results.get_best_result(metric=METRIC, mode="max", scope="all")
    hyperparams = hyperparameters(env_id, algo, best.config)
    score = max(best.metrics_dataframe[METRIC])
    header = f"# agents.tune {env_id} {algo}: best periodic return {score:.4g} ({best.path})\n"
    path.write_text(header + yaml.safe_dump({env_id: hyperparams}))
    return hyperparams


def summary(results) -> str:
    """Every trial's best periodic return and success rate, evaluations and sampled parameters, best first."""
    rows = []
    for result in results:
        frame = result.metrics_dataframe
        if frame is None or METRIC not in frame:
            rows.append((float("-inf"), float("nan"), 0, result.config))
            continue
        success = float(frame["success"].max()) if "success" in frame else float("nan")
        rows.append((float(frame[METRIC].max()), success, len(frame), result.config))
    rows.sort(key=lambda row: -row[0])
    return "\n".join(
        f"{best:10.4g}  success {success:4.0%}  {n:3d} evaluations  {config}" for best, success, n, config in rows
    )


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", required=True, choices=[e for e in ENV_IDS if e in baselines.ENVS])
    parser.add_argument("--algo", required=True, choices=ALGOS)
    parser.add_argument("--samples", type=positive_int, required=True, help="trials")
    parser.add_argument("--timesteps", type=positive_int, required=True, help="training steps per trial")
    parser.add_argument("--evaluations", type=positive_int, default=10, help="periodic evaluations per trial")
    parser.add_argument("--episodes", type=positive_int, default=10, help="episodes of each periodic evaluation")
    parser.add_argument("--seed", type=cli.seed_int, default=0, help="of the sampler and of every trial's training")
    parser.add_argument(
        "--address", type=cluster.address, help="join the Ray cluster at ADDR (default: start a local Ray)"
    )
    parser.add_argument("--jobs", type=positive_int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--runs", type=cli.writable_dir, default=RUNS, help="folder of the sweeps")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> dict:
    args = parse_args(argv)
    results = sweep(
        args.env, args.algo, args.samples, args.timesteps, args.evaluations, args.seed, args.address, args.runs,
        args.jobs, args.episodes,
    )  # fmt: skip
    print(summary(results))
    best = Path(args.runs).resolve() / f"{baselines.short(args.env)}_{args.algo}" / "best.yml"
    hyperparams = write_best(results, args.env, args.algo, best)
    print(f"best hyperparameters -> {best}\n{yaml.safe_dump({args.env: hyperparams})}")
    return hyperparams


if __name__ == "__main__":
    cli.run(main, PROG)
