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

With --env-kwargs module:factory the envs are made with the kwargs factory() returns (a dict, or a system, which
becomes {"system": system}): enough to train on a user's own system,

    python train.py --env connenv/ActiveConstraint-v0 --env-kwargs my_robot:env_kwargs --algo ppo

The module is imported from the working directory or the Python path; the analytic controller is then left out of
the final evaluation (there is none for a user's system).

With --vector-env the training and periodic-evaluation envs are the env's native vector env (gym.make_vec with its
vector_entry_point, through agents.vec_env.NativeVecEnv) instead of SB3's DummyVecEnv of single envs; the final
evaluation stays on single envs.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import torch as th
from rl_zoo3.exp_manager import ExperimentManager
from rl_zoo3.utils import ALGOS
from stable_baselines3.common.callbacks import BaseCallback, EvalCallback
from stable_baselines3.common.utils import set_random_seed
from tqdm import TqdmExperimentalWarning

import agents
from agents import evaluate
from agents.controllers import CONTROLLERS
from agents.vec_env import make_native_vec_env

HYPERPARAMS = Path(agents.__file__).parent / "hyperparams"
PERIODIC_EVAL_EPISODES = 10
warnings.filterwarnings("ignore", category=TqdmExperimentalWarning)  # SB3's progress bar is tqdm.rich, "experimental"


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
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
    parser.add_argument("--runs", default="runs", help="folder of the run folders")
    parser.add_argument("--num-threads", type=evaluate.positive_int, default=1, help="torch threads")
    parser.add_argument("--vector-env", action="store_true", help="train on the env's native vector env")
    parser.add_argument("--env-kwargs", help="module:factory returning the make kwargs (or the system) of --env")
    args = parser.parse_args(argv)
    args.hyperparams = args.hyperparams or str(HYPERPARAMS / f"{args.algo}.yml")
    if not Path(args.hyperparams).is_file():
        parser.error(f"--hyperparams {args.hyperparams!r}: no such file; give a YAML file for --algo {args.algo}")
    return args


class SaveBestVecNormalize(BaseCallback):
    """On a new best periodic evaluation, save the VecNormalize statistics it was evaluated with to `path`."""

    def __init__(self, path: Path):
        super().__init__()
        self.path = path

    def _on_step(self) -> bool:
        if self.model.get_vec_normalize_env() is not None:
            self.model.get_vec_normalize_env().save(str(self.path))
        return True


class BestStatsExperimentManager(ExperimentManager):
    """rl-zoo3's ExperimentManager, keeping the VecNormalize statistics of the best model as well as the final."""

    def create_callbacks(self):
        super().create_callbacks()
        for callback in self.callbacks:
            if isinstance(callback, EvalCallback):
                callback.callback_on_new_best = SaveBestVecNormalize(Path(self.params_path) / "best_vecnormalize.pkl")
                callback.callback_on_new_best.parent = callback


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


def train(args: argparse.Namespace, env_kwargs: dict | None = None):
    """Train with rl-zoo3's ExperimentManager into the run folder; return the model and the path of its zip."""
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
    model, _ = manager.setup_experiment()
    manager.learn(model)
    manager.save_trained_model(model)
    return model, Path(manager.save_path) / f"{manager.env_name}.zip"


def main(argv: list[str] | None = None) -> dict:
    """Train, evaluate beside the analytic controller and a random policy, print the table, write results.json."""
    args = parse_args(argv)
    env_kwargs = evaluate.env_kwargs_of(args.env_kwargs)
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
    main()
