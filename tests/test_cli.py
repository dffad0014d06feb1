"""Every command line answers bad input in one line (issue 30, item 4): exit status 2, one line on stderr naming the
argument (and the value), no traceback, in seconds, before any work. A table of bad arguments over train.py,
agents.evaluate, agents.tune, agents.baselines, connenv.throughput, connenv.play and connenv.bench, each run in
process through its main and connenv.cli.run, the path `python -m` takes; a few run as real processes."""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from agents import baselines, evaluate, imitate, randomized, tune
from connenv import bench, cli, play, throughput

ROOT = Path(__file__).resolve().parents[1]
SWING, ACTIVE = "connenv/Swing-v0", "connenv/ActiveConstraint-v0"
RANDOMIZED = ["--env", SWING, "--runs", "."]  # a later --runs replaces it
TUNE = ["--env", SWING, "--algo", "sac", "--samples", "1", "--timesteps", "10"]
FACTORIES = """
import sympy as sp

theta, theta_dot, u, u_dot = sp.symbols("theta theta_dot u u_dot")


def system():
    from connenv.core.lagrangian import LagrangianSystem

    return LagrangianSystem(theta_dot**2 + (theta_dot + u_dot) ** 2 / 4, 0, [theta], [u])


def bad_dt():
    return {"system": system(), "u_low": -3.0, "u_high": 3.0, "dt": -1}


def raises():
    raise RuntimeError("the factory fails")


not_callable = 3
"""

