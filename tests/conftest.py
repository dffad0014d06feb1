"""Fixtures shared by the test modules: the seeded random rollout, train.py and the check of its run folder, the
steppers made to diverge, and the native vector env stepped beside a SyncVectorEnv of single envs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import connenv  # noqa: F401  (registers the envs)
from agents import evaluate
from connenv.bench.stability import VALLEY_KAPPA_MAX

ROOT = Path(__file__).resolve().parents[1]


# -- the seeded random rollout ----------------------------------------------------------------------------------


def seeded_rollout_of(env, seed, steps, extras, options=None, flatten=np.ravel):
    """Observations, rewards and extras(info) of `steps` uniform random actions from reset(seed), resetting
    when an episode ends, as one flat array."""
    obs, _ = env.reset(seed=seed, options=options)
    env.action_space.seed(seed)
    trace = [flatten(obs)]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace.append(np.append(flatten(obs), [reward, *extras(info)]))
        if terminated or truncated:
            trace.append(flatten(env.reset()[0]))
    return np.concatenate(trace)


@pytest.fixture
def seeded_rollout():
    """seeded_rollout(env, seed, steps, extras, options=None, flatten=np.ravel) -> one flat array."""
    return seeded_rollout_of


# -- train.py and its run folder --------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def train():
    """agents.train, the logic of the top-level train.py (imported when a test asks for it: it brings rl-zoo3)."""
    from agents import train

    return train


def check_run_folder(results: dict, algo: str):
    """The run folder of a Swing-v0 run holds the model, the hyperparameters used and the results; the model
    reloads and acts."""
    env_id = "connenv/Swing-v0"
    model_path = Path(results["model"])
    run_dir = model_path.parent
    assert run_dir.name == f"Swing-v0_{algo}_s0"
    config = yaml.load((run_dir / "connenv-Swing-v0" / "config.yml").read_text(), Loader=yaml.UnsafeLoader)
    book = yaml.safe_load((ROOT / "agents" / "hyperparams" / f"{algo}.yml").read_text())
    expected = book.get(env_id, book.get("default"))  # rl-zoo3's: `default` for an env without an entry of its own
    assert dict(config) == expected
    assert json.loads((run_dir / "results.json").read_text())["timesteps"] == results["timesteps"]
    labels = [row["policy"] for row in results["evaluation"]["policies"]]
    assert labels == [f"{algo}:{run_dir.name}", "analytic", "random"]
    policy = evaluate.load_model(model_path, env_id)  # the algorithm is read from the run folder
    env = gym.make(env_id)
    for seed in range(5):
        action, _ = policy.predict(env.reset(seed=seed)[0], deterministic=True)
        assert env.action_space.contains(action)
    return policy


@pytest.fixture
def check_run():
    """check_run(results, algo) -> the reloaded policy, after checking train.py's run folder."""
    return check_run_folder


# -- steppers made to diverge -----------------------------------------------------------------------------------

DIVERGING = [  # (env_id, make kwargs, reset state, action, the StepperError's message)
    (
        "connenv/Swing-v0",
        {"integrator": "euler", "r_min": 0.1},
        {"theta": 1.0, "r": 0.1},
        [-1.0],
        r"Euler\(substeps=1\) diverged: \|energy error\| .* dt = 0.05, r_min = 0.1,",
    ),
    (
        "connenv/Skier-v0",
        {"integrator": "rk4", "h_max": 0.99 / VALLEY_KAPPA_MAX},
        {"x": 2.0, "h": 0.99 / VALLEY_KAPPA_MAX},
        [1.0],
        r"RK4\(substeps=1\) diverged: .* dt = 0.05, .*min 1 − κ h_max = 0.01,",
    ),
    (
        "connenv/RollingBall-v0",
        {"integrator": "euler", "radius": 0.5},
        {},
        [1.0, 0.0],
        r"Euler\(substeps=1\) left SO\(3\).* dt = 0.1, radius = 0.5",
    ),
    (
        "connenv/KapitzaPendulum-v0",
        {"integrator": "euler", "v_max": 100.0, "dt": 0.02},
        {"theta": math.pi + 0.1},
        [1.0],
        r"Euler\(substeps=1\) diverged: \|energy error\| .* dt = 0.02, .*v_max = 100.0, a_max = 0.1",
    ),
    (
        "connenv/KozlovShell-v0",
        {"integrator": "semi_implicit_euler", "mass": 10.0 * (1.0 + math.pi / 4)},
        {"momentum": (0.3, 0.1, 0.05)},
        [1.0, 1.0],
        r"SemiImplicitEuler\(substeps=1\) diverged: the spatial momentum .* dt = 0.1, .*m/\(M \+ λ₁\) = 10.0,",
    ),
    (
        "connenv/SnakeSwimmer-v0",
        {"integrator": "euler", "b": 0.005},  # links of aspect ratio 100
        {"momentum": (0.2, 1.0, 0.5)},
        [1.0, 1.0],
        r"Euler\(substeps=1\) diverged: the spatial momentum .* dt = 0.05, a = 0.5, b = 0.005,",
    ),
]


