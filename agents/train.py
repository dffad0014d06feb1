"""Train an agent with rl-zoo3, then compare it with the analytic controller and a random policy.

    python train.py --env ID --algo ppo --timesteps N --seed 0    # ID: a connenv id (--help lists them)

Hyperparameters come from agents/hyperparams/{algo}.yml (rl-zoo3's layout, the env id as top-level key, or
``default`` for every env without its own) or from --hyperparams PATH, without the key ``long`` (the budget curves'
overrides, which agents.baselines reads); --timesteps overrides their n_timesteps. rl-zoo3's ExperimentManager reads
them, builds the envs, shows a progress bar and evaluates periodically on a separate env: every --eval-freq steps,
by default a tenth of the budget (at most 25 000 steps, and at least one rollout of an on-policy algorithm, whose
policy changes only once per rollout). The run folder, runs/{env}_{algo}_s{seed}/, is laid out as rl-zoo3's: the
model {env}.zip, best_model.zip and evaluations.npz of the periodic evaluation, {env}/config.yml (the
hyperparameters used), {env}/args.yml and {env}/vecnormalize.pkl if normalized; train.py adds
{env}/best_vecnormalize.pkl, the statistics best_model.zip was evaluated with (rl-zoo3 overwrites vecnormalize.pkl
with the final ones), and results.json, the final evaluation of agents.evaluate on the same episodes for every
policy ("status": "finished").

A run folder holds one run. If it holds an earlier one, train.py refuses to start, naming the two ways out: --resume
continues the earlier run from its last checkpoint, --overwrite moves it aside to {run}.{date-time} and trains anew.
It neither resumes unasked (the same command would then do two different things) nor deletes or moves a run unasked
(a run is hours of work); starting over in place would leave the earlier run's best model and evaluations beside
the new model.

Ctrl-C (SIGINT) stops training: the model so far is saved as {env}.zip, results.json records "status":
"interrupted" and the steps trained (no final evaluation), and train.py exits with 130, as a shell does for an
interrupted command, so that a calling script sees it.

With --env-kwargs the envs are made with the kwargs given as a JSON object ('{"dt": 0.02}') or as module:factory,
the kwargs factory() returns (a dict, or a system, which becomes {"system": system}); several update one another in
order. Enough to train on a user's own system, BUILDER the id of one of the two builders (README):

    python train.py --env BUILDER --env-kwargs my_robot:env_kwargs --algo ppo
    python train.py --env BUILDER --env-kwargs my_robot:system '{"u_low": -3, "u_high": 3}'

The module is imported from the working directory or the Python path; the analytic controller is then left out of
the final evaluation (there is none for a user's system). Bad input of any argument ends train.py in one line
naming it, before any training.

With --checkpoint-freq N the run saves a checkpoint into {run}/checkpoints/ (SB3's CheckpointCallback's files: the
model, the VecNormalize statistics, the replay buffer) between rollouts, at the first one past every N steps, and at
the end of training: a checkpoint inside a rollout would resume with that rollout's steps counted but not learned
from, and a resumed PPO run would train one rollout past its budget. With --resume a run continues from its last
checkpoint to the same n_timesteps (the same steps as a run never stopped), its periodic evaluations so far kept; a
folder with no run yet starts from step 0, and says so; a run with no checkpoint is refused. --resume --overwrite
resumes a run that has a checkpoint and moves aside one that has none (what agents.tune's trials use).
agents.baselines uses --resume, so that a run whose process is killed is retried from its last checkpoint.

With --vector-env the training and periodic-evaluation envs are the env's native vector env (gym.make_vec with its
vector_entry_point, through agents.vec_env.NativeVecEnv) instead of SB3's DummyVecEnv of single envs; the final
evaluation stays on single envs.
"""

from __future__ import annotations

import argparse
import inspect
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import torch as th
import yaml
from rl_zoo3.exp_manager import ExperimentManager
from rl_zoo3.utils import ALGOS
from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback, EvalCallback, ProgressBarCallback
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import VecNormalize
from tqdm import TqdmExperimentalWarning

import agents
from agents import curriculum, evaluate
from agents.controllers import CONTROLLERS
from agents.run_folders import claim_run_folder, holds_run, latest_checkpoint, move_aside  # noqa: F401 (train.py's API)
from agents.vec_env import make_native_vec_env
from connenv import cli

