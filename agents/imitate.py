"""Behaviour cloning of the analytic controllers into the policy class RL trains, and the diagnosis it serves
(docs/guides/reference-results.md, "Why it did not learn, and what did").

    python -m agents.imitate --env ID --episodes 20 --epochs 30 --seed 0 --out runs/imitate  # --help lists the ids
    python -m agents.imitate --diagnose --jobs 2 --write docs/baselines/diagnosis.json

A clone is the policy of SB3's PPO with the env's entry of agents/hyperparams/ppo.yml (its policy class, net_arch
and gSDE), trained by supervised regression: the mean squared error between its deterministic action and the
controller's, by Adam in plain torch. (The `imitation` library's BC would pin gymnasium 0.29 and SB3 2.2, older than
the project's.) Where ppo.yml normalizes observations, the clone sees them through a VecNormalize fitted on the
demonstrations, saved beside it, so it is the same function of the observation as an RL policy. The clone is saved
as rl-zoo3 lays out a run, {out}/{env}_bc_s{seed}/model.zip with connenv-{env}/args.yml and vecnormalize.pkl, so
``python -m agents.evaluate --policy PATH/model.zip`` loads it as it loads a trained model.

Demonstrations: the controller's episodes from reset seeds DEMO_SEED + 1000·seed + i, never the evaluation's.
Then DAgger (Ross, Gordon & Bagnell 2011): the clone drives, the controller runs beside it on the clone's
observations, its own memory threaded through the episode, and labels every visited state; the clone is trained
on all labels so far. This is sound only where the controller answers for a state it did not plan for, which
`diagnose` measures as the success of the controller made memoryless (`Memoryless`: it forgets its plan and mode
before every step). The bead's tilt law and the coin's planner keep no memory; the balls' optimal arc is replanned
from any state into the rest of the same arc; the Kapitza swing-up's mode (pumping or holding, a hysteresis of the
angle) is threaded along the clone's episode. The ball's holonomy planner and the snake's gait planner cannot label:
planned afresh from a state inside a plan, the ball's loops are placed anew and the snake returns to its base
shape, and neither then reaches the target. Those two are cloned from demonstrations alone (no DAgger rounds),
which tests whether a memoryless MLP reproduces the plans on the states they visit.

The diagnosed envs and their budgets are the ``CLONES`` of their controller modules (agents.controllers), where the
reasons for each are. The diagnosis evaluates, on the episodes reset with seeds EVAL_SEED, EVAL_SEED + 1, ... (the
budget's eval_episodes of them; seeds that no training, tuning or selection used): the analytic controller, the same
made memoryless, a clone per seed, the best pretrained RL model (chosen by the committed table,
docs/baselines/results.json, seeds 0..99), random and, on the dense-shaped nonholonomic tasks, a one-step greedy
ascent of the reward (`GreedyReward`, on the budget's first greedy_episodes). Returns carry a 95% bootstrap interval
(scipy.stats.bootstrap, BCa); the clones' mean over seeds a percentile-bootstrap interval over the seeds.
"""

from __future__ import annotations

import argparse
import copy
import json
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import gymnasium as gym
import numpy as np
import yaml

import connenv  # noqa: F401  (registers the envs)
from agents.baselines import DOCS, HYPERPARAMS, hyperparams, pretrained_label, short
from agents.controllers import CONTROLLERS, controller, module_of
from agents.evaluate import (
    RandomPolicy,
    evaluate,
    make_policy,
    positive_int,
    pretrained_models,
    run_episode,
    seed_int,
    summarize,
)
from agents.progress import progress
from connenv import cli
from connenv.envs.spec import registry

PROG = "python -m agents.imitate"
DEMO_SEED = 20_000
"""Demonstrations and DAgger rollouts of clone seed s reset with seeds DEMO_SEED + 1000 s + i: disjoint from the
evaluation's EVAL_SEED.. and from the reference table's 0..99."""
EVAL_SEED = 10_000
EVAL_EPISODES = 100
HELD_OUT = 5  # demonstration episodes kept out of training, on which the clone's action error is measured
BATCH = 256
LEARNING_RATE = 1e-3
CONFIDENCE = 0.95
CLONE_SEEDS = (0, 1, 2)
DAGGER_EPISODES = 10  # clone episodes a DAgger round


