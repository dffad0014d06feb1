"""Training and evaluation: train.py and agents.evaluate on tiny budgets, and rl-zoo3 run on the package unchanged."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from agents import evaluate

ROOT = Path(__file__).resolve().parents[1]
ENV_ID = "connenv/Swing-v0"
DT = 0.05  # Swing-v0's default step, s


@pytest.fixture(scope="module")
def ppo_run(tmp_path_factory, train):
    """A PPO run of one rollout (8 envs × 256 steps), evaluated periodically every 1024 steps, checkpointed at its
    end."""
    runs = tmp_path_factory.mktemp("runs")
    argv = ["--algo", "ppo", "--timesteps", "300", "--runs", str(runs), "--eval-episodes", "2", "--eval-freq", "1024"]
    return train.main([*argv, "--checkpoint-freq", "1024"])


def test_ppo_run_folder_holds_normalized_model_and_periodic_evaluations(ppo_run, train, check_run):
    assert ppo_run["timesteps"] == 8 * 256  # PPO collects whole rollouts
    policy = check_run(ppo_run, "ppo")
    assert isinstance(policy, evaluate.NormalizedPolicy)  # ppo.yml normalizes observations
    periodic = np.load(Path(ppo_run["model"]).parent / "evaluations.npz")
    assert list(periodic["timesteps"]) == [1024, 2048]
    assert periodic["results"].shape == (2, train.PERIODIC_EVAL_EPISODES)
    # best_model.zip comes with the statistics it was evaluated with: those after the best evaluation's steps and
    # the 8 first observations (VecNormalize's running count starts at 1e-4)
    best = evaluate.load_model(Path(ppo_run["model"]).parent / "best_model.zip", ENV_ID)
    steps = periodic["timesteps"][periodic["results"].mean(axis=1).argmax()]
    assert best.vec_normalize.obs_rms.count == pytest.approx(steps + 8 + 1e-4, rel=1e-12)


def test_best_model_is_loaded_with_its_own_statistics_and_the_final_model_with_the_final(ppo_run, tmp_path):
    run = shutil.copytree(Path(ppo_run["model"]).parent, tmp_path / "run")
    stats = VecNormalize.load(
        str(run / "connenv-Swing-v0" / "vecnormalize.pkl"), DummyVecEnv([lambda: gym.make(ENV_ID)])
    )
    stats.obs_rms.mean = stats.obs_rms.mean + 1.0  # best statistics told apart from the final ones
    stats.save(str(run / "connenv-Swing-v0" / "best_vecnormalize.pkl"))
    best = evaluate.load_model(run / "best_model.zip", ENV_ID).vec_normalize.obs_rms.mean
    final = evaluate.load_model(run / "connenv-Swing-v0.zip", ENV_ID).vec_normalize.obs_rms.mean
    np.testing.assert_allclose(best - final, 1.0, rtol=1e-12)


@pytest.mark.parametrize("algo", ["sac", "td3"])
def test_off_policy_run_folder_holds_model_that_reloads(algo, tmp_path, train, check_run):
    argv = ["--algo", algo, "--timesteps", "1100", "--runs", str(tmp_path), "--eval-episodes", "2", "--eval-freq", "-1"]
    results = train.main(argv)
    assert results["timesteps"] == 1100  # past learning_starts, so some gradient steps were taken
    check_run(results, algo)


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(path.relative_to(folder)): path.read_bytes() for path in folder.rglob("*") if path.is_file()}


@pytest.mark.parametrize(
    ("flags", "checkpoint", "named"),
    [
        ([], True, ["--resume continues it from its checkpoint at step 2048", "--overwrite moves it aside"]),
        ([], False, ["no checkpoint to resume from", "--overwrite moves it aside"]),
        (["--resume"], False, ["no checkpoint to resume from", "--overwrite moves it aside"]),
    ],
)
def test_a_second_run_in_a_run_folder_is_refused_naming_the_folder_and_the_ways_out(
    flags, checkpoint, named, ppo_run, tmp_path, train
):
    """One folder, one run: train.py stops before it changes anything, in one line that names the folder."""
    run = shutil.copytree(Path(ppo_run["model"]).parent, tmp_path / "Swing-v0_ppo_s0")
    if not checkpoint:
        shutil.rmtree(run / "checkpoints")
    before = files_of(run)
    argv = ["--algo", "ppo", "--timesteps", "300", "--runs", str(tmp_path), "--eval-episodes", "1", *flags]
    with pytest.raises(SystemExit) as exit_info:
        train.main(argv)
    message = str(exit_info.value.code)
    assert "\n" not in message and f"{run} holds a run" in message
    assert all(words in message for words in named), message
    assert files_of(run) == before and [path.name for path in tmp_path.iterdir()] == [run.name]


def test_overwrite_moves_the_earlier_run_aside_whole_and_trains_anew(ppo_run, tmp_path, train, capsys):
    """The earlier run's files, best model and evaluations included, go to {run}.{date-time} unchanged; the new
    run's folder holds none of them (it has no periodic evaluation)."""
    earlier = files_of(Path(ppo_run["model"]).parent)
    run = shutil.copytree(Path(ppo_run["model"]).parent, tmp_path / "Swing-v0_ppo_s0")
    argv = ["--algo", "ppo", "--timesteps", "300", "--runs", str(tmp_path), "--eval-episodes", "1", "--eval-freq", "0"]
    results = train.main([*argv, "--overwrite"])
    (aside,) = [path for path in tmp_path.iterdir() if path != run]
    assert aside.name.startswith(f"{run.name}.") and f"moved aside to {aside}" in capsys.readouterr().out
    assert files_of(aside) == earlier
    assert results["status"] == "finished" and Path(results["model"]).parent == run
    assert not {"best_model.zip", "evaluations.npz", "checkpoints"} & {path.name for path in run.iterdir()}


