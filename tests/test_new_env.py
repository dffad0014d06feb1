"""docs/guides/new-env.md followed once: an env declared in its own module, with its spec and nothing else, registers,
passes Gymnasium's checker, and appears in every table read off the specs (baselines, controllers, docs site, test
tables). The env is a throwaway written into a temporary package, in a fresh interpreter, so that the registry of
the other tests never sees it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SYSTEM = '''
"""A point on a line whose velocity is assigned: ẋ = u, exact over a step."""


def flow(x, u, dt):
    return x + u * dt
'''

ENV = '''
"""Point-v0: drive a point to x = 1 by its velocity."""

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from connenv.core.backend import BATCH, SCALAR
from connenv.core.params import Args, step
from connenv.core.state import Fields, Options, number
from connenv.envs.base import State, TaskEnv
from connenv.envs.spec import Measure, Spec
from throwaway.point_rendering import PointRenderer
from throwaway.point_system import flow

DT_MAX = 1.0


@dataclass
class PointState(State):
    x: float
    target: float
    t: float


class PointEnv(TaskEnv):
    """## Description

    A point on a line, its velocity assigned, to bring to a target.

    ## Starting State

    x uniform in [−1, 0], the target x* = 1, t = 0. `reset(options={"state": {...}, "target": x*})` sets either:

    ## Arguments
    """

    renderer = PointRenderer
    ARGS = Args(step(0.1, DT_MAX))
    STATE = Fields(number("x", "m", bound=10.0))
    OPTIONS = Options(number("target", "m", "x*", bound=5.0))

    def __init__(self, render_mode=None, **kwargs):
        a, _ = self.check_args(kwargs)
        super().__init__(render_mode, a.dt)
        self.stepper = None  # the flow is exact
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.state = PointState(0.0, 1.0, 0.0)

    def start(self, options):
        values = self.reset_values(options, {"x": self.np_random.uniform(-1.0, 0.0), "target": 1.0})
        return PointState(values["x"], values["target"], 0.0)

    def command(self, a):
        return (SCALAR if a.ndim == 1 else BATCH).components(a)[0]

    def advance(self, s, u, stepper, ops=SCALAR):
        return PointState(ops.clip(flow(s.x, u, self.dt), -10.0, 10.0), s.target, s.t + self.dt)

    def observe(self, s, ops=SCALAR):
        return ops.pack([ops.clip((s.target - s.x) / 10.0, -1.0, 1.0)])

    def describe(self, s, ops=SCALAR):
        return {"state": {"x": s.x, "t": s.t}, "target": s.target, "is_success": ops.flag(abs(s.target - s.x) < 0.05)}

    def reward(self, before, after, info, ops=SCALAR):
        return abs(before.target - before.x) - abs(after.target - after.x)


SPECS = (
    Spec(
        "throwaway/Point-v0", PointEnv, max_episode_steps=50, dt_max=DT_MAX, physics="point.md",
        measure=Measure("time to target", "s", "time_to_success"), controllers=("toward",),
        golden=(("point", {"max_episode_steps": 20}, None),),
    ),
)
'''

RENDERER = '''
"""pygame drawing of the point."""

from connenv.rendering import Canvas, Renderer


class PointRenderer(Renderer):
    def __init__(self, env):
        self.canvas = Canvas(env, 2.0)

    def draw(self, env):
        c = self.canvas
        c.screen.fill((255, 255, 255))
        c.pygame.draw.circle(c.screen, (40, 40, 40), c.px(env.state.x, 0.0), 8)
        return c.show()
'''

CONTROLLER = '''
"""Reference controller of the point: full speed toward x = 1."""

import numpy as np


class Toward:
    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return np.sign(np.asarray(obs, np.float32)), state


def toward(env):
    return Toward()
'''

CHECK = """
import importlib.util, json, sys
import gymnasium as gym
from gymnasium.utils.env_checker import check_env

import connenv
from connenv.envs.spec import discover, register, registry