PROG = "train.py"
HYPERPARAMS = Path(agents.__file__).parent / "hyperparams"
PERIODIC_EVAL_EPISODES = 10
EVAL_FREQ_MAX = 25_000  # steps between periodic evaluations by default, at most
warnings.filterwarnings("ignore", category=TqdmExperimentalWarning)  # SB3's progress bar is tqdm.rich, "experimental"


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default=evaluate.DEFAULT_ENV, choices=evaluate.ENV_IDS, help="default: %(default)s")
    parser.add_argument("--algo", default="ppo", choices=sorted(ALGOS))
    parser.add_argument(
        "--backend",
        default="sb3",
        choices=("sb3", "jax"),
        help="sb3: rl-zoo3 and SB3 on the numpy env (default); jax: PPO compiled with the env (agents.jax_train)",
    )
    parser.add_argument(
        "--seeds", type=evaluate.positive_int, default=1, help="--backend jax: seeds --seed … --seed + SEEDS − 1 at once"
    )
    parser.add_argument("--timesteps", type=evaluate.positive_int, help="default: n_timesteps of the hyperparameters")
    parser.add_argument("--seed", type=evaluate.seed_int, default=0)
    parser.add_argument("--hyperparams", help="rl-zoo3 YAML file (default: agents/hyperparams/{algo}.yml)")
    parser.add_argument(
        "--eval-freq",
        type=int,
        help="steps between periodic evaluations, ≤ 0: none (default: a tenth of the budget, at most 25 000 and at "
        "least one rollout)",
    )
    parser.add_argument("--eval-episodes", type=evaluate.positive_int, default=100, help="episodes of the final table")
    parser.add_argument(
        "--periodic-episodes",
        type=evaluate.positive_int,
        default=PERIODIC_EVAL_EPISODES,
        help=f"episodes of each periodic evaluation (default: {PERIODIC_EVAL_EPISODES})",
    )
    parser.add_argument(
        "--eval-seed", type=evaluate.seed_int, default=0, help="final episode i is reset with eval-seed + i"
    )
    parser.add_argument("--runs", type=cli.writable_dir, default="runs", help="folder of the run folders")
    parser.add_argument("--num-threads", type=evaluate.positive_int, default=1, help="torch threads")
    parser.add_argument("--vector-env", action="store_true", help="train on the env's native vector env")
    parser.add_argument("--env-kwargs", nargs="+", metavar="KWARGS", help=evaluate.ENV_KWARGS_HELP)
    parser.add_argument("--checkpoint-freq", type=int, default=0, help="steps between checkpoints, ≤ 0: none")
    parser.add_argument("--resume", action="store_true", help="continue from the run folder's last checkpoint")
    parser.add_argument(
        "--overwrite", action="store_true", help="move an earlier run in the run folder aside to {run}.{date-time}"
    )
    args = parser.parse_args(argv)
    if args.backend == "sb3" and args.seeds != 1:
        parser.error(f"argument --seeds: {args.seeds} seeds at once train on --backend jax; sb3 trains one --seed")
    if args.backend == "jax" and args.algo != "ppo":
        parser.error(f"argument --algo: --backend jax trains ppo, not {args.algo}")
    name = "ppo_jax" if args.backend == "jax" else args.algo
    args.hyperparams = args.hyperparams or str(HYPERPARAMS / f"{name}.yml")
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
    if not (isinstance(loaded, dict) and isinstance(loaded.get(env_id, loaded.get("default")), dict)):
        return f"holds no hyperparameters for {env_id} (rl-zoo3's layout: the env id, or default, as key of a mapping)"
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
    """SB3's CheckpointCallback's files, saved between rollouts: at the first rollout start past every `frequency`
    steps, when the previous rollout has been learned from (PPO's update, SAC's gradient steps), and at the end of
    training. Each completed checkpoint is then named in {path}/latest (written atomically, so that a run killed
    while saving resumes from the one before) and the one before is deleted (a replay buffer's checkpoint is as large
    as the buffer)."""

    def __init__(self, frequency: int, path: Path):
        super().__init__(1, str(path), save_replay_buffer=True, save_vecnormalize=True)  # its _on_step saves each call
        self.frequency = frequency
        self.saved = 0  # the steps of the last checkpoint, or those trained before

    def _on_training_start(self) -> None:
        self.saved = self.model.num_timesteps  # a resumed run's checkpoint

    def _on_step(self) -> bool:
        return True

    def _on_rollout_start(self) -> None:
        if self.model.num_timesteps // self.frequency > self.saved // self.frequency:
            self.save()

    def _on_training_end(self) -> None:
        if self.model.num_timesteps != self.saved:
            self.save()

    def save(self):
        self.num_timesteps = self.model.num_timesteps
        super()._on_step()
        path = Path(self.save_path)
        before = latest_checkpoint(path.parent)
        (path / "latest.tmp").write_text(str(self.num_timesteps))
        os.replace(path / "latest.tmp", path / "latest")
        if before is not None and before != self.num_timesteps:
            for kind in ("", "replay_buffer_", "vecnormalize_"):
                for old in path.glob(f"rl_model_{kind}{before}_steps.*"):
                    old.unlink()
        self.saved = self.num_timesteps