@pytest.fixture(params=DIVERGING, ids=[case[0].removeprefix("connenv/") for case in DIVERGING])
def diverging(request):
    """(env_id, make kwargs, reset state, action, message): a stepper that diverges from that start under that
    action (alternated in sign for the shell and the pendulum) and the StepperError's message."""
    return request.param


# -- the native vector env beside a SyncVectorEnv of single envs ------------------------------------------------

RTOL = 1e-12  # |vector − single| ≤ RTOL · max(1, |single|), for every number of obs, reward and info

SHORT_EPISODES = {  # kwargs that make episodes short, so that a run holds terminations, truncations and autoresets
    "connenv/Swing-v0": {"max_episode_steps": 40, "target_amplitude": 0.12},
    "connenv/Skier-v0": {"max_episode_steps": 15, "target_x": 0.3},  # one goal, reached from the side of the start
    "connenv/RollingBall-v0": {"max_episode_steps": 30, "tolerance": 2.0},
    "connenv/RollingBallPose-v0": {"max_episode_steps": 30, "tolerance": 2.5, "position_tolerance": 0.2},
    "connenv/RollingBallGoal-v0": {"max_episode_steps": 30, "tolerance": 2.0},
    "connenv/KozlovShell-v0": {"max_episode_steps": 30, "success_radius": 0.45},
    "connenv/KapitzaPendulum-v0": {"max_episode_steps": 60, "tolerance": 0.21, "pivot": "horizontal"},  # it falls
    "connenv/KapitzaSwingUp-v0": {"max_episode_steps": 40, "hold_time": 0.05, "tolerance": 3.07},
    "connenv/RollingCoinSurface-v0": {"max_episode_steps": 30, "tolerance": 3.0},
}
BALLS = ("connenv/RollingBall-v0", "connenv/RollingBallPose-v0", "connenv/RollingBallGoal-v0")
VECTOR_ONLY = {env_id: {"measure_distance": True} for env_id in BALLS}  # the single envs always measure it


@pytest.fixture
def short_episodes():
    """{env_id: make kwargs under which its episodes end both ways, terminated and truncated, within a few dozen
    steps}."""
    return SHORT_EPISODES


def flat(info, prefix=""):
    """{dotted key: array} of a vector info, masks left out; tuples and strings of SyncVectorEnv's object arrays
    become numbers and strings."""
    out = {}
    for key, value in info.items():
        if isinstance(value, dict):
            out.update(flat(value, f"{prefix}{key}."))
        elif not key.startswith("_"):
            array = np.asarray(value)
            if array.dtype == object:
                array = np.array([v if isinstance(v, str) else np.asarray(v, float) for v in value])
            out[prefix + key] = array
    return out


def assert_same(native, sync, what):
    native, sync = (flat(native), flat(sync)) if isinstance(native, dict) else ({"": native}, {"": sync})
    assert native.keys() == sync.keys(), what
    for key, a in native.items():
        b = sync[key]
        assert a.shape == b.shape, (what, key)
        if a.dtype.kind in "USb":
            assert np.array_equal(a, b), (what, key, a, b)
        else:
            a, b = a.astype(float), b.astype(float)
            both_nan = np.isnan(a) & np.isnan(b)
            gap = np.where(both_nan, 0.0, np.abs(a - b) / np.maximum(1.0, np.abs(b)))
            assert np.all(gap <= RTOL), (what, key, float(np.max(gap)))


def single_env(env_id, kwargs):
    """gym.make(env_id) under Gymnasium's own TimeLimit: rl_zoo3, once imported (by other tests), replaces it by
    one that reports no truncation on a step that also terminates."""
    time_limit = next(c for c in gym.wrappers.TimeLimit.__mro__ if c.__module__.startswith("gymnasium"))
    env_kwargs = {key: value for key, value in kwargs.items() if key != "max_episode_steps"}
    steps = kwargs.get("max_episode_steps", gym.spec(env_id).max_episode_steps)
    return time_limit(gym.make(env_id, **env_kwargs).unwrapped, steps)


def run_native_and_sync(env_id, n, steps, seed, kwargs, options=None):
    """Step the native vector env and a SyncVectorEnv of single envs on the same seed and random actions,
    asserting equality at every step; return how many episodes ended by termination and by truncation."""
    vector_kwargs = {**kwargs, **VECTOR_ONLY.get(env_id, {})}
    native = gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", **vector_kwargs)
    sync = gym.vector.SyncVectorEnv([lambda: single_env(env_id, kwargs)] * n)
    for a, b, name in zip(native.reset(seed=seed, options=options), sync.reset(seed=seed, options=options), "oi"):
        assert_same(a, b, f"reset {name}")
    actions = np.random.default_rng(seed).uniform(-1.0, 1.0, (steps, *native.action_space.shape)).astype(np.float32)
    ends = np.zeros(2, int)
    for t, action in enumerate(actions):
        got, want = native.step(action), sync.step(action)
        for name, a, b in zip(("obs", "reward", "terminated", "truncated", "info"), got, want):
            assert_same(a, b, f"{name} at step {t}")
        ends += [got[2].sum(), got[3].sum()]
    return ends


@pytest.fixture
def run_both():
    """run_both(env_id, n, steps, seed, kwargs, options=None) -> (terminations, truncations): row i of the native
    vector env equals env i of a SyncVectorEnv at every step, to RTOL."""
    return run_native_and_sync
