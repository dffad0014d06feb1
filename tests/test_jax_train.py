"""PPO on connenv.jax (agents.jax_ppo, train.py --backend jax): its advantages bootstrap a time limit as a time limit,
its running statistics are the data's, the policy file numpy runs is the network JAX trained, and a run from the
command line leaves run folders that agents.evaluate and the score read."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

# as tests/test_jax.py: XLA without LLVM's optimization passes compiles several times faster; IEEE results either way
os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()
jax = pytest.importorskip("jax")
pytest.importorskip("optax")
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp

from agents import jax_ppo, jax_train, train
from agents.evaluate import make_policy
from agents.jax_policy import JaxPolicy


def test_a_time_limit_is_bootstrapped_and_a_terminal_state_is_not():
    """A constant reward r under an exact value V = r / (1 − γ): every advantage is 0 when the clock cuts an episode
    (the final observation's value stands in for the future), and after a terminal step the advantage is the
    missing future −γV; PureJaxRL's done-as-terminal would give −γV at the cut too."""
    gamma, lam, r, T = 0.99, 0.95, 1.0, 6
    V = r / (1 - gamma)
    value, reward = jnp.full((T, 1), V, jnp.float32), jnp.full((T, 1), r)
    flags = lambda t: jnp.zeros((T, 1), bool).at[t].set(True)
    cut = jax_ppo.gae(reward, value, jnp.full(1, V), jnp.full((T, 1), V), flags(T + 1), flags(2), gamma, lam)
    np.testing.assert_allclose(cut, 0.0, atol=1e-4)
    ended = jax_ppo.gae(reward, value, jnp.full(1, V), jnp.full((T, 1), V), flags(2), flags(T + 1), gamma, lam)
    np.testing.assert_allclose(ended[2, 0], -gamma * V, rtol=1e-5)  # the terminal step loses the whole future
    np.testing.assert_allclose(ended[:2, 0], -gamma * V * (gamma * lam) ** np.arange(2, 0, -1), rtol=1e-5)
    np.testing.assert_allclose(ended[3:], 0.0, atol=1e-4)  # the next episode: its own, exact


def test_running_statistics_are_the_data_s_mean_and_variance():
    """Chan et al.'s update over batches of different sizes gives the pooled mean and (population) variance."""
    rng = np.random.default_rng(0)
    batches = [rng.normal(3.0, 2.0, (n, 3)) for n in (5, 17, 64)]
    stats = jax_ppo.stats_init(3)
    for batch in batches:
        stats = jax_ppo.stats_update(stats, jnp.asarray(batch))
    data = np.concatenate(batches)
    np.testing.assert_allclose(stats["mean"], data.mean(0), rtol=1e-4)  # the prior's 1e-4 pseudo-count
    np.testing.assert_allclose(stats["var"], data.var(0), rtol=1e-4)


def test_hyperparameters_are_read_as_rl_zoo3_writes_them_and_unknown_keys_refused():
    config = jax_ppo.Config.from_hyperparams({"n_timesteps": "1e5", "learning_rate": "lin_3e-4", "net_arch": [32]})
    assert (config.n_timesteps, config.learning_rate, config.linear_lr, config.net_arch) == (100000, 3e-4, True, (32,))
    with pytest.raises(ValueError, match="use_sde"):
        jax_ppo.Config.from_hyperparams({"n_timesteps": 1, "use_sde": True})
    with pytest.raises(ValueError, match="n_envs = 0"):
        jax_ppo.Config.from_hyperparams({"n_timesteps": 1, "n_envs": 0})


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--backend", "jax", "--algo", "sac"], "--backend jax trains ppo"),
        (["--seeds", "4"], "seeds at once train on --backend jax"),
    ],
)
def test_train_py_refuses_what_the_backend_cannot_do(argv, message, capsys):
    with pytest.raises(SystemExit):
        train.parse_args(argv)
    assert message in capsys.readouterr().err


