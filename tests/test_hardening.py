"""Bad input at every boundary (issue 16): reset states and make kwargs out of range, actions that are no real
array, clones of a rendered env, negative seeds on the command lines, the benchmark's help, the goal env under
SB3's checker and HER, and the test extra."""

from __future__ import annotations

import ast
import copy
import importlib.metadata
import math
import pickle
import re
import sys
import time
import warnings
from pathlib import Path
from typing import NamedTuple

import gymnasium as gym
import numpy as np
import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

import connenv  # noqa: F401  (registers the envs)
from audit import RANDOMIZED
from connenv.core import StepperError
from connenv.core.validation import DT_MIN
from connenv.envs.spec import registry, spec

ROOT = Path(__file__).resolve().parents[1]
IDS = sorted(registry)  # every id with a spec


def make(env_id, **extra):
    kwargs = spec(env_id).make_kwargs()
    return gym.make(env_id, **{**kwargs, **extra})


# -- item 2: a rendered env pickles and deep-copies ------------------------------------------------------------


CLONES = {"deepcopy": copy.deepcopy, "pickle": lambda env: pickle.loads(pickle.dumps(env))}


@pytest.mark.parametrize("clone", CLONES.values(), ids=CLONES.keys())
def test_a_rendered_env_clones_without_its_renderer_and_the_clone_renders_anew(clone):
    env = gym.make("connenv/Swing-v0", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    twin = clone(env)
    assert twin.unwrapped._renderer is None and env.unwrapped._renderer is not None
    assert np.array_equal(twin.render(), frame)
    env.close()
    twin.close()


# -- item 5: messages that name the thing ----------------------------------------------------------------------


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("bad", [5, "x", [1.0]], ids=["int", "str", "list"])
def test_a_reset_state_that_is_no_mapping_is_refused_naming_it(env_id, bad):
    env = make(env_id)
    with pytest.raises(ValueError, match=r"options\['state'\]=.* must be a mapping"):
        env.reset(options={"state": bad})
    with pytest.raises(ValueError, match=r"reset options=.* must be a mapping"):
        env.reset(options=bad)


@pytest.mark.parametrize("env_id", IDS)
def test_string_and_complex_actions_are_refused_naming_the_action(env_id):
    env = make(env_id)
    env.reset(seed=0)
    size = env.action_space.shape[0]
    with pytest.raises(ValueError, match=r"action=.*'a'.* must be real numbers"):
        env.step(["a"] * size)
    with pytest.raises(ValueError, match=r"action=.*j\]\) is complex"):
        env.step(np.full(size, 0.5 + 1j))
    vector = gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point", **make(env_id).spec.kwargs)
    vector.reset(seed=0)
    with pytest.raises(ValueError, match="is complex"):
        vector.step(np.full((2, size), 0.5 + 1j))


@pytest.mark.parametrize(
    ("env_id", "names"),
    [
        ("connenv/RollingBallPose-v0", ["position_tolerance", "radius", "v_max", "dt", "tolerance", "integrator"]),
        ("connenv/KapitzaSwingUp-v0", ["hold_time", "pivot", "v_max", "a_max", "dt", "tolerance", "integrator"]),
        ("connenv/Swing-v0", ["r_min", "r_max", "dt", "integrator", "substeps"]),
    ],
)
def test_an_unknown_kwarg_lists_every_valid_name_of_the_class_and_its_bases(env_id, names):
    with pytest.raises(ValueError, match="unknown parameter") as error:
        gym.make(env_id, nosuch=1.0)
    valid = error.value.args[0].split("valid: ")[1]
    for name in names:
        assert f"'{name}'" in valid
    assert "'kwargs'" not in valid and "'stepper_options'" not in valid


# -- item 3: a negative seed is an argparse error --------------------------------------------------------------


def test_a_negative_seed_is_a_usage_error_of_evaluate_and_train(train, capsys):
    from agents import evaluate

    for parse in (evaluate.parse_args, train.parse_args):
        for flag in ("--seed", "--eval-seed") if parse is train.parse_args else ("--seed",):
            with pytest.raises(SystemExit) as exit_:
                parse([flag, "-1"])
            assert exit_.value.code == 2
            assert f"argument {flag}: '-1' is not a seed" in capsys.readouterr().err
    assert evaluate.parse_args(["--seed", "0"]).seed == 0


# -- item 4: the benchmark's command line lists its subcommands ------------------------------------------------


def test_bench_help_lists_every_subcommand_and_no_arguments_prints_it(capsys):
    from connenv import bench

    bench.main([])
    listing = capsys.readouterr().out
    for command in ("all", "precision", "stability", "steppers", "generic"):
        assert re.search(rf"^    {command}\b", listing, re.MULTILINE)
    with pytest.raises(SystemExit):
        bench.main(["--help"])
    assert capsys.readouterr().out == listing
    with pytest.raises(SystemExit) as exit_:
        bench.main(["nosuch"])
    assert exit_.value.code == 2 and "invalid choice: 'nosuch'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        bench.main(["precision", "--help"])
    assert "--quick" in capsys.readouterr().out


# -- item 9: the test extra installs what the tests that do not train import -----------------------------------


def imported_modules(path):
    """The top-level names of every module a file imports, at module level or inside functions."""
    tree = ast.parse(path.read_text())
    names = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    names |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.level == 0}
    return {name.split(".")[0] for name in names}


