"""The guides' code as a reader runs it: every Python block of docs/guides/model.md and jax.md on its own, in a fresh
interpreter, as written (no block leans on another's imports); every command is one its command line accepts, and
runs where it is short."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guides" / "model.md"
BLOCKS = re.findall(r"^```(python|bash)\n(.*?)^```", GUIDE.read_text(), flags=re.S | re.M)
JAX_GUIDE = ROOT / "docs" / "guides" / "jax.md"  # its blocks need the jax extra
JAX_BLOCKS = re.findall(r"^```python\n(.*?)^```", JAX_GUIDE.read_text(), flags=re.S | re.M)
PYTHON = [code for language, code in BLOCKS if language == "python"]
COMMANDS = [line for language, code in BLOCKS if language == "bash" for line in code.splitlines() if line.strip()]
HERE = {**os.environ, "PYTHONPATH": str(ROOT)}  # this checkout's packages, wherever the working directory is
LONG = {  # commands that train or evaluate for minutes: their arguments are checked, they are not run here
    "train.py": "trains 150 000 PPO steps",
    "agents.evaluate": "plans 30 episodes",
}


@pytest.mark.parametrize("code", PYTHON, ids=[f"python-{i}" for i in range(len(PYTHON))])
def test_each_python_block_runs_on_its_own(code, tmp_path, env=HERE):
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env=env)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.parametrize("code", JAX_BLOCKS, ids=[f"jax-python-{i}" for i in range(len(JAX_BLOCKS))])
def test_each_python_block_of_the_jax_guide_runs_on_its_own(code, tmp_path):
    """As tests/test_jax.py: XLA without LLVM's optimization passes, which compiles several times faster."""
    pytest.importorskip("jax")
    flags = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()
    test_each_python_block_runs_on_its_own(code, tmp_path, {**HERE, "XLA_FLAGS": flags})


@pytest.mark.parametrize("command", COMMANDS, ids=[f"bash-{i}" for i in range(len(COMMANDS))])
def test_each_command_is_accepted_and_the_short_ones_run(command, tmp_path):
    argv = shlex.split(command)
    assert argv[0] == "python"
    if argv[1] == "-m":
        module, args = argv[2], argv[3:]
        main = __import__(module, fromlist=["main"])
    else:
        module, args = argv[1], argv[2:]
        from agents import train as main
    long = next((why for key, why in LONG.items() if key == module), None)
    if long:
        parsed = main.parse_args(args)  # exits 2 on an argument it does not take
        if module == "train.py":  # a run folder of its own: an earlier run of the env and algorithm is not refused
            assert parsed.runs != main.parse_args([]).runs, command
        pytest.skip(f"{command}: {long}; arguments checked")
    done = subprocess.run([sys.executable, *argv[1:]], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env=HERE)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