def test_a_run_trains_seeds_together_and_leaves_policies_numpy_runs(tmp_path):
    """Two seeds of Swing-v0, a few updates: each seed's folder has its config, evaluations, progress, policies and a
    finished results.json; the policy file, run by numpy, gives the actions of the network JAX trained (float32 in
    JAX, float64 in numpy: to 1e-5); a second run into the same folders is refused, naming --resume, and with --resume
    goes on from its checkpoint, its curves and wall time continued."""
    hyperparams = tmp_path / "ppo_jax.yml"
    hyperparams.write_text("connenv/Swing-v0: {n_timesteps: 512, n_envs: 4, n_steps: 64, batch_size: 128, "
                           "n_epochs: 2, eval_episodes: 2, eval_freq: 256}\n")  # fmt: skip
    argv = ["--backend", "jax", "--env", "connenv/Swing-v0", "--seeds", "2", "--seed", "3", "--runs", str(tmp_path),
            "--hyperparams", str(hyperparams), "--eval-episodes", "2", "--checkpoint-freq", "256"]  # fmt: skip
    report = train.main(argv)
    labels = [row["policy"] for row in report["policies"]]
    assert labels == ["ppo_jax:Swing-v0_ppo_jax_s3", "ppo_jax:Swing-v0_ppo_jax_s4", "analytic", "random"]
    for seed in (3, 4):
        folder = jax_train.run_folder(tmp_path, "connenv/Swing-v0", seed)
        results = json.loads((folder / "results.json").read_text())
        assert results["status"] == "finished" and results["timesteps"] == 512 and results["seed"] == seed
        assert next(row["policy"] for row in results["evaluation"]["policies"]) == f"ppo_jax:{folder.name}"
        assert np.load(folder / "evaluations.npz")["timesteps"].tolist() == [256, 512]
        assert (folder / "connenv-Swing-v0" / "config.yml").is_file() and (folder / "progress.csv").is_file()
    assert make_policy(f"jax:{folder}", "connenv/Swing-v0", 0)[0] == f"ppo_jax:{folder.name}"

    import connenv.jax

    env, params = connenv.jax.make("connenv/Swing-v0")
    obs = np.asarray(env.reset_rows(jax.random.key(1), 8, params)[0])
    policy = JaxPolicy(folder / "policy.npz", "connenv/Swing-v0")
    checkpoint = jax_train.load_checkpoint(folder.with_name(folder.name.replace("s4", "s3")),
                                           _template(env, params, hyperparams), 512)  # fmt: skip
    trainer = _trainer(env, params, hyperparams)
    runner = jax.tree_util.tree_map(lambda v: v[1], checkpoint)  # seed 4, the second of the two
    expected = jnp.clip(jax_ppo.forward(runner["params"]["pi"], trainer.normalized(runner, jnp.asarray(obs)), jnp),
                        trainer.low, trainer.high)  # fmt: skip
    np.testing.assert_allclose(policy.action(obs), expected, atol=1e-5)
    with pytest.raises(SystemExit, match="--resume continues it from its checkpoint at step 512"):
        train.main(argv)
    before = jax_train.read_progress(folder)
    train.main(argv + ["--resume", "--timesteps", "768"])  # continued from its checkpoint to a larger budget
    after, results = jax_train.read_progress(folder), json.loads((folder / "results.json").read_text())
    assert np.load(folder / "evaluations.npz")["timesteps"].tolist() == [256, 512, 768]
    assert after[: len(before)] == before and [row["timesteps"] for row in after][-1] == 768
    seconds = [row["seconds"] for row in after]  # the wall time goes on from the checkpoint's, not from 0
    assert seconds == sorted(seconds) and results["train_seconds"] >= seconds[-1] > before[-1]["seconds"] > 0


def test_the_networks_are_drawn_orthogonal_as_jaxs_initializer_draws_them_and_several_seeds_start():
    """The weights drawn on the host are JAX's orthogonal draw (the same normal matrix, its QR by numpy: to float32
    rounding) and orthogonal (WᵀW or WWᵀ = gain² I); two seeds' runners start (their vmapped init deadlocked XLA:CPU
    on 2 cores while it took a batched LAPACK QR)."""
    key = jax.random.key(7)
    for shape, gain in [((3, 64), 1.5), ((64, 64), 2**0.5), ((64, 1), 0.01)]:
        W = np.asarray(jax_ppo.orthogonal(key, shape, gain), float)
        reference = jax.nn.initializers.orthogonal(gain)(key, shape, jnp.float32)  # one matrix: no batched QR
        np.testing.assert_allclose(W, reference, atol=2e-6 * gain)
        gram = W.T @ W if shape[0] >= shape[1] else W @ W.T
        np.testing.assert_allclose(gram, gain**2 * np.eye(min(shape)), atol=1e-6 * gain**2)
    import connenv.jax

    env, params = connenv.jax.make("connenv/FallingCat-v0")
    hyperparams = {"n_timesteps": 64, "n_envs": 2, "n_steps": 8, "batch_size": 16}
    trainer = jax_ppo.Trainer(env, params, jax_ppo.Config.from_hyperparams(hyperparams))
    runners = jax.block_until_ready(trainer.init(jnp.stack([jax.random.key(s) for s in range(4)])))
    assert runners["params"]["pi"][0][0].shape == (4, trainer.obs_dim, 64)
    assert not np.array_equal(runners["params"]["pi"][0][0][0], runners["params"]["pi"][0][0][1])  # seeds differ


