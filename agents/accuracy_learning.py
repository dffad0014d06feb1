"""How much accuracy does learning need? JAX PPO trained on each stepper of a ladder, evaluated on the exact physics.

    python -m agents.accuracy_learning                  # the four envs, 5 seeds a stepper (hours on 2 cores)
    python -m agents.accuracy_learning --quick          # a tiny budget: the pipeline end to end, in minutes

For each env (Swing-v0, KapitzaPendulum-v0, SnakeSwimmer-v0, FallingCat-v0; --envs to choose) and each stepper of
LADDER — explicit Euler, RK4 at 1, 2 and 4 substeps, and the env's default (its closed form, or the swimmer's
Lie-group step) — one ``python train.py --backend jax --seeds 5`` run trains the seeds together on that stepper
(--runs/{env}/{stepper}/; a run whose seeds all finished is skipped, an interrupted one resumed from its
checkpoint). Then, for every seed's best policy:

- **exact physics** (the chart): its return and success on the numpy env with its default stepper, on the unseen
  episodes (reset seeds agents.baselines.UNSEEN_SEED + i, which no training saw), all episodes at once in the
  native vector env; the mean over a seed's episodes, then the mean over seeds with a 95% bootstrap interval
  (scipy.stats.bootstrap, percentile) over the seeds;
- **exploitation**: the same policy on connenv.jax, on Euler and on the default step, from the same JAX keys:
  return, success, the episodes a stepper failure cut short (``info["stepper_failed"]``, where numpy raises
  StepperError), and where the env keeps the stepper's energy error (the swing, the Kapitza pendulum:
  the change of E on segments where the control is held, summed since reset, so 0 for the exact flow) the energy a
  stepper gave from nothing per episode;
- **one-step error** of each stepper on the env: from STATES states (rows of the default env under uniform random
  actions, sampled along the episode) and a random action, one env step with the stepper and one with the default;
  the error is the largest difference of the state's entries (float64), each in units of its spread over the
  states, the median over the states, beside the share of the steps where the stepper fails.

It writes ``--docs``/precision/accuracy_learning.csv (a row per env and stepper), accuracy_learning_jax.csv (the
exploitation table), accuracy_learning.png (the chart) and guides/speed-accuracy-learning.md (the page, its
numbers and its summary generated from the run; --page rewrites the chart and the page from the CSVs alone).
--quick writes them under --runs/docs unless --docs is given.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
ENVS = ("connenv/Swing-v0", "connenv/KapitzaPendulum-v0", "connenv/SnakeSwimmer-v0", "connenv/FallingCat-v0")
LADDER = (
    ("euler", {"integrator": "euler"}),
    ("rk4", {"integrator": "rk4", "substeps": 1}),
    ("rk4×2", {"integrator": "rk4", "substeps": 2}),
    ("rk4×4", {"integrator": "rk4", "substeps": 4}),
    ("default", {}),
)
BUDGETS = {"connenv/SnakeSwimmer-v0": 500_000}
"""Steps per seed where they differ from agents/hyperparams/ppo_jax.yml's n_timesteps: the swimmer's 2·10⁶ steps × 5
seeds × 5 steppers did not fit the time of the first run on a shared 2-core machine (at 5·10⁵ no stepper learns it)."""
DIVERGES = 0.5  # a stepper failing this share of single steps from the sampled states is not trained: its episodes
# end at their first steps (the falling cat's Euler leaves SO(3) at once)
NOT_RUN = "--errors-only"  # the note of a row that this run did not train
EXPLOIT_PHYSICS = ("euler", "default")  # the physics every policy also runs on in connenv.jax (RK4's differ from the
# default by less than 1e-6 a step: see the one-step error)
STALL_SECONDS, ATTEMPTS = 900, 3  # a training whose log is silent this long is stopped and resumed, this many tries
QUICK_TIMESTEPS = 4096  # two rollouts of 16 × 128
SEEDS, QUICK_SEEDS = 5, 2
EPISODES, QUICK_EPISODES = 100, 8
STATES, QUICK_STATES = 256, 32
ENERGY_ERROR = "energy_error"  # the state entry of the envs that keep their stepper's energy error
CSV_NAME, JAX_CSV_NAME, PNG_NAME = "accuracy_learning.csv", "accuracy_learning_jax.csv", "accuracy_learning.png"
PAGE = Path("guides") / "speed-accuracy-learning.md"


def short(env_id: str) -> str:
    return env_id.split("/")[-1]


def default_name(env_id: str) -> str:
    """The default stepper's name (exact, magnus): its class's."""
    import gymnasium as gym

    import connenv  # noqa: F401

    env = gym.make(env_id)
    name = type(env.unwrapped.stepper).__name__.lower()
    env.close()
    return name


def label_of(env_id: str, stepper: str) -> str:
    return f"{default_name(env_id)} (default)" if stepper == "default" else stepper


# -- training -------------------------------------------------------------------------------------------------------


def run_dir(runs: Path, env_id: str, stepper: str) -> Path:
    return Path(runs) / short(env_id) / stepper.replace("×", "x")


def seed_folders(runs: Path, env_id: str, stepper: str, seeds: int) -> list[Path]:
    from agents.jax_train import run_folder

    return [run_folder(run_dir(runs, env_id, stepper), env_id, seed) for seed in range(seeds)]


def finished(folder: Path) -> bool:
    path = folder / "results.json"
    return path.is_file() and json.loads(path.read_text()).get("status") == "finished"


def train(env_id: str, stepper: str, kwargs: dict, runs: Path, seeds: int, timesteps: int | None,
          eval_episodes: int) -> dict:  # fmt: skip
    """One train.py --backend jax run of all seeds on this stepper, unless finished: its results.json (seed 0's)."""
    folders = seed_folders(runs, env_id, stepper, seeds)
    if not all(map(finished, folders)):
        directory = run_dir(runs, env_id, stepper)
        directory.mkdir(parents=True, exist_ok=True)
        command = [sys.executable, str(ROOT / "train.py"), "--backend", "jax", "--env", env_id, "--seeds", str(seeds),
                   "--runs", str(directory), "--eval-episodes", str(eval_episodes), "--checkpoint-freq", "100000",
                   "--resume", "--overwrite"]  # fmt: skip
        command += ["--env-kwargs", json.dumps(kwargs)] if kwargs else []
        command += ["--timesteps", str(timesteps)] if timesteps else []
        print(f"{short(env_id)} {stepper}: training {seeds} seeds (log: {directory / 'train.log'})", flush=True)
        start = time.perf_counter()
        for attempt in range(ATTEMPTS):
            returncode = _train_watched(command, directory / "train.log")
            if returncode is not None:
                break
            print(f"{short(env_id)} {stepper}: train.py wrote nothing for {STALL_SECONDS} s: stopped, resumed from its "
                  "checkpoint", flush=True)  # fmt: skip
        if returncode != 0 or not all(map(finished, folders)):
            tail = (directory / "train.log").read_text().strip().splitlines()[-3:]
            raise RuntimeError(f"{short(env_id)} {stepper}: train.py exited {returncode}: {' | '.join(tail)}")
        print(f"{short(env_id)} {stepper}: trained in {time.perf_counter() - start:.0f} s", flush=True)
    return json.loads((folders[0] / "results.json").read_text())


def _train_watched(command: list[str], log_path: Path) -> int | None:
    """Run train.py with its output appended to log_path: its exit status, or None if it stalled (its log unchanged
    for STALL_SECONDS: XLA's CPU runtime has been seen to wait forever, every thread idle), then stopped."""
    with open(log_path, "a") as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT,
                                   env={**os.environ, "PYTHONPATH": str(ROOT)})  # fmt: skip
        size, changed = -1, time.monotonic()
        while process.poll() is None:
            time.sleep(5)
            if log_path.stat().st_size != size:
                size, changed = log_path.stat().st_size, time.monotonic()
            elif time.monotonic() - changed > STALL_SECONDS:
                process.kill()
                process.wait()
                return None
    return process.returncode


