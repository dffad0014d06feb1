"""The baselines on Ray (agents.baselines train, agents.cluster): the same model as a direct run, fault tolerance
(a run whose worker is killed resumes from its checkpoint; the others are not repeated), and a cluster of two nodes
started as docs/scaling.md says. A local Ray of two CPUs and tiny budgets."""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml

from agents import baselines

ROOT = Path(__file__).resolve().parents[1]
STEPS = 2048  # per run, with an evaluation and a checkpoint every 1024 steps
TINY = {"timesteps": STEPS, "evaluations": 2, "episodes": (2, 2)}  # 2 episodes a periodic evaluation and at the end
ROLLOUT = 8 * 256  # PPO's on Swing-v0: 8 envs × n_steps


@pytest.fixture(scope="module")
def ray_local():
    from agents import cluster

    ray = cluster.connect(num_cpus=2)
    yield ray
    ray.shutdown()


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(path.relative_to(folder)): path.read_bytes() for path in folder.rglob("*") if path.is_file()}


def policy_parameters(folder):
    from stable_baselines3 import PPO

    return PPO.load(folder / "connenv-Swing-v0.zip", device="cpu").policy.state_dict()


def test_a_run_on_ray_gives_the_model_of_a_direct_run(ray_local, tmp_path):
    """Single-thread torch on CPU, the same seed: the final model is the same to the bit on either scheduler."""
    from agents import train

    baselines.train_all(["connenv/Swing-v0"], ["ppo"], 2, seeds=[1], runs=tmp_path / "ray", **TINY)
    train.main(baselines.train_argv("connenv/Swing-v0", "ppo", 1, tmp_path / "direct", **TINY))
    on_ray = policy_parameters(baselines.run_folder("connenv/Swing-v0", "ppo", 1, tmp_path / "ray"))
    direct = policy_parameters(baselines.run_folder("connenv/Swing-v0", "ppo", 1, tmp_path / "direct"))
    assert on_ray.keys() == direct.keys()
    assert all(torch.equal(on_ray[key], direct[key]) for key in on_ray)