def closure(requirements):
    """The normalized names of the distributions these requirements install, their dependencies included, with the
    extras each requirement asks for (``connenv[scale]`` in the test extra brings Ray)."""
    seen, todo = set(), [Requirement(r) for r in requirements]
    while todo:
        requirement = todo.pop()
        name, extras = canonicalize_name(requirement.name), ("", *sorted(requirement.extras))
        if (name, extras) in seen:
            continue
        seen.add((name, extras))
        for text in importlib.metadata.requires(requirement.name) or []:
            dependency = Requirement(text)
            if dependency.marker is None or any(dependency.marker.evaluate({"extra": e}) for e in extras):
                todo.append(dependency)
    return {name for name, _ in seen}


def test_the_test_extra_installs_every_module_the_package_and_the_tests_that_do_not_train_import():
    tomllib = pytest.importorskip("tomllib")  # Python ≥ 3.11
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    installed = closure(project["dependencies"] + project["optional-dependencies"]["test"])
    files = [*ROOT.glob("connenv/**/*.py"), *ROOT.glob("agents/**/*.py"), *ROOT.glob("tests/**/*.py")]
    modules = set().union(*(imported_modules(f) for f in files if f.name != "test_training.py"))
    local = {"connenv", "agents", "golden", "train", "conftest", "audit"}
    third_party = modules - set(sys.stdlib_module_names) - local
    providers = importlib.metadata.packages_distributions()
    missing = {m for m in third_party if not {canonicalize_name(d) for d in providers.get(m, [m])} & installed}
    assert not missing, f"imported by the package or the tests but not installed by .[test]: {sorted(missing)}"


def test_ci_runs_the_readmes_test_command():
    command = 'pip install "torch==2.13.0" -e ".[train,test]" && python -m pytest'
    assert f"\n    {command}\n" in (ROOT / "README.md").read_text()
    assert (ROOT / ".ci" / "run").read_text().splitlines()[-1] == command


# -- item 8: the goal env under SB3's checker and HER ----------------------------------------------------------


def test_the_goal_env_passes_sb3s_checker_unwrapped_and_trains_with_her():
    """SB3's checker calls compute_reward on the env it is given, which Gymnasium's wrappers do not forward (the
    docstring says so); HER reaches it through the vec env's env_method, and relabels with it."""
    from stable_baselines3 import SAC, HerReplayBuffer
    from stable_baselines3.common.env_checker import check_env

    from connenv.envs.rolling_ball import RollingBallGoalEnv

    env = gym.make("connenv/RollingBallGoal-v0")
    with pytest.raises(AttributeError, match="compute_reward"):
        check_env(env)
    check_env(env.unwrapped)
    assert "check_env(env.unwrapped)" in RollingBallGoalEnv.__doc__ and "env_method" in RollingBallGoalEnv.__doc__
    kwargs = {"n_sampled_goal": 4, "goal_selection_strategy": "future"}
    short = gym.make("connenv/RollingBallGoal-v0", max_episode_steps=20)
    model = SAC("MultiInputPolicy", short, replay_buffer_class=HerReplayBuffer, replay_buffer_kwargs=kwargs,
                learning_starts=50, batch_size=32, policy_kwargs={"net_arch": [16]}, seed=0)
    model.learn(150)
    batch = model.replay_buffer.sample(256)
    goals = (batch.next_observations["achieved_goal"], batch.observations["desired_goal"])
    expected = env.unwrapped.compute_reward(*(g.cpu().numpy() for g in goals), None)
    assert np.array_equal(batch.rewards.cpu().numpy()[:, 0], expected)
    assert 0 < np.count_nonzero(expected == 0.0) < len(expected)  # relabelled goals reached, and others not


# -- item 1: reset states have physical bounds, refused at reset -----------------------------------------------

HUGE_STATES = [  # (env_id, reset options, the key and range the message names)
    ("connenv/KozlovShell-v0", {"state": {"momentum": (1e5, 0, 0)}}, r"state momentum\[0\]=100000.0 .*\[-"),
    ("connenv/KozlovShell-v0", {"state": {"x": 1.5e308}}, r"state x=1.5e\+308 .*\[-100.0, 100.0\]"),
    ("connenv/KozlovShell-v0", {"target": (-1.5e308, 0)}, r"target\[0\]=-1.5e\+308 .*\[-100.0, 100.0\]"),
    ("connenv/KozlovShell-v0", {"state": {"theta": 1e10}}, r"state theta=10000000000.0 .*\[-6.28"),
    ("connenv/RollingBallPose-v0", {"state": {"x": 1.7e308, "y": 1.7e308}}, r"state x=1.7e\+308 .*\[-37.69"),
    ("connenv/Skier-v0", {"state": {"x_dot": 1e6}}, r"state x_dot=1000000.0 .*\[-"),
    ("connenv/Skier-v0", {"state": {"p": 1e200}}, r"state p=1e\+200 .*\[-"),
    ("connenv/Swing-v0", {"state": {"theta": 1e10}}, r"state theta=10000000000.0 .*\[-6.28"),
    ("connenv/Swing-v0", {"state": {"p": 1e200}}, r"state p=1e\+200 .*\[-"),
    ("connenv/KapitzaPendulum-v0", {"state": {"theta": 1e10}}, r"state theta=10000000000.0 .*\[-6.28"),
    ("connenv/KapitzaPendulum-v0", {"state": {"theta_dot": 1e6}}, r"state theta_dot=1000000.0 .*\[-31.3"),
    ("connenv/KapitzaSwingUp-v0", {"state": {"p": 1e200}}, r"state p=1e\+200 .*\[-"),
    ("connenv/ActiveConstraint-v0", {"state": {"p": [1e200]}}, r"state p\[0\]=1e\+200 .*\[-1000.0, 1000.0\]"),
    ("connenv/Connection-v0", {"state": {"s": [-5e167]}}, r"state s\[0\]=-5e\+167 .*\[-1000.0, 1000.0\]"),
]