@dataclass(frozen=True)
class Budget:
    """How much a clone learns from: demonstrations, regression epochs (at the start and after each DAgger round),
    DAgger rounds; and the diagnosis's evaluation episodes, the first greedy_episodes of them also for the greedy
    policy (0: none; it steps a copy of the env once per candidate action)."""

    demonstrations: int = 100
    epochs: int = 100
    rounds: int = 4
    eval_episodes: int = EVAL_EPISODES
    greedy_episodes: int = 0


def clone_budgets() -> dict[str, Budget]:
    """The diagnosed envs' budgets, in the registry's order: the ``CLONES`` of their controller modules."""
    budgets = {}
    for env_id in CONTROLLERS:
        clones = getattr(module_of(registry[env_id]), "CLONES", {})
        if env_id in clones:
            budgets[env_id] = Budget(**clones[env_id])
    return budgets


BUDGETS = clone_budgets()
DIAGNOSED = tuple(BUDGETS)
GREEDY_POINTS = 5  # candidate actions per action dimension: a grid of GREEDY_POINTS^dim over the action box
CLONABLE = sorted(set(CONTROLLERS) & set(yaml.safe_load((HYPERPARAMS / "ppo.yml").read_text())))
"""The envs with an analytic controller and PPO hyperparameters."""


class Memoryless:
    """A controller that forgets before every step: its plans (the ball's and the gait planners' `plans`) and its
    recurrent state (the swing-up's mode) are dropped, so it answers from the observation alone."""

    def __init__(self, law):
        self.law = law

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        plans = getattr(self.law, "plans", None)
        if plans is not None:
            plans.clear()
        return self.law.predict(obs, None, None, deterministic)


class GreedyReward:
    """Pick, from a grid over the action box, the action whose next reward is largest, looked up on a deepcopy of
    the env: a one-step greedy ascent of the reward's potential. Where the reward is a potential's decrease, this
    follows the potential down; where the potential has no descent direction the system can take (a
    nonholonomic constraint), it stalls."""

    def __init__(self, env: gym.Env, points: int = GREEDY_POINTS):
        space = env.action_space
        axes = [np.linspace(low, high, points) for low, high in zip(space.low, space.high, strict=True)]
        self.env = env
        self.candidates = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, space.shape[0])
        self.candidates = self.candidates.astype(space.dtype)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        rewards = [copy.deepcopy(self.env).step(action)[1] for action in self.candidates]
        return self.candidates[int(np.argmax(rewards))], state


def budget(env_id: str) -> Budget:
    return BUDGETS.get(env_id, Budget())


def policy_kwargs(params: dict) -> dict:
    """rl-zoo3's policy_kwargs, a Python expression in ppo.yml (e.g. "dict(net_arch=[64, 64])")."""
    import torch

    text = params.get("policy_kwargs", "dict()")
    return eval(text, {"dict": dict, "nn": torch.nn}) if isinstance(text, str) else dict(text)


def new_model(env_id: str, seed: int):
    """An untrained PPO with the env's ppo.yml policy (class, net_arch, gSDE), on CPU."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    params = hyperparams("ppo", env_id)
    venv = DummyVecEnv([lambda: gym.make(env_id)])
    return PPO(
        params["policy"], venv, seed=seed, use_sde=params.get("use_sde", False),
        policy_kwargs=policy_kwargs(params), device="cpu",
    )  # fmt: skip


def stack(observations: list):
    """A batch of observations: an array, or a dict of arrays for a Dict observation."""
    if isinstance(observations[0], dict):
        return {key: np.stack([obs[key] for obs in observations]) for key in observations[0]}
    return np.stack(observations)


def fit_normalizer(env_id: str, observations):
    """A VecNormalize whose observation statistics are those of the demonstrations (frozen), or None where ppo.yml
    does not normalize."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    if not hyperparams("ppo", env_id).get("normalize", False):
        return None
    normalizer = VecNormalize(DummyVecEnv([lambda: gym.make(env_id)]), norm_obs=True, norm_reward=False)
    if isinstance(normalizer.obs_rms, dict):
        for key, rms in normalizer.obs_rms.items():
            rms.update(observations[key])
    else:
        normalizer.obs_rms.update(observations)
    normalizer.training = False
    return normalizer


