"""Fuzz over every registered id (issue 16), and every input at the edges of float64 (issue 30).

The seeded random fuzz draws bad make kwargs, reset states and actions, a few seconds per id: each is refused
with a ValueError naming the bad key, or else every number that leaves the env, observation, reward and info, is
finite. Its make kwargs are values that are no finite real, dt of any magnitude, and each number's default scaled
by up to 10 either way.

The edge tests run cases of the bad-input audit (tests/audit.py, which runs them all: `python tests/audit.py`) with
few steps each: every numeric make kwarg at zero, the subnormals and powers of ten out to the largest float, and
given a string, a bool or a complex number; the stepper options; reset states and actions that are subnormal,
huge, non-finite, complex or of the wrong shape. Each is refused at make or reset (ValueError or TypeError naming
the argument, before the state moved) or runs with every number finite and no warning, single and vector env
alike. The two builders' make kwargs (ActiveConstraint-v0, Connection-v0) are left to their own tests."""

from __future__ import annotations

import math
import re
import time
import warnings
import zlib

import audit
import gymnasium as gym
import numpy as np
import pytest
from audit import OPTION_KEYS, STATE_KEYS, make_kwargs

import connenv  # noqa: F401  (registers the envs)
from connenv.core.integrators import SUBSTEPS_MAX
from connenv.envs.spec import registry

IDS = sorted(registry)  # every id with a spec
BUILDERS = tuple(spec.id for spec in registry.values() if spec.example)  # made with a worked system
BUDGET = 1.5  # s of fuzzing per id
STEPS = 5  # random steps after each accepted make or reset

INVALID = [math.nan, math.inf, -math.inf, "1", 1j, True, [1.0], 0.0]
SPECIAL = [*INVALID, None, -1.0, 1e308, -1e308, 1e-308, 1e30, -1e30]


def numeric_parameters(env_id):
    """The make kwargs of env_id that take a number (or None for a number): name -> default."""
    return {k: v for k, v in audit.numeric_parameters(env_id).items() if not isinstance(v, list)}


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
    assert cases >= 10, f"only {cases} cases in {BUDGET} s"


# -- the edges of float64 (issue 30): cases of tests/audit.py, few steps each --------------------------------------

EDGE_STEPS = 3  # random steps of an env made with an edge kwarg (then a reset); its vector env takes 2
MAGNITUDES = (5e-324, 1e-310, 1e-300, 1e-100, 1e-30, 1e-10, 1e10, 1e30, 1e100, 1e300, 1.7e308)
EDGES = [0.0, *MAGNITUDES, *(-m for m in MAGNITUDES)]
NOT_NUMBERS = ["1.0", True, 1 + 0j, np.complex128(2 + 3j), np.array([1.0])]


HANG = 30.0  # s a case may run before it counts as a hang (a bound of "does not hang", not a timing)


def open_cases(cases):
    """The audit's verdict on each case; the cases that ended neither in a clear error nor in a finite run."""
    verdicts = [(case, audit.judge(case, timeout=HANG)) for case in cases]
    return [f"{case.what[:120]}: {verdict.detail}" for case, verdict in verdicts if verdict.kind == "open"]


@pytest.mark.parametrize("env_id", [env_id for env_id in IDS if env_id not in BUILDERS])
def test_every_numeric_kwarg_at_the_float64_edges_is_refused_naming_it_or_runs_finite_single_and_vector(env_id):
    """Zero, subnormals, powers of ten out to the largest float, either sign, and values that are no real number
    (a string, a bool, complex numbers, an array): refused at make naming the kwarg, or reset and stepped with
    every number finite and no warning, by the single env and the vector env."""
    cases = audit.make_kwarg_cases([env_id], values=EDGES + NOT_NUMBERS, steps=EDGE_STEPS, vector_steps=2)
    assert open_cases(cases) == []


@pytest.mark.parametrize("env_id", IDS)
def test_stepper_options_out_of_their_ranges_are_refused_at_make(env_id):
    """substeps beyond SUBSTEPS_MAX (10⁹ stalled a step), rtol below scipy's floor, atol at the float64 edges:
    refused at make naming the option; within the ranges the env steps."""
    values = {"substeps": [0, 1, SUBSTEPS_MAX + 1, 10**9, 2**63, 2.0],
              "rtol": [5e-324, 1e-15, 1e-8, 2.0, 1e300], "atol": [5e-324, 1e-150, 1e-8, 1e150, 1.7e308]}
    assert open_cases(audit.stepper_cases([env_id], values=values)) == []


@pytest.mark.parametrize("env_id", IDS)
def test_reset_states_subnormal_huge_complex_or_of_the_wrong_type_are_refused_or_run_finite(env_id):
    """Every reset state key and option at the edge numbers, non-finite, complex (numpy casts a complex array to
    its real part with only a warning), a string or a bool, of the wrong shape; rotations given complex: refused
    at reset naming the key, or stepped finite without a warning."""
    assert open_cases(audit.reset_cases([env_id])) == []