# -- evaluation on the numpy env: the exact physics, the unseen episodes --------------------------------------------


def numpy_episodes(env_id: str, policy, episodes: int, first_seed: int, env_kwargs: dict | None = None) -> dict:
    """Returns and successes of a policy (rows of observations → rows of actions) on the episodes reset with seeds
    first_seed + i, all at once in the native vector env (row i's episode is gym.make(id).reset(seed=first_seed + i)'s).
    A row's first episode is counted; it ends at its first terminated or truncated step."""
    import gymnasium as gym

    import connenv  # noqa: F401

    envs = gym.make_vec(env_id, episodes, vectorization_mode="vector_entry_point", **(env_kwargs or {}))
    obs, _ = envs.reset(seed=first_seed)
    total, success, running = np.zeros(episodes), np.zeros(episodes, bool), np.ones(episodes, bool)
    while running.any():
        obs, reward, terminated, truncated, info = envs.step(policy(obs))
        done = terminated | truncated
        total += np.where(running, reward, 0.0)
        success = np.where(running & done, np.asarray(info["is_success"], bool), success)
        running &= ~done
    envs.close()
    return {"returns": total, "successes": success}


def interval(values) -> tuple[float, float, float]:
    """Mean and 95% bootstrap interval (percentile, 10 000 resamples) of per-seed values."""
    from scipy.stats import bootstrap

    values = np.asarray(values, float)
    mean = float(values.mean())
    if len(values) < 2 or np.all(values == values[0]):
        return mean, mean, mean
    result = bootstrap((values,), np.mean, confidence_level=0.95, n_resamples=10_000, method="percentile",
                       random_state=0)  # fmt: skip
    return mean, float(result.confidence_interval.low), float(result.confidence_interval.high)