def deterministic_action(policy, obs):
    """The policy's deterministic action before clipping, as a differentiable tensor: the mean of its Gaussian
    (gSDE's too), which SB3's predict(deterministic=True) clips to the action box."""
    features = policy.extract_features(obs, policy.pi_features_extractor)
    return policy.action_net(policy.mlp_extractor.forward_actor(features))


def fit(model, normalizer, observations, actions: np.ndarray, epochs: int, optimizer, rng) -> float:
    """Minibatch regression of the policy's deterministic action on `actions`; the last epoch's mean loss."""
    import torch

    obs = normalizer.normalize_obs(observations) if normalizer else observations
    obs_tensor, _ = model.policy.obs_to_tensor(obs)
    target = torch.as_tensor(actions, dtype=torch.float32)
    model.policy.set_training_mode(True)
    for _ in range(epochs):
        order, losses = torch.as_tensor(rng.permutation(len(target))), []
        for start in range(0, len(target), BATCH):
            batch = order[start : start + BATCH]
            inputs = {k: v[batch] for k, v in obs_tensor.items()} if isinstance(obs_tensor, dict) else obs_tensor[batch]
            loss = torch.nn.functional.mse_loss(deterministic_action(model.policy, inputs), target[batch])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            losses.append(loss.item())
    model.policy.set_training_mode(False)
    return float(np.mean(losses))


def labelled_episode(env: gym.Env, labeller, seed: int, driver=None) -> tuple[list, list, bool]:
    """One episode from reset(seed=seed), driven by `driver` (default: the labeller itself), every observation
    labelled with the labeller's action, its memory threaded through the episode; (observations, labels,
    success)."""
    space = env.action_space
    obs, _ = env.reset(seed=seed)
    observations, labels, state, done, info, first = [], [], None, False, {}, True
    while not done:
        label, state = labeller.predict(obs, state=state, episode_start=np.array([first]), deterministic=True)
        label = np.clip(label, space.low, space.high).astype(space.dtype)
        action = label if driver is None else driver.predict(obs, deterministic=True)[0]
        observations.append(obs)
        labels.append(label)
        obs, _, terminated, truncated, info = env.step(action)
        done, first = terminated or truncated, False
    return observations, labels, bool(info.get("is_success", False))


def demonstrations(env: gym.Env, labeller, seeds) -> tuple[list, list, float]:
    """The controller's own episodes: observations, actions and its success rate."""
    observations, labels, successes = [], [], []
    for seed in seeds:
        obs, act, success = labelled_episode(env, labeller, seed)
        observations += obs
        labels += act
        successes.append(success)
    return observations, labels, float(np.mean(successes))


def action_error(policy, observations: list, labels: list) -> float:
    """Root mean square difference between the policy's (clipped) actions and the labels, over all components."""
    actions = np.array([policy.predict(obs, deterministic=True)[0] for obs in observations])
    return float(np.sqrt(np.mean((actions - np.array(labels)) ** 2)))


