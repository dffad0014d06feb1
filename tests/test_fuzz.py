"""Fuzz over every registered id (issue 16): seeded random bad make kwargs, reset states and actions, a few
seconds per id. Each is refused with a ValueError naming the bad key, or else every number that leaves the env,
observation, reward and info, is finite.

Make kwargs are drawn among values that are no finite real, dt of any magnitude, and each number's default
scaled by up to 10 either way: the physical parameters' ranges are open above, so a mass of 1e300 is accepted
and its physics is not fuzzed here."""

from __future__ import annotations

import inspect
import math
import time
import zlib

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv import examples
from connenv.core.validation import init_parameters

IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))
BUDGET = 3.0  # s of fuzzing per id
STEPS = 5  # random steps after each accepted make or reset

STATE_KEYS = {  # reset state keys: the number of entries of each (0: a number)
    "connenv/Swing-v0": {"theta": 0, "theta_dot": 0, "p": 0, "r": 0},
    "connenv/Skier-v0": {"x": 0, "x_dot": 0, "p": 0, "h": 0},
    "connenv/RollingBall-v0": {"x": 0, "y": 0},
    "connenv/RollingBallPose-v0": {"x": 0, "y": 0},
    "connenv/RollingBallGoal-v0": {"x": 0, "y": 0},
    "connenv/KozlovShell-v0": {"x": 0, "y": 0, "theta": 0, "u": 2, "momentum": 3},
    "connenv/ChaplyginSleigh-v0": {key: 0 for key in ("x", "y", "phi", "v", "omega", "u", "u_dot", "u_along",
                                                         "u_along_dot")},
    "connenv/SnakeSwimmer-v0": {"x": 0, "y": 0, "theta": 0, "alpha": 0, "beta": 0, "momentum": 3},
    "connenv/KapitzaPendulum-v0": {"theta": 0, "theta_dot": 0, "p": 0, "u": 2, "u_dot": 2},
    "connenv/KapitzaSwingUp-v0": {"theta": 0, "theta_dot": 0, "p": 0, "u": 2, "u_dot": 2},
    "connenv/RollingCoinSurface-v0": {"x": 0, "y": 0, "theta": 0, "phi": 0, "phi_dot": 0},
    "connenv/ActiveConstraint-v0": {"q": 1, "p": 1, "u": 1},  # examples.swing(): n = m = 1
    "connenv/Connection-v0": {"s": 1},  # examples.beanie(): k = 1
    "connenv/RollingCoin-v0": {"x": 0, "y": 0, "theta": 0, "phi": 0},
    "connenv/ElroysBeanie-v0": {"theta": 0, "psi": 0, "momentum": 0},
    "connenv/BeadOnBar-v0": {"r": 0, "r_dot": 0, "theta": 0},
    "connenv/TubeTwist-v0": {},  # R: a rotation matrix (tests/test_tube_env.py)
    "connenv/FallingCat-v0": {"bend": 2},  # R: a rotation matrix (tests/test_falling_cat_env.py)
}
OPTION_KEYS = {  # reset options beside "state"
    "connenv/KozlovShell-v0": {"target": 2},
    "connenv/RollingCoin-v0": {"target": 3},
    "connenv/ElroysBeanie-v0": {"target": 0},
    "connenv/RollingCoinSurface-v0": {"target": 2},
    "connenv/BeadOnBar-v0": {"target": 0},
    "connenv/TubeTwist-v0": {"target": 0},
    "connenv/SnakeSwimmer-v0": {"target": 2},
    "connenv/ChaplyginSleigh-v0": {"target": 2},
}
NOT_NUMBERS = {"render_mode", "system", "connection", "task", "draw", "trail", "trail_params", "group", "frame",
               "control", "integrator", "pivot", "vectorized", "surface", "surface_params"}
INVALID = [math.nan, math.inf, -math.inf, "1", 1j, True, [1.0], 0.0]
SPECIAL = [*INVALID, None, -1.0, 1e308, -1e308, 1e-308, 1e30, -1e30]


def make_kwargs(env_id):
    return examples.MAKE_KWARGS[env_id]() if env_id in examples.MAKE_KWARGS else {}


def numeric_parameters(env_id):
    """The make kwargs of env_id that take a number (or None for a number): name -> default."""
    cls = gym.spec(env_id).entry_point
    module, name = cls.split(":")
    cls = getattr(__import__(module, fromlist=[name]), name)
    defaults = {}
    for klass in cls.__mro__:
        if "__init__" in vars(klass):
            for p in inspect.signature(klass.__init__).parameters.values():
                defaults.setdefault(p.name, p.default)
    names = [n for n in init_parameters(cls) if n not in NOT_NUMBERS]
    return {n: defaults.get(n) for n in names if isinstance(defaults.get(n), (int, float, type(None)))}