def test_a_killed_run_resumes_from_its_checkpoint_and_no_other_run_is_repeated(ray_local, tmp_path, capsys):
    """Kill the worker of seed 0 once it has checkpointed: Ray retries it from that checkpoint, seed 1 runs once,
    and both runs finish. The checkpoint lies between rollouts (an evaluation and a checkpoint are due every 1536
    steps, inside PPO's second rollout), so the resumed run trains the two rollouts of the run never stopped. Seed
    1's folder holds a run interrupted before its first checkpoint: it is moved aside whole, and seed 1 trains anew."""
    folders = [baselines.run_folder("connenv/Swing-v0", "ppo", seed, tmp_path) for seed in (0, 1)]
    (folders[1] / "connenv-Swing-v0").mkdir(parents=True)
    hyperparams = yaml.safe_dump(baselines.hyperparams("ppo", "connenv/Swing-v0"))
    (folders[1] / "connenv-Swing-v0" / "config.yml").write_text(hyperparams)
    (folders[1] / "results.json").write_text(json.dumps({"status": "interrupted", "timesteps": 1024}))
    interrupted = files_of(folders[1])
    killed = []

    def kill_seed_0():
        checkpoint, attempts = folders[0] / "checkpoints" / "latest", folders[0] / "attempts.log"
        deadline = time.monotonic() + 120
        while not checkpoint.is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
        pid = int(attempts.read_text().split()[1])
        os.kill(pid, signal.SIGKILL)
        killed.append((pid, int(checkpoint.read_text())))

    killer = threading.Thread(target=kill_seed_0)
    killer.start()
    budget = {**TINY, "timesteps": 3 * ROLLOUT // 2}
    outcomes = baselines.train_all(["connenv/Swing-v0"], ["ppo"], 2, seeds=(0, 1), runs=tmp_path, **budget)
    killer.join()
    print("\n".join(outcomes), *(f.name + ": " + (f / "attempts.log").read_text() for f in folders), sep="\n")
    ((pid, checkpoint_steps),) = killed
    assert sorted(outcome.split(":")[0] for outcome in outcomes) == sorted(f.name for f in folders)
    assert all(baselines.finished(folder) for folder in folders)
    first, retry = (folders[0] / "attempts.log").read_text().splitlines()
    assert first.startswith(f"pid {pid} from step 0 on node") and f" from step {checkpoint_steps} on node" in retry
    assert checkpoint_steps == ROLLOUT
    (attempt,) = (folders[1] / "attempts.log").read_text().splitlines()
    assert " from step 0 on node " in attempt
    (aside,) = tmp_path.glob(f"{folders[1].name}.*")
    assert files_of(aside) == interrupted
    assert [json.loads((folder / "results.json").read_text())["timesteps"] for folder in folders] == [2 * ROLLOUT] * 2
    periodic = np.load(folders[0] / "evaluations.npz")  # the evaluations before the checkpoint kept, successes too
    assert len(periodic["successes"]) == len(periodic["timesteps"]) == 2
    never_stopped = np.load(folders[1] / "evaluations.npz")["timesteps"]
    assert periodic["timesteps"].tolist() == never_stopped.tolist()  # the resumed run evaluates on the same steps


def test_a_sampled_configuration_becomes_rl_zoo3_hyperparameters():
    """rl-zoo3's PPO sampler on a fixed configuration: the YAML form evaluates back to what the sampler returned."""
    from rl_zoo3.hyperparams_opt import HYPERPARAMS_SAMPLER
    from torch import nn

    from agents import tune

    config = {"batch_size_pow": 6, "n_steps_pow": 8, "one_minus_gamma": 0.01, "one_minus_gae_lambda": 0.05,
              "learning_rate": 3e-4, "ent_coef": 1e-3, "clip_range": 0.2, "n_epochs": 10, "max_grad_norm": 0.5,
              "net_arch": "medium", "activation_fn": "relu"}  # fmt: skip
    hyperparams = tune.hyperparameters("connenv/KapitzaSwingUp-v0", "ppo", config)
    assert hyperparams["n_steps"] == 256 and hyperparams["batch_size"] == 64 and hyperparams["gamma"] == 0.99
    assert eval(hyperparams["policy_kwargs"], {"nn": nn}) == {
        "net_arch": {"pi": [256, 256], "vf": [256, 256]},
        "activation_fn": nn.ReLU,
    }
    assert hyperparams["normalize"] is True  # kept from agents/hyperparams/ppo.yml
    arguments = tune.sampler_arguments("connenv/RollingBallGoal-v0", "sac")
    assert arguments[2]["using_her_replay_buffer"]
    her = {"one_minus_gamma": 0.02, "batch_size_pow": 8, "learning_rate": 1e-3, "train_freq": 1, "tau": 0.02,
           "net_arch": "medium", "n_sampled_goal": 2, "goal_selection_strategy": "episode"}  # fmt: skip
    assert HYPERPARAMS_SAMPLER["sac"](optuna_fixed(her), *arguments)["replay_buffer_kwargs"] == {
        "n_sampled_goal": 2,
        "goal_selection_strategy": "episode",
    }
    sampled = tune.hyperparameters("connenv/RollingBallGoal-v0", "sac", her)
    assert eval(sampled["replay_buffer_kwargs"]) == {"n_sampled_goal": 2, "goal_selection_strategy": "episode"}


def optuna_fixed(params):
    import optuna

    return optuna.trial.FixedTrial(params)


def test_a_sweep_writes_its_best_hyperparameters_for_train_py_and_resumes(ray_local, tmp_path, capsys):
    """Three trials of Optuna + ASHA; best.yml trains with train.py; the same command again restores the finished
    sweep instead of running it anew."""
    import yaml

    from agents import train, tune

    argv = ["--env", "connenv/Swing-v0", "--algo", "sac", "--samples", "3", "--timesteps", "300"]
    argv += ["--evaluations", "2", "--episodes", "2", "--runs", str(tmp_path)]
    best = tune.main(argv)
    path = tmp_path / "Swing-v0_sac" / "best.yml"
    assert yaml.safe_load(path.read_text()) == {"connenv/Swing-v0": best}
    assert {"learning_rate", "batch_size", "gamma", "tau", "train_freq", "gradient_steps"} <= best.keys()
    trials = sorted(p.name for p in (tmp_path / "Swing-v0_sac" / "trials").iterdir())
    assert len(trials) == 3
    results = train.main(["--env", "connenv/Swing-v0", "--algo", "sac", "--hyperparams", str(path), "--timesteps",
                          "200", "--eval-freq", "0", "--eval-episodes", "1", "--runs", str(tmp_path / "check")])  # fmt: skip
    assert results["timesteps"] >= 200  # SAC steps in chunks of train_freq
    logs = {path: path.stat().st_mtime_ns for path in (tmp_path / "Swing-v0_sac" / "trials").glob("*/train.log")}
    capsys.readouterr()
    tune.main(argv)
    assert "resuming the sweep" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "Swing-v0_sac" / "trials").iterdir()) == trials
    assert {path: path.stat().st_mtime_ns for path in logs} == logs  # no trial trained again