def imitate(env_id: str, plan: Budget | None = None, seed: int = 0, out: Path | None = None) -> dict:
    """Clone the env's analytic controller into its PPO policy: the budget's demonstrations and epochs of
    regression, then its DAgger rounds of DAGGER_EPISODES clone episodes each, its epochs again on all labels after
    each (default: the env's budget). Saves the clone under `out` if given. Returns the clone (a policy answering
    predict, behind its normalizer), where it was saved, and the training record."""
    import torch

    from agents.evaluate import NormalizedPolicy

    torch.set_num_threads(1)
    torch.manual_seed(seed)
    plan = plan or budget(env_id)
    env = gym.make(env_id)
    labeller = controller(env_id, env=env)
    first = DEMO_SEED + 1000 * seed
    held_obs, held_labels, _ = demonstrations(env, labeller, range(first, first + HELD_OUT))
    next_seed = first + HELD_OUT + plan.demonstrations
    observations, labels, demo_success = demonstrations(env, labeller, range(first + HELD_OUT, next_seed))
    model = new_model(env_id, seed)
    normalizer = fit_normalizer(env_id, stack(observations))
    clone = NormalizedPolicy(model, normalizer) if normalizer else model
    optimizer = torch.optim.Adam(model.policy.parameters(), lr=LEARNING_RATE)
    rng = np.random.default_rng(seed)
    loss = fit(model, normalizer, stack(observations), np.array(labels), plan.epochs, optimizer, rng)
    record = {"demonstrations": plan.demonstrations, "demonstration_success": demo_success, "epochs": plan.epochs,
              "bc_samples": len(labels), "rounds": []}  # fmt: skip
    for _ in range(plan.rounds):
        successes = []
        for episode_seed in range(next_seed, next_seed + DAGGER_EPISODES):
            obs, act, success = labelled_episode(env, labeller, episode_seed, driver=clone)
            observations += obs
            labels += act
            successes.append(success)
        next_seed += DAGGER_EPISODES
        loss = fit(model, normalizer, stack(observations), np.array(labels), plan.epochs, optimizer, rng)
        record["rounds"].append({"clone_success": float(np.mean(successes)), "samples": len(labels)})
    record.update(
        samples=len(labels),
        final_loss=loss,
        held_out_rmse=action_error(clone, held_obs, held_labels),
        held_out_label_std=float(np.std(held_labels)),
    )
    path = save(model, normalizer, env_id, seed, record, out) if out is not None else None
    return {"policy": clone, "path": path, "record": record}


def save(model, normalizer, env_id: str, seed: int, record: dict, out: Path) -> Path:
    """The clone as an rl-zoo3 run folder that agents.evaluate loads: model.zip, connenv-{env}/args.yml (the
    algorithm, ppo) and connenv-{env}/vecnormalize.pkl."""
    folder = Path(out) / f"{short(env_id)}_bc_s{seed}"
    params = folder / f"connenv-{short(env_id)}"
    params.mkdir(parents=True, exist_ok=True)
    model.save(folder / "model.zip")
    args = {"algo": "ppo", "env": env_id, "seed": seed, "behaviour_cloning": record}
    (params / "args.yml").write_text(yaml.safe_dump(args, sort_keys=False))
    if normalizer is not None:
        normalizer.save(str(params / "vecnormalize.pkl"))
    return folder / "model.zip"


def bootstrap_interval(values, statistic=np.mean, method: str = "BCa") -> list[float]:
    """The 95% bootstrap interval of a statistic of the values (scipy.stats.bootstrap); a point where they are all
    equal."""
    from scipy.stats import bootstrap

    values = np.asarray(values, float)
    if np.ptp(values) == 0.0:
        return [float(values[0])] * 2
    result = bootstrap((values,), statistic, confidence_level=CONFIDENCE, method=method, random_state=0)
    return [float(result.confidence_interval.low), float(result.confidence_interval.high)]


def row(label: str, episodes) -> dict:
    """agents.evaluate's summary of the episodes, with bootstrap intervals of the mean return and the success rate,
    without the episodes themselves."""
    summary = summarize(label, episodes)
    returns, successes = [e.ret for e in episodes], [float(e.success) for e in episodes]
    summary.update(return_ci=bootstrap_interval(returns), success_ci=bootstrap_interval(successes))
    del summary["episodes"]
    return summary


def best_pretrained(env_id: str) -> Path:
    """The pretrained model with the highest success, then return, in the committed table (seeds 0..99): the
    evaluation's seeds play no part in the choice."""
    (report,) = [r for r in json.loads((DOCS / "results.json").read_text()) if r["env"] == env_id]
    models = {pretrained_label(model): model for model in pretrained_models(env_id)}
    scored = [(r["success_rate"], r["return_mean"], r["label"]) for r in report["policies"] if r["label"] in models]
    return models[max(scored)[2]]


def run_greedy(env_id: str, episodes: int, seed: int) -> list:
    env = gym.make(env_id)
    policy = GreedyReward(env)
    return [run_episode(env, policy, seed + i) for i in range(episodes)]


