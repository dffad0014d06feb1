"""PPO on connenv.jax: rollouts, advantages and updates of many seeds in one compiled program.

    python train.py --backend jax --env connenv/Swing-v0 --seeds 16

PPO (Schulman et al. 2017) as SB3 runs it — the same hyperparameters (agents/hyperparams/ppo_jax.yml, rl-zoo3's
layout), the clipped surrogate, GAE, advantages normalized per minibatch, Adam with ε 1e-5 and the global gradient
norm clipped, separate tanh MLPs for the policy and the value, a state-independent log σ, observations and rewards
normalized as VecNormalize does (running mean and variance; the reward by the running standard deviation of the
discounted return) — written in the style of PureJaxRL (Lu et al. 2022): the env is ``connenv.jax``'s, stepped as
rows (``env.step_rows``, autoresets included), and a whole update (a rollout of n_steps on n_envs rows, GAE, n_epochs
of minibatch steps) is one function that ``lax.scan`` repeats and ``vmap`` runs for several seeds at once.

Why not a library: rejax (PPO and SAC on gymnax-style envs) depends on gymnax, whose release 1.0.1 pins gymnasium
below 1.4, the version connenv is tested on; PureJaxRL is a set of scripts, not a package. What is written here
beyond them: an episode cut by the time limit (truncated) is bootstrapped with the value of its final observation
(``info["final_observation"]``), as SB3 does, not counted as terminal (PureJaxRL's scripts treat both as done, which
biases the value of a task whose episodes end only by the clock); VecNormalize's statistics are kept in the state.

With ``recurrent: H`` the policy and the value read a GRU's state beside the observation (PureJaxRL's ppo_rnn
layout): the state restarts from zeros with each episode, and each minibatch is whole rows' rollouts, the GRU run
along them from the state the rollout started it in. With ``curriculum: NAME`` a share of the ended training episodes
restart from agents.curriculum's starts.

Each update is followed, every ``eval_freq`` steps, by a deterministic evaluation on ``eval_episodes`` episodes of
the JAX env from a key fixed per seed; the best of these is kept as the seed's best policy. What a seed leaves is
a policy file (agents.jax_policy), which numpy alone runs.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax

from agents import jax_policy
from agents.jax_policy import features, flat_observation, forward, normalize


@dataclasses.dataclass(frozen=True)
class Config:
    """PPO's hyperparameters, with SB3's names (those of agents/hyperparams/ppo_jax.yml)."""

    n_timesteps: int
    n_envs: int = 8
    n_steps: int = 256
    batch_size: int = 256
    n_epochs: int = 10
    learning_rate: float = 1e-3
    linear_lr: bool = False  # rl-zoo3's "lin_<rate>": decayed linearly to 0 over the budget
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    net_arch: tuple[int, ...] = (64, 64)
    log_std_init: float = 0.0
    normalize: bool = True
    clip_obs: float = 10.0
    clip_reward: float = 10.0
    eval_freq: int = 0  # steps between evaluations per seed; 0: a tenth of the budget
    eval_episodes: int = 16
    curriculum: str | None = None  # a start curriculum of agents.curriculum for the training rows (not the evaluation)
    recurrent: int = 0  # a GRU of this many units before the MLPs (0: none); minibatches are then whole rows' rollouts

    @property
    def rollout(self) -> int:
        return self.n_envs * self.n_steps

    @property
    def n_updates(self) -> int:
        return math.ceil(self.n_timesteps / self.rollout)

    @property
    def n_minibatches(self) -> int:
        return max(self.rollout // self.batch_size, 1)

    @property
    def updates_per_eval(self) -> int:
        frequency = self.eval_freq or self.n_timesteps // 10
        return min(max(frequency // self.rollout, 1), self.n_updates)

    @classmethod
    def from_hyperparams(cls, entry: dict, n_timesteps: int | None = None) -> Config:
        """A Config of a hyperparameter entry (rl-zoo3's layout: ``lin_1e-3`` a linear schedule, ``policy_kwargs``
        a dict(net_arch=[…]) text); unknown keys are refused by name."""
        entry = dict(entry)
        names = {f.name for f in dataclasses.fields(cls)}
        if isinstance(entry.get("learning_rate"), str) and entry["learning_rate"].startswith("lin_"):
            entry["learning_rate"], entry["linear_lr"] = float(entry["learning_rate"][4:]), True
        if "net_arch" in entry:
            entry["net_arch"] = tuple(int(n) for n in entry["net_arch"])
        unknown = sorted(set(entry) - names)
        if unknown:
            raise ValueError(f"hyperparameters {unknown} are not PPO's on JAX; it takes {sorted(names)}")
        if n_timesteps is not None:
            entry["n_timesteps"] = n_timesteps
        kinds = {f.name: f.type for f in dataclasses.fields(cls)}
        if entry.get("curriculum") is not None:
            from agents import curriculum

            curriculum.jax_starts(entry["curriculum"])  # a ValueError naming it, before anything is built
        for key, value in entry.items():
            if kinds[key] in ("int", "float") and not isinstance(value, bool):
                entry[key] = int(float(value)) if kinds[key] == "int" else float(value)
        config = cls(**entry)
        for key in ("n_timesteps", "n_envs", "n_steps", "batch_size", "n_epochs"):
            if getattr(config, key) < 1:
                raise ValueError(f"hyperparameter {key} = {getattr(config, key)} must be ≥ 1")
        whole = config.batch_size % config.n_steps == 0 and config.batch_size <= config.rollout
        if config.recurrent < 0 or config.recurrent and not whole:
            raise ValueError(f"hyperparameters recurrent = {config.recurrent}, batch_size = {config.batch_size}: a "
                             f"recurrent policy's minibatches are whole rollouts of rows, so batch_size must be a "
                             f"multiple of n_steps = {config.n_steps} up to n_envs · n_steps = {config.rollout}")  # fmt: skip
        return config


# -- the policy -----------------------------------------------------------------------------------------------------


def orthogonal(key, shape: tuple[int, int], gain: float):
    """`jax.nn.initializers.orthogonal(gain)(key, shape, float32)`'s draw, its QR taken by numpy on the host: XLA:CPU's
    LAPACK QR of a batch (the seeds' inits, vmapped) waits for its parts on the thread pool it runs on, and where that
    pool has two threads (2 cores) two such waits deadlock the program."""
    n_rows, n_cols = shape
    wide = n_rows < n_cols
    A = np.asarray(jax.random.normal(key, (n_cols, n_rows) if wide else shape, jnp.float32), float)
    Q, R = np.linalg.qr(A)
    Q = Q * np.sign(np.diag(R))
    return jnp.asarray(gain * (Q.T if wide else Q), jnp.float32)


def init_layers(key, sizes: list[int], last_gain: float):
    """SB3's initialization: orthogonal weights of gain √2 (the last layer's `last_gain`), zero biases; float32."""
    layers = []
    keys = jax.random.split(key, len(sizes) - 1)
    for i, (n_in, n_out) in enumerate(itertools.pairwise(sizes)):
        gain = last_gain if i == len(sizes) - 2 else math.sqrt(2)
        layers.append((orthogonal(keys[i], (n_in, n_out), gain), jnp.zeros(n_out, jnp.float32)))
    return layers


def init_params(key, obs_dim: int, act_dim: int, config: Config) -> dict:
    """One seed's networks, drawn on the host (not traceable: see `orthogonal`); with `recurrent` H, a GRU cell
    (orthogonal weights of gain 1, zero biases) whose state the MLPs read beside the observation."""
    H = config.recurrent
    k_pi, k_vf, *k_gru = jax.random.split(key, 4 if H else 2)  # an MLP policy's draws as before
    sizes = list(config.net_arch)
    params = {
        "pi": init_layers(k_pi, [obs_dim + H, *sizes, act_dim], 0.01),
        "vf": init_layers(k_vf, [obs_dim + H, *sizes, 1], 1.0),
        "log_std": jnp.full(act_dim, config.log_std_init, jnp.float32),
    }
    if H:
        params["gru"] = {"Wx": orthogonal(k_gru[0], (obs_dim, 3 * H), 1.0), "Wh": orthogonal(k_gru[1], (H, 3 * H), 1.0),
                         "b": jnp.zeros(3 * H, jnp.float32)}  # fmt: skip
    return params


def init_runners(trainer, keys, config: Config) -> dict:
    """The runners of the seeds' keys (S,): each key split in (networks, reset, runner's own), the networks drawn on
    the host (`init_params`), the rest by the trainer's compiled, vmapped `_init(keys, params)`."""
    splits = jax.vmap(lambda key: jax.random.split(key, 3))(keys)
    nets = [init_params(k, trainer.obs_dim, trainer.act_dim, config) for k in splits[:, 0]]
    params = jax.tree_util.tree_map(lambda *leaves: jnp.stack(leaves), *nets)
    return trainer.init_rows(splits[:, 1:], params)


