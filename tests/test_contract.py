"""The contract of every registered id: Gymnasium's and SB3's checkers pass with warnings as errors, a seed fixes
the run to the bit, an env pickles and deep-copies mid-run and the copy continues identically, the native vector
env is a SyncVectorEnv of single envs row for row through autoresets, and rgb_array renders an image."""

from __future__ import annotations

import copy
import pickle
import warnings
from typing import NamedTuple

import gymnasium as gym
import numpy as np
import pytest
from audit import OUT_OF_DATE
from gymnasium.utils.env_checker import check_env as gym_check_env
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import connenv  # noqa: F401  (registers the envs)
from connenv.envs.spec import registry

IDS = sorted({*registry, *(env_id for env_id in gym.registry if env_id.startswith("connenv/"))})

CONTRACT_KWARGS = {spec.id: [v() if callable(v) else v for v in spec.variants] for spec in registry.values()}
"""Make kwargs of each registered id (its spec's variants): more than one where another code path is worth the
contract; the generic ids on connenv.examples' systems."""
RESET_OPTIONS = {spec.id: list(spec.starts) for spec in registry.values()}
"""Starts that take another code path (its spec's): the shell with a momentum is in the full (Kirchhoff) model."""


class Case(NamedTuple):
    env_id: str
    kwargs: dict | None  # None: the id is registered without a spec
    options: dict | None

    def make(self, **extra):
        return gym.make(self.env_id, **self.kwargs, **extra)


def label(env_id, kwargs, options):
    words = [f"{k}={v}" if isinstance(v, (str, int, float)) else k for k, v in (kwargs or {}).items()]
    words += [f"reset:{','.join(options['state'])}"] if options else []
    return "-".join([env_id.removeprefix("connenv/"), *words])


CASES = [
    Case(env_id, kwargs, options)
    for env_id in IDS
    for kwargs in CONTRACT_KWARGS.get(env_id, [None])
    for options in RESET_OPTIONS.get(env_id, [None])
]


@pytest.fixture(params=CASES, ids=[label(*case) for case in CASES])
def case(request):
    if request.param.kwargs is None:
        pytest.fail(
            f"{request.param.env_id} is registered but has no spec: declare it in its module's SPECS "
            "(connenv.envs.spec), with the make kwargs it is checked with"
        )
    return request.param


def leaves(tree, path=""):
    """[(path, array or string)] of an observation or info, dicts walked in sorted key order; None is left out."""
    if isinstance(tree, dict):
        return [leaf for key in sorted(tree) for leaf in leaves(tree[key], f"{path}.{key}")]
    if tree is None:
        return []
    return [(path, tree if isinstance(tree, str) else np.asarray(tree, float))]


def numbers(tree):
    return [x for _, value in leaves(tree) if not isinstance(value, str) for x in np.ravel(value)]


def flat_obs(obs):
    return np.asarray(numbers(obs))


def assert_identical(a, b):
    """Two step (or reset) results are the same to the bit: observation, reward, flags and every entry of info."""
    a, b = leaves(dict(enumerate(a))), leaves(dict(enumerate(b)))
    assert [path for path, _ in a] == [path for path, _ in b]
    for (path, x), (_, y) in zip(a, b):
        same = x == y if isinstance(x, str) else np.array_equal(x, y, equal_nan=True)
        assert same, (path, x, y)


UNBOUNDED = ("connenv/ActiveConstraint-v0", "connenv/Connection-v0")  # default observation: (q, p, u), (g, s), no bound


def test_gymnasium_and_sb3_checkers_pass_with_warnings_as_errors(case):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", OUT_OF_DATE, DeprecationWarning)
        if case.env_id in UNBOUNDED:  # the checkers warn of an infinite Box bound, which a user's system may need
            warnings.filterwarnings("ignore", message=".*Box observation space (minimum|maximum) value is")
        gym_check_env(case.make().unwrapped)
        env = case.make()
        # SB3's goal-env check calls env.compute_reward, which Gymnasium 1.x wrappers no longer forward
        sb3_check_env(env.unwrapped if hasattr(env.unwrapped, "compute_reward") else env, warn=True)


