"""SHAC and analytic policy gradients on connenv.jax: the actor learned by backpropagation through the env's step.

    python -m agents.jax_shac --env connenv/Swing-v0 --seeds 5 --timesteps 200000 --runs runs

SHAC (Xu et al., ICLR 2022, "Accelerated Policy Learning with Parallel Differentiable Simulation"): each update
rolls the stochastic policy (a Gaussian, its sample reparameterized: a = μ(s) + σ·ε) for `horizon` steps on
`n_envs` rows from where the last update left them, and the actor's loss is the negative of the window's return
plus γ^h V(s_h) of a target critic — an episode that ends inside the window adds its partial return and, where the
clock cut it, γ^t V(final observation) — divided by h·N; its gradient is taken by reverse mode through every step
of the env (`env.step_env_rows`, the exact physics traced by connenv.jax). The actor steps by Adam (β = 0.7, 0.95)
with the gradient's global norm clipped; the critic regresses on TD(λ) targets of the window computed with the
target critic, for `critic_iterations` epochs of minibatches, and the target follows it by Polyak averaging
(α = 0.2), SHAC's defaults. ``--apg`` drops the critic: the loss is the window's return alone (analytic policy
gradients; give a horizon as long as the episode, or as long as memory allows).

Written in the style of PureJaxRL and of agents.jax_ppo (whose Trainer this one extends: the same observation
normalization, rows of all seeds stepped as one batch, evaluation and policy file, agents.jax_policy): one update
is one compiled function, ``lax.scan`` repeats it and the seeds are a leading axis of every array (their losses
summed, so that one reverse pass gives each seed its own gradient).

What the gradient does where the step is not differentiable:
- the action clip to the action space (the env's own, in `_advance_rows`): zero derivative outside the bounds,
  so a sample beyond a bound teaches nothing about it (SHAC's dflex envs clip alike); a mean action that drifts
  beyond a bound would stop learning there, so the loss adds `bound_coef` × its squared excess (0 inside);
- end stops and other one-sided min/max inside the physics: the derivative of the branch taken (as the model's
  complex-step Jacobians take it);
- a termination (or the clock) inside the window: the autoreset's `where` passes no gradient from the new
  episode into the old one, the old one's tail is its partial return (+ γ^t V(final) if truncated);
- a reward with a floor (Swing's and KapitzaSwingUp's log of the lift, floored at 1e-4): zero derivative below it;
- a stepper failure: the step holds the state (info["stepper_failed"]) and the episode is truncated; a gradient
  that comes out non-finite (NaN or inf anywhere) is dropped for that seed's update (counted in progress.csv).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import optax

from agents import jax_policy, jax_ppo
from agents.jax_policy import forward

SHAC_LOSSES = ("actor_loss", "critic_loss", "grad_norm", "nonfinite", "std", "stepper_failures")

ALGO = "shac_jax"
APG_ALGO = "apg_jax"


@dataclasses.dataclass(frozen=True)
class Config:
    """SHAC's hyperparameters (Xu et al.'s names where they have one; their defaults where they fit a CPU)."""

    n_timesteps: int
    n_envs: int = 64
    horizon: int = 32  # SHAC's steps_num: the window backpropagated through
    gamma: float = 0.99
    lam: float = 0.95  # TD(λ) of the critic's targets
    actor_lr: float = 2e-3
    critic_lr: float = 2e-3
    linear_lr: bool = True  # both rates decayed linearly to 0 over the budget, as SHAC's lr_schedule "linear"
    betas: tuple[float, float] = (0.7, 0.95)
    max_grad_norm: float = 1.0
    critic_iterations: int = 16
    critic_minibatches: int = 4
    target_alpha: float = 0.2  # target ← α target + (1 − α) critic
    net_arch: tuple[int, ...] = (64, 64)
    log_std_init: float = -1.0
    reward_scale: float = 1.0
    normalize: bool = True
    clip_obs: float = 10.0
    bound_coef: float = 1.0  # penalty on the mean action's excess beyond the bounds, where the clip's gradient is 0
    critic: bool = True  # False: analytic policy gradients (the window's return alone)
    eval_freq: int = 0  # steps between evaluations per seed; 0: a tenth of the budget
    eval_episodes: int = 16

    @property
    def rollout(self) -> int:
        return self.n_envs * self.horizon

    @property
    def n_updates(self) -> int:
        return max(math.ceil(self.n_timesteps / self.rollout), 1)

    @property
    def updates_per_eval(self) -> int:
        frequency = self.eval_freq or self.n_timesteps // 10
        return min(max(frequency // self.rollout, 1), self.n_updates)

    @property
    def algo(self) -> str:
        return ALGO if self.critic else APG_ALGO


def schedule(rate: float, steps: int, linear: bool):
    return optax.linear_schedule(rate, 0.0, steps) if linear else rate


class Trainer(jax_ppo.Trainer):
    """SHAC of one env and Config: ``init(keys)`` the runners of several seeds, ``run(runners)`` updates_per_eval
    updates of each and an evaluation (agents.jax_ppo.Trainer's), compiled once."""

    def __init__(self, env, env_params, config: Config):
        self.env, self.env_params, self.config = env, env_params, config
        space = env.observation_space(env_params)
        self.obs_keys = sorted(space.spaces) if hasattr(space, "spaces") else None
        sample = env.reset(jax.random.key(0), env_params)[0]
        self.obs_dim = int(jax_policy.flat_observation(sample, self.obs_keys, jnp).shape[-1])
        action_space = env.action_space(env_params)
        self.act_dim = int(np.prod(action_space.shape))
        self.low, self.high = np.asarray(action_space.low, float), np.asarray(action_space.high, float)
        c = config
        b1, b2 = c.betas
        self.actor_opt = optax.chain(optax.clip_by_global_norm(c.max_grad_norm),
                                     optax.adam(schedule(c.actor_lr, c.n_updates, c.linear_lr), b1, b2))  # fmt: skip
        critic_steps = c.n_updates * c.critic_iterations * c.critic_minibatches
        self.critic_opt = optax.chain(optax.clip_by_global_norm(c.max_grad_norm),
                                      optax.adam(schedule(c.critic_lr, critic_steps, c.linear_lr), b1, b2))  # fmt: skip
        self.run = jax.jit(self._run)
        self.init_rows = jax.jit(jax.vmap(self._init))

    dtype = jnp.float32  # the networks' inputs (float64: the loss computed in float64 throughout, as the test does)

    def normalized(self, runner, obs):
        return jax_ppo.Trainer.normalized(self, runner, obs).astype(self.dtype)

    def init(self, keys) -> dict:
        """The runners of the seeds' keys (S,), drawn as PPO's."""
        ppo_like = jax_ppo.Config(n_timesteps=1, net_arch=self.config.net_arch, log_std_init=self.config.log_std_init)
        return jax_ppo.init_runners(self, keys, ppo_like)

    def _init(self, keys, params) -> dict:
        c = self.config
        k_reset, key = keys
        obs, state = self.env.reset_rows(k_reset, c.n_envs, self.env_params)
        actor = {"pi": params["pi"], "log_std": params["log_std"]}
        return {
            "params": params,
            "target_vf": params["vf"],
            "actor_opt": self.actor_opt.init(actor),
            "critic_opt": self.critic_opt.init(params["vf"]),
            "obs_stats": jax_ppo.stats_init(self.obs_dim),
            "env_state": state,
            "obs": self.observe(obs),
            "episode_return": jnp.zeros(c.n_envs),
            "key": key,
            "update": jnp.zeros((), jnp.int32),
            "eval_key": jax.random.fold_in(k_reset, 1),
        }

    # -- the actor's loss: the window rolled out, differentiated through the env ---------------------------------

    def _window(self, actors, runners, noise, keys):
        """The window of `horizon` steps of every seed from its runner's rows, actions μ + σ ε (noise (h, S, N, m)):
        (the seeds' summed actor losses, (runners' rows after it, the transitions (h, S, N, …)))."""
        c = self.config
        vf = lambda p, x: forward(p, x, jnp)[..., 0]
        S = noise.shape[1]
        center, half = jnp.asarray((self.high + self.low) / 2), jnp.asarray((self.high - self.low) / 2)

        def step(carry, xs):
            state, obs, acc, discount, loss = carry
            eps, key, last = xs
            nobs = jax.vmap(self.normalized)(runners, obs)
            mean = jax.vmap(lambda p, x: forward(p, x, jnp))(actors["pi"], nobs)
            excess = jnp.maximum(jnp.abs(mean - center) - half, 0.0)
            loss = loss + c.bound_coef * jnp.sum(excess**2, axis=(-2, -1)) / self.act_dim
            action = mean + jnp.exp(actors["log_std"])[:, None, :] * eps
            obs_next, state, reward, terminated, truncated, info = self._env_step(key, state, action.astype(float),
                                                                                 runners)  # fmt: skip
            final = jax.vmap(self.normalized)(runners, self.observe(info["final_observation"]))
            final_value = jax.vmap(vf)(runners["target_vf"], final)
            done = terminated | truncated
            acc = acc + discount * reward * c.reward_scale
            discount = discount * c.gamma
            if c.critic:  # the target critic's value where the window or the clock cuts the episode
                tail = acc + discount * jnp.where(terminated, 0.0, final_value)
            else:
                tail = acc
            loss = loss - jnp.sum(jnp.where(done | last, tail, 0.0), axis=-1)
            acc, discount = jnp.where(done, 0.0, acc), jnp.where(done, 1.0, discount)
            transition = {"raw_obs": jax.lax.stop_gradient(obs), "nobs": jax.lax.stop_gradient(nobs),
                          "reward": jax.lax.stop_gradient(reward) * c.reward_scale,
                          "final_value": jax.lax.stop_gradient(final_value), "terminated": terminated,
                          "done": done, "success": info["is_success"].astype(bool),
                          "failed": info["stepper_failed"], "raw_reward": jax.lax.stop_gradient(reward)}  # fmt: skip
            return (state, self.observe(obs_next), acc, discount, loss), transition

        N = c.n_envs
        zeros = jnp.zeros((S, N))
        last = jnp.arange(c.horizon) == c.horizon - 1
        carry = (runners["env_state"], runners["obs"], zeros, jnp.ones((S, N)), jnp.zeros(S))
        (state, obs, _, _, loss), t = jax.lax.scan(step, carry, (noise, keys, last))
        loss = loss / (c.horizon * N)
        return jnp.sum(loss), (jax.lax.stop_gradient((state, obs)), loss, t)

    def _critic_targets(self, t, last_value):
        """TD(λ) targets of the window (h, N), from the target critic's values after each step (`final_value`: that
        of the step's own final observation, 0 past a terminal state), the last step's bootstrapped whole."""
        c = self.config
        after = jnp.where(t["terminated"], 0.0, t["final_value"]).astype(float)
        cut = t["done"].at[-1].set(True)

        def back(G_next, x):
            reward, value, cut = x
            G = reward + c.gamma * jnp.where(cut, value, (1 - c.lam) * value + c.lam * G_next)
            return G, G

        _, targets = jax.lax.scan(back, last_value.astype(float), (t["reward"], after, cut), reverse=True)
        return targets

    def _learn_critic(self, runner, t):
        """One seed's critic regressed on its window's TD(λ) targets; the target critic averaged towards it."""
        c = self.config
        targets = self._critic_targets(t, t["final_value"][-1])
        batch = {"nobs": t["nobs"].reshape(-1, self.obs_dim).astype(jnp.float32),
                 "target": targets.reshape(-1).astype(jnp.float32)}  # fmt: skip
        size = batch["target"].shape[0] // c.critic_minibatches

        def loss(vf, mb):
            return jnp.mean((forward(vf, mb["nobs"], jnp)[..., 0] - mb["target"]) ** 2)

        def epoch(carry, key):
            order = jax.random.permutation(key, batch["target"].shape[0])[: size * c.critic_minibatches]
            minibatches = jax.tree_util.tree_map(lambda v: v[order].reshape(c.critic_minibatches, size,
                                                                            *v.shape[1:]), batch)  # fmt: skip

            def minibatch(carry, mb):
                vf, opt_state = carry
                value, grads = jax.value_and_grad(loss)(vf, mb)
                updates, opt_state = self.critic_opt.update(grads, opt_state, vf)
                return (optax.apply_updates(vf, updates), opt_state), value

            return jax.lax.scan(minibatch, carry, minibatches)

        key, k_epochs = jax.random.split(runner["key"])
        (vf, opt_state), losses = jax.lax.scan(epoch, (runner["params"]["vf"], runner["critic_opt"]),
                                               jax.random.split(k_epochs, c.critic_iterations))  # fmt: skip
        target = jax.tree_util.tree_map(lambda a, b: c.target_alpha * a + (1 - c.target_alpha) * b,
                                        runner["target_vf"], vf)  # fmt: skip
        runner = {**runner, "params": {**runner["params"], "vf": vf}, "critic_opt": opt_state, "target_vf": target,
                  "key": key}  # fmt: skip
        return runner, jnp.mean(losses)

    def _update(self, runners, _):
        c = self.config
        S = runners["update"].shape[0]
        keys = jax.vmap(lambda k: jax.random.split(k, 3))(runners["key"])
        noise = jax.vmap(lambda k: jax.random.normal(k, (c.horizon, c.n_envs, self.act_dim)))(keys[:, 1])
        noise = jnp.swapaxes(noise, 0, 1)
        step_keys = jnp.swapaxes(jax.vmap(lambda k: jax.random.split(k, c.horizon))(keys[:, 2]), 0, 1)
        actors = {"pi": runners["params"]["pi"], "log_std": runners["params"]["log_std"]}
        grads, ((state, obs), losses, t) = jax.grad(self._window, has_aux=True)(actors, runners, noise, step_keys)
        t = jax.tree_util.tree_map(lambda v: jnp.swapaxes(v, 0, 1), t)  # seeds first: (S, h, N, …)
        norms = jax.vmap(optax.global_norm)(grads)
        finite = jnp.isfinite(norms)
        grads = jax.tree_util.tree_map(lambda g: jnp.where(finite.reshape(-1, *[1] * (g.ndim - 1)), g, 0.0), grads)

        def actor_step(actor, grad, opt_state, ok):
            updates, new_state = self.actor_opt.update(grad, opt_state, actor)
            new_actor = optax.apply_updates(actor, updates)
            keep = lambda a, b: jnp.where(ok, a, b)
            return jax.tree_util.tree_map(keep, new_actor, actor), jax.tree_util.tree_map(keep, new_state, opt_state)

        actors, actor_opt = jax.vmap(actor_step)(actors, grads, runners["actor_opt"], finite)
        runners = {**runners, "params": {**runners["params"], **actors}, "actor_opt": actor_opt,
                   "key": keys[:, 0], "env_state": state, "obs": obs}  # fmt: skip
        if c.normalize:
            stats = jax.vmap(lambda s, x: jax_ppo.stats_update(s, x.reshape(-1, self.obs_dim)))(
                runners["obs_stats"], t["raw_obs"]
            )
            runners = {**runners, "obs_stats": stats}
        if c.critic:
            runners, critic_loss = jax.vmap(self._learn_critic)(runners, t)
        else:
            critic_loss = jnp.zeros(S)

        # the training episodes' returns, for progress.csv
        def returns(carry, x):
            reward, done = x
            total = carry + reward
            return jnp.where(done, 0.0, total), total

        episode_return, totals = jax.lax.scan(returns, runners["episode_return"],
                                              (jnp.swapaxes(t["raw_reward"], 0, 1), jnp.swapaxes(t["done"], 0, 1)))  # fmt: skip
        totals = jnp.swapaxes(totals, 0, 1)
        ended = t["done"] & ~t["failed"]
        metrics = {
            "episodes": jnp.sum(ended, axis=(1, 2)),
            "episode_return": jnp.sum(jnp.where(ended, totals, 0.0), axis=(1, 2)),
            "successes": jnp.sum(ended & t["success"], axis=(1, 2)),
            "stepper_failures": jnp.sum(t["failed"], axis=(1, 2)),
            "actor_loss": losses,
            "critic_loss": critic_loss,
            "grad_norm": norms,
            "nonfinite": (~finite).astype(jnp.int32),
            "std": jnp.mean(jnp.exp(runners["params"]["log_std"]), axis=-1),
        }
        runners = {**runners, "episode_return": episode_return, "update": runners["update"] + 1}
        return runners, metrics

    def _run(self, runners):
        runners, metrics = jax.lax.scan(self._update, runners, None, self.config.updates_per_eval)
        metrics = jax.tree_util.tree_map(lambda v: jnp.swapaxes(v, 0, 1), metrics)
        return runners, metrics, self._evaluate(runners)

    def policy_arrays(self, runner: dict, seed_index: int):
        return jax_ppo.Trainer.policy_arrays(self, runner, seed_index)


# -- the command ------------------------------------------------------------------------------------------------


def run_folder(runs: Path, env_id: str, seed: int, algo: str = ALGO) -> Path:
    return Path(runs) / f"{env_id.split('/')[-1]}_{algo}_s{seed}"


def train(env_id: str, config: Config, seeds: list[int], runs: Path, eval_episodes: int = 100,
          eval_seed: int = 100_000, overwrite: bool = False, quiet: bool = False) -> dict:  # fmt: skip
    """Train `seeds` together, write their run folders, evaluate their best policies on the numpy env (episodes reset
    with seeds eval_seed, eval_seed + 1, …): the agents.evaluate report."""
    jax.config.update("jax_enable_x64", True)  # connenv.jax computes the physics in float64
    import connenv.jax
    from agents import evaluate
    from agents.jax_train import record_chunk, wait, write_records

    folders = [run_folder(runs, env_id, seed, config.algo) for seed in seeds]
    for folder in folders:
        if (folder / "results.json").is_file() and not overwrite:
            raise FileExistsError(f"{folder} holds a finished run; --overwrite replaces it")
        folder.mkdir(parents=True, exist_ok=True)
    env, env_params = connenv.jax.make(env_id)
    start = time.perf_counter()
    trainer = Trainer(env, env_params, config)
    runner = trainer.init(jnp.stack([jax.random.key(seed) for seed in seeds]))
    compiled = trainer.run.lower(runner).compile()
    compile_seconds = time.perf_counter() - start
    say = (lambda *a, **k: None) if quiet else print
    say(f"{env_id}: {config.algo} on JAX, {len(seeds)} seeds × {config.n_timesteps} steps, {config.n_envs} envs × "
        f"horizon {config.horizon}; compiled in {compile_seconds:.1f} s", flush=True)  # fmt: skip
    meta = trainer.meta(env_id) | {"algo": config.algo}
    evaluations = {seed: {"timesteps": [], "results": [], "successes": []} for seed in seeds}
    progress = {seed: [] for seed in seeds}
    best = {seed: -math.inf for seed in seeds}
    updates = 0
    train_start = time.perf_counter()
    while updates < config.n_updates:
        runner, metrics, evaluation = compiled(runner)
        wait(runner)  # in short sleeps: Ctrl-C interrupts at once
        updates += config.updates_per_eval
        timesteps = updates * config.rollout
        wall = time.perf_counter() - train_start
        metrics, evaluation = jax.tree_util.tree_map(np.asarray, (metrics, evaluation))
        record_chunk(trainer, runner, seeds, folders, evaluations, progress, best, meta, metrics, evaluation,
                     updates, wall, SHAC_LOSSES, eval_means=True)  # fmt: skip
        say(f"{timesteps:>10} steps  {wall:7.1f} s  evaluation: return {np.mean(evaluation['return']):.4g}, "
            f"success {np.mean(evaluation['success']):.0%} (mean of {len(seeds)} seeds)", flush=True)  # fmt: skip
    train_seconds = time.perf_counter() - train_start
    timesteps = updates * config.rollout
    for i, folder in enumerate(folders):
        jax_policy.save(folder / "policy.npz", *trainer.policy_arrays(runner, i), meta)
    write_records(seeds, folders, evaluations, progress)
    say(f"trained {len(seeds)} seeds × {timesteps} timesteps in {train_seconds:.1f} s (+ {compile_seconds:.1f} s "
        "compiling)", flush=True)  # fmt: skip
    specs = [f"jax:{folder / 'best_policy.npz'}" for folder in folders]
    report = evaluate.compare(env_id, specs, eval_episodes, eval_seed) if eval_episodes else None
    if report is not None:
        say(evaluate.format_table(report))
    common = {"algo": config.algo, "backend": "jax", "timesteps": timesteps, "train_seconds": train_seconds,
              "compile_seconds": compile_seconds, "seeds_trained_together": seeds,
              "config": {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(config).items()},
              "jax_devices": [str(d) for d in jax.devices()]}  # fmt: skip
    for i, (seed, folder) in enumerate(zip(seeds, folders)):
        own = None
        if report is not None:
            own = {**report, "policies": [report["policies"][i]]}
        evaluate.write_json({"status": "finished", "seed": seed, **common, "model": str(folder / "best_policy.npz"),
                             "evaluation": own}, folder / "results.json")  # fmt: skip
    return {"report": report, **common}


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m agents.jax_shac", description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", required=True, help="a registered id, e.g. connenv/Swing-v0")
    parser.add_argument("--seeds", type=int, default=1, help="how many seeds, trained together (vmap)")
    parser.add_argument("--seed", type=int, default=0, help="the first seed")
    parser.add_argument("--timesteps", type=float, default=2e5, help="env steps per seed")
    parser.add_argument("--runs", default="runs", help="the folder of the run folders {env}_shac_jax_s{seed}")
    parser.add_argument("--apg", action="store_true", help="analytic policy gradients: no critic")
    parser.add_argument("--horizon", type=int, help="the window backpropagated through (default 32; --apg: 128)")
    parser.add_argument("--n-envs", type=int, default=64)
    parser.add_argument("--actor-lr", type=float, default=2e-3)
    parser.add_argument("--gamma", type=float, default=0.99)
    parser.add_argument("--eval-episodes", type=int, default=100, help="numpy-env episodes per seed at the end")
    parser.add_argument("--eval-seed", type=int, default=100_000, help="their first reset seed (unseen in training)")
    parser.add_argument("--overwrite", action="store_true")
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.timesteps < 1:
        parser.error("--seeds and --timesteps must be ≥ 1")
    return args


def config_of(args: argparse.Namespace) -> Config:
    horizon = args.horizon or (128 if args.apg else 32)
    return Config(n_timesteps=int(args.timesteps), n_envs=args.n_envs, horizon=horizon, critic=not args.apg,
                  actor_lr=args.actor_lr, gamma=args.gamma)  # fmt: skip


def main(argv=None):
    args = parse_args(argv)
    try:
        result = train(args.env, config_of(args), list(range(args.seed, args.seed + args.seeds)), Path(args.runs),
                       args.eval_episodes, args.eval_seed, args.overwrite)  # fmt: skip
    except (FileExistsError, ValueError, NotImplementedError, RuntimeError) as error:
        raise SystemExit(f"agents.jax_shac: error: {error}") from None
    return result


if __name__ == "__main__":
    main()