# (program, argv, words the one line holds: the argument and what is wrong)
CASES = [
    ("imitate", [], ["--env ID", "--diagnose"]),
    ("imitate", ["--env", "connenv/Nope-v0"], ["--env", "'connenv/Nope-v0'"]),
    ("imitate", ["--env", "connenv/BeadOnBar-v0", "--episodes", "0"], ["--episodes", "'0'"]),
    ("imitate", ["--env", "connenv/BeadOnBar-v0", "--dagger", "-1"], ["--dagger", "'-1'"]),
    ("imitate", ["--env", "connenv/BeadOnBar-v0", "--seed", "-1"], ["--seed", "'-1'"]),
    ("imitate", ["--env", "connenv/BeadOnBar-v0", "--out", "a_file/clones"], ["--out", "'a_file' is a file"]),
    ("imitate", ["--diagnose", "--jobs", "0"], ["--jobs", "'0'"]),
    ("train", ["--env-kwargs", '{"dt": -1}'], ["--env-kwargs", "dt=-1"]),
    ("train", ["--env-kwargs", '{"bogus": 1}'], ["--env-kwargs", "bogus"]),
    ("train", ["--env-kwargs", "{bad json"], ["--env-kwargs", "not a JSON object"]),
    ("train", ["--env-kwargs", "[1, 2]"], ["--env-kwargs", "module:factory"]),
    ("train", ["--env-kwargs", "nosuchmodule:f"], ["--env-kwargs", "No module named 'nosuchmodule'"]),
    ("train", ["--env-kwargs", "nocolon"], ["--env-kwargs", "'nocolon'"]),
    ("train", ["--env-kwargs", "cli_factories:missing"], ["--env-kwargs", "'missing'"]),
    ("train", ["--env-kwargs", "cli_factories:not_callable"], ["--env-kwargs", "not callable"]),
    ("train", ["--env-kwargs", "cli_factories:raises"], ["--env-kwargs", "the factory fails"]),
    ("train", ["--env", ACTIVE, "--env-kwargs", "cli_factories:bad_dt"], ["--env-kwargs", "dt=-1"]),
    ("train", ["--env", ACTIVE, "--env-kwargs", "cli_factories:system"], ["--env-kwargs", "u_low"]),
    ("train", ["--env", ACTIVE], ["--env-kwargs", "system=None"]),
    ("train", ["--hyperparams", "corrupt.yml"], ["--hyperparams", "'corrupt.yml'", "not YAML"]),
    ("train", ["--hyperparams", "empty.yml"], ["--hyperparams", "no hyperparameters for connenv/Swing-v0"]),
    ("train", ["--hyperparams", "other.yml"], ["--hyperparams", "no hyperparameters for connenv/Swing-v0"]),
    ("train", ["--hyperparams", "nosuch.yml"], ["--hyperparams", "no such file"]),
    ("train", ["--env", "connenv/Connection-v0"], ["--hyperparams", "no hyperparameters for connenv/Connection-v0"]),
    ("train", ["--runs", "a_file/runs"], ["--runs", "'a_file' is a file"]),
    ("train", ["--timesteps", "abc"], ["--timesteps", "'abc'"]),
    ("train", ["--timesteps", "-5"], ["--timesteps", "'-5'"]),
    ("train", ["--num-threads", "0"], ["--num-threads", "'0'"]),
    ("train", ["--eval-episodes", "-1"], ["--eval-episodes", "'-1'"]),
    ("train", ["--seed", "-1"], ["--seed", "'-1'"]),
    ("train", ["--seed", "4294967296"], ["--seed", "'4294967296'"]),
    ("train", ["--eval-seed", "abc"], ["--eval-seed", "'abc'"]),
    ("train", ["--eval-freq", "abc"], ["--eval-freq", "'abc'"]),
    ("train", ["--checkpoint-freq", "1.5"], ["--checkpoint-freq", "'1.5'"]),
    ("train", ["--env", "Nope-v0"], ["--env", "'Nope-v0'"]),
    ("train", ["--algo", "bogus"], ["--algo", "'bogus'"]),
    ("train", ["extra"], ["unrecognized arguments: extra"]),
    ("evaluate", ["--policy", "empty.zip"], ["--policy", "'empty.zip' is not a zip file"]),
    ("evaluate", ["--policy", "text.zip"], ["--policy", "'text.zip' is not a zip file"]),
    ("evaluate", ["--policy", "truncated.zip"], ["--policy", "'truncated.zip'"]),
    ("evaluate", ["--policy", "foreign.zip", "--algo", "ppo"], ["--policy", "'foreign.zip'", "no SB3 model"]),
    ("evaluate", ["--policy", "nosuch.zip"], ["--policy", "'nosuch.zip'"]),
    ("evaluate", ["--policy", "model.zip", "--algo", "sac"], ["model.zip", "SAC", "--algo"]),
    ("evaluate", ["--policy", "arc"], ["--policy", "'arc' is no controller of connenv/Swing-v0"]),
    ("evaluate", ["--env", ACTIVE, "--policy", "pretrained"], ["--policy", "'pretrained'", "ActiveConstraint-v0"]),
    ("evaluate", ["--video", "x.mp4"], ["--video", "'x.mp4'", ".gif"]),
    ("evaluate", ["--video", "a_file/x.gif"], ["--video", "'a_file' is a file"]),
    ("evaluate", ["--json", "a_file/e.json"], ["--json", "'a_file' is a file"]),
    ("evaluate", ["--json", "."], ["--json", "'.' is a directory"]),
    ("evaluate", ["--algo", "bogus"], ["--algo", "'bogus'"]),
    ("evaluate", ["--env-kwargs", '{"dt": -1}'], ["--env-kwargs", "dt=-1"]),
    ("evaluate", ["--env-kwargs", "nosuchmodule:f"], ["--env-kwargs", "nosuchmodule"]),
    ("evaluate", ["--env-kwargs", '{"dt": "fast"}'], ["--env-kwargs", "dt='fast'"]),
    ("evaluate", ["--episodes", "abc"], ["--episodes", "'abc'"]),
    ("evaluate", ["--episodes", "0"], ["--episodes", "'0'"]),
    ("evaluate", ["--seed", "-1"], ["--seed", "'-1'"]),
    ("evaluate", ["--env", "bogus"], ["--env", "'bogus'"]),
    ("throughput", ["--sizes", "0"], ["--sizes", "'0'"]),
    ("throughput", ["--sizes", "-1"], ["--sizes", "'-1'"]),
    ("throughput", ["--sizes", "abc"], ["--sizes", "'abc'"]),
    ("throughput", ["--single-steps", "-5"], ["--single-steps", "'-5'"]),
    ("throughput", ["--single-steps", "0"], ["--single-steps", "'0'"]),
    ("throughput", ["--seconds", "-1"], ["--seconds", "'-1'"]),
    ("throughput", ["--seconds", "0"], ["--seconds", "'0'"]),
    ("throughput", ["--seconds", "nan"], ["--seconds", "'nan'"]),
    ("throughput", ["--seconds", "inf"], ["--seconds", "'inf'"]),
    ("throughput", ["--sync-max", "-1"], ["--sync-max", "'-1'"]),
    ("throughput", ["--envs", "bogus"], ["--envs", "'bogus'"]),
    ("throughput", ["--write", "a_file/t.md"], ["--write", "'a_file' is a file"]),
    ("throughput", ["--shell-steppers", "bogus"], ["--shell-steppers", "'bogus'"]),
    ("throughput", ["--shell-steppers", "magnus:abc"], ["--shell-steppers", "'magnus:abc'"]),
    ("throughput", ["--shell-steppers", "magnus:-1"], ["--shell-steppers", "'magnus:-1'"]),
    ("tune", [*TUNE, "--seed", "-1"], ["--seed", "'-1'"]),
    ("tune", [*TUNE, "--samples", "0"], ["--samples", "'0'"]),
    ("tune", [*TUNE, "--evaluations", "0"], ["--evaluations", "'0'"]),
    ("tune", [*TUNE, "--timesteps", "0"], ["--timesteps", "'0'"]),
    ("tune", [*TUNE, "--algo", "td3"], ["--algo", "'td3'"]),
    ("tune", [*TUNE, "--env", "connenv/Connection-v0"], ["--env", "'connenv/Connection-v0'"]),
    ("tune", [*TUNE, "--jobs", "0"], ["--jobs", "'0'"]),
    ("tune", [*TUNE, "--runs", "a_file/r"], ["--runs", "'a_file' is a file"]),
    ("tune", [*TUNE, "--address", "127.0.0.1:1"], ["--address", "127.0.0.1:1"]),
    ("tune", [*TUNE, "--address", "nonsense"], ["--address", "'nonsense'"]),
    ("tune", [], ["required", "--env"]),
    ("baselines", ["train", "--seeds", "-1"], ["--seeds", "'-1'"]),
    ("baselines", ["train", "--seeds", "abc"], ["--seeds", "'abc'"]),
    ("baselines", ["train", "--jobs", "0"], ["--jobs", "'0'"]),
    ("baselines", ["train", "--timesteps", "0"], ["--timesteps", "'0'"]),
    ("baselines", ["train", "--algo", "td3"], ["--algo", "'td3'"]),
    ("baselines", ["train", "--env", SWING, "--algo", "ppo", "--address", "127.0.0.1:1"], ["--address", "127.0.0.1:1"]),
    ("baselines", ["train", "--address", "host:99999"], ["--address", "'host:99999'"]),
    ("baselines", ["train", "--runs", "a_file/r"], ["--runs", "'a_file' is a file"]),
    ("baselines", ["collect", "--env", SWING, "--algo", "ppo", "--runs", "empty_runs"], ["empty_runs/Swing-v0_ppo_s0"]),
    ("baselines", ["table", "--env", "bogus"], ["--env", "'bogus'"]),
    ("baselines", ["bogus"], ["command", "'bogus'"]),
    ("play", [SWING, "--seed", "-1"], ["--seed", "'-1'"]),
    ("play", [SWING, "--scale", "-1"], ["--scale", "'-1'"]),
    ("play", [SWING, "--scale", "0"], ["--scale", "'0'"]),
    ("play", [SWING, "--scale", "nan"], ["--scale", "'nan'"]),
    ("play", [SWING, "--frames", "-1"], ["--frames", "'-1'"]),
    ("play", [SWING, "--frames", "0"], ["--frames", "'0'"]),
    ("play", [SWING, "--frames", "abc"], ["--frames", "'abc'"]),
    ("play", [SWING, "--screenshot", "a_file/s.png"], ["--screenshot", "'a_file' is a file"]),
    ("play", ["bogus/Env-v0"], ["ENV_ID", "'bogus/Env-v0'"]),
    ("play", [SWING, "--kwargs", "dt=-1"], ["--kwargs dt=-1", "dt=-1.0 is out of range"]),
    ("play", [SWING, "--kwargs", "nokey"], ["--kwargs", "'nokey'"]),
    ("play", [SWING, "--kwargs", "bogus=1"], ["--kwargs bogus=1", "'bogus'"]),
    ("randomized", [*RANDOMIZED, "--randomize", "[1, 2]"], ["--randomize", "'[1, 2]'", "{name: [low, high]}"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"g": "79"}'], ["--randomize", "'{\"g\": \"79\"}'"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"bogus": [1, 2]}'], ["--randomize", "'bogus'"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"g": [12, 7]}'], ["--randomize", "low must be at most high"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"g": [7, 12]}', "--runs", "a_file"], ["--runs", "'a_file'"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"g": [7, 12]}', "--runs", "empty_runs"], ["--runs", "Swing-v0_ppo_s"]),
    ("randomized", [*RANDOMIZED, "--randomize", '{"g": [7, 12]}', "--runs", "no_model"], ["--runs", "best_model.zip"]),
    ("bench", ["nosuch"], ["'nosuch'"]),
    ("bench", ["precision", "--env", "nope"], ["--env", "'nope'"]),
    ("bench", ["stability", "--env", "nope"], ["--env", "'nope'"]),
    ("bench", ["steppers", "--env", "nope"], ["--env", "'nope'"]),
    ("bench", ["steppers", "--integrators", "nope"], ["--integrators", "'nope'"]),
    ("bench", ["precision", "--bogus"], ["--bogus"]),
    ("bench", ["generic", "--bogus"], ["--bogus"]),
    ("bench", ["page", "--bogus"], ["--bogus"]),
    ("bench", ["all", "--env", "connection"], ["--env", "'connection'"]),  # precision has it, stability not
]