def diagnose_env(env_id: str, seeds=CLONE_SEEDS, out: Path | None = None, plan: Budget | None = None) -> dict:
    """Clones of the env's analytic controller for each seed, and every policy of the diagnosis on the same unseen
    episodes (see the module docstring). plan: default the env's budget."""
    import torch

    torch.set_num_threads(1)
    plan = plan or budget(env_id)
    episodes = plan.eval_episodes
    env = gym.make(env_id)
    law = controller(env_id, env=env)

    def evaluated(label, policy):
        return row(label, evaluate(env_id, policy, episodes, EVAL_SEED))

    rows = {
        "analytic": evaluated(f"{next(iter(CONTROLLERS[env_id]))} (analytic)", law),
        "memoryless": evaluated("analytic, memoryless", Memoryless(law)),
    }
    clones = []
    for seed in seeds:
        clone = imitate(env_id, plan, seed, out)
        policy = make_policy(str(clone["path"]), env_id, EVAL_SEED)[1] if clone["path"] else clone["policy"]
        clones.append({"seed": seed, **evaluated(f"BC s{seed}", policy), "training": clone["record"]})
    model = best_pretrained(env_id)
    rows["rl"] = evaluated(pretrained_label(model), make_policy(str(model), env_id, EVAL_SEED)[1])
    rows["random"] = evaluated("random", RandomPolicy(env.action_space, EVAL_SEED))
    if plan.greedy_episodes:
        rows["greedy"] = row("greedy", run_greedy(env_id, min(plan.greedy_episodes, episodes), EVAL_SEED))
    success, returns = [c["success_rate"] for c in clones], [c["return_mean"] for c in clones]
    summary = {
        "success_mean": float(np.mean(success)),
        "success_ci": bootstrap_interval(success, method="percentile"),
        "return_mean": float(np.mean(returns)),
        "return_ci": bootstrap_interval(returns, method="percentile"),
    }
    return {
        "env": env_id,
        "eval_seeds": [EVAL_SEED, EVAL_SEED + episodes - 1],
        "budget": asdict(plan),
        "rows": rows,
        "clones": clones,
        "clone_summary": summary,
    }


def diagnose(envs=DIAGNOSED, jobs: int = 1, out: Path | None = None, plans: dict | None = None,
             write: Path | None = None) -> list[dict]:  # fmt: skip
    """diagnose_env for each env, `jobs` envs at a time (one process each); plans: budgets by env (default each
    env's). With `write`, each env's report replaces its old one in that JSON file as soon as it is done, the
    other envs' kept. Returns the reports of the file (or of these envs), in DIAGNOSED's order."""
    plans = plans or {}
    reports = json.loads(write.read_text()) if write and write.is_file() else []
    with ProcessPoolExecutor(jobs) as pool:
        futures = [pool.submit(diagnose_env, env_id, CLONE_SEEDS, out, plans.get(env_id)) for env_id in envs]
        for future in progress(as_completed(futures), len(futures), "envs", "diagnose"):
            report = future.result()
            reports = [r for r in reports if r["env"] != report["env"]] + [report]
            reports.sort(key=lambda r: DIAGNOSED.index(r["env"]) if r["env"] in DIAGNOSED else len(DIAGNOSED))
            if write:
                write.parent.mkdir(parents=True, exist_ok=True)
                write.write_text(json.dumps(reports, indent=1) + "\n")
            print(f"{short(report['env'])}: done", flush=True)
    return reports


def percent(value: float) -> str:
    return f"{100 * value:.0f}%"


def header(columns: list[str]) -> str:
    """A markdown table's header and separator rows."""
    return f"| {' | '.join(columns)} |\n|{'---|' * len(columns)}"