@pytest.mark.parametrize(("env_id", "options", "message"), HUGE_STATES, ids=[f"{c[0][8:]}-{c[1]}" for c in HUGE_STATES])
def test_a_reset_state_beyond_its_physical_bounds_is_refused_naming_key_value_and_range(env_id, options, message):
    with pytest.raises(ValueError, match=message):
        make(env_id).reset(options=options)


@pytest.mark.parametrize("env_id", ["connenv/ActiveConstraint-v0"])
def test_a_finite_bound_of_a_users_coordinate_beyond_1e3_is_refused(env_id):
    with pytest.raises(ValueError, match=r"u_low=-1e\+307.* within ±1000.0"):
        make(env_id, u_low=-1e307)


@pytest.mark.parametrize(
    ("env_id", "state"),
    [
        ("connenv/Swing-v0", {"theta": 2 * np.pi, "p": -(2.0**2) * (2.0 / 1.6) ** 2 * 2 * (9.81 / 1.6) ** 0.5}),
        ("connenv/KapitzaPendulum-v0", {"theta": -2 * np.pi, "theta_dot": 10 * 9.81**0.5}),
        ("connenv/KozlovShell-v0", {"x": 100.0, "y": -100.0, "momentum": (0.0, 0.0, 0.01)}),
        ("connenv/RollingBallPose-v0", {"x": 12 * np.pi, "y": -12 * np.pi}),
    ],
)
def test_a_reset_state_at_its_bounds_is_accepted_and_steps_finite(env_id, state):
    env = make(env_id)
    env.reset(seed=0, options={"state": state})
    for _ in range(5):
        obs, reward, *_, info = env.step(env.action_space.sample())
        assert np.isfinite(obs).all() and np.isfinite(reward) and np.isfinite(info["state"]["t"])


# -- item 7: KapitzaPendulum-v0's reward, on every step --------------------------------------------------------


def test_kapitza_pendulums_reward_is_documented_on_every_step_and_keeps_its_documented_bounds():
    from connenv.envs.kapitza import KapitzaPendulumEnv

    env = gym.make("connenv/KapitzaPendulum-v0")
    floor = 1 - (np.pi / 0.3) ** 2
    assert "on every step" in KapitzaPendulumEnv.__doc__ and f"−{-floor:.1f}" in KapitzaPendulumEnv.__doc__
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step([0.0])
    assert 0 <= reward <= 1 and not terminated  # held
    env.reset(options={"state": {"theta": np.pi + 0.299, "theta_dot": 3.0}})
    _, reward, terminated, _, info = env.step([0.0])
    assert terminated and floor < reward < 0  # the step that falls
    env.reset(options={"state": {"theta": 2 * np.pi}})  # hanging: δ = π
    _, reward, terminated, _, _ = env.step([0.0])
    assert terminated and reward == pytest.approx(floor, abs=1e-3)


# -- item 6: dt has a documented range, within which the default stepper keeps up ------------------------------

FAST_STARTS = {spec.id: spec.fast_start for spec in registry.values() if spec.fast_start}
"""The fastest reset states allowed (item 1), where a long step costs the stepper most (each spec's)."""


@pytest.mark.parametrize("env_id", IDS)
def test_dt_is_checked_against_its_documented_range_and_steps_at_both_ends(env_id):
    high = spec(env_id).dt_max
    docstring = "".join(base.__doc__ or "" for base in spec(env_id).env.__mro__)
    assert f"[{DT_MIN:g}, {high:g}] s |" in docstring
    for bad in (high * 1.001, 1e6, 0.99 * DT_MIN, 0.0, -0.05, np.nan):
        with pytest.raises(ValueError, match=rf"dt=.* must be finite and in \[{DT_MIN:g}, "):
            make(env_id, dt=bad)
    for dt in (DT_MIN, high):
        env = make(env_id, dt=dt)
        env.reset(seed=0, options=FAST_STARTS.get(env_id))
        env.action_space.seed(0)
        for _ in range(3):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            assert np.isfinite(reward) and np.isfinite(info["state"]["t"])
            if terminated:
                env.reset()


def test_a_ball_started_at_its_target_reports_a_finite_path_ratio():
    env = gym.make("connenv/RollingBall-v0")
    _, info = env.reset(seed=0, options={"target": np.eye(3)})
    assert info["distance"] == 0.0 and info["path_ratio"] == 1.0


# -- issue 30 §2: the builders under hostile systems -----------------------------------------------------------


class MetricSystem:
    """A system for ActiveConstraint-v0 given by plain functions (n = m = 1): metric(q, u) -> (G11, G12, G22),
    potential(q, u), and optionally vector_field(y, u, u̇) and exact_segment(y, u, u̇, τ). By default a unit mass
    and a free rotor, G = I, V = 0."""

    n = m = 1

    def __init__(self, metric=None, potential=None, **methods):
        self._metric, self._potential = metric, potential
        for name, method in methods.items():
            setattr(self, name, method)

    def metric(self, q, u):
        if self._metric is not None:
            return self._metric(q, u)
        one = np.ones(np.shape(q)[:-1] + (1, 1))
        return one, 0.0 * one, one

    def potential(self, q, u):
        return 0.0 * np.asarray(q)[..., 0] if self._potential is None else self._potential(q, u)