def load(name, path):
    module = importlib.util.module_from_spec(importlib.util.spec_from_file_location(name, path))
    sys.modules[name] = module
    module.__spec__.loader.exec_module(module)
    return module


register(*discover("throwaway"))  # a package of its own registers its specs (connenv.envs: from its table)
load("agents.controllers.point", CONTROLLER)  # where agents/controllers/point.py would be found
sys.path.insert(0, "tests")
import agents.controllers, audit, test_contract, test_fuzz, test_hardening
from golden import record
from agents import baselines
docs_site = load("docs_site", "docs/site.py")

ID = "throwaway/Point-v0"
env = gym.make(ID)
check_env(env.unwrapped)
vector = gym.make_vec(ID, 3, vectorization_mode="vector_entry_point")
vector.reset(seed=0)
vector.step(vector.action_space.sample())
model = env.unwrapped.model  # the model comes with the task: no code of its own
model_env = gym.make(ID).unwrapped
model_env.reset(seed=1)
x = model.pack(model_env.state)
model_env.step([0.5])
A, B = model.jacobians(x, [0.5])
law = agents.controllers.controller(ID, env=env)
obs, _ = env.reset(seed=0)
for _ in range(50):
    obs, reward, terminated, truncated, info = env.step(law.predict(obs)[0])
    if terminated:
        break
print(json.dumps({
    "registered": ID in gym.registry and ID in registry,
    "solved": bool(info["is_success"]),
    "baselines": ID in baselines.ENVS and baselines.MEASURES[ID][:2] == ("time to target", "s"),
    "controllers": agents.controllers.controller_names(ID),
    "contract": [case.env_id for case in test_contract.CASES].count(ID),
    "golden": [case[0] for case in record.CASES if case[1] == ID],
    "audit": [audit.STATE_KEYS[ID], audit.OPTION_KEYS[ID]],
    "fuzz, hardening": [ID in test_fuzz.IDS, ID in test_hardening.IDS],
    "dt_max": registry[ID].dt_max,
    "docs_page": docs_site.page(ID).splitlines()[0],
    "tables": [line for line in docs_site.page(ID).splitlines() if line.startswith(("| dt ", "| `x` ", "| `target` "))],
    "model": bool((model.step(x, [0.5]) == model.pack(model_env.state)).all()) and B[model.state_names.index("x"), 0],
}))
"""


def test_an_env_declared_in_its_own_files_is_registered_checked_and_tabled(tmp_path):
    """The throwaway Point-v0: its system, env module (with its ARGS, STATE, OPTIONS and SPECS), renderer and
    controller module are all it takes; the declarations write its page's tables and the audit's."""
    package = tmp_path / "throwaway"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "point_system.py").write_text(textwrap.dedent(SYSTEM))
    (package / "point.py").write_text(textwrap.dedent(ENV))
    (package / "point_rendering.py").write_text(textwrap.dedent(RENDERER))
    (tmp_path / "point_controller.py").write_text(textwrap.dedent(CONTROLLER))
    code = f"CONTROLLER = {str(tmp_path / 'point_controller.py')!r}\n" + CHECK
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(tmp_path)]), "SDL_VIDEODRIVER": "dummy"}
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=environment, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-3000:]
    found = json.loads(result.stdout.strip().splitlines()[-1])
    assert found == {
        "registered": True,
        "solved": True,
        "baselines": True,
        "controllers": ["analytic", "toward"],
        "contract": 1,
        "golden": ["point"],
        "audit": [{"x": 0}, {"target": 0}],
        "fuzz, hardening": [True, True],
        "dt_max": 1.0,
        "docs_page": "# Point-v0",
        "tables": ["| `x` | number | m | ±10 |", "| `target` | number | m | ±5; x* |", "| dt | 0.1 | [1e-12, 1] s |"],
        "model": 0.1,  # ∂x′/∂a = dt · speed: the step is the env's, and its Jacobian the exact flow's
    }