class TrainingInterrupted(KeyboardInterrupt):
    """An interrupt (Ctrl-C) that stopped training, raised once the model so far is saved at `path`."""

    def __init__(self, model, path: Path):
        super().__init__(f"training interrupted at step {model.num_timesteps}; the model so far is {path}")
        self.model, self.path = model, path


class BestStatsExperimentManager(ExperimentManager):
    """rl-zoo3's ExperimentManager, keeping the VecNormalize statistics of the best model as well as the final; with
    ``checkpoint_freq`` saving checkpoints, and ``after_eval`` (a callback) called after each periodic evaluation;
    ``eval_freq`` None fits the periodic evaluations to the budget; an interrupt sets ``interrupted``."""

    checkpoint_freq = 0
    after_eval: BaseCallback | None = None
    interrupted = False

    curriculum = None  # the training env's wrapper of agents.curriculum, from the hyperparameter "curriculum"

    def read_hyperparameters(self):
        """rl-zoo3's, noting the rollout length n_steps of an on-policy algorithm (1 for an off-policy one), with
        the hyperparameter "curriculum" taken out for train.py (it stays in the saved config.yml) and "long" left
        out (of the saved config.yml too, which agents.baselines compares with the env's hyperparameters)."""
        hyperparams, saved_hyperparams = super().read_hyperparameters()
        for held in (hyperparams, saved_hyperparams):
            held.pop("long", None)
        if "curriculum" in hyperparams:
            self.curriculum = curriculum.wrapper(hyperparams.pop("curriculum"))
        n_steps = inspect.signature(ALGOS[self.algo]).parameters.get("n_steps")
        self.n_steps = hyperparams.get("n_steps", n_steps.default) if n_steps else 1
        return hyperparams, saved_hyperparams

    def create_envs(self, n_envs: int, eval_env: bool = False, no_log: bool = False):
        """rl-zoo3's envs, the training env's wrapped in the curriculum if there is one (never the evaluation's)."""
        if eval_env or self.curriculum is None:
            return super().create_envs(n_envs, eval_env, no_log)
        if self.env_wrapper is not None:
            raise ValueError("a curriculum and an env_wrapper hyperparameter cannot be combined")
        self.env_wrapper = self.curriculum
        try:
            return super().create_envs(n_envs, eval_env, no_log)
        finally:
            self.env_wrapper = None

    def create_callbacks(self):
        if self.eval_freq is None:  # a tenth of the budget, within [one rollout, EVAL_FREQ_MAX] where it can
            self.eval_freq = max(min(EVAL_FREQ_MAX, self.n_timesteps // 10), self.n_steps * self.n_envs)
        super().create_callbacks()
        for callback in self.callbacks:
            if isinstance(callback, EvalCallback):
                callback.callback_on_new_best = SaveBestVecNormalize(Path(self.params_path) / "best_vecnormalize.pkl")
                callback.callback_on_new_best.parent = callback
                if self.after_eval is not None:
                    callback.callback, self.after_eval.parent = self.after_eval, callback
        if self.checkpoint_freq > 0:
            self.callbacks.append(Checkpoints(self.checkpoint_freq, Path(self.save_path) / "checkpoints"))

    def resume(self, model, steps: int):
        """The model of the checkpoint at `steps`, on model's env, with its VecNormalize statistics, its replay buffer
        and the periodic evaluations up to it, the next due where the run never stopped would have made it (SB3's
        EvalCallback counts its calls, one per step of the vector env, from the start of the run)."""
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
            if isinstance(callback, EvalCallback):
                callback.n_calls = steps // resumed.get_env().num_envs
            if isinstance(callback, EvalCallback) and evaluations.is_file():
                kept = np.load(evaluations)["timesteps"] <= steps
                data = {key: value[kept] for key, value in np.load(evaluations).items()}
                callback.evaluations_timesteps = data["timesteps"].tolist()
                callback.evaluations_results = data["results"].tolist()
                callback.evaluations_length = data["ep_lengths"].tolist()
                callback.evaluations_successes = data["successes"].tolist() if "successes" in data else []
                if len(data["results"]):
                    callback.best_mean_reward = float(np.max(np.mean(data["results"], axis=1)))
        return resumed

    def learn(self, model):
        """rl-zoo3's learn to n_timesteps, a resumed model from its step count on; an interrupt (Ctrl-C) stops it
        and sets ``interrupted`` (rl-zoo3 passes over it, so that a caller could not tell)."""
        try:
            model.learn(
                max(self.n_timesteps - model.num_timesteps, 0),
                callback=self.callbacks,
                reset_num_timesteps=not model.num_timesteps,
            )
        except KeyboardInterrupt:
            self.interrupted = True
            for callback in self.callbacks:
                if isinstance(callback, ProgressBarCallback):
                    callback.on_training_end()  # closes the bar
        finally:
            model.env.close()


class VectorExperimentManager(BestStatsExperimentManager):
    """rl-zoo3's ExperimentManager on the native vector env: create_envs is the one hook that builds the training
    and periodic-evaluation envs. Both are native, so that SB3 finds the same wrappers around them when it copies
    the VecNormalize statistics from one to the other."""

    def create_envs(self, n_envs: int, eval_env: bool = False, no_log: bool = False):
        if self.env_wrapper is not None or self.frame_stack is not None or self.curriculum is not None:
            raise ValueError(
                "--vector-env takes no env_wrapper, frame_stack or curriculum hyperparameters; they wrap single envs"
            )
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


def experiment(args: argparse.Namespace, env_kwargs: dict | None = None, after_eval: BaseCallback | None = None):
    """rl-zoo3's ExperimentManager (ours) for the arguments, in the run folder runs/{env}_{algo}_s{seed}/; after_eval:
    a callback run after each periodic evaluation."""
    manager = (VectorExperimentManager if args.vector_env else BestStatsExperimentManager)(
        args,
        args.algo,
        args.env,
        args.runs,
        n_timesteps=args.timesteps or 0,
        eval_freq=args.eval_freq,
        n_eval_episodes=args.periodic_episodes,
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
    return manager


def train(args: argparse.Namespace, env_kwargs: dict | None = None, after_eval: BaseCallback | None = None):
    """Train with rl-zoo3's ExperimentManager into the run folder, from its last checkpoint with --resume; return the
    model and the path of its zip. after_eval: a callback run after each periodic evaluation. Raises FileExistsError
    if the folder holds an earlier run (claim_run_folder), TrainingInterrupted on an interrupt once the model is
    saved."""
    set_random_seed(args.seed)
    th.set_num_threads(args.num_threads)
    manager = experiment(args, env_kwargs, after_eval)
    steps = claim_run_folder(Path(manager.save_path), args.resume, args.overwrite)
    model, _ = manager.setup_experiment()
    if steps is not None:
        model = manager.resume(model, steps)
        print(f"resumed from the checkpoint at {steps} steps")
    manager.learn(model)
    manager.save_trained_model(model)
    path = Path(manager.save_path) / f"{manager.env_name}.zip"
    if manager.interrupted:
        raise TrainingInterrupted(model, path)
    return model, path


def main(argv: list[str] | None = None) -> dict:
    """Train, evaluate beside the analytic controller and a random policy, print the table, write results.json. An
    interrupted run writes results.json without the evaluation and exits with 130; a run folder holding an earlier
    run exits with an error naming it."""
    args = parse_args(argv)
    if args.backend == "jax":
        from agents import jax_train

        return jax_train.run(args)
    env_kwargs = evaluate.make_kwargs(args.env, args.env_kwargs)
    start = time.perf_counter()
    try:
        model, model_path = train(args, env_kwargs)
    except FileExistsError as error:
        raise SystemExit(f"train.py: error: {error}") from None
    except TrainingInterrupted as interrupt:
        results = run_results(args, interrupt.model, interrupt.path, time.perf_counter() - start, None)
        evaluate.write_json(results, interrupt.path.parent / "results.json")
        steps = latest_checkpoint(interrupt.path.parent)
        resume = "" if steps is None else f"; --resume continues it from its checkpoint at step {steps}"
        print(f"{interrupt}; results.json marks the run interrupted{resume}", file=sys.stderr)
        raise SystemExit(130) from None
    train_seconds = time.perf_counter() - start
    specs = [str(model_path), *(["analytic"] if args.env in CONTROLLERS else []), "random"]
    report = evaluate.compare(args.env, specs, args.eval_episodes, args.eval_seed, args.algo, env_kwargs=env_kwargs)
    print(f"trained {model.num_timesteps} timesteps in {train_seconds:.0f} s")
    print(evaluate.format_table(report))
    results = run_results(args, model, model_path, train_seconds, report)
    evaluate.write_json(results, model_path.parent / "results.json")
    return results


def run_results(args: argparse.Namespace, model, model_path: Path, train_seconds: float, report: dict | None) -> dict:
    """results.json: the run's status ("finished", or "interrupted" with no evaluation), steps and evaluation."""
    return {
        "status": "interrupted" if report is None else "finished",
        "algo": args.algo,
        "seed": args.seed,
        "timesteps": model.num_timesteps,
        "train_seconds": train_seconds,
        "hyperparams": args.hyperparams,
        "model": str(model_path),
        "evaluation": report,
    }


if __name__ == "__main__":
    cli.run(main, PROG)