class Task:
    """A task for either builder whose methods answer what they are given (a value, or a function of the state)."""

    def __init__(self, reward=0.0, observation=None, reset=None):
        self._reward, self._reset = reward, reset or {}
        if observation is not None:
            self.observation = observation

    def reset(self, np_random):
        return self._reset

    def reward(self, state, next_state):
        return self._reward

    def terminated(self, state):
        return False


def ones(q):
    return np.ones(np.shape(q)[:-1] + (1, 1))


def lagrangian(kinetic, potential):
    """ActiveConstraint-v0's kwargs for T, V in (q, u) through from_lagrangian's system."""
    import sympy as sp

    from connenv.core.lagrangian import LagrangianSystem

    q, u = sp.symbols("q u")
    return {"system": LagrangianSystem(kinetic, potential, [q], [u])}


def q_dot_u_dot():
    import sympy as sp

    return sp.symbols("q_dot u_dot")


AC = {"u_low": -1.0, "u_high": 1.0}
SO2 = {"group": "SO2", "shape_low": [-1.0], "shape_high": [1.0]}
IDENTITY = {**SO2, "connection": lambda s: np.eye(1)}


class Hostile(NamedTuple):
    label: str
    kwargs: object  # () -> the builder's kwargs ("system" in them: ActiveConstraint-v0, else Connection-v0)
    error: type
    words: str  # a regex the message matches: it names the argument, or the user's function, and what is expected
    steps: int = 0  # 0: refused at construction; else raised within that many steps (the single and vector env)
    physics: bool = False  # raised by the step's physics, before the state changes (a task's answer comes after)