def format_diagnosis(reports: list[dict]) -> str:
    """Two markdown tables from diagnosis.json: success (analytic, memoryless, each clone seed and their mean with
    its interval, the clones' RMS action error on held-out demonstrations over the spread of the controller's
    actions there, best RL, random, greedy), and mean returns with their 95% intervals."""
    success_columns = ["env", "analytic", "analytic, memoryless", "BC clone per seed", "BC clone, mean [95% CI]",
                       "BC action error / spread", "best RL", "random", "greedy"]  # fmt: skip
    return_columns = ["env", "analytic", "BC clone, mean over seeds", "best RL", "random", "greedy"]
    success, returns = [header(success_columns)], [header(return_columns)]
    for report in reports:
        rows, summary = report["rows"], report["clone_summary"]
        greedy = rows.get("greedy")
        rounds = report["budget"]["rounds"]
        dagger = f"DAgger ×{rounds}" if rounds else "BC only"
        seeds = ", ".join(percent(c["success_rate"]) for c in report["clones"])
        error = np.mean(
            [c["training"]["held_out_rmse"] / c["training"]["held_out_label_std"] for c in report["clones"]]
        )
        lo, hi = summary["success_ci"]
        success.append(
            f"| {short(report['env'])} | {percent(rows['analytic']['success_rate'])} "
            f"| {percent(rows['memoryless']['success_rate'])} | {seeds} ({dagger}) "
            f"| {percent(summary['success_mean'])} [{percent(lo)}, {percent(hi)}] | {error:.2f} "
            f"| {percent(rows['rl']['success_rate'])} ({rows['rl']['policy']}) | {percent(rows['random']['success_rate'])} "
            f"| {percent(greedy['success_rate']) if greedy else '–'} |"
        )

        def cell(mean, interval):
            return f"{mean:.2f} [{interval[0]:.2f}, {interval[1]:.2f}]"

        returns.append(
            f"| {short(report['env'])} | {cell(rows['analytic']['return_mean'], rows['analytic']['return_ci'])} "
            f"| {cell(summary['return_mean'], summary['return_ci'])} "
            f"| {cell(rows['rl']['return_mean'], rows['rl']['return_ci'])} "
            f"| {cell(rows['random']['return_mean'], rows['random']['return_ci'])} "
            f"| {cell(greedy['return_mean'], greedy['return_ci']) if greedy else '–'} |"
        )
    return "\n".join(success) + "\n\n" + "\n".join(returns)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", choices=CLONABLE, help="clone this env's analytic controller (with --diagnose: its)")
    parser.add_argument("--diagnose", action="store_true", help=f"the diagnosis of {', '.join(map(short, DIAGNOSED))}")
    parser.add_argument("--episodes", type=positive_int, help="demonstrations (default: the env's budget)")
    parser.add_argument("--epochs", type=positive_int, help="regression epochs, at the start and after each round")
    parser.add_argument("--dagger", type=cli.non_negative_int, help="DAgger rounds (default: the env's budget)")
    parser.add_argument("--seed", type=seed_int, default=0, help="the clone's seed (--diagnose: 0, 1, 2)")
    parser.add_argument("--out", type=cli.writable_dir, default="runs/imitate", help="folder of the clones' run folders")
    parser.add_argument("--eval-episodes", type=positive_int, help="--diagnose's (default: the env's budget)")
    parser.add_argument("--jobs", type=positive_int, default=1, help="--diagnose: envs at a time, one process each")
    parser.add_argument("--write", type=cli.writable_file, help="--diagnose: update the reports in this JSON file, env by env")
    args = parser.parse_args(argv)
    if not args.diagnose and args.env is None:
        parser.error("give --env ID to clone its controller, or --diagnose")
    args.out, args.write = Path(args.out), args.write and Path(args.write)
    return args


def overridden(env_id: str, args: argparse.Namespace) -> Budget:
    """The env's budget with the command line's overrides."""
    given = {"demonstrations": args.episodes, "epochs": args.epochs, "rounds": args.dagger,
             "eval_episodes": args.eval_episodes}  # fmt: skip
    return replace(budget(env_id), **{key: value for key, value in given.items() if value is not None})


def main(argv: list[str] | None = None):
    args = parse_args(argv)
    if args.diagnose:
        envs = [args.env] if args.env else list(DIAGNOSED)
        plans = {env_id: overridden(env_id, args) for env_id in envs}
        reports = diagnose(envs, args.jobs, args.out, plans, args.write)
        print(format_diagnosis(reports))
        if args.write:
            print(f"wrote {args.write}")
        return reports
    clone = imitate(args.env, overridden(args.env, args), args.seed, args.out)
    print(json.dumps(clone["record"], indent=1))
    print(f"wrote {clone['path']}")
    return clone


if __name__ == "__main__":
    cli.run(main, PROG)
