"""Train an agent with rl-zoo3, then compare it with the analytic controller and a random policy.

    python train.py --env connenv/Swing-v0 --algo ppo --timesteps 150000 --seed 0

Hyperparameters come from agents/hyperparams/{algo}.yml (rl-zoo3's layout, the env id as top-level key) or from
--hyperparams PATH; --timesteps overrides their n_timesteps. rl-zoo3's ExperimentManager reads them, builds the
envs, shows a progress bar and evaluates periodically on a separate env. The run folder, runs/{env}_{algo}_s{seed}/,
is laid out as rl-zoo3's: the model {env}.zip, best_model.zip and evaluations.npz of the periodic evaluation,
{env}/config.yml (the hyperparameters used), {env}/args.yml and {env}/vecnormalize.pkl if normalized; train.py adds
{env}/best_vecnormalize.pkl, the statistics best_model.zip was evaluated with (rl-zoo3 overwrites vecnormalize.pkl
with the final ones), and results.json, the final evaluation of agents.evaluate on the same episodes for every
policy.

With --env-kwargs the envs are made with the kwargs given as a JSON object ('{"dt": 0.02}') or as module:factory,
the kwargs factory() returns (a dict, or a system, which becomes {"system": system}); several update one another in
order. Enough to train on a user's own system,

    python train.py --env connenv/ActiveConstraint-v0 --env-kwargs my_robot:env_kwargs --algo ppo
    python train.py --env connenv/ActiveConstraint-v0 --env-kwargs my_robot:system '{"u_low": -3, "u_high": 3}'

The module is imported from the working directory or the Python path; the analytic controller is then left out of
the final evaluation (there is none for a user's system). Bad input of any argument ends train.py in one line
naming it, before any training.

With --checkpoint-freq N the run saves a checkpoint every N steps into {run}/checkpoints/ (SB3's CheckpointCallback:
the model, the VecNormalize statistics, the replay buffer); with --resume a run whose folder holds one continues from
it to the same n_timesteps, its periodic evaluations so far kept. agents.baselines uses both, so that a run whose
process is killed is retried from its last checkpoint.

With --vector-env the training and periodic-evaluation envs are the env's native vector env (gym.make_vec with its
vector_entry_point, through agents.vec_env.NativeVecEnv) instead of SB3's DummyVecEnv of single envs; the final
evaluation stays on single envs.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np
import torch as th
import yaml
from rl_zoo3.exp_manager import ExperimentManager
from rl_zoo3.utils import ALGOS
from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback, EvalCallback
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import VecNormalize
from tqdm import TqdmExperimentalWarning

import agents
from agents import evaluate
from agents.controllers import CONTROLLERS
from agents.vec_env import make_native_vec_env
from connenv import cli

PROG = "train.py"
HYPERPARAMS = Path(agents.__file__).parent / "hyperparams"
PERIODIC_EVAL_EPISODES = 10
warnings.filterwarnings("ignore", category=TqdmExperimentalWarning)  # SB3's progress bar is tqdm.rich, "experimental"


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="connenv/Swing-v0", choices=evaluate.ENV_IDS)
    parser.add_argument("--algo", default="ppo", choices=sorted(ALGOS))
    parser.add_argument("--timesteps", type=evaluate.positive_int, help="default: n_timesteps of the hyperparameters")
    parser.add_argument("--seed", type=evaluate.seed_int, default=0)
    parser.add_argument("--hyperparams", help="rl-zoo3 YAML file (default: agents/hyperparams/{algo}.yml)")
    parser.add_argument("--eval-freq", type=int, default=25_000, help="steps between periodic evaluations, ≤ 0: none")
    parser.add_argument("--eval-episodes", type=evaluate.positive_int, default=100, help="episodes of the final table")
    parser.add_argument(
        "--eval-seed", type=evaluate.seed_int, default=0, help="final episode i is reset with eval-seed + i"
    )
    parser.add_argument("--runs", type=cli.writable_dir, default="runs", help="folder of the run folders")
    parser.add_argument("--num-threads", type=evaluate.positive_int, default=1, help="torch threads")
    parser.add_argument("--vector-env", action="store_true", help="train on the env's native vector env")
    parser.add_argument("--env-kwargs", nargs="+", metavar="KWARGS", help=evaluate.ENV_KWARGS_HELP)
    parser.add_argument("--checkpoint-freq", type=int, default=0, help="steps between checkpoints, ≤ 0: none")
    parser.add_argument("--resume", action="store_true", help="continue from the run folder's last checkpoint")
    args = parser.parse_args(argv)
    args.hyperparams = args.hyperparams or str(HYPERPARAMS / f"{args.algo}.yml")
    if not Path(args.hyperparams).is_file():
        parser.error(f"--hyperparams {args.hyperparams!r}: no such file; give a YAML file for --algo {args.algo}")
    if fault := hyperparams_fault(Path(args.hyperparams), args.env):
        parser.error(f"--hyperparams {args.hyperparams!r} {fault}")
    return args


def hyperparams_fault(path: Path, env_id: str) -> str | None:
    """What keeps rl-zoo3 from reading env_id's hyperparameters from the YAML file at path, or None."""
    try:
        loaded = yaml.safe_load(path.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        return f"is not YAML ({error})"
    if not (isinstance(loaded, dict) and isinstance(loaded.get(env_id), dict)):
        return f"holds no hyperparameters for {env_id} (rl-zoo3's layout: the env id as key of a mapping)"
    return None


class SaveBestVecNormalize(BaseCallback):
    """On a new best periodic evaluation, save the VecNormalize statistics it was evaluated with to `path`."""

    def __init__(self, path: Path):
        super().__init__()
        self.path = path

    def _on_step(self) -> bool:
        if self.model.get_vec_normalize_env() is not None:
            self.model.get_vec_normalize_env().save(str(self.path))
        return True


class Checkpoints(CheckpointCallback):
    """SB3's CheckpointCallback, which then names the checkpoint it completed in {path}/latest (written atomically,
    so that a run killed while saving resumes from the one before) and deletes the one before (a replay buffer's
    checkpoint is as large as the buffer)."""

    def __init__(self, save_freq: int, path: Path):
        super().__init__(save_freq, str(path), save_replay_buffer=True, save_vecnormalize=True)

    def _on_step(self) -> bool:
        super()._on_step()
        if self.n_calls % self.save_freq == 0:
            path = Path(self.save_path)
            before = latest_checkpoint(path.parent)
            (path / "latest.tmp").write_text(str(self.num_timesteps))
            os.replace(path / "latest.tmp", path / "latest")
            if before is not None and before != self.num_timesteps:
                for kind in ("", "replay_buffer_", "vecnormalize_"):
                    for old in path.glob(f"rl_model_{kind}{before}_steps.*"):
                        old.unlink()
        return True


def latest_checkpoint(run: Path) -> int | None:
    """The steps of the run folder's last completed checkpoint, or None."""
    latest = run / "checkpoints" / "latest"
    return int(latest.read_text()) if latest.is_file() else None


class BestStatsExperimentManager(ExperimentManager):
    """rl-zoo3's ExperimentManager, keeping the VecNormalize statistics of the best model as well as the final; with
    ``checkpoint_freq`` saving checkpoints, and ``after_eval`` (a callback) called after each periodic evaluation."""

    checkpoint_freq = 0
    after_eval: BaseCallback | None = None

    def create_callbacks(self):
        super().create_callbacks()
        for callback in self.callbacks:
            if isinstance(callback, EvalCallback):
                callback.callback_on_new_best = SaveBestVecNormalize(Path(self.params_path) / "best_vecnormalize.pkl")
                callback.callback_on_new_best.parent = callback
                if self.after_eval is not None:
                    callback.callback, self.after_eval.parent = self.after_eval, callback
        if self.checkpoint_freq > 0:
            frequency = max(self.checkpoint_freq // self.n_envs, 1)
            self.callbacks.append(Checkpoints(frequency, Path(self.save_path) / "checkpoints"))

    def resume(self, model, steps: int):
        """The model of the checkpoint at `steps`, on model's env, with its VecNormalize statistics, its replay buffer
        and the periodic evaluations up to it."""
        path = Path(self.save_path) / "checkpoints"
        resumed = type(model).load(path / f"rl_model_{steps}_steps.zip", env=model.get_env(), device=model.device)
        if (path / f"rl_model_replay_buffer_{steps}_steps.pkl").is_file():
            resumed.load_replay_buffer(path / f"rl_model_replay_buffer_{steps}_steps.pkl")
        normalize = resumed.get_vec_normalize_env()
        if normalize is not None:
            saved = VecNormalize.load(str(path / f"rl_model_vecnormalize_{steps}_steps.pkl"), normalize.venv)
            normalize.obs_rms, normalize.ret_rms = saved.obs_rms, saved.ret_rms
        evaluations = Path(self.save_path) / "evaluations.npz"
        for callback in self.callbacks:
            if isinstance(callback, EvalCallback) and evaluations.is_file():
                kept = np.load(evaluations)["timesteps"] <= steps
                data = {key: value[kept] for key, value in np.load(evaluations).items()}
                callback.evaluations_timesteps = data["timesteps"].tolist()
                callback.evaluations_results = data["results"].tolist()
                callback.evaluations_length = data["ep_lengths"].tolist()
                if len(data["results"]):
                    callback.best_mean_reward = float(np.max(np.mean(data["results"], axis=1)))
        return resumed

    def learn(self, model):
        """rl-zoo3's learn from scratch; a resumed model learns on to n_timesteps, its step count kept."""
        if not model.num_timesteps:
            return super().learn(model)
        try:
            model.learn(self.n_timesteps - model.num_timesteps, callback=self.callbacks, reset_num_timesteps=False)
        finally:
            model.env.close()


class VectorExperimentManager(BestStatsExperimentManager):
    """rl-zoo3's ExperimentManager on the native vector env: create_envs is the one hook that builds the training
    and periodic-evaluation envs. Both are native, so that SB3 finds the same wrappers around them when it copies
    the VecNormalize statistics from one to the other."""

    def create_envs(self, n_envs: int, eval_env: bool = False, no_log: bool = False):
        if self.env_wrapper is not None or self.frame_stack is not None:
            raise ValueError("--vector-env takes no env_wrapper or frame_stack hyperparameters; they wrap single envs")
        env = make_native_vec_env(
            self.env_name.gym_id,
            n_envs,
            seed=self.seed,
            env_kwargs=self.eval_env_kwargs if eval_env else self.env_kwargs,
            monitor_dir=None if eval_env or no_log else self.save_path,
            monitor_kwargs=self.monitor_kwargs,
        )
        if self.vec_env_wrapper is not None:
            env = self.vec_env_wrapper(env)
        return self._maybe_normalize(env, eval_env)


def train(args: argparse.Namespace, env_kwargs: dict | None = None, after_eval: BaseCallback | None = None):
    """Train with rl-zoo3's ExperimentManager into the run folder, from its last checkpoint with --resume; return the
    model and the path of its zip. after_eval: a callback run after each periodic evaluation."""
    set_random_seed(args.seed)
    th.set_num_threads(args.num_threads)
    manager = (VectorExperimentManager if args.vector_env else BestStatsExperimentManager)(
        args,
        args.algo,
        args.env,
        args.runs,
        n_timesteps=args.timesteps or 0,
        eval_freq=args.eval_freq,
        n_eval_episodes=PERIODIC_EVAL_EPISODES,
        seed=args.seed,
        config=args.hyperparams,
        env_kwargs=env_kwargs,
        log_interval=-1,
        show_progress=True,
        verbose=0,
    )
    # One named folder per env, algo and seed instead of rl-zoo3's numbered {log_folder}/{algo}/{env}_{n}.
    manager.save_path = str(Path(args.runs) / f"{args.env.split('/')[-1]}_{args.algo}_s{args.seed}")
    manager.params_path = str(Path(manager.save_path) / manager.env_name)
    manager.checkpoint_freq, manager.after_eval = args.checkpoint_freq, after_eval
    steps = latest_checkpoint(Path(manager.save_path)) if args.resume else None
    model, _ = manager.setup_experiment()
    if steps is not None:
        model = manager.resume(model, steps)
        print(f"resumed from the checkpoint at {steps} steps")
    manager.learn(model)
    manager.save_trained_model(model)
    return model, Path(manager.save_path) / f"{manager.env_name}.zip"


def main(argv: list[str] | None = None) -> dict:
    """Train, evaluate beside the analytic controller and a random policy, print the table, write results.json."""
    args = parse_args(argv)
    env_kwargs = evaluate.make_kwargs(args.env, args.env_kwargs)
    start = time.perf_counter()
    model, model_path = train(args, env_kwargs)
    train_seconds = time.perf_counter() - start
    specs = [str(model_path), *(["analytic"] if args.env in CONTROLLERS else []), "random"]
    report = evaluate.compare(args.env, specs, args.eval_episodes, args.eval_seed, args.algo, env_kwargs=env_kwargs)
    print(f"trained {model.num_timesteps} timesteps in {train_seconds:.0f} s")
    print(evaluate.format_table(report))
    results = {
        "algo": args.algo,
        "seed": args.seed,
        "timesteps": model.num_timesteps,
        "train_seconds": train_seconds,
        "hyperparams": args.hyperparams,
        "model": str(model_path),
        "evaluation": report,
    }
    evaluate.write_json(results, model_path.parent / "results.json")
    return results


if __name__ == "__main__":
    cli.run(main, PROG)