# -- connenv.jax: the one-step error and the policies on each physics -----------------------------------------------


def jax_env(env_id: str, kwargs: dict):
    import jax

    jax.config.update("jax_enable_x64", True)
    import connenv.jax

    return connenv.jax.make(env_id, **kwargs)


def sample_states(env_id: str, states: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(X, A): `states` states x (the model's, float64) of the default env under uniform random actions, rows of
    states // 4 episodes of the native vector env each sampled at 4 times spread over its time limit, and a uniform
    random action for each."""
    import gymnasium as gym

    import connenv  # noqa: F401

    rows, samples = max(states // 4, 1), 4
    envs = gym.make_vec(env_id, rows, vectorization_mode="vector_entry_point")
    model = gym_model(env_id)
    envs.reset(seed=seed)
    envs.action_space.seed(seed)
    steps = gym.spec(env_id).max_episode_steps
    keep = set(np.linspace(0, steps - 2, samples).astype(int).tolist())
    kept = []
    for t in range(max(keep) + 1):
        if t in keep:
            kept.append(model.pack(envs.unwrapped.state))
        envs.step(envs.action_space.sample())
    envs.close()
    X = np.concatenate(kept)[:states]
    space = envs.single_action_space
    A = np.random.default_rng(seed).uniform(space.low, space.high, (len(X), *space.shape))
    return X, A


def gym_model(env_id: str, **kwargs):
    """The numpy model (connenv.core.model.Model) of the env with these make kwargs."""
    import gymnasium as gym

    import connenv  # noqa: F401

    return gym.make(env_id, **kwargs).unwrapped.model


def one_step(env_id: str, kwargs: dict, X: np.ndarray, A: np.ndarray) -> np.ndarray:
    """x after one env step from each state of X under A with the stepper of kwargs (numpy, each state on the
    single env's path); NaN rows where the stepper fails (StepperError)."""
    from connenv.core.steppers import StepperError

    model = gym_model(env_id, **kwargs)
    out = np.full(X.shape, np.nan)
    for i, (x, a) in enumerate(zip(X, A)):
        try:
            out[i] = model.step(x, a)
        except StepperError:
            pass
    return out


def one_step_error(env_id: str, kwargs: dict, X, A, reference=None) -> dict:
    """The stepper's one-step error on the env against the default stepper from the same states and actions: per
    state the largest entry of |x − x_default| / (that entry's spread, its standard deviation over X; entries that
    do not vary left out), then its median and 90th percentile over the states the stepper stepped, and the share
    of states where it fails (StepperError). The stepper's energy error, an entry of the swing's and the Kapitza
    pendulum's state, is left out: it is 0 under the default, whose spread over X is rounding."""
    reference = one_step(env_id, {}, X, A) if reference is None else reference
    x = one_step(env_id, kwargs, X, A)
    spread = np.std(X, axis=0)
    names = gym_model(env_id).state_names
    varies = (spread > 0) & np.array([name != ENERGY_ERROR for name in names])  # that one is a stepper's error itself
    failed = np.isnan(x).any(axis=1)
    error = np.max(np.abs(x - reference)[:, varies] / spread[varies], axis=1)[~failed]
    median, p90 = (float(np.median(error)), float(np.percentile(error, 90))) if error.size else (math.nan, math.nan)
    return {"error_median": median, "error_p90": p90, "failed_share": float(np.mean(failed))}


def jax_rollout(env_id: str, kwargs: dict, meta: dict):
    """A compiled function of (actor layers, obs mean, obs var, keys): the deterministic policy's first episode from
    each key on the JAX env of kwargs: return, success, stepper failure and (where the env keeps it) the stepper's
    energy error at the episode's end."""
    import jax
    import jax.numpy as jnp

    from agents.jax_policy import flat_observation, forward, normalize

    env, params = jax_env(env_id, kwargs)
    low, high = jnp.asarray(meta["action_low"], float), jnp.asarray(meta["action_high"], float)
    index = env.state_names.index(ENERGY_ERROR) if ENERGY_ERROR in env.state_names else None

    @jax.jit
    def run(pi, mean, var, keys):
        obs, state = jax.vmap(env.reset_env, (0, None))(keys, params)
        n = keys.shape[0]

        def step(carry, _):
            obs, state, total, success, failed, energy, running = carry
            x = normalize(flat_observation(obs, meta["obs_keys"], jnp), mean, var, meta["clip_obs"], jnp)
            action = jnp.clip(forward(pi, x, jnp), low, high)
            obs, after, reward, terminated, truncated, info = env.step_env_rows(None, state, action, params)
            done = terminated | truncated
            total = total + jnp.where(running, reward, 0.0)
            success = jnp.where(running & done, info["is_success"].astype(bool), success)
            failed = failed | (running & info["stepper_failed"])
            if index is not None:
                energy = jnp.where(running, after.x[:, index], energy)
            return (obs, after, total, success, failed, energy, running & ~done), None

        zeros = jnp.zeros(n)
        carry = (obs, state, zeros, zeros.astype(bool), zeros.astype(bool), zeros, jnp.ones(n, bool))
        (_, _, total, success, failed, energy, _), _ = jax.lax.scan(step, carry, None, params.max_steps_in_episode)
        return total, success, failed, energy

    def episodes(policy, keys) -> dict:
        pi = [(jnp.asarray(W), jnp.asarray(b)) for W, b in policy.pi]
        total, success, failed, energy = run(pi, jnp.asarray(policy.obs_mean), jnp.asarray(policy.obs_var), keys)
        return {"returns": np.asarray(total), "successes": np.asarray(success), "failed": np.asarray(failed),
                "energy_gained": None if index is None else np.asarray(energy)}  # fmt: skip

    return episodes


# -- the study ------------------------------------------------------------------------------------------------------


def study(env_id: str, args) -> tuple[list[dict], list[dict]]:
    """Train (or skip) every stepper of the ladder, evaluate its seeds: the rows of both CSVs for this env."""
    import jax

    from agents.baselines import UNSEEN_SEED
    from agents.jax_policy import JaxPolicy

    X, A = sample_states(env_id, args.states)
    reference = one_step(env_id, {}, X, A)
    keys = jax.vmap(jax.random.key)(np.arange(UNSEEN_SEED, UNSEEN_SEED + args.episodes))
    rows, jax_rows, policies = [], [], {}
    timesteps = QUICK_TIMESTEPS if args.quick else args.timesteps or BUDGETS.get(env_id)
    for stepper, kwargs in LADDER:
        error = one_step_error(env_id, kwargs, X, A, reference)
        row = {"env": short(env_id), "stepper": label_of(env_id, stepper), "kwargs": json.dumps(kwargs),
               "seeds": args.seeds}  # fmt: skip
        diverges = error["failed_share"] >= DIVERGES
        if diverges or args.errors_only:
            nan = math.nan
            row["note"] = f"it fails {error['failed_share']:.0%} of single steps" if diverges else args.errors_only
            rows.append({**row, "timesteps": 0, "train_seconds": nan, "compile_seconds": nan, "episodes": 0,
                         "success": nan, "success_low": nan, "success_high": nan, "return": nan, "return_low": nan,
                         "return_high": nan, "training_failures": nan, **error})  # fmt: skip
            print(f"{short(env_id)} {stepper}: not trained: {row['note']}", flush=True)
            continue
        results = train(env_id, stepper, kwargs, args.runs, args.seeds, timesteps, args.eval_episodes)
        folders = seed_folders(args.runs, env_id, stepper, args.seeds)
        policies[stepper] = [JaxPolicy(folder / "best_policy.npz", env_id) for folder in folders]
        exact = [numpy_episodes(env_id, p.action, args.episodes, UNSEEN_SEED) for p in policies[stepper]]
        success = interval([e["successes"].mean() for e in exact])
        ret = interval([e["returns"].mean() for e in exact])
        failures = [_training_failures(folder) for folder in folders]
        rows.append({
            **row, "note": "", "timesteps": results["timesteps"], "train_seconds": round(results["train_seconds"], 1),
            "compile_seconds": round(results["compile_seconds"], 1), "episodes": args.episodes,
            "success": success[0], "success_low": success[1], "success_high": success[2],
            "return": ret[0], "return_low": ret[1], "return_high": ret[2],
            "training_failures": int(sum(failures)), **error,
        })  # fmt: skip
        print(
            f"{short(env_id)} {stepper}: exact physics success {success[0]:.0%} [{success[1]:.0%}, "
            f"{success[2]:.0%}], return {ret[0]:.3g}; one-step error {error['error_median']:.2e}",
            flush=True,
        )
    physics = {stepper: kwargs for stepper, kwargs in LADDER}
    for on in (
        EXPLOIT_PHYSICS if "default" in policies else ()
    ):  # compiled once per physics: every policy's weights are arguments
        episodes = jax_rollout(env_id, physics[on], policies["default"][0].meta)
        for trained, trained_policies in policies.items():
            outcomes = [episodes(policy, keys) for policy in trained_policies]
            gained = [o["energy_gained"] for o in outcomes if o["energy_gained"] is not None]
            jax_rows.append({
                "env": short(env_id), "trained_on": label_of(env_id, trained), "physics": label_of(env_id, on),
                "return": float(np.mean([o["returns"].mean() for o in outcomes])),
                "success": float(np.mean([o["successes"].mean() for o in outcomes])),
                "failed": float(np.mean([o["failed"].mean() for o in outcomes])),
                "energy_gained": float(np.mean([g.mean() for g in gained])) if gained else "",
            })  # fmt: skip
    return rows, jax_rows


def _training_failures(folder: Path) -> float:
    from agents.jax_train import read_progress

    return sum(row.get("stepper_failures", 0.0) for row in read_progress(folder))


# -- the outputs ----------------------------------------------------------------------------------------------------


def write_csv(rows: list[dict], path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    keys = list(dict.fromkeys(key for row in rows for key in row))  # rows of earlier runs may lack a later column
    with open(path, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=keys, restval="")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: f"{v:.6g}" if isinstance(v, float) else v for k, v in row.items()})


def read_csv(path: Path) -> list[dict]:
    with open(path) as file:
        return [{k: _number(v) for k, v in row.items()} for row in csv.DictReader(file)]


def _number(text: str):
    try:
        return float(text)
    except ValueError:
        return text


def chart(rows: list[dict], path: Path):
    """Per env: success and return on the exact physics against training wall time (each point its stepper, the bar
    its 95% interval over seeds), and each stepper's one-step error."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = list(dict.fromkeys(row["env"] for row in rows))
    figure, axes = plt.subplots(len(envs), 3, figsize=(14, 3.4 * len(envs)), squeeze=False)
    for ax_row, env in zip(axes, envs):
        mine = [row for row in rows if row["env"] == env]
        for ax, key, name in ((ax_row[0], "success", "success on exact physics"),
                              (ax_row[1], "return", "return on exact physics")):  # fmt: skip
            for i, row in enumerate(mine):
                x, y = row["train_seconds"], row[key]
                if math.isnan(x):
                    continue
                ax.errorbar(x, y, yerr=[[y - row[f"{key}_low"]], [row[f"{key}_high"] - y]], fmt="o", capsize=3)
                offset = (5, 6 - 9 * (i % 3))  # three heights: points at about the same time and success
                ax.annotate(row["stepper"], (x, y), textcoords="offset points", xytext=offset, fontsize=8)
            ax.set_xlabel(f"training wall time, {int(mine[0]['seeds'])} seeds together (s)")
            ax.set_ylabel(name)
            ax.set_title(f"{env}: {name}", fontsize=10)
            ax.grid(alpha=0.3)
            if all(math.isnan(row["train_seconds"]) for row in mine):
                ax.text(0.5, 0.5, "not trained: see the page", ha="center", transform=ax.transAxes)
        ax_row[0].set_ylim(-0.05, 1.05)
        ax = ax_row[2]
        steppers = [row["stepper"] for row in mine]
        errors = [row["error_median"] if row["error_median"] > 0 else 1e-17 for row in mine]  # log axis: 0 (or none)
        bars = ax.barh(steppers, errors, color=["tab:red" if row["failed_share"] > 0 else "tab:blue" for row in mine])
        ax.set_xscale("log")
        ax.set_xlabel("one-step state error / spread (median)")
        ax.set_title(f"{env}: one-step error", fontsize=10)
        for bar, row in zip(bars, mine):
            notes = ["0" if row["error_median"] == 0 else ""]
            notes += [f"fails {row['failed_share']:.0%} of steps"] if row["failed_share"] > 0 else []
            ax.annotate(" ".join(n for n in notes if n), (bar.get_width(), bar.get_y() + 0.3), fontsize=8)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=90)
    plt.close(figure)


def good_enough(row: dict, default: dict) -> bool:
    """A stepper's policies do as well on the exact physics as the default's: its success interval reaches the
    default's mean, or its mean lies within 5 points of it."""
    return row["success_high"] >= default["success"] or row["success"] >= default["success"] - 0.05


def in_short(rows: list[dict]) -> str:
    """The summary's first sentences: where a cheaper stepper trained policies as good as the default's, where not."""
    learned, worse, unlearned = [], [], []
    for env in dict.fromkeys(row["env"] for row in rows):
        mine = [row for row in rows if row["env"] == env]
        default = next(row for row in mine if row["stepper"].endswith("(default)"))
        if math.isnan(default["train_seconds"]):
            continue
        if default["success"] == 0:
            unlearned.append(env)
            continue
        cheap = [row for row in mine if row is not default and not math.isnan(row["train_seconds"])]
        bad = [row["stepper"] for row in cheap if not good_enough(row, default)]
        (worse if bad else learned).append(f"{env} ({', '.join(bad)})" if bad else env)
    diverged = [f"{row['env']}'s {row['stepper']} ({row['failed_share']:.0%} of single steps)" for row in rows
                if row["failed_share"] >= DIVERGES]  # fmt: skip
    text = "In short: "
    text += (f"on {' and '.join(learned)} every cheaper stepper of the ladder, explicit Euler included, trained "
             "policies as good on the exact physics as the default step did. " if learned else "")  # fmt: skip
    text += f"Worse than the default's: {'; '.join(worse)}. " if worse else ""
    text += f"At this budget nothing learned {', '.join(unlearned)}, on any stepper. " if unlearned else ""
    text += (f"A cheaper model stopped being usable where it fails the env's divergence check: {', '.join(diverged)}."
             if diverged else "")  # fmt: skip
    return text.strip()


def summary(rows: list[dict], jax_rows: list[dict]) -> list[str]:
    """What the run shows, in sentences made from its numbers."""
    lines = [in_short(rows)]
    for env in dict.fromkeys(row["env"] for row in rows):
        mine = [row for row in rows if row["env"] == env]
        default = next(row for row in mine if row["stepper"].endswith("(default)"))
        diverged = [row for row in mine if math.isnan(row["train_seconds"])]
        if default in diverged:  # not trained in this run (--errors-only): the one-step errors alone
            errors = ", ".join(
                f"{row['stepper']} {row['error_median']:.1e}"
                + (f" (fails {row['failed_share']:.0%} of single steps)" if row["failed_share"] else "")
                for row in mine
            )
            lines.append(f"**{env}**: not trained in this run ({default.get('note', '')}). One-step errors: {errors}.")
            continue
        cheap = [row for row in mine if row is not default and row not in diverged]
        good = [row["stepper"] for row in cheap if good_enough(row, default)]
        bad = [f"{row['stepper']} ({row['success']:.0%})" for row in cheap if not good_enough(row, default)]
        fastest = min((row for row in mine if row not in diverged), key=lambda row: row["train_seconds"])
        text = (f"**{env}**: trained on the default step the policies succeed in {default['success']:.0%} "
                f"[{default['success_low']:.0%}, {default['success_high']:.0%}] of the exact episodes "
                f"({default['train_seconds']:.0f} s of training). ")  # fmt: skip
        if default["success"] == 0:
            text += "At this budget no policy succeeds, whatever its stepper: compare the returns. "
            good = [row["stepper"] for row in cheap if row["return_high"] >= default["return_low"]]
            bad = [f"{row['stepper']} (return {row['return']:.3g})" for row in cheap if row["stepper"] not in good]
            text += f"Returns within the default's interval: {', '.join(good)}. " if good else ""
        else:
            text += (
                f"As good on the exact physics: {', '.join(good)}. " if good else "No cheaper stepper does as well. "
            )
        text += f"Not good enough: {', '.join(bad)}. " if bad else ""
        names = ", ".join(row["stepper"] for row in diverged)
        text += f"Not trained, as it fails most single steps (the env's divergence check): {names}. " if names else ""
        failed = [f"{row['stepper']} ({row['failed_share']:.0%} of single steps)" for row in mine
                  if row["failed_share"] > 0]  # fmt: skip
        text += f"Steppers that fail the env's divergence check: {', '.join(failed)}. " if failed else ""
        text += (f"The fastest training was {fastest['stepper']} ({fastest['train_seconds']:.0f} s against "
                 f"{default['train_seconds']:.0f} s).")  # fmt: skip
        lines.append(text)
    for env in dict.fromkeys(row["env"] for row in jax_rows):
        own = {(r["trained_on"], r["physics"]): r for r in jax_rows if r["env"] == env}
        default = next(k for k, _ in own if k.endswith("(default)"))
        e_e, e_d, d_e = own.get(("euler", "euler")), own.get(("euler", default)), own.get((default, "euler"))
        d_d = own.get((default, default))
        if not (e_e and e_d and d_e and d_d):
            continue
        text = (f"**{env}, Euler's error**: the policies trained on Euler return {e_e['return']:.3g} on Euler "
                f"(success {e_e['success']:.0%}, {e_e['failed']:.0%} of the episodes cut short by a stepper failure) "
                f"and {e_d['return']:.3g} on the {default} step (success {e_d['success']:.0%}); the policies trained "
                f"on the {default} step return {d_e['return']:.3g} on Euler (success {d_e['success']:.0%}, "
                f"{d_e['failed']:.0%} cut short) (connenv.jax, the same episodes): Euler's error is worth "
                f"{e_e['return'] - e_d['return']:+.3g} of return to the Euler-trained policies and "
                f"{d_e['return'] - d_d['return']:+.3g} to the {default}-trained ones.")  # fmt: skip
        if e_e["energy_gained"] != "" and d_e["energy_gained"] != "":
            text += (f" Energy from nothing (Euler's energy error at the episode's end): {e_e['energy_gained']:.3g} J "
                     f"per episode under the Euler-trained policies, {d_e['energy_gained']:.3g} J under the "
                     f"{default}-trained ones.")  # fmt: skip
        lines.append(text)
    return lines


def page(rows: list[dict], jax_rows: list[dict], args, wall: float | None) -> str:
    png = f"../precision/{PNG_NAME}"
    budgets = {env: int(max(r["timesteps"] for r in rows if r["env"] == env)) for env in dict.fromkeys(
        r["env"] for r in rows)}  # fmt: skip
    budgets = {env: steps for env, steps in budgets.items() if steps > 0}  # the envs trained
    out = [
        "# How much accuracy does learning need?",
        "",
        "Generated by `python -m agents.accuracy_learning` (its docstring: what each number is); do not edit by hand.",
        f"This run: {args.seeds} seeds a stepper trained together by JAX PPO (agents/hyperparams/ppo_jax.yml), "
        f"{args.episodes} unseen episodes a seed (reset seeds 100000 on), {args.states} states for the one-step "
        f"error{'' if wall is None else f'; {wall / 60:.0f} min in all on this machine'}. Steps per seed: "
        + ", ".join(f"{env} {steps:,}" for env, steps in budgets.items())
        + (
            ""
            if args.quick
            else f" (SnakeSwimmer-v0 at {BUDGETS['connenv/SnakeSwimmer-v0']:,}, a quarter of "
            "ppo_jax.yml's 2·10⁶, to fit the study into the hours of a shared 2-core machine)"
        )
        + ".",
        "",
        (
            "Each env is trained with each stepper of a ladder — explicit Euler, RK4 at 1, 2 and 4 substeps and the "
            "env's default — and every policy is evaluated on the **default physics** (the closed form; the swimmer's "
            "Lie-group step). Success and return are the mean over seeds of each seed's mean over the episodes, with a "
            "95% bootstrap interval over the seeds; training wall time is the run's, all seeds together, without "
            "compiling. The one-step error is each stepper's, measured here (not read from docs/precision, whose charts "
            "hold other steppers and episodes): after one env step from the same state and action as the default's, "
            "the largest difference of the state's entries, each in units of its spread over the states (the median "
            "over states of the default env under random actions); 0 for the default itself; a red bar where the "
            "stepper fails some steps (the env's divergence check). The wall times were taken on a machine "
            "of 2 cores shared with other trainings: read differences below about 2× as noise, and the one-step "
            "costs of the steppers on docs/speed-accuracy.md for their cost alone."
        ),
        "",
        f"![accuracy against learning]({png})",
        "",
        "## What it shows",
        "",
        *[line + "\n" for line in summary(rows, jax_rows)],
        "## On the exact physics",
        "",
        "| env | stepper | training (s) | compiling (s) | success | return | one-step error (median) | steps failed "
        + "| failures in training |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if math.isnan(r["train_seconds"]):
            out.append(f"| {r['env']} | {r['stepper']} | not trained: {r.get('note', '')} | | | | "
                       f"{r['error_median']:.2e} | {r['failed_share']:.0%} | |")  # fmt: skip
            continue
        out.append(
            f"| {r['env']} | {r['stepper']} | {r['train_seconds']:.0f} | {r['compile_seconds']:.0f} | "
            f"{r['success']:.0%} [{r['success_low']:.0%}, {r['success_high']:.0%}] | {r['return']:.3g} "
            f"[{r['return_low']:.3g}, {r['return_high']:.3g}] | {r['error_median']:.2e} | {r['failed_share']:.0%} | "
            f"{int(r['training_failures'])} |"
        )
    out += [
        "",
        "## Each policy on Euler and on the default step",
        "",
        (
            "On connenv.jax from the same keys (100000 on): a stepper failure (numpy's StepperError: Euler's energy "
            "error "
            "past its bound, Euler off SO(3)) ends the episode there. Energy gained: the stepper's energy error at the "
            "episode's end (the change of E on held segments summed since reset, J), where the env keeps it."
        ),
        "",
        "| env | trained on | run on | return | success | episodes cut by a failure | energy gained (J) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in jax_rows:
        energy = "" if r["energy_gained"] == "" else f"{r['energy_gained']:.3g}"
        out.append(f"| {r['env']} | {r['trained_on']} | {r['physics']} | {r['return']:.3g} | {r['success']:.0%} | "
                   f"{r['failed']:.0%} | {energy} |")  # fmt: skip
    out += ["", f"Data: [{CSV_NAME}](../precision/{CSV_NAME}), [{JAX_CSV_NAME}](../precision/{JAX_CSV_NAME}).", ""]
    return "\n".join(out)


def write_outputs(rows: list[dict], jax_rows: list[dict], docs: Path, args, wall: float | None):
    write_csv(rows, docs / "precision" / CSV_NAME)
    write_csv(jax_rows, docs / "precision" / JAX_CSV_NAME)
    chart(rows, docs / "precision" / PNG_NAME)
    (docs / PAGE).parent.mkdir(parents=True, exist_ok=True)
    (docs / PAGE).write_text(page(rows, jax_rows, args, wall))


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m agents.accuracy_learning", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--envs", nargs="+", default=list(ENVS), choices=ENVS, metavar="ID")
    parser.add_argument("--quick", action="store_true", help="a tiny budget, few seeds and episodes")
    parser.add_argument("--runs", type=Path, default=Path("runs/accuracy_learning"))
    parser.add_argument(
        "--docs", type=Path, help="where the CSVs, chart and page go (default: docs; --quick: RUNS/docs)"
    )
    parser.add_argument("--errors-only", nargs="?", const=NOT_RUN, metavar="REASON",
                        help="no training: the one-step errors alone (REASON: why, for the page)")  # fmt: skip
    parser.add_argument("--page", action="store_true", help="only rewrite the chart and the page from the CSVs")
    parser.add_argument("--timesteps", type=int, help="steps per seed for every env (default: ppo_jax.yml's, BUDGETS)")
    args = parser.parse_args(argv)
    args.seeds = QUICK_SEEDS if args.quick else SEEDS
    args.episodes = QUICK_EPISODES if args.quick else EPISODES
    args.states = QUICK_STATES if args.quick else STATES
    args.eval_episodes = 2 if args.quick else 10
    args.docs = args.docs or (args.runs / "docs" if args.quick else ROOT / "docs")
    return args


def main(argv=None):
    args = parse_args(argv)
    if args.page:
        rows, jax_rows = (read_csv(args.docs / "precision" / name) for name in (CSV_NAME, JAX_CSV_NAME))
        write_outputs(rows, jax_rows, args.docs, args, None)
        print(f"wrote {args.docs / PAGE} and {args.docs / 'precision' / PNG_NAME} from the CSVs")
        return rows, jax_rows
    start = time.perf_counter()
    rows, jax_rows = [], []
    for env_id in args.envs:
        env_rows, env_jax_rows = study(env_id, args)
        rows += env_rows
        jax_rows += env_jax_rows
        write_outputs(rows, jax_rows, args.docs, args, time.perf_counter() - start)  # after each env: partial results
    print(f"wrote {args.docs / PAGE} and {args.docs / 'precision' / PNG_NAME} in {time.perf_counter() - start:.0f} s")
    return rows, jax_rows


if __name__ == "__main__":
    main()