def log_prob(mean, log_std, action):
    return jnp.sum(-0.5 * ((action - mean) / jnp.exp(log_std)) ** 2 - log_std - 0.5 * math.log(2 * math.pi), -1)


# -- running statistics (VecNormalize's RunningMeanStd) -------------------------------------------------------------


def stats_init(shape) -> dict:
    return {"mean": jnp.zeros(shape), "var": jnp.ones(shape), "count": jnp.asarray(1e-4)}


def stats_update(stats: dict, batch) -> dict:
    """Chan et al.'s parallel update of mean and variance by a batch (rows along axis 0), as RunningMeanStd."""
    mean, var, count = jnp.mean(batch, 0), jnp.var(batch, 0), batch.shape[0]
    delta, total = mean - stats["mean"], stats["count"] + count
    m2 = stats["var"] * stats["count"] + var * count + delta**2 * stats["count"] * count / total
    return {"mean": stats["mean"] + delta * count / total, "var": m2 / total, "count": total}


def gae(reward, value, last_value, final_value, terminated, truncated, gamma: float, lam: float):
    """Generalized advantage estimates (Schulman et al. 2016) of a rollout (time first: reward, value, flags (T, N);
    last_value (N,) the value of the state after it). After a terminal step the value is 0; after a step the clock
    cut (truncated), the value of its final observation (final_value), as SB3 bootstraps a time limit, not 0; the
    recursion does not run across either. float32, the learning side's precision."""
    next_value = jnp.concatenate([value[1:], last_value[None]], 0)
    bootstrap = jnp.where(truncated, final_value, next_value) * (1.0 - terminated)
    delta = (reward + gamma * bootstrap - value).astype(jnp.float32)
    done = (terminated | truncated).astype(jnp.float32)

    def step(carry, x):
        delta, done = x
        carry = delta + gamma * lam * (1.0 - done) * carry
        return carry, carry

    return jax.lax.scan(step, jnp.zeros_like(delta[0]), (delta, done), reverse=True)[1]