def test_a_start_curriculum_restarts_a_share_of_the_ended_training_rows_and_cuts_them_at_its_max_steps():
    """kapitza_release on JAX (agents.curriculum, share 0.5, max_steps 2000): of 4000 rows that end, about half restart
    released from |θ| on [0.1, π] and the others start as the task does (|θ| on [0.05, 0.1]); rows that did not end
    are kept; a curriculum row is truncated at 2000 steps, the task's own is not; bead_near_target, which reads the
    reset's info, is refused on JAX by name."""
    import connenv.jax

    env, params = connenv.jax.make("connenv/KapitzaSwingUp-v0")
    config = jax_ppo.Config.from_hyperparams({"n_timesteps": 64, "n_envs": 2000, "n_steps": 8, "batch_size": 16,
                                              "curriculum": "kapitza_release"})  # fmt: skip
    trainer = jax_ppo.Trainer(env, params, config)
    obs, state = jax.vmap(env.reset_rows, (0, None, None))(jax.random.split(jax.random.key(0), 2), 2000, params)
    done = jnp.ones((2, 2000), bool).at[:, :100].set(False)
    _, new_state, started = trainer._curriculum_reset(jax.random.split(jax.random.key(1), 2), obs, state, done)
    theta = np.abs(np.asarray(new_state.x[..., 0]))
    started = np.asarray(started)
    assert not started[:, :100].any() and np.array_equal(np.asarray(new_state.x[:, :100]), np.asarray(state.x[:, :100]))
    assert abs(started.mean() - 0.5 * 0.95) < 0.03
    assert np.all((theta[started] >= 0.1) & (theta[started] <= np.pi)) and theta[started].max() > 3.0
    assert np.all((theta[~started] >= 0.05) & (theta[~started] <= 0.1))
    late = connenv.jax.EnvState(new_state.x[:, :4], jnp.full((2, 4), 1999, jnp.int32))
    cut = jnp.array([[True, False, True, False]] * 2)
    truncated = trainer._env_step(jax.random.split(jax.random.key(2), 2), late, jnp.zeros((2, 4, 1)), None, cut)[4]
    assert np.asarray(truncated).tolist() == [[True, False, True, False]] * 2
    with pytest.raises(ValueError, match="curriculum 'bead_near_target' reads the reset's info"):
        jax_ppo.Config.from_hyperparams({"n_timesteps": 64, "curriculum": "bead_near_target"})


def test_a_recurrent_policy_learns_from_the_states_its_rollout_ran_and_numpy_runs_it_as_jax_did(tmp_path):
    """A GRU policy (recurrent: 8) on Swing-v0 with 12-step episodes, so that episodes end inside the 32-step rollout:
    the loss's GRU, run along each row's rollout from the state the rollout started it in and restarted from zeros
    after each end, gives the rollout's own log-probabilities and values (float32); a policy file of it, run by numpy
    with SB3's predict (state and episode_start), gives JAX's actions along an episode (float32 in JAX: to 1e-5); a
    batch_size that splits rows' rollouts is refused by name."""
    import dataclasses

    import connenv.jax
    from agents import jax_policy

    env, params = connenv.jax.make("connenv/Swing-v0")
    params = dataclasses.replace(params, max_steps_in_episode=12)
    config = jax_ppo.Config.from_hyperparams({"n_timesteps": 1024, "n_envs": 4, "n_steps": 32, "batch_size": 64,
                                              "recurrent": 8})  # fmt: skip
    trainer = jax_ppo.Trainer(env, params, config)
    runners = trainer.init(jnp.stack([jax.random.key(0)]))
    runners, t = jax.jit(trainer._rollout)(runners)
    t = jax.tree_util.tree_map(lambda v: v[0], t)  # the one seed's (T, N, …)
    ended = np.asarray(t["terminated"] | t["truncated"])
    assert ended[:-1].any() and np.all(np.asarray(t["hidden"][1:])[ended[:-1]] == 0.0)  # restarted after an end
    first = jnp.concatenate([jnp.zeros_like(ended[:1]), ended[:-1]], 0)
    one = jax.tree_util.tree_map(lambda v: v[0], runners["params"])
    mean, value = trainer._heads(one, {"nobs": t["nobs"], "hidden": t["hidden"], "first": first})
    np.testing.assert_allclose(value, t["value"], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(jax_ppo.log_prob(mean, one["log_std"], t["action"]), t["logp"], rtol=1e-5, atol=1e-5)

    path = tmp_path / "policy.npz"
    jax_policy.save(path, *trainer.policy_arrays(runners, 0), trainer.meta("connenv/Swing-v0"))
    policy = jax_policy.JaxPolicy(path, "connenv/Swing-v0")
    obs = np.asarray(t["raw_obs"][:, 0])  # one row's observations along the rollout, normalized as in training
    state, hidden = None, jnp.zeros((1, 1, 8), jnp.float32)
    for step in range(12):
        action, state = policy.predict(obs[step], state, np.array([step == 0]))
        _, expected, _, hidden = trainer._policy(runners, jnp.asarray(obs[step])[None, None], hidden)
        np.testing.assert_allclose(action, np.clip(expected[0, 0], trainer.low, trainer.high), atol=1e-5)
    with pytest.raises(ValueError, match="recurrent = 8, batch_size = 48: .* multiple of n_steps = 32"):
        jax_ppo.Config.from_hyperparams({"n_timesteps": 1024, "n_envs": 4, "n_steps": 32, "batch_size": 48,
                                         "recurrent": 8})  # fmt: skip


def _trainer(env, params, hyperparams):
    entry = jax_train.hyperparams_entry(hyperparams, "connenv/Swing-v0")
    return jax_ppo.Trainer(env, params, jax_ppo.Config.from_hyperparams(entry))


def _template(env, params, hyperparams):
    return _trainer(env, params, hyperparams).init(jnp.stack([jax.random.key(3), jax.random.key(4)]))