HOSTILE = [
    # ActiveConstraint-v0: the system's functions, tried at construction
    Hostile("metric raises", lambda: {"system": MetricSystem(lambda q, u: 1 / 0), **AC}, ValueError,
            r"system\.metric\(q, u\) at a batch of 12 points raised ZeroDivisionError"),
    Hostile("metric returns None", lambda: {"system": MetricSystem(lambda q, u: None), **AC}, TypeError,
            r"system\.metric\(q, u\) .* returned None; expected \(G11, G12, G22\)"),
    Hostile("metric complex", lambda: {"system": MetricSystem(lambda q, u: ((1 + 1j) * ones(q), 0 * ones(q), ones(q))),
            **AC}, ValueError, r"system\.metric\(q, u\) .* block G11, returned complex values"),
    Hostile("metric NaN", lambda: {"system": MetricSystem(lambda q, u: (np.nan * ones(q), 0 * ones(q), ones(q))), **AC},
            ValueError, r"system\.metric\(q, u\) .* block G11, returned non-finite values"),
    Hostile("potential None", lambda: {"system": type("S", (MetricSystem,), {"potential": None})(), **AC},
            ValueError, r"system\.potential=None is not callable"),
    Hostile("potential raises", lambda: {"system": MetricSystem(potential=lambda q, u: 1 / 0), **AC}, ValueError,
            r"system\.potential\(q, u\) .* raised ZeroDivisionError"),
    Hostile("potential None returned", lambda: {"system": MetricSystem(potential=lambda q, u: None), **AC}, TypeError,
            r"system\.potential\(q, u\) .* returned None; expected V"),
    Hostile("vector_field None", lambda: {"system": MetricSystem(vector_field=lambda y, u, u_dot: None), **AC},
            TypeError, r"system\.vector_field\(y, u, u_dot\) .* returned None; expected real finite arrays of y's"),
    Hostile("vector_field shape", lambda: {"system": MetricSystem(vector_field=lambda y, u, u_dot: np.zeros(5)), **AC},
            ValueError, r"system\.vector_field\(y, u, u_dot\) .* returned shape \(5,\); expected .* shape \(2,\)"),
    Hostile("Lagrangian zoo", lambda: lagrangian(q_dot_u_dot()[0] ** 2 / 2 + q_dot_u_dot()[1] ** 2 / 2, "zoo"),
            ValueError, r"potential=zoo holds zoo, oo or nan: it must be finite"),
    Hostile("Lagrangian None", lambda: lagrangian(q_dot_u_dot()[0] ** 2 / 2 + q_dot_u_dot()[1] ** 2 / 2, None),
            TypeError, r"potential=None must be a sympy expression"),
    Hostile("Lagrangian complex", lambda: lagrangian(q_dot_u_dot()[0] ** 2 / 2 + q_dot_u_dot()[1] ** 2 / 2, "I*q"),
            ValueError, r"potential=I\*q holds the imaginary unit I"),
    Hostile("control speed 1e300", lambda: {"system": MetricSystem(), **AC, "max_control_speed": 1e300}, ValueError,
            r"max_control_speed=1e\+300 is out of range: must be finite and in \(0.0, 1000.0\]"),
    Hostile("ac task=3", lambda: {"system": MetricSystem(), **AC, "task": 3}, TypeError,
            r"task=3 must be an object with methods reset\(np_random\) -> state dict, reward"),
    # ActiveConstraint-v0: at a step
    Hostile("ac exact_segment shape", lambda: {"system": MetricSystem(vector_field=lambda y, u, u_dot: 0 * y,
            exact_segment=lambda y, u, u_dot, tau: np.zeros(5)), **AC}, ValueError,
            r"MetricSystem\.exact_segment returned \(5,\) .* the state's shape", 1, True),
    Hostile("ac reward NaN", lambda: {"system": MetricSystem(), **AC, "task": Task(reward=np.nan)}, ValueError,
            r"task\.reward\(state, next_state\) returned nan; expected a finite number", 1),
    Hostile("ac reward None", lambda: {"system": MetricSystem(), **AC, "task": Task(reward=None)}, TypeError,
            r"task\.reward\(state, next_state\) returned None; expected a real number", 1),
    Hostile("ac observation inf", lambda: {"system": MetricSystem(), **AC,
            "task": Task(observation=lambda s: [np.inf if s["t"] > 0 else 0.0])}, ValueError,
            r"task\.observation\(state\) returned non-finite values", 1),
    Hostile("ac observation beyond float32", lambda: {"system": MetricSystem(), **AC,
            "task": Task(observation=lambda s: [1e300 * s["t"]])}, ValueError,
            r"task\.observation\(state\) returned .* beyond float32's range", 1),
    Hostile("ac state beyond float32", lambda: {**lagrangian("1e-40 * q_dot**2 / 2 + u_dot**2 / 2", 0), **AC,
            "task": Task(reset={"p": [1.0]})}, StepperError, r"\(q, p\) = .* has left float32's range", 1, True),
    # Connection-v0: the connection and exact_segment, tried at construction
    Hostile("connection raises", lambda: {**SO2, "connection": lambda s: 1 / 0}, ValueError,
            r"connection\(s\) at s=\[0\.\] raised ZeroDivisionError"),
    Hostile("connection None", lambda: {**SO2, "connection": lambda s: None}, TypeError,
            r"connection\(s\) at s=\[0\.\] returned None; expected A\(s\), finite real numbers of shape \(1, 1\)"),
    Hostile("connection complex", lambda: {**SO2, "connection": lambda s: np.array([[1j]])}, ValueError,
            r"connection\(s\) at s=\[0\.\] returned complex values"),
    Hostile("constant A complex", lambda: {**SO2, "connection": np.array([[1 + 1j]])}, ValueError,
            r"connection=array\(\[\[1\.\+1\.j\]\]\) is complex"),
    Hostile("vectorized, connection is not", lambda: {**SO2, "connection": lambda s: np.array([[float(s[0])]]),
            "vectorized": True}, ValueError, r"connection\(s\) at a batch of 2 shapes .* \(vectorized=True\) raised"),
    Hostile("vectorized not a bool", lambda: {**IDENTITY, "vectorized": "yes"}, TypeError,
            r"vectorized='yes' must be True or False"),
    Hostile("exact_segment raises", lambda: {**IDENTITY, "exact_segment": lambda g, s, s_dot, tau: 1 / 0},
            ValueError, r"exact_segment=.* raised ZeroDivisionError"),
    Hostile("shape speed 1e300", lambda: {**IDENTITY, "max_shape_speed": 1e300}, ValueError,
            r"max_shape_speed=1e\+300 is out of range: must be finite and in \(0.0, 1000.0\]"),
    Hostile("cn task=3", lambda: {**IDENTITY, "task": 3}, TypeError,
            r"task=3 must be an object with methods reset\(np_random\) -> state dict, reward"),
    Hostile("cn task observation_space", lambda: {**IDENTITY, "task": type("T", (Task,), {"observation_space": 3})()},
            TypeError, r"task\.observation_space=3 must be a gymnasium\.spaces\.Space"),
    # Connection-v0: at a step
    Hostile("exact_segment corrupts g", lambda: {**IDENTITY, "exact_segment": lambda g, s, s_dot, tau: g if np.all(
            s[..., 0] < 0.05) else np.zeros(5)}, ValueError, r"exact_segment returned \(5,\) .* the state's shape", 2,
            True),
    Hostile("cn reward inf", lambda: {**IDENTITY, "task": Task(reward=np.inf)}, ValueError,
            r"task\.reward\(state, next_state\) returned inf", 1),
    Hostile("cn observation inf", lambda: {**IDENTITY, "task": Task(observation=lambda s: [np.inf if s["t"] else 0])},
            ValueError, r"task\.observation\(state\) returned non-finite values", 1),
    Hostile("cn task reset no dict", lambda: {**IDENTITY, "task": Task(reset=3)}, ValueError,
            r"the state of task\.reset\(np_random\)=3 must be a mapping", 1),
    Hostile("g beyond float32", lambda: {"group": "R2", "connection": lambda s: np.full((2, 1), 1e300),
            "shape_low": [-1.0], "shape_high": [1.0]}, StepperError, r"g = .* has left float32's range", 1, True),
]  # fmt: skip


def build(kwargs, vector=False):
    env_id = "connenv/ActiveConstraint-v0" if "system" in kwargs else "connenv/Connection-v0"
    if vector:
        return gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point", **kwargs)
    return gym.make(env_id, **kwargs)