def test_resume_in_a_folder_with_no_run_says_it_starts_from_step_0(tmp_path, train, capsys):
    argv = ["--algo", "sac", "--timesteps", "10", "--runs", str(tmp_path), "--eval-episodes", "1", "--eval-freq", "0"]
    results = train.main([*argv, "--resume"])
    run = tmp_path / "Swing-v0_sac_s0"
    assert f"{run}: no checkpoint to resume from, training from step 0" in capsys.readouterr().out
    assert results["timesteps"] == 10


@pytest.mark.parametrize(
    ("argv", "every"),
    [
        (["--env", "connenv/RollingBall-v0", "--algo", "sac"], 4000),  # the README's example: the tuned 40 000 steps
        ([], 15_000),  # PPO's 150 000 steps on Swing-v0
        (["--timesteps", "300"], 8 * 256),  # PPO trains one rollout: its policy changes once
    ],
)
def test_periodic_evaluations_fit_the_budget_by_default(argv, every, tmp_path, train):
    """A tenth of the budget (ten evaluations, the last at its end, so that there is a best model) but not more
    often than an on-policy algorithm's policy changes."""
    from stable_baselines3.common.callbacks import EvalCallback

    manager = train.experiment(train.parse_args([*argv, "--runs", str(tmp_path)]))
    model, _ = manager.setup_experiment()
    (evaluation,) = [callback for callback in manager.callbacks if isinstance(callback, EvalCallback)]
    assert evaluation.eval_freq * model.n_envs == every
    model.env.close()
    evaluation.eval_env.close()


def test_an_interrupted_run_saves_its_model_marks_its_results_and_exits_130(tmp_path):
    """Ctrl-C (SIGINT) once the run has checkpointed: the model so far is saved, results.json says "interrupted",
    and the exit status tells a calling script."""
    import signal

    run = tmp_path / "Swing-v0_ppo_s0"
    command = [sys.executable, str(ROOT / "train.py"), "--timesteps", "1000000", "--eval-freq", "0"]
    command += ["--checkpoint-freq", "2048", "--runs", str(tmp_path)]
    # SIGINT's default action in the child: a shell without job control starts background jobs with it ignored,
    # which the child would inherit, and Ctrl-C would then not reach train.py
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # noqa: PLW1509 (no lock taken)
    try:
        deadline = time.monotonic() + 120
        while not (run / "checkpoints" / "latest").is_file() and process.poll() is None:
            assert time.monotonic() < deadline, "no checkpoint within 120 s"
            time.sleep(0.05)
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130, err[-2000:]
    results = json.loads((run / "results.json").read_text())
    assert results["status"] == "interrupted" and results["evaluation"] is None
    assert 2048 <= results["timesteps"] < 1_000_000
    checkpoint = int((run / "checkpoints" / "latest").read_text())
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"training interrupted at step {results['timesteps']}; the model so far is {run}")
    assert last.endswith(f"--resume continues it from its checkpoint at step {checkpoint}")
    assert PPO.load(run / "connenv-Swing-v0.zip").num_timesteps == results["timesteps"]