def free_ports(n: int) -> list[int]:
    sockets = [socket.socket() for _ in range(n)]
    for sock in sockets:
        sock.bind(("", 0))
    ports = [sock.getsockname()[1] for sock in sockets]
    for sock in sockets:
        sock.close()
    return ports


def ray_start(args: list[str], env: dict, log: Path) -> subprocess.Popen:
    """`ray start ARGS --block` in a process group of its own, once it says "Ray runtime started."."""
    ray = shutil.which("ray", path=os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")]))
    with log.open("w") as out:
        process = subprocess.Popen([ray, "start", *args, "--block"], env=env, stdout=out, stderr=subprocess.STDOUT,
                                   start_new_session=True)  # fmt: skip
    deadline = time.monotonic() + 60
    while "Ray runtime started." not in log.read_text():
        assert process.poll() is None and time.monotonic() < deadline, log.read_text()[-3000:]
        time.sleep(0.2)
    return process


@pytest.fixture
def two_node_ray():
    """A Ray cluster of two nodes of one CPU each on this machine, started as docs/scaling.md says: token
    authentication on (RAY_AUTH_MODE=token, the cluster's token in RAY_AUTH_TOKEN), a head, and a node that joins it
    at 127.0.0.1:PORT. Free ports, a temp dir each, Ray's variables of this process left out. Yields the head's
    address and the environment of a driver; kills the process groups of both `ray start --block` (the nodes'
    processes) even on failure."""
    env = {key: value for key, value in os.environ.items() if not key.startswith("RAY_")}
    env.update(RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32), RAY_USAGE_STATS_ENABLED="0")
    gcs, dashboard, head_agent, node_agent = free_ports(4)
    address = f"127.0.0.1:{gcs}"
    each = ["--num-cpus", "1", "--object-store-memory", str(100 * 2**20)]
    temp = Path(tempfile.mkdtemp(prefix="ray"))  # short: Ray's socket paths must fit in 107 characters
    processes = []
    try:
        head = ["--head", "--port", str(gcs), "--include-dashboard", "false", "--dashboard-port", str(dashboard)]
        head += ["--dashboard-agent-listen-port", str(head_agent), "--temp-dir", str(temp / "head"), *each]
        processes.append(ray_start(head, env, temp / "head.log"))
        node = ["--address", address, "--dashboard-agent-listen-port", str(node_agent)]
        processes.append(ray_start([*node, "--temp-dir", str(temp / "node"), *each], env, temp / "node.log"))
        yield address, env
    finally:  # SIGKILL: Ray's graceful stop takes seconds per process; the workers end with their raylet
        for process in processes:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        shutil.rmtree(temp, ignore_errors=True)