@pytest.fixture(scope="session")
def work(tmp_path_factory):
    """A folder of bad inputs: YAML and model files that are broken, a file where a folder belongs, factories."""
    folder = tmp_path_factory.mktemp("cli")
    (folder / "corrupt.yml").write_text("connenv/Swing-v0: [unclosed\n  : :\n")
    (folder / "empty.yml").write_text("")
    (folder / "other.yml").write_text("connenv/Skier-v0:\n  n_timesteps: 10\n")
    (folder / "empty.zip").write_bytes(b"")
    (folder / "text.zip").write_text("hello")
    model = ROOT / "agents" / "pretrained" / "Swing-v0_ppo" / "best_model.zip"
    shutil.copy(model, folder / "model.zip")
    (folder / "truncated.zip").write_bytes(model.read_bytes()[: model.stat().st_size // 2])
    with zipfile.ZipFile(folder / "foreign.zip", "w") as archive:
        archive.writestr("a.txt", "hello")
    (folder / "a_file").write_text("")
    (folder / "empty_runs").mkdir()
    (folder / "no_model" / "Swing-v0_ppo_s0").mkdir(parents=True)
    (folder / "cli_factories.py").write_text(FACTORIES)
    return folder


@pytest.fixture
def mains(train):
    return {
        "train": (train.main, train.PROG),
        "evaluate": (evaluate.main, evaluate.PROG),
        "tune": (tune.main, tune.PROG),
        "baselines": (baselines.main, baselines.PROG),
        "throughput": (throughput.main, throughput.PROG),
        "play": (play.main, play.PROG),
        "bench": (bench.main, bench.PROG),
        "imitate": (imitate.main, imitate.PROG),
        "randomized": (randomized.main, randomized.PROG),
    }


def one_line_error(err: str, prog: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(prog) and ": error: " in lines[0] and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize(("program", "argv", "named"), CASES, ids=[f"{p} {' '.join(a)}" for p, a, _ in CASES])
def test_bad_input_ends_a_command_in_one_line_naming_it(program, argv, named, mains, work, monkeypatch, capsys):
    main, prog = mains[program]
    monkeypatch.chdir(work)
    monkeypatch.setattr(randomized, "success", lambda *args: pytest.fail("an evaluation ran before the check"))
    start = time.perf_counter()
    with pytest.raises(SystemExit) as exit_:
        cli.run(main, prog, argv)
    assert exit_.value.code == 2
    assert time.perf_counter() - start < 30  # before any work: no training, no benchmark, no wait on an address
    line = one_line_error(capsys.readouterr().err, prog)
    for word in named:
        assert word in line


def test_a_factory_in_the_working_directory_may_return_the_system_and_json_gives_the_bounds(work, monkeypatch):
    """module:factory is imported from the working directory (as `python train.py` from elsewhere needs), and a
    later JSON object completes the system a factory returns alone."""
    monkeypatch.chdir(work)
    monkeypatch.delitem(sys.modules, "cli_factories", raising=False)
    monkeypatch.setattr(sys, "path", [path for path in sys.path if path not in ("", ".", str(work))])
    kwargs = evaluate.make_kwargs(ACTIVE, ["cli_factories:system", '{"u_low": -3, "u_high": 3, "dt": 0.1}'])
    assert set(kwargs) == {"system", "u_low", "u_high", "dt"} and kwargs["system"].n == 1
    assert str(work) not in sys.path  # the working directory is on the path only while the module is imported


def test_json_env_kwargs_reach_the_evaluated_env(tmp_path, capsys):
    """--env-kwargs '{"dt": 0.1}': the episodes' simulated time is length × 0.1 s (Swing-v0's default dt is 0.05)."""
    argv = ["--policy", "random", "--episodes", "1", "--json", str(tmp_path / "e.json"), "--env-kwargs"]
    report = evaluate.main([*argv, '{"dt": 0.1, "max_episode_steps": 7}'])
    (episode,) = report["policies"][0]["episodes"]
    assert episode["length"] == 7 and episode["time"] == pytest.approx(0.7)


def test_collect_reads_the_runs_folder_it_is_given(tmp_path, monkeypatch):
    """collect --runs DIR looks for its run folders in DIR, not in runs/baselines/."""
    monkeypatch.setattr(baselines, "RUNS", tmp_path / "default")
    with pytest.raises(FileNotFoundError, match=re.escape(str(tmp_path / "given" / "Swing-v0_ppo_s3"))):
        baselines.main(["collect", "--env", SWING, "--algo", "ppo", "--runs", str(tmp_path / "given"), "--seeds", "3"])


def test_the_ray_address_is_probed_before_ray_waits_on_it():
    """An address where nothing listens fails at once naming it; one that is no HOST:PORT is refused as such."""
    from agents import cluster

    start = time.perf_counter()
    with pytest.raises(ConnectionError, match="--address 127.0.0.1:1: nothing answers there"):
        cluster.connect("127.0.0.1:1")
    assert time.perf_counter() - start < 30
    for bad in ("nonsense", "host:0", "host:65536", ":6379", "host:port"):
        with pytest.raises(ValueError, match="is not a Ray address"):
            cluster.host_port(bad)
    assert cluster.host_port("ray://10.0.0.1:10001") == ("10.0.0.1", 10001)
    assert cluster.host_port("[::1]:6379") == ("::1", 6379) and cluster.host_port("auto") is None


def test_as_processes_the_commands_answer_in_one_line_and_do_not_hang(work):
    """`python train.py` (its factory in the working directory, which it did not import from), `python -m
    agents.baselines train --address` (which waited > 90 s on ray.init) and `python -m connenv.play` on a machine
    without the display it needs: run at once, each within 30 s, exit status 2, one line."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "nosuch"}  # no such display driver
    commands = {
        "train.py": [str(ROOT / "train.py"), "--env", ACTIVE, "--env-kwargs", "cli_factories:bad_dt"],
        "python -m agents.baselines": ["-m", "agents.baselines", "train", "--env", SWING, "--address", "127.0.0.1:1"],
        "python -m connenv.play": ["-m", "connenv.play", SWING, "--frames", "1"],
    }
    processes = {
        prog: subprocess.Popen([sys.executable, *argv], cwd=work, env=environment, stderr=subprocess.PIPE, text=True)
        for prog, argv in commands.items()
    }
    for prog, process in processes.items():
        try:
            _, err = process.communicate(timeout=30)
        finally:
            process.kill()
        assert process.returncode == 2, err
        line = one_line_error(err, prog)
        assert {"train.py": "dt=-1", "python -m agents.baselines": "127.0.0.1:1"}.get(prog, "no display") in line


def test_the_helper_reports_only_errors_of_input(capsys):
    """A ValueError becomes the one line; any other exception (a bug) keeps its traceback."""

    def bad_input(argv):
        raise ValueError("--x 3: must be\nbelow 2")

    def bug(argv):
        raise KeyError("state")

    with pytest.raises(SystemExit) as exit_:
        cli.run(bad_input, "prog", [])
    assert exit_.value.code == 2 and capsys.readouterr().err == "prog: error: --x 3: must be below 2\n"
    with pytest.raises(KeyError):
        cli.run(bug, "prog", [])
    assert json.dumps(cli.run(lambda argv: {"argv": argv}, "prog", ["a"])) == '{"argv": ["a"]}'


def test_an_existing_page_is_overwritten_when_its_command_regenerates_it(tmp_path):
    page = tmp_path / "throughput.md"
    page.write_text("the last run's tables")
    assert cli.writable_file(str(page)) == str(page)
    assert cli.writable_dir(str(tmp_path)) == str(tmp_path)
    with pytest.raises(argparse.ArgumentTypeError, match="is a file"):
        cli.writable_dir(str(page))
    with pytest.raises(argparse.ArgumentTypeError, match="is a directory"):
        cli.writable_file(str(tmp_path))


UNSEEN_RUN = {"algo": "ppo", "seed": 0, "returns": [1.0], "successes": [True]}
UNSEEN_ENTRY = {"random": {"returns": [0.0], "successes": [False]},
                "analytic": {"name": "arc", "returns": [2.0], "successes": [True]}, "runs": [UNSEEN_RUN]}  # fmt: skip
BROKEN_UNSEEN = [
    ({"first_seed": 1}, "no key 'envs'"),
    ({"envs": {SWING: UNSEEN_ENTRY}}, "no key 'first_seed'"),
    ({"first_seed": 1, "envs": {}}, "'envs' holds no env"),
    ({"first_seed": 1, "envs": {SWING: {"analytic": UNSEEN_ENTRY["analytic"]}}}, f"no key envs['{SWING}']['random']"),
    ({"first_seed": 1, "envs": {SWING: {**UNSEEN_ENTRY, "random": {"returns": []}}}}, "['random']['successes']"),
    ({"first_seed": 1, "envs": {SWING: {**UNSEEN_ENTRY, "runs": [{"algo": "ppo"}]}}}, "['runs'][0]['seed']"),
    ("{not json", "not JSON"),
]


@pytest.mark.parametrize(("data", "named"), BROKEN_UNSEEN, ids=[named for _, named in BROKEN_UNSEEN])
def test_score_names_the_file_and_the_key_it_misses(data, named, tmp_path, monkeypatch, capsys):
    """`python -m agents.baselines score` on a results file without a key it reads: one line naming the file and
    the key (it ended in KeyError 'envs', StopIteration or KeyError 'random')."""
    path = tmp_path / "unseen.json"
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    monkeypatch.setattr(baselines, "UNSEEN", path)
    monkeypatch.setattr(baselines, "DOCS", tmp_path)
    with pytest.raises(SystemExit) as exit_:
        cli.run(baselines.main, baselines.PROG, ["score"])
    line = one_line_error(capsys.readouterr().err, baselines.PROG)
    assert exit_.value.code == 2 and str(path) in line and named in line
    assert not (tmp_path / "score.md").exists()


def test_an_old_version_is_made_without_gymnasiums_notice(work):
    """On BeadOnBar-v0 (v1 exists) the commands printed Gymnasium's DeprecationWarning, two lines each time the env
    was made, above their one-line error: the project keeps old versions on purpose."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    commands = {
        "python -m connenv.geometry": ["-m", "connenv.geometry", "connenv/BeadOnBar-v0"],
        "python -m agents.identify": ["-m", "agents.identify", "--env", "connenv/BeadOnBar-v0", "--true", "bogus=1"],
    }
    processes = {
        prog: subprocess.Popen([sys.executable, *argv], cwd=work, env=environment, stderr=subprocess.PIPE, text=True)
        for prog, argv in commands.items()
    }
    for prog, process in processes.items():
        try:
            _, err = process.communicate(timeout=60)
        finally:
            process.kill()
        assert process.returncode == 2 and "DeprecationWarning" not in err, err
        one_line_error(err, prog)


def test_an_evaluation_shows_its_progress_on_stderr(tmp_path, capsys):
    """`--policy analytic mpc ilqr --episodes 10` on ChaplyginSleigh-v0 ran 429 s without a line: each policy's
    episodes are counted on stderr (done of total, elapsed < left), the table alone on stdout."""
    evaluate.main(["--policy", "random", "--episodes", "3", "--json", str(tmp_path / "e.json")])
    out, err = capsys.readouterr()
    assert "random: " in err and "/3 [" in err and "episodes" in err and "<" in err
    assert "/3 [" not in out