def test_train_table_evaluates_all_policies_on_the_same_episodes(ppo_run):
    report = ppo_run["evaluation"]
    assert (report["seed"], report["episodes"]) == (0, 2)
    assert [len(row["episodes"]) for row in report["policies"]] == [2, 2, 2]
    analytic = evaluate.compare(ENV_ID, ["analytic"], 2, 0)["policies"][0]
    assert analytic["episodes"] == report["policies"][1]["episodes"]


def test_evaluation_is_deterministic_on_seeded_episodes():
    first = evaluate.compare(ENV_ID, ["analytic", "random"], episodes=4, seed=7)
    again = evaluate.compare(ENV_ID, ["analytic", "random"], episodes=4, seed=7)
    other = evaluate.compare(ENV_ID, ["analytic"], episodes=4, seed=8)
    assert first == again
    returns = [e["ret"] for e in first["policies"][0]["episodes"]]
    assert [e["ret"] for e in other["policies"][0]["episodes"]][:3] == returns[1:]  # episode i is seed + i


def test_analytic_controller_beats_random_policy():
    report = evaluate.compare(ENV_ID, ["analytic", "random"], episodes=10, seed=0)
    analytic, random = report["policies"]
    assert analytic["success_rate"] == 1.0 and random["success_rate"] == 0.0
    assert analytic["return_mean"] > random["return_mean"]
    assert random["time_to_success_mean"] is None and random["length_mean"] == 500  # the time limit
    table = evaluate.format_table(report).splitlines()
    mean, std = f"{analytic['return_mean']:.3f}", f"{analytic['return_std']:.3f}"
    assert table[2].split()[:5] == ["analytic", mean, "±", std, "100%"]


def test_time_to_success_is_simulated_time_of_the_steps_taken():
    episodes = evaluate.evaluate(ENV_ID, evaluate.make_policy("analytic", ENV_ID, 0)[1], episodes=3, seed=0)
    for episode in episodes:
        assert episode.success
        assert episode.time == pytest.approx(episode.length * DT)


def test_video_is_a_gif_of_the_first_episode(tmp_path):
    from PIL import Image

    video = tmp_path / "swing.gif"
    (episode,) = evaluate.evaluate(ENV_ID, evaluate.make_policy("analytic", ENV_ID, 0)[1], 1, 0, video)
    with Image.open(video) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == len(range(0, episode.length + 1, evaluate.GIF_FRAME_STRIDE))  # reset + each step


def test_evaluate_cli_writes_table_and_json(tmp_path, capsys):
    out = tmp_path / "eval.json"
    evaluate.main(["--policy", "analytic", "random", "--episodes", "2", "--seed", "5", "--json", str(out)])
    report = json.loads(out.read_text())
    assert [row["policy"] for row in report["policies"]] == ["analytic", "random"]
    assert "analytic" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("program", "argv", "named"),
    [
        ("train", ["--env", "Nope-v0"], ["'Nope-v0'", "connenv/Swing-v0"]),
        ("train", ["--algo", "nope"], ["'nope'", "ppo", "sac", "td3"]),
        ("train", ["--timesteps", "0"], ["'0'", "positive integer"]),
        ("train", ["--timesteps", "-5"], ["'-5'", "positive integer"]),
        ("train", ["--algo", "a2c"], ["a2c.yml", "--hyperparams"]),
        ("evaluate", ["--episodes", "0"], ["'0'", "positive integer"]),
        ("evaluate", ["--policy", "nope"], ["'nope'", "analytic", "random"]),
    ],
)
def test_bad_cli_input_exits_naming_value_and_choices(program, argv, named, capsys, train):
    main = {"train": train.main, "evaluate": evaluate.main}[program]
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    for word in named:
        assert word in err


def test_model_of_another_env_is_rejected(tmp_path):
    path = tmp_path / "pendulum.zip"
    PPO("MlpPolicy", "Pendulum-v1", n_steps=64, batch_size=64).save(path)
    with pytest.raises(ValueError, match="observation_space"):
        evaluate.load_model(path, ENV_ID, algo="ppo")
    with pytest.raises(ValueError, match="pass --algo"):
        evaluate.load_model(path, ENV_ID)