# -- training -------------------------------------------------------------------------------------------------------


class Trainer:
    """PPO of one env and Config; ``init(keys)`` the runners of several seeds, ``run(runners)`` updates_per_eval
    updates of each and an evaluation, compiled once."""

    recurrent = 0  # the GRU's units (Config.recurrent)

    def __init__(self, env, env_params, config: Config):
        self.env, self.env_params, self.config = env, env_params, config
        self.recurrent = config.recurrent
        space = env.observation_space(env_params)
        self.obs_keys = sorted(space.spaces) if hasattr(space, "spaces") else None
        sample = env.reset(jax.random.key(0), env_params)[0]
        self.obs_dim = int(flat_observation(sample, self.obs_keys, jnp).shape[-1])
        action_space = env.action_space(env_params)
        self.act_dim = int(np.prod(action_space.shape))
        self.low, self.high = np.asarray(action_space.low, float), np.asarray(action_space.high, float)
        steps_per_update = config.n_epochs * config.n_minibatches
        if config.linear_lr:  # SB3's: constant within an update, 1 − (updates done) / n_updates of the rate
            learning_rate = lambda count: config.learning_rate * (1.0 - (count // steps_per_update) / config.n_updates)
        else:
            learning_rate = config.learning_rate
        self.optimizer = optax.chain(
            optax.clip_by_global_norm(config.max_grad_norm), optax.adam(learning_rate=learning_rate, eps=1e-5)
        )
        self.curriculum = None  # (starts, share, max_steps): agents.curriculum's, on the training rows alone
        if config.curriculum is not None:
            from agents import curriculum

            self.curriculum = curriculum.jax_starts(config.curriculum)
        self.run = jax.jit(self._run)  # of runners with a leading seed axis (init's)
        self.init_rows = jax.jit(jax.vmap(self._init))

    def init(self, keys) -> dict:
        """The runners of the seeds' keys (S,)."""
        return init_runners(self, keys, self.config)

    def meta(self, env_id: str) -> dict:
        return {"env": env_id, "obs_keys": self.obs_keys, "clip_obs": self.config.clip_obs,
                "action_low": self.low.tolist(), "action_high": self.high.tolist()}  # fmt: skip

    def observe(self, obs):
        return flat_observation(obs, self.obs_keys, jnp).astype(float)

    def normalized(self, runner, obs):
        if not self.config.normalize:
            return obs.astype(jnp.float32)
        s = runner["obs_stats"]
        return normalize(obs, s["mean"], s["var"], self.config.clip_obs, jnp).astype(jnp.float32)

    def _init(self, keys, params) -> dict:
        c = self.config
        k_reset, key = keys
        obs, state = self.env.reset_rows(k_reset, c.n_envs, self.env_params)
        return {
            "params": params,
            "opt_state": self.optimizer.init(params),
            "obs_stats": stats_init(self.obs_dim),
            "ret_stats": stats_init(()),
            "env_state": state,
            "obs": self.observe(obs),
            "discounted": jnp.zeros(c.n_envs),  # the discounted return VecNormalize scales rewards by
            "episode_return": jnp.zeros(c.n_envs),
            "key": key,
            "update": jnp.zeros((), jnp.int32),
            "eval_key": jax.random.fold_in(k_reset, 1),
            **({"curriculum_rows": jnp.zeros(c.n_envs, bool)} if self.curriculum else {}),  # rows it started
            **({"hidden": jnp.zeros((c.n_envs, self.recurrent), jnp.float32)} if self.recurrent else {}),
        }

    def _policy(self, runners, obs, hidden=None):
        """(normalized obs, mean action, value) of every seed's rows: obs (S, N, d), the seeds' own weights; a
        recurrent policy's from its hidden state (S, N, H), and the state after the observation as a fourth."""
        nobs = jax.vmap(self.normalized)(runners, obs)
        h, x = jax.vmap(lambda p, h, x: features(p.get("gru"), h, x, jnp))(runners["params"], hidden, nobs)
        mean = jax.vmap(lambda p, x: forward(p["pi"], x, jnp))(runners["params"], x)
        value = jax.vmap(lambda p, x: forward(p["vf"], x, jnp)[..., 0])(runners["params"], x)
        return (nobs, mean, value) if hidden is None else (nobs, mean, value, h)

    def _env_step(self, keys, state, action, runners, cut=None):
        """The env step of every seed's rows at once (one batch of S·N rows, so that a branch no row takes is
        skipped, which a vmap over the seeds would compute), then the autoreset of those rows, each seed's from its
        own key (the done rows alone reset). cut (S, N): the rows a curriculum started, truncated at its max_steps."""
        S, N = action.shape[:2]
        flat = lambda v: v.reshape(S * N, *v.shape[2:])
        rows = lambda v: v.reshape(S, N, *v.shape[1:])
        obs, after, reward, terminated, truncated, info = self.env.step_env_rows(
            None, jax.tree_util.tree_map(flat, state), flat(action), self.env_params
        )
        if cut is not None and self.curriculum[2] is not None:
            truncated = truncated | (flat(cut) & (after.time >= self.curriculum[2]) & ~terminated)
        obs, state, info = self.env.autoreset_rows(keys, obs, after, terminated | truncated, info, self.env_params)
        return jax.tree_util.tree_map(rows, (obs, state, reward, terminated, truncated, info))

    def _rollout(self, runners):
        """n_steps of the stochastic policy on every seed's rows: the transitions (n_steps, S, N, …), the runners
        after them."""
        c = self.config

        def step(runners, _):
            keys = jax.vmap(lambda k: jax.random.split(k, 3))(runners["key"])
            hidden_in = runners.get("hidden")
            nobs, mean, value, *hidden = self._policy(runners, runners["obs"], hidden_in)
            params = runners["params"]
            log_std = params["log_std"][:, None, :]
            noise = jax.vmap(lambda k, m: jax.random.normal(k, m.shape, m.dtype))(keys[:, 1], mean)
            action = mean + jnp.exp(log_std) * noise
            logp = log_prob(mean, log_std, action)
            obs, state, reward, terminated, truncated, info = self._env_step(
                keys[:, 2], runners["env_state"], action.astype(float), runners, runners.get("curriculum_rows")
            )
            done = terminated | truncated
            if self.curriculum:
                obs, state, started = self._curriculum_reset(keys[:, 2], obs, state, done)
                runners = {**runners, "curriculum_rows": jnp.where(done, started, runners["curriculum_rows"])}
            final = self.observe(info["final_observation"])  # its value from the state the step left
            final_value = self._policy(runners, final, hidden[0] if hidden else None)[2]
            discounted = runners["discounted"] * c.gamma + reward
            episode_return = runners["episode_return"] + reward
            transition = {
                "nobs": nobs, "action": action, "logp": logp, "value": value, "reward": reward,
                "terminated": terminated, "truncated": truncated, "final_value": final_value,
                "raw_obs": runners["obs"], "discounted": discounted, "episode_return": episode_return,
                "success": info["is_success"].astype(bool), "failed": info["stepper_failed"],
                **({"hidden": hidden_in} if hidden else {}),  # the state before the step: the sequences' start
            }  # fmt: skip
            runners = {**runners, "key": keys[:, 0], "env_state": state, "obs": self.observe(obs),
                       "discounted": jnp.where(done, 0.0, discounted),
                       "episode_return": jnp.where(done, 0.0, episode_return)}  # fmt: skip
            if hidden:  # a new episode starts from zeros
                runners["hidden"] = jnp.where(done[..., None], 0.0, hidden[0])
            return runners, transition

        runners, t = jax.lax.scan(step, runners, None, c.n_steps)
        return runners, jax.tree_util.tree_map(lambda v: jnp.swapaxes(v, 0, 1), t)  # seeds first

    def _curriculum_reset(self, keys, obs, state, done):
        """Of the rows just reset (done), a share restarted from the curriculum's starts (`reset_env` with the
        start function as its options, drawing from each row's key): (obs, state, the rows it started)."""
        starts, share, _ = self.curriculum
        S, N = done.shape
        row_keys = jax.vmap(lambda k: jax.random.split(jax.random.fold_in(k, 2), N))(keys)  # (S, N)
        drawn = jax.vmap(jax.vmap(lambda k: jax.random.uniform(jax.random.fold_in(k, 0)) < share))(row_keys)
        reset = lambda k: self.env.reset_env(jax.random.fold_in(k, 1), self.env_params, starts)
        fresh_obs, fresh = jax.vmap(jax.vmap(reset))(row_keys)
        started = done & drawn

        def pick(new, old):
            return jnp.where(started.reshape(S, N, *([1] * (jnp.ndim(old) - 2))), new, old)

        obs, state = jax.tree_util.tree_map(pick, (fresh_obs, fresh), (obs, state))
        return obs, state, started

    def _learn(self, runner, t):
        """One seed's PPO update from its rollout t (n_steps, N, …): GAE, n_epochs of minibatch steps; the runner
        after it and its metrics."""
        c = self.config
        reward = t["reward"]
        # the rollout's values were computed with the statistics before this update's: so is the last one
        _, x = features(runner["params"].get("gru"), runner.get("hidden"), self.normalized(runner, runner["obs"]), jnp)
        last_value = forward(runner["params"]["vf"], x, jnp)[..., 0]
        if c.normalize:
            scale = jnp.sqrt(runner["ret_stats"]["var"] + OBS_EPSILON)
            reward = jnp.clip(reward / scale, -c.clip_reward, c.clip_reward)
            ret_stats = stats_update(runner["ret_stats"], t["discounted"].reshape(-1))
            obs_stats = stats_update(runner["obs_stats"], t["raw_obs"].reshape(-1, self.obs_dim))
            runner = {**runner, "ret_stats": ret_stats, "obs_stats": obs_stats}
        advantages = gae(reward, t["value"], last_value, t["final_value"], t["terminated"], t["truncated"],
                         c.gamma, c.gae_lambda)  # fmt: skip
        returns = advantages + t["value"]
        batch = {"nobs": t["nobs"], "action": t["action"], "logp": t["logp"], "advantage": advantages,
                 "return": returns}  # fmt: skip
        if self.recurrent:  # minibatches of whole rows (time first), each from its state at the rollout's start
            ended = t["terminated"] | t["truncated"]
            batch |= {"hidden": t["hidden"], "first": jnp.concatenate([jnp.zeros_like(ended[:1]), ended[:-1]], 0)}
        else:
            batch = jax.tree_util.tree_map(lambda v: v.reshape(c.rollout, *v.shape[2:]), batch)
        opt_state = runner["opt_state"]

        def epoch(carry, key):
            params, opt_state = carry
            if self.recurrent:
                rows = c.batch_size // c.n_steps
                order = jax.random.permutation(key, c.n_envs)[: c.n_minibatches * rows]
                minibatches = jax.tree_util.tree_map(
                    lambda v: jnp.swapaxes(v[:, order].reshape(c.n_steps, c.n_minibatches, rows, *v.shape[2:]), 0, 1),
                    batch,
                )
            else:
                order = jax.random.permutation(key, c.rollout)[: c.n_minibatches * c.batch_size]
                minibatches = jax.tree_util.tree_map(
                    lambda v: v[order].reshape(c.n_minibatches, c.batch_size, *v.shape[1:]), batch
                )

            def minibatch_step(carry, mb):
                params, opt_state = carry
                grads, losses = jax.grad(self._loss, has_aux=True)(params, mb)
                updates, opt_state = self.optimizer.update(grads, opt_state, params)
                return (optax.apply_updates(params, updates), opt_state), losses

            return jax.lax.scan(minibatch_step, (params, opt_state), minibatches)

        key, k_epochs = jax.random.split(runner["key"])
        (params, opt_state), losses = jax.lax.scan(
            epoch, (runner["params"], opt_state), jax.random.split(k_epochs, c.n_epochs)
        )
        ended = (t["terminated"] | t["truncated"]) & ~t["failed"]
        metrics = {
            "episodes": jnp.sum(ended),
            "episode_return": jnp.sum(jnp.where(ended, t["episode_return"], 0.0)),
            "successes": jnp.sum(ended & t["success"]),
            "stepper_failures": jnp.sum(t["failed"]),
            **jax.tree_util.tree_map(jnp.mean, losses),
        }
        runner = {**runner, "params": params, "opt_state": opt_state, "key": key, "update": runner["update"] + 1}
        return runner, metrics

    def _heads(self, params, mb):
        """(mean action, value) of a minibatch's observations; a recurrent policy's by its GRU run along each row's
        rollout (time first) from the state the rollout started it in, restarted from zeros where an episode did."""
        if not self.recurrent:
            return forward(params["pi"], mb["nobs"], jnp), forward(params["vf"], mb["nobs"], jnp)[..., 0]

        def step(h, xs):
            nobs, first = xs
            h, x = features(params["gru"], jnp.where(first[:, None], 0.0, h), nobs, jnp)
            return h, (forward(params["pi"], x, jnp), forward(params["vf"], x, jnp)[..., 0])

        return jax.lax.scan(step, mb["hidden"][0], (mb["nobs"], mb["first"]))[1]

    def _loss(self, params, mb):
        c = self.config
        mean, value = self._heads(params, mb)
        logp = log_prob(mean, params["log_std"], mb["action"])
        advantage = mb["advantage"]
        advantage = (advantage - advantage.mean()) / (advantage.std() + 1e-8)
        ratio = jnp.exp(logp - mb["logp"])
        clipped = jnp.clip(ratio, 1 - c.clip_range, 1 + c.clip_range)
        policy_loss = -jnp.mean(jnp.minimum(ratio * advantage, clipped * advantage))
        value_loss = jnp.mean((mb["return"] - value) ** 2)
        entropy = jnp.sum(params["log_std"] + 0.5 * math.log(2 * math.pi * math.e))
        loss = policy_loss + c.vf_coef * value_loss - c.ent_coef * entropy
        return loss, {"policy_loss": policy_loss, "value_loss": value_loss, "entropy": entropy,
                      "approx_kl": jnp.mean((ratio - 1) - jnp.log(ratio)),
                      "clip_fraction": jnp.mean(jnp.abs(ratio - 1) > c.clip_range)}  # fmt: skip

    def _evaluate(self, runners):
        """The deterministic policy on eval_episodes episodes of the JAX env per seed (each its first episode, from
        the seed's fixed evaluation key): their returns and successes (S, eval_episodes)."""
        n = self.config.eval_episodes
        obs, state = jax.vmap(self.env.reset_rows, (0, None, None))(runners["eval_key"], n, self.env_params)
        low, high = jnp.asarray(self.low), jnp.asarray(self.high)

        def step(carry, keys):
            obs, state, total, success, running, hidden = carry
            _, action, _, *hidden = self._policy(runners, self.observe(obs), hidden)
            action = jnp.clip(action.astype(float), low, high)
            obs, state, reward, terminated, truncated, info = self._env_step(keys, state, action, runners)
            done = terminated | truncated
            total = total + jnp.where(running, reward, 0.0)
            success = jnp.where(running & done, info["is_success"].astype(bool), success)
            return (obs, state, total, success, running & ~done, hidden[0] if hidden else None), None

        steps = self.env_params.max_steps_in_episode
        keys = jax.vmap(lambda k: jax.random.split(jax.random.fold_in(k, 1), steps))(runners["eval_key"])
        S = keys.shape[0]
        hidden = jnp.zeros((S, n, self.recurrent), jnp.float32) if self.recurrent else None  # each episode's start
        carry = (obs, state, jnp.zeros((S, n)), jnp.zeros((S, n), bool), jnp.ones((S, n), bool), hidden)
        (_, _, total, success, _, _), _ = jax.lax.scan(step, carry, jnp.swapaxes(keys, 0, 1))
        return {"return": total, "success": success}

    def _run(self, runners):
        """updates_per_eval updates of every seed, then an evaluation: (runners, metrics (S, updates), evaluation)."""

        def update(runners, _):
            runners, t = self._rollout(runners)
            return jax.vmap(self._learn)(runners, t)

        runners, metrics = jax.lax.scan(update, runners, None, self.config.updates_per_eval)
        metrics = jax.tree_util.tree_map(lambda v: jnp.swapaxes(v, 0, 1), metrics)
        return runners, metrics, self._evaluate(runners)

    def policy_arrays(self, runner: dict, seed_index: int) -> tuple[dict, np.ndarray, np.ndarray]:
        """(params, obs_mean, obs_var) of one seed of vmapped runners, as numpy (float64 weights: numpy's
        evaluation computes in float64 what training computed in float32)."""
        pick = lambda v: np.asarray(v[seed_index], float)
        params = jax.tree_util.tree_map(pick, runner["params"])
        stats = runner["obs_stats"]
        if not self.config.normalize:
            return params, np.zeros(self.obs_dim), np.ones(self.obs_dim) - jax_policy.OBS_EPSILON
        return params, pick(stats["mean"]), pick(stats["var"])


OBS_EPSILON = jax_policy.OBS_EPSILON


def to_numpy(tree: Any):
    return jax.tree_util.tree_map(np.asarray, tree)