def bad_number(rng):
    """A special value, or a number of any magnitude and sign."""
    if rng.random() < 0.5:
        return SPECIAL[rng.integers(len(SPECIAL))]
    return float(rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-300, 300))


def bad_kwarg(rng, key, default):
    """A value no make kwarg takes (not a finite real), dt of any magnitude, or the default (1 where it is 0 or
    None) scaled by up to 10 either way and of either sign: a real number may lie inside the kwarg's range."""
    kind = rng.integers(3)
    if kind == 0:
        return INVALID[rng.integers(len(INVALID))]
    if kind == 1 and key == "dt":
        return float(10.0 ** rng.uniform(-300, 300))
    base = default if isinstance(default, (int, float)) and default else 1.0
    return float(rng.choice([-1.0, 1.0]) * base * 10.0 ** rng.uniform(-1, 1))


def bad_value(rng, size):
    """A bad number, or `size` entries one of which is bad (a wrong length now and then)."""
    if size == 0:
        return bad_number(rng)
    vector = list(rng.uniform(-0.1, 0.1, size + (rng.random() < 0.1)))
    vector[rng.integers(len(vector))] = bad_number(rng)
    return vector


def bad_action(rng, space):
    kind = rng.integers(5)
    if kind == 0:
        return SPECIAL[rng.integers(len(SPECIAL))]
    if kind == 1:
        return np.zeros(space.shape[0] + 1)
    a = list(rng.uniform(-1.0, 1.0, space.shape))
    a[rng.integers(len(a))] = bad_number(rng)
    return a


def numbers(tree):
    """Every number in an observation, reward or info (strings left out)."""
    if isinstance(tree, dict):
        return [x for value in tree.values() for x in numbers(value)]
    if tree is None or isinstance(tree, str):
        return []
    return list(np.ravel(np.asarray(tree, float)))


def assert_finite(what, *results):
    values = np.array([x for result in results for x in numbers(result)])
    assert np.all(np.isfinite(values)), f"{what}: a non-finite number left the env"


def refused(call, key):
    """Run call; True if it raised a ValueError that names key, False if it returned; any other outcome fails."""
    try:
        call()
    except ValueError as error:
        assert key in str(error), f"the ValueError does not name {key!r}: {error}"
        return True
    return False


def run(env, rng, what, options=None):
    """Reset with options and step random actions, every number finite."""
    result = env.reset(seed=int(rng.integers(2**31)), options=options)
    assert_finite(what + " reset", *result)
    env.action_space.seed(int(rng.integers(2**31)))
    for _ in range(STEPS):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert_finite(what + " step", obs, reward, info)
        if terminated or truncated:
            assert_finite(what + " reset", *env.reset())


@pytest.mark.parametrize("env_id", IDS)
def test_bad_kwargs_states_and_actions_are_refused_naming_the_key_or_leave_every_number_finite(env_id):
    rng = np.random.default_rng(zlib.crc32(env_id.encode()))
    kwargs, numeric = make_kwargs(env_id), numeric_parameters(env_id)
    env = gym.make(env_id, disable_env_checker=True, **kwargs)  # the checker trips over a reset that raised
    state_keys, option_keys = STATE_KEYS[env_id], OPTION_KEYS.get(env_id, {})
    deadline, cases = time.monotonic() + BUDGET, 0
    while time.monotonic() < deadline:
        kind = rng.integers(3)
        if kind == 0:
            key = list(numeric)[rng.integers(len(numeric))]
            value = bad_kwarg(rng, key, numeric[key])
            what = f"{env_id} with {key}={value!r}"
            made, changed = [], {**kwargs, key: value}
            if not refused(lambda: made.append(gym.make(env_id, disable_env_checker=True, **changed)), key):
                run(made[0], rng, what)
        elif kind == 1:
            key = list({**state_keys, **option_keys})[rng.integers(len(state_keys) + len(option_keys))]
            value = bad_value(rng, {**state_keys, **option_keys}[key])
            options = {key: value} if key in option_keys else {"state": {key: value}}
            what = f"{env_id} reset with {options}"
            if not refused(lambda: env.reset(options=options), key):
                run(env, rng, what, options)
        else:
            env.reset(seed=int(rng.integers(2**31)))
            action = bad_action(rng, env.action_space)
            step = []
            if not refused(lambda: step.append(env.step(action)), "action"):
                assert_finite(f"{env_id} step with action={action!r}", *step[0][:2], step[0][4])
        cases += 1
    assert cases >= 20, f"only {cases} cases in {BUDGET} s"