@pytest.mark.parametrize("env_id", IDS)
def test_actions_subnormal_huge_non_finite_or_complex_step_finite_without_warnings_single_and_vector(env_id):
    """From rest, an action with an entry (or all) subnormal, huge, non-finite, complex, of the wrong shape or
    type: refused naming the action with the state unchanged, or stepped three times with every number finite
    and no warning (a subnormal joint command once divided by zero in SnakeSwimmer-v0, and leaked overflow
    warnings from the vector envs' segments)."""
    assert open_cases(audit.action_cases([env_id])) == []


EDGE_REGRESSIONS = [  # (env_id, make kwargs): issue 30's cases, each once an exception other than ValueError
    ("connenv/Swing-v0", {"r_max": 1e300}),  # OverflowError
    ("connenv/Swing-v0", {"r_min": 1e-300}),  # OverflowError
    ("connenv/KozlovShell-v0", {"a": 1e300}),  # OverflowError
    ("connenv/KozlovShell-v0", {"b": 1e-300}),  # OverflowError
    ("connenv/KozlovShell-v0", {"u1_max": 1e300}),  # OverflowError
    ("connenv/KapitzaPendulum-v0", {"length": 1e300}),  # OverflowError
    ("connenv/KapitzaPendulum-v0", {"v_max": 1e300}),  # OverflowError at the first step
    ("connenv/KapitzaPendulum-v0", {"tolerance": 1e-300}),  # OverflowError; the vector env's rewards -inf
    ("connenv/FallingCat-v0", {"max_bend": 1e-300}),  # ZeroDivisionError
    ("connenv/Skier-v0", {"g": 1e300}),  # StepperError at the first step
    ("connenv/Skier-v0", {"substeps": 10**9}),  # a step stalled
    ("connenv/ChaplyginSleigh-v0", {"substeps": 10**9}),
    ("connenv/RollingCoinSurface-v0", {"substeps": 10**9}),
]


@pytest.mark.parametrize(("env_id", "kwargs"), EDGE_REGRESSIONS, ids=[f"{c[0][8:]}-{c[1]}" for c in EDGE_REGRESSIONS])
def test_issue_30s_edge_kwargs_are_value_errors_at_make_naming_kwarg_value_and_range_single_and_vector(env_id, kwargs):
    (key, value), = kwargs.items()
    for make in (gym.make, lambda env_id, **kw: gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point", **kw)):
        with pytest.raises(ValueError, match=rf"^{re.escape(f'{key}={value!r}')} .*\[") as error:
            make(env_id, **kwargs)
        assert "must" in str(error.value)


def test_a_subnormal_joint_command_from_rest_leaves_the_snake_where_it_was():
    """(1e-310, 0) from rest: a move below what floats resolve is none, single and vector (it raised "math domain
    error", and StepperError on NaN in the vector env)."""
    single = gym.make("connenv/SnakeSwimmer-v0")
    single.reset(seed=0)
    info = single.step(np.array([1e-310, 0.0]))[4]
    assert info["state"]["x"] == info["state"]["y"] == info["state"]["theta"] == 0.0
    vector = gym.make_vec("connenv/SnakeSwimmer-v0", 2, vectorization_mode="vector_entry_point")
    vector.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", audit.OUT_OF_DATE, DeprecationWarning)
        info = vector.step(np.array([[1e-310, 0.0], [0.5, 0.0]]))[4]
    assert info["state"]["x"][0] == 0.0 and info["state"]["x"][1] != 0.0


def test_a_step_at_the_most_substeps_ends_within_a_generous_bound():
    """SUBSTEPS_MAX substeps on the env whose steps cost most per substep (RK8 with its energy projection): a step
    ends, where 10⁹ substeps stalled for minutes. A bound of "does not hang", not a timing."""
    env = gym.make("connenv/Skier-v0", substeps=SUBSTEPS_MAX)
    env.reset(seed=0)
    start = time.monotonic()
    env.step(np.array([1.0]))
    assert time.monotonic() - start < 30.0


@pytest.mark.parametrize("bad", ["1.0", True, 1 + 0j, np.array([1.0 + 0j]), [True]], ids=repr)
def test_a_bound_that_is_no_real_number_is_refused_naming_it(bad):
    """The shared check of bounds (the builders' u_low, u_high, shape_low, shape_high) refuses what numpy's cast
    would take: a numeric string, a bool, a complex number (u_low="1.0" and u_low=True were accepted)."""
    with pytest.raises(ValueError, match=r"^u_low=.* (must be|is complex; expected) real numbers"):
        gym.make("connenv/ActiveConstraint-v0", **{**make_kwargs("connenv/ActiveConstraint-v0"), "u_low": bad})
