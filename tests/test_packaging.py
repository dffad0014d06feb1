"""What a user installs and how the package is found: the extras ask for one pygame, and a clone named connenv in
the working directory does not hide the installed package."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from importlib.metadata import requires
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def name_and_extras(requirement: str) -> tuple[str, set[str], str]:
    """(normalized name, extras, marker) of a requirement string."""
    requirement, _, marker = requirement.partition(";")
    match = re.match(r"\s*([A-Za-z0-9_.-]+)\s*(?:\[([^\]]*)\])?", requirement)
    extras = {e.strip() for e in (match.group(2) or "").split(",") if e.strip()}
    return re.sub(r"[-_.]+", "-", match.group(1)).lower(), extras, marker


def distributions(extras: set[str]) -> set[str]:
    """The distributions connenv with these extras asks for, following its own extras and gymnasium's (from the
    installed gymnasium's metadata): what pip would install, by name."""
    names, todo, seen = set(), [("connenv", set(extras))], set()
    while todo:
        name, wanted = todo.pop()
        if (name, frozenset(wanted)) in seen:
            continue
        seen.add((name, frozenset(wanted)))
        if name == "connenv":
            lines = PROJECT["dependencies"] + [r for e in wanted for r in PROJECT["optional-dependencies"][e]]
        elif name == "gymnasium":
            lines = [r for r in requires("gymnasium") if "extra ==" not in r or any(f'extra == "{e}"' in r
                                                                                 for e in wanted)]  # fmt: skip
        else:
            names.add(name)
            continue
        for line in lines:
            dependency, more, _ = name_and_extras(line)
            if dependency in ("connenv", "gymnasium"):
                names.add(dependency)
                todo.append((dependency, more))
            else:
                names.add(dependency)
    return names


def test_no_extra_installs_two_pygames():
    """pygame and pygame-ce write the same pygame/ folder (pip check says nothing): every combination of the extras
    asks for one of them (pygame-ce, through gymnasium[classic-control])."""
    for extras in ({"train", "test"}, {"test"}, {"train"}, set(PROJECT["optional-dependencies"])):
        found = distributions(extras) & {"pygame", "pygame-ce"}
        assert len(found) <= 1, f"connenv[{','.join(sorted(extras))}] installs {sorted(found)}"
    assert "pygame-ce" in distributions({"test"}), "the tests render: the test extra needs a pygame"


def test_a_clone_named_connenv_run_from_the_folder_above_gives_the_package(tmp_path):
    """The Quick start run in the folder above a clone named connenv makes an env: the clone's root is the package
    there (its __init__.py loads connenv/connenv), not an empty namespace package."""
    (tmp_path / "connenv").symlink_to(ROOT, target_is_directory=True)
    quick_start = (
        "import gymnasium as gym\n"
        "import connenv, connenv.envs.swing\n"
        "env = gym.make('connenv/Swing-v0')\n"
        "env.reset(seed=0)\n"
        "print(sorted(connenv.__all__), connenv.__version__, connenv.envs.swing.__file__)\n"
    )
    done = subprocess.run([sys.executable, "-c", quick_start], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-1] == str(tmp_path / "connenv" / "connenv" / "envs" / "swing.py"), done.stdout