def test_a_seed_fixes_the_run_to_the_bit_and_another_seed_changes_it_and_every_number_is_finite(case, seeded_rollout):
    """Random actions for 300 steps, resets after every episode's end included; every number of the observations,
    rewards and infos is finite."""

    def rollout(seed):
        env = case.make()
        return seeded_rollout(env, seed, 300, numbers, case.options, flat_obs)

    a, b, c = rollout(7), rollout(7), rollout(8)
    assert np.isfinite(a).all() and np.isfinite(c).all()  # no NaN or inf leaves an env
    assert np.array_equal(a, b, equal_nan=True)
    assert not np.array_equal(a, c, equal_nan=True)


CLONES = {"pickle": lambda env: pickle.loads(pickle.dumps(env)), "deepcopy": copy.deepcopy}


@pytest.mark.parametrize("clone", CLONES.values(), ids=CLONES.keys())
@pytest.mark.parametrize(
    "when",
    [
        "after reset",
        "after steps",
        "after render",
    ],
)
def test_a_copy_continues_identically(case, clone, when):
    """A pickled or deep-copied env steps (and resets, where an episode ends) as the original, to the bit."""
    env = case.make(render_mode="rgb_array") if when == "after render" else case.make()
    env.reset(seed=3, options=case.options)
    env.action_space.seed(3)
    if when != "after reset":
        for _ in range(10):
            if any(env.step(env.action_space.sample())[2:4]):
                env.reset()
    if when == "after render":
        env.render()
    twin = clone(env)
    for _ in range(30):
        action = env.action_space.sample()
        a, b = env.step(action), twin.step(action)
        assert_identical(a, b)
        if a[2] or a[3]:
            assert_identical(env.reset(), twin.reset())


def test_the_vector_env_is_registered_with_next_step_autoreset(case):
    env = gym.make_vec(case.env_id, 5, vectorization_mode="vector_entry_point", **case.kwargs)
    assert env.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert env.action_space.shape == (5, *env.single_action_space.shape)
    obs, _ = env.reset(seed=0, options=case.options)
    assert env.observation_space.contains(obs)


def test_each_row_of_the_vector_env_is_the_single_env_over_episodes_and_autoresets(case, run_both, short_episodes):
    """Row i, seeded s + i, follows gym.make(env_id) reset with seed s + i, through NEXT_STEP autoresets, to 1e-12.
    short_episodes' kwargs, which override the case's, make both ways an episode ends happen; an id without an
    entry there (the generic envs, whose default task never terminates) is compared over truncations."""
    kwargs = {**case.kwargs, **short_episodes.get(case.env_id, {"max_episode_steps": 30})}
    terminated, truncated = run_both(case.env_id, 4, 100, 7, kwargs, options=case.options)
    assert truncated > 0
    assert terminated > 0 or case.env_id not in short_episodes


def test_every_info_has_is_success_a_bool_alone_and_one_per_row(case):
    """info["is_success"] is part of every env's info contract (agents.evaluate and SB3's success rate read it):
    a bool after reset and after every step of the single env, and a bool per row in the vector env's info."""
    env = case.make()
    _, info = env.reset(seed=0, options=case.options)
    env.action_space.seed(0)
    infos = [info] + [env.step(env.action_space.sample())[4] for _ in range(3)]
    assert all(isinstance(info["is_success"], (bool, np.bool_)) for info in infos)
    vector = gym.make_vec(case.env_id, 2, vectorization_mode="vector_entry_point", **case.kwargs)
    vector.action_space.seed(0)
    for vector_info in (vector.reset(seed=0, options=case.options)[1], vector.step(vector.action_space.sample())[4]):
        success = np.asarray(vector_info["is_success"])
        assert success.dtype == bool and success.shape == (2,)


def test_rgb_array_render_is_an_image(case):
    """At the start and after a few steps: an (H, W, 3) uint8 image with something drawn on its background."""
    env = case.make(render_mode="rgb_array")
    env.reset(seed=0, options=case.options)
    env.action_space.seed(0)
    for steps in (0, 5):
        for _ in range(steps):
            env.step(env.action_space.sample())
        frame = env.render()
        assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
        assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 2
    env.close()