@pytest.mark.parametrize("conf", [[], ["--conf-file", str(ROOT / "agents" / "hyperparams" / "ppo.yml")]])
def test_rl_zoo3_trains_on_the_package_unchanged(conf, tmp_path):
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", ENV_ID, "--gym-packages", "connenv"]
    command += ["--n-timesteps", "200", "--eval-freq", "-1", "--seed", "0", "--num-threads", "1", "-f", str(tmp_path)]
    command += conf
    done = subprocess.run(command, check=False, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    (model_path,) = (tmp_path / "ppo").glob("connenv-Swing-v0_1/connenv-Swing-v0.zip")
    action, _ = evaluate.load_model(model_path, ENV_ID).predict(np.zeros(4, np.float32))
    assert gym.make(ENV_ID).action_space.contains(action)


def test_skier_trains_with_its_hyperparameters_and_the_controller_escapes(tmp_path, train):
    """train.py and the evaluation CLI on Skier-v0: a tiny PPO run, and analytic against random."""
    argv = ["--env", "connenv/Skier-v0", "--timesteps", "300", "--runs", str(tmp_path), "--eval-episodes", "2"]
    results = train.main([*argv, "--eval-freq", "-1"])
    assert Path(results["model"]).name == "connenv-Skier-v0.zip"
    analytic, random = results["evaluation"]["policies"][1:]
    assert analytic["success_rate"] == 1.0 and random["success_rate"] == 0.0


FACTORY = '''
import sympy as sp

theta, theta_dot, u, u_dot = sp.symbols("theta theta_dot u u_dot")


class Turn:
    def reset(self, np_random):
        return {"q": np_random.uniform(-0.5, 0.5, 1)}

    def reward(self, state, next_state):
        return -abs(next_state["q"][0] - 1.0)

    def terminated(self, state):
        return abs(state["q"][0] - 1.0) < 0.05


def rotor():
    from connenv.core.lagrangian import LagrangianSystem

    system = LagrangianSystem(theta_dot**2 + (theta_dot + u_dot) ** 2 / 4, 0, [theta], [u])
    return {"system": system, "u_low": -3.0, "u_high": 3.0, "task": Turn(), "max_episode_steps": 20}
'''


def test_train_on_a_users_system_named_by_a_factory(tmp_path, monkeypatch, train):
    """--env-kwargs module:factory is all train.py needs for ActiveConstraint-v0 on a user's own system."""
    (tmp_path / "my_rotor.py").write_text(FACTORY)
    monkeypatch.syspath_prepend(str(tmp_path))
    argv = ["--env", "connenv/ActiveConstraint-v0", "--env-kwargs", "my_rotor:rotor", "--algo", "ppo"]
    argv += ["--timesteps", "300", "--runs", str(tmp_path / "runs"), "--eval-episodes", "2", "--eval-freq", "0"]
    results = train.main(argv)
    assert results["timesteps"] == 8 * 256
    assert [row["policy"] for row in results["evaluation"]["policies"]] == ["ppo:ActiveConstraint-v0_ppo_s0", "random"]
    assert all(row["length_mean"] <= 20 for row in results["evaluation"]["policies"])  # the factory's time limit
    from agents.evaluate import env_kwargs_of

    kwargs = env_kwargs_of("my_rotor:rotor")
    env = gym.make("connenv/ActiveConstraint-v0", **kwargs)
    policy = evaluate.load_model(results["model"], "connenv/ActiveConstraint-v0", env_kwargs=kwargs)
    assert env.action_space.contains(policy.predict(env.reset(seed=0)[0], deterministic=True)[0])


def test_the_readmes_training_command_trains_the_reference_tables_budget(train, tmp_path):
    """A newcomer copies the README's train.py line: it runs the tuned budget (the hyperparameters' n_timesteps,
    what the reference table's row trained), not a shorter one that learns less than the table shows."""
    import yaml

    readme = (ROOT / "README.md").read_text().splitlines()
    commands = [line.split("#")[0].split()[2:] for line in readme if line.strip().startswith("python train.py")]
    assert commands
    for command in commands:
        args = train.parse_args([*command, "--runs", str(tmp_path)])
        tuned = yaml.safe_load((ROOT / "agents" / "hyperparams" / f"{args.algo}.yml").read_text())[args.env]
        assert args.timesteps in (None, tuned["n_timesteps"]), f"{command}: {args.timesteps} steps, tuned {tuned}"