@pytest.mark.parametrize("case", HOSTILE, ids=[case.label for case in HOSTILE])
def test_a_hostile_system_or_task_is_a_clear_error_at_construction_or_at_its_step(case):
    """Each case of issue 30's list, and its kin: a user's metric, potential, vector_field, connection, exact_segment
    or task that raises, returns no real numbers, complex or non-finite ones or the wrong shape, and kwargs whose
    state the float32 observation cannot hold. What construction can know is refused there, naming the argument;
    the rest raises at the step that meets it, in the single env and in the vector env, naming the function, and
    a step refused so leaves the single env's state as it was."""
    with np.errstate(all="ignore"):
        if not case.steps:
            with pytest.raises(case.error, match=case.words):
                build(case.kwargs())
            return
        for vector in (False, True):
            env = build(case.kwargs(), vector)
            with pytest.raises(case.error, match=case.words):
                env.reset(seed=0)
                action = np.ones(env.action_space.shape, np.float32)
                for _ in range(case.steps):
                    before = copy.deepcopy(env.unwrapped.state) if not vector else None
                    env.step(action)
            if case.physics and not vector:  # the step did not happen
                for key, value in before.fields().items():
                    assert np.array_equal(getattr(env.unwrapped.state, key), value)


def singular_metric(q, u):
    """G11 = 1 − q²: positive definite for |q| < 1 only, singular at q = ±1."""
    return (1.0 - np.asarray(q)[..., :1] ** 2)[..., None], 0.0 * ones(q), ones(q)


def test_a_step_that_stalls_on_a_numerical_gradient_raises_within_seconds():
    """Issue 30's stall: G11 = 1 − q² and V = −q², from q = 0.5 at rest. The potential pushes q outward, and on the
    level E = H the speed q̇ = √(2 (E + q²)/(1 − q²)) diverges at q = 1, reached in finite time: there is no flow
    past it. DOP853 on the system's numerical gradient (no vector_field of its own) then shrinks its step without
    end (the gradient's stencil reaches past q = 1); the budget of evaluations per segment of a numerical field
    makes that a StepperError within seconds, where it ran for minutes. The steps before move q outward, finite."""
    from connenv import ActiveConstraintEnv

    env = ActiveConstraintEnv(MetricSystem(singular_metric, lambda q, u: -np.asarray(q)[..., 0] ** 2), -1.0, 1.0)
    env.reset(options={"state": {"q": [0.5]}})
    trace, start = [], time.monotonic()
    with pytest.raises(StepperError, match=r"1000 evaluations of MetricField's vector field brought it to s ="):
        for _ in range(30):
            trace.append(env.step(np.array([0.0]))[4]["state"]["q"][0])
    assert time.monotonic() - start < 30.0
    assert 0.5 < trace[0] and np.all(np.diff(trace) > 0) and trace[-1] < 1.0 and len(trace) >= 10


def test_every_adaptive_stepper_keeps_a_systems_own_evaluation_budget():
    """A system may set max_evaluations, its budget per segment (MetricField does): scipy's methods and the vector
    env's per-row DOP853 stop there with a StepperError, as they do at MAX_EVALUATIONS for any other system."""
    from connenv.core.batched import EmbeddedRK
    from connenv.core.steppers import MAX_EVALUATIONS, Scipy, evaluation_budget

    class Stiff:
        max_evaluations = 50

        def vector_field(self, y, u, u_dot):  # ẏ = −10⁴ y: DOP853 takes hundreds of evaluations over 1 s
            return -1e4 * y

    assert evaluation_budget(Stiff()) == 50 and evaluation_budget(object()) == MAX_EVALUATIONS
    for stepper, y in ((Scipy("DOP853"), np.ones(2)), (Scipy("LSODA"), np.ones(2)), (EmbeddedRK(), np.ones((3, 2)))):
        with pytest.raises(StepperError, match="cannot meet its tolerance: 50 evaluations"):
            stepper(Stiff(), y, np.zeros(1), np.zeros(1), 1.0)


def test_a_connection_with_a_pole_on_the_shapes_path_raises_instead_of_returning_a_finite_wrong_g():
    """Issue 30's pole: on SO2, A(s) = 1/(1 − s) and ṡ = 1 give θ = ln(1 − s), which diverges at s = 1. Nine steps
    of 0.1 follow the closed form; the tenth ends on the pole, where every quadrature is finite (−10.78 was
    returned) but more substeps keep moving it: the Lie-group step checks its substeps against twice as many and
    raises StepperError, alone and in the vector env."""
    from connenv import ConnectionEnv

    env = ConnectionEnv("SO2", lambda s: np.array([[1.0 / (1.0 - s[0])]]), [-2.0], [2.0])
    env.reset(seed=0)
    for k in range(1, 10):
        env.step(np.array([1.0]))
        assert env.state.g[0] == pytest.approx(np.log(1.0 - 0.1 * k), abs=1e-9)
    with pytest.raises(StepperError, match=r"cannot meet atol: with \d+ substeps .* a pole on the shape's path"):
        env.step(np.array([1.0]))
    vector = gym.make_vec("connenv/Connection-v0", 2, vectorization_mode="vector_entry_point", group="SO2",
                          connection=lambda s: np.array([[1.0 / (1.0 - s[0])]]), shape_low=[-2.0], shape_high=[2.0])
    vector.reset(seed=0, options={"state": {"s": [0.9]}})
    with pytest.raises(StepperError, match="cannot meet atol"):
        vector.step(np.ones((2, 1)))