def test_a_cluster_joined_with_the_token_runs_a_run_on_each_node(two_node_ray, tmp_path):
    """agents.baselines train --address on the two-node cluster: two runs of one CPU each, at once, one per node
    (the Ray node each attempt ran on is in its attempts.log)."""
    address, env = two_node_ray
    command = [sys.executable, "-m", "agents.baselines", "train", "--env", "connenv/FallingCat-v0", "--algo", "ppo"]
    command += ["--seeds", "0", "1", "--timesteps", "2048", "--runs", str(tmp_path), "--address", address]
    done = subprocess.run(command, check=False, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    folders = [baselines.run_folder("connenv/FallingCat-v0", "ppo", seed, tmp_path) for seed in (0, 1)]
    assert all(baselines.finished(folder) for folder in folders)
    attempts = [(folder / "attempts.log").read_text().splitlines() for folder in folders]
    assert [len(lines) for lines in attempts] == [1, 1]
    assert len({lines[0].split(" on node ")[1] for lines in attempts}) == 2


def test_unseen_scores_every_finished_seed_on_the_unseen_episodes_and_skips_runs_moved_aside(tmp_path, monkeypatch):
    """`unseen` evaluates the best model of each finished run (a run moved aside is not one) on episodes reset with
    UNSEEN_SEED + i, beside random and the analytic controller on the same episodes; agents.score then gives each
    run a normalized score, 0 for random and 1 for the controller."""
    from agents import score, train

    runs = tmp_path / "runs"
    for seed in (0, 1):
        train.main(baselines.train_argv("connenv/Swing-v0", "ppo", seed, runs, **TINY))
    aside = baselines.run_folder("connenv/Swing-v0", "ppo", 1, runs)
    aside.rename(aside.with_name(aside.name + ".20261125-120000"))
    monkeypatch.setattr(baselines, "EPISODES", 3)
    entry = baselines.unseen_env("connenv/Swing-v0", ["ppo"], runs, pretrained=False)
    assert [(run["algo"], run["seed"], len(run["returns"])) for run in entry["runs"]] == [("ppo", 0, 3)]
    analytic = baselines.evaluate("connenv/Swing-v0", baselines.make_policy("pumping", "connenv/Swing-v0", 0)[1], 3,
                                  baselines.UNSEEN_SEED)  # fmt: skip
    assert entry["analytic"]["returns"] == pytest.approx([episode.ret for episode in analytic], rel=1e-9)
    by_algo = score.env_scores({**entry, "runs": entry["runs"] + [{**entry["analytic"], "algo": "copy", "seed": 0}]})
    assert by_algo["copy"][0]["score"] == 1.0


def test_collect_ships_the_seed_whose_best_model_returns_most_on_the_selection_episodes(tmp_path, monkeypatch):
    """Of two seeds, collect ships the one whose best model returns more on the selection episodes (reset with
    SELECTION_SEED + i, none of the table's or the score's), and records every seed's mean return there."""
    from agents import train

    runs = tmp_path / "runs"
    for seed in (0, 1):
        train.main(baselines.train_argv("connenv/Swing-v0", "ppo", seed, runs, **TINY))
    monkeypatch.setattr(baselines, "EPISODES", 3)
    monkeypatch.setattr(baselines, "PRETRAINED", tmp_path / "pretrained")
    monkeypatch.setattr(baselines, "DOCS", tmp_path / "docs")
    monkeypatch.setattr(baselines, "UNSEEN", tmp_path / "docs" / "unseen.json")
    baselines.collect(["connenv/Swing-v0"], ["ppo"], runs, seeds=(0, 1))
    entry = json.loads((tmp_path / "pretrained" / "runs.json").read_text())["connenv/Swing-v0"]["ppo"]
    returns = {}
    for seed in (0, 1):
        model = baselines.run_folder("connenv/Swing-v0", "ppo", seed, runs) / "best_model.zip"
        policy = baselines.make_policy(str(model), "connenv/Swing-v0", 0, "ppo")[1]
        episodes = baselines.evaluate("connenv/Swing-v0", policy, 3, baselines.SELECTION_SEED)
        returns[seed] = np.mean([episode.ret for episode in episodes])
        assert entry["seeds"][str(seed)]["selection_return"] == pytest.approx(returns[seed], rel=1e-5)
    assert returns[0] != returns[1] and entry["pretrained_seed"] == max(returns, key=returns.get)