@pytest.mark.parametrize(
    ("env_id", "state", "key"),
    [
        ("connenv/ActiveConstraint-v0", {"q": np.array([0.1 + 2j])}, "q"),
        ("connenv/ActiveConstraint-v0", {"p": np.array([0.1 + 2j])}, "p"),
        ("connenv/ActiveConstraint-v0", {"u": np.complex128(1.7)}, "u"),
        ("connenv/Connection-v0", {"s": np.array([2 + 3j])}, "s"),
        ("connenv/Connection-v0", {"g": np.eye(2) * (1 + 1e-3j)}, "g"),
    ],
)
def test_a_complex_array_in_a_builders_reset_state_is_refused_not_made_real(env_id, state, key):
    """numpy makes a complex array real with only a ComplexWarning; the builders refuse it as they refuse a complex
    list, naming the key."""
    env = make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=rf"(?s)state {key}=.* is complex; expected .*real numbers"):
            env.reset(options={"state": state})


# -- issue 44 §1: seeds, resets and parameters ---------------------------------------------------------------------

PARAMETRIZED = [env_id for env_id in IDS if RANDOMIZED[env_id]]  # the ids with physical parameters that may vary


def seeded_run(env, seed=0, steps=5):
    """Observations and rewards of a run whose actions are sampled from the env's seeded action space, over two
    seeded resets (a randomized reset draws the parameters)."""
    env.action_space.seed(seed)
    out = []
    for episode in range(2):
        obs, info = env.reset(seed=seed + episode)
        out.append((obs, info.get("params")))
        for _ in range(steps):
            obs, reward, *_ = env.step(env.action_space.sample())
            out.append((obs, reward))
    return out


def same(x, y) -> bool:
    """Whether two observations, rewards or parameter dicts are equal to the bit (a goal env's dicts key by key)."""
    if isinstance(x, dict):
        return x.keys() == y.keys() and all(same(x[k], y[k]) for k in x)
    return x is None and y is None or np.array_equal(np.asarray(x, float), np.asarray(y, float), equal_nan=True)


def same_runs(a, b):
    return len(a) == len(b) and all(same(x, y) for p, q in zip(a, b) for x, y in zip(p, q))


@pytest.mark.parametrize("observe_params", [False, True])
@pytest.mark.parametrize("env_id", PARAMETRIZED)
def test_a_randomized_env_keeps_its_seeded_spaces_and_its_seeded_runs_repeat(env_id, observe_params):
    """A reset that draws or sets parameters keeps the spaces make fixed, and a space the user seeded with them."""
    env = make(env_id, randomize=RANDOMIZED[env_id], observe_params=observe_params)
    spaces = env.action_space, env.observation_space
    env.action_space.seed(0)
    env.reset(seed=0)
    name = next(iter(RANDOMIZED[env_id]))
    env.reset(options={"params": {name: RANDOMIZED[env_id][name][1]}})
    assert env.action_space is spaces[0] and env.observation_space is spaces[1]
    again = make(env_id, randomize=RANDOMIZED[env_id], observe_params=observe_params)
    assert same_runs(seeded_run(env), seeded_run(again))


BAD_RESETS = [  # (seed, options) a reset refuses: a bad state key after good params, a bad parameter, a bad type
    (123, {"params": "first", "state": {"no such key": 0.0}}),
    (123, {"params": {"no such parameter": 1.0}}),
    (None, {"params": "first", "state": {"no such key": 0.0}}),
    (None, {"params": {"first": True}}),
    (7, {"params": "first", "no such option": 1}),
]


@pytest.mark.parametrize("randomized", [False, True])
@pytest.mark.parametrize("env_id", PARAMETRIZED)
def test_a_reset_that_raises_leaves_the_env_and_its_generator_as_they_were(env_id, randomized):
    """Everything a reset is given is checked before anything changes: after the ValueError the env steps, draws
    and resets as its copy made before it."""
    env = make(env_id, **({"randomize": RANDOMIZED[env_id]} if randomized else {})).unwrapped
    env.reset(seed=0, options={"params": {name: high for name, (low, high) in RANDOMIZED[env_id].items()}})
    name, (low, high) = next(iter(RANDOMIZED[env_id].items()))
    for seed, options in BAD_RESETS:
        before = copy.deepcopy(env)
        params = {name: low} if options["params"] == "first" else {
            (name if k == "first" else k): v for k, v in options["params"].items()}
        with pytest.raises(ValueError):
            env.reset(seed=seed, options={**options, "params": params})
        assert env.context.current == before.context.current
        assert env.np_random.bit_generator.state == before.np_random.bit_generator.state
        action = env.action_space.sample()
        assert same_runs([env.step(action)[:2]], [before.step(action)[:2]])
        assert same_runs([env.reset()[:1]], [before.reset()[:1]])


def test_the_issues_swing_reset_keeps_g_and_the_state_and_a_seed_is_taken_only_with_a_good_reset():
    env = make("connenv/Swing-v0").unwrapped
    env.reset(seed=0)
    state, generator = env.state, env.np_random
    with pytest.raises(ValueError, match="state theta=99"):
        env.reset(options={"params": {"g": 3.0}, "state": {"theta": 99}})
    with pytest.raises(ValueError, match="'bogus'"):
        env.reset(seed=123, options={"params": {"bogus": 1}})
    assert env.system.g == 9.81 and env.state is state and env.np_random is generator


@pytest.mark.parametrize("env_id", PARAMETRIZED)
def test_a_vector_env_goes_back_to_its_make_values_as_the_single_env(env_id):
    """After a reset with "params", a reset without them runs as a new vector env, to the bit."""
    name, (low, high) = next(iter(RANDOMIZED[env_id].items()))
    made = [gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", **spec(env_id).make_kwargs())
            for _ in range(2)]
    made[0].reset(seed=0, options={"params": {name: high}})
    runs = []
    for envs in made:
        obs, info = envs.reset(seed=0)
        assert "params" not in info
        envs.action_space.seed(0)
        runs.append([obs, *(envs.step(0.8 * envs.action_space.sample())[0] for _ in range(5))])
    assert all(same(a, b) for a, b in zip(*runs))


def test_a_vector_reset_that_a_row_refuses_leaves_every_row_as_it_was():
    """Row 0 takes b = 0.28, row 1 draws a = 0.25 and refuses it (b < a): neither row changes."""
    envs = gym.make_vec("connenv/SnakeSwimmer-v0", num_envs=2, vectorization_mode="vector_entry_point",
                        randomize={"a": (0.25, 0.6)})  # fmt: skip
    obs, _ = envs.reset(seed=0)
    rows = copy.deepcopy(envs.unwrapped.row_params)
    for seed in range(40):
        draws = [np.random.default_rng(seed + i) for i in range(2)]
        if 0.28 < math.exp(draws[0].uniform(math.log(0.25), math.log(0.6))) and 0.28 >= math.exp(
                draws[1].uniform(math.log(0.25), math.log(0.6))):
            break
    with pytest.raises(ValueError, match="b=0.28"):
        envs.reset(seed=seed, options={"params": {"b": 0.28}})
    assert envs.unwrapped.row_params == rows
    assert same(envs.step(np.zeros((2, 2)))[0], envs_after_reset(seed=0).step(np.zeros((2, 2)))[0])


def envs_after_reset(seed):
    envs = gym.make_vec("connenv/SnakeSwimmer-v0", num_envs=2, vectorization_mode="vector_entry_point",
                        randomize={"a": (0.25, 0.6)})  # fmt: skip
    envs.reset(seed=seed)
    return envs


@pytest.mark.parametrize("env_id", PARAMETRIZED)
def test_the_model_steps_rows_of_their_own_params_as_the_randomized_vector_env_to_the_bit(env_id):
    """model.step(X, A, params=rows) is the randomized vector env's step, whose rows step by their own values."""
    envs = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point", **spec(env_id).make_kwargs(),
                        randomize=RANDOMIZED[env_id])  # fmt: skip
    envs.reset(seed=4)
    envs.action_space.seed(4)
    model = make(env_id).unwrapped.model
    for _ in range(5):
        actions = 0.8 * envs.action_space.sample()
        x, params = model.pack(envs.unwrapped.state), [dict(p) for p in envs.unwrapped.row_params]
        x_next = model.step(x, actions, params=params)
        envs.step(actions)
        assert np.array_equal(x_next, model.pack(envs.unwrapped.state), equal_nan=True)


def test_the_goal_env_observes_its_parameters_as_a_key_of_their_own():
    """RollingBallGoal-v0's Dict observation gains "params", in the single env and the vector env."""
    kwargs = {"randomize": {"radius": (0.05, 0.2)}, "observe_params": True}
    env = make("connenv/RollingBallGoal-v0", **kwargs)
    obs, info = env.reset(seed=0)
    assert set(env.observation_space.spaces) == {"observation", "achieved_goal", "desired_goal", "params"}
    assert obs in env.observation_space and obs["params"].shape == (1,)
    obs, *_ = env.step(env.action_space.sample())
    assert obs in env.observation_space
    envs = gym.make_vec("connenv/RollingBallGoal-v0", num_envs=2, vectorization_mode="vector_entry_point", **kwargs)
    obs, info = envs.reset(seed=0)
    assert obs in envs.observation_space and obs["params"].shape == (2, 1)
    assert obs["params"][0] == env.reset(seed=0)[0]["params"]


@pytest.mark.parametrize("value", [True, np.bool_(True), 1 + 0j, np.complex128(1.0), "1.0", [1.0]])
def test_a_parameter_that_is_no_real_number_is_refused_even_where_it_equals_the_current_value(value):
    """mass = 1 is the make value, and True == 1 + 0j == 1.0: the check does not rest on the comparison."""
    env = make("connenv/Swing-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"mass=.* must be a real number in \[1e-6, 1e6\] kg"):
        env.reset(options={"params": {"mass": value}})
    model, x = env.model, env.model.pack(env.state)
    with pytest.raises(ValueError, match=r"mass=.* must be a real number"):
        model.step(x, np.zeros(1), params={"mass": value})
    with pytest.raises(ValueError, match=r"mass=.* must be a real number"):
        model.step(np.stack([x, x]), np.zeros((2, 1)), params=[{"mass": 1.0}, {"mass": value}])


def test_the_context_sweep_finds_every_bad_range_and_value_refused_by_name():
    """tests/audit.py's context cases (randomize ranges that are no pair of reals, reversed or out of range; reset
    params that are no real number or out of range, on the single env, which must be unchanged after a refused
    reset, and the vector env; observe_params), on every id's first parameter: each is a ValueError or TypeError
    naming what was bad, or runs finite. randomize of an optional parameter that is off at make (Swing-v0's
    max_radial_speed) raised numpy's "must be real number, not NoneType" before."""
    import audit

    verdicts = [(case, audit.judge(case)) for case in audit.context_cases(audit.IDS, quick=True)]
    open_cases = [f"{case.where}: {case.what}: {verdict.detail}" for case, verdict in verdicts if verdict.kind == "open"]
    assert len(verdicts) > 1000 and not open_cases, open_cases[:5]
