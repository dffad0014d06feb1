"""env.unwrapped.model for every registered id: its step is the env's to the bit (single and rows), its Jacobians
are the derivatives of that step, its state, reward and termination are the env's."""

from __future__ import annotations

import math
import pickle
import re

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from connenv.core.steppers import StepperError
from connenv.envs.spec import registry

IDS = sorted(registry)
ROWS = 3
RELATIVE = 1e-6  # the Jacobians' agreement with central differences, relative to each column's largest entry
FLOAT32_DERIVED = {"goal_error"}  # RollingBallGoal-v0's angle between its float32 goals: differences see the rounding


def make(env_id, **kwargs):
    return gym.make(env_id, **registry[env_id].make_kwargs(), **kwargs).unwrapped


def vector(env_id):
    return gym.make_vec(env_id, num_envs=ROWS, vectorization_mode="vector_entry_point",
                        **registry[env_id].make_kwargs())  # fmt: skip


def walked(env_id, steps=3):
    """A single env a few random steps from a seeded reset, and the actions' generator."""
    env = make(env_id)
    env.reset(seed=11)
    env.action_space.seed(11)
    for _ in range(steps):
        env.step(0.8 * env.action_space.sample())
    return env


@pytest.mark.parametrize("env_id", IDS)
def test_the_model_steps_one_state_as_the_env_to_the_bit(env_id):
    env = walked(env_id, steps=0)
    model = env.model
    for _ in range(5):
        a = 0.8 * env.action_space.sample()
        x = model.pack(env.state)
        _, reward, terminated, _, _ = env.step(a)
        x_next = model.step(x, a)
        assert np.array_equal(x_next, model.pack(env.state), equal_nan=True)
        assert model.reward(x, a, x_next) == reward and model.terminated(x_next) == terminated


@pytest.mark.parametrize("env_id", IDS)
def test_the_model_steps_rows_as_the_vector_env_to_the_bit(env_id):
    envs = vector(env_id)
    envs.reset(seed=3)
    model = make(env_id).model
    actions = 0.8 * envs.action_space.sample()
    x = model.pack(envs.state)
    _, reward, terminated, _, _ = envs.step(actions)
    x_next = model.step(x, actions)
    assert x.shape == (ROWS, model.n) and np.array_equal(x_next, model.pack(envs.state), equal_nan=True)
    assert np.array_equal(model.reward(x, actions, x_next), reward)
    assert np.array_equal(model.terminated(x_next), terminated)


def jacobian_case(env_id):
    """A model, rows x after a few random steps from a seeded reset, actions a, the float64 entries (the rows
    compared: float32 copies of the state, such as the goals of a goal env, carry its rounding) that are no NaN."""
    envs = vector(env_id)
    envs.reset(seed=5)
    for _ in range(3):
        envs.step(0.8 * envs.action_space.sample())
    model = make(env_id).model
    x, a = model.pack(envs.state), (0.8 * envs.action_space.sample()).astype(float)
    compared = np.array([e.dtype == np.float64 and e.name not in FLOAT32_DERIVED for e in model.entries
                         for _ in range(e.size)])
    return model, x, a, compared & ~np.isnan(x).any(axis=0)


def assert_close(exact, central, name):
    scale = np.max(np.abs(central))
    assert np.max(np.abs(exact - central)) <= RELATIVE * scale + 1e-9, f"∂x_next/∂{name}"


@pytest.mark.parametrize("env_id", IDS)
def test_the_action_jacobian_is_the_steps_derivative(env_id):
    """∂x_next/∂a by complex step against central differences in each action entry, h = 1e-5."""
    model, x, a, rows = jacobian_case(env_id)
    _, B = model.jacobians(x, a)
    assert B.shape == (ROWS, model.n, model.m)
    for j in range(model.m):
        up, down = a.copy().reshape(ROWS, -1), a.copy().reshape(ROWS, -1)
        up[:, j] += 1e-5
        down[:, j] -= 1e-5
        central = (model.step(x, up.reshape(a.shape)) - model.step(x, down.reshape(a.shape)))[:, rows] / 2e-5
        assert_close(B[:, rows, j], central, f"action {j}")


@pytest.mark.parametrize("env_id", IDS)
def test_the_state_jacobian_carries_reachable_moves_as_the_step_does(env_id):
    """A(x₁, a₁) · B(x₀, a₀) d against central differences of ε ↦ step(step(x₀, a₀ + ε d), a₁): a move of the
    state the env can make, which keeps an attitude on its group, as moving one entry of it alone would not."""
    model, x0, a0, rows = jacobian_case(env_id)
    rng = np.random.default_rng(0)
    d = rng.uniform(-1.0, 1.0, a0.shape)
    a1 = np.clip(a0[::-1] + 0.1, -0.8, 0.8)
    x1 = model.step(x0, a0)
    (A, _), (_, B0) = model.jacobians(x1, a1), model.jacobians(x0, a0)
    moved = np.einsum("nij,nj->ni", B0, d.reshape(ROWS, -1))
    step = lambda e: model.step(model.step(x0, a0 + e * d), a1)  # noqa: E731
    central = (step(1e-5) - step(-1e-5))[:, rows] / 2e-5
    assert_close(np.einsum("nij,nj->ni", A, moved)[:, rows], central, "x along B d")


@pytest.mark.parametrize("env_id", IDS)
def test_the_state_jacobian_is_the_steps_derivative_in_each_free_entry(env_id):
    """∂x_next/∂x_j against central differences, h = 1e-6 max(1, |x_j|), for every entry that can move alone: an
    entry of an attitude cannot (the step refuses a state off its group), and the test above covers it."""
    model, x, a, rows = jacobian_case(env_id)
    A, _ = model.jacobians(x, a)
    assert A.shape == (ROWS, model.n, model.n)
    free = [j for j in np.flatnonzero([e.real for e in model.entries for _ in range(e.size)])]
    checked = 0
    for j in free:
        h = 1e-6 * max(1.0, np.max(np.abs(x[:, j])))
        up, down = x.copy(), x.copy()
        up[:, j] += h
        down[:, j] -= h
        try:
            central = (model.step(up, a) - model.step(down, a))[:, rows] / (2 * h)
        except StepperError as error:
            assert "off" in str(error) or "left" in str(error)  # off its group: only an attitude's entry
            continue
        assert_close(A[:, rows, j], central, model.state_names[j])
        checked += 1
    assert checked >= 1


@pytest.mark.parametrize("env_id", IDS)
def test_the_state_vector_holds_the_task_state_and_reads_back_the_info(env_id):
    env = walked(env_id)
    model = env.model
    x = model.pack(env.state)
    assert x.dtype == np.float64 and x.shape == (model.n,) == (len(model.state_names),)
    assert np.array_equal(model.pack(model.unpack(x)), x, equal_nan=True)
    read, reported = model.info(x)["state"], env.describe(env.state)["state"]
    assert read.keys() == reported.keys()
    assert all(np.array_equal(read[k], reported[k], equal_nan=True) for k in read)


def test_the_swing_step_is_symplectic_where_the_radius_is_held():
    """At held r the exact flow of (θ, p) is Hamiltonian: det ∂(θ′, p′)/∂(θ, p) = 1."""
    env = walked("connenv/Swing-v0")
    model = env.model
    x = model.pack(env.state)
    r = model.unpack(x)["r"]
    a = np.array([2.0 * (r - env.r_min) / (env.r_max - env.r_min) - 1.0])  # the action that holds r
    A, _ = model.jacobians(x, a)
    y = [model.state_names.index(name) for name in ("theta", "p")]
    assert np.linalg.det(A[np.ix_(y, y)]) == pytest.approx(1.0, abs=1e-12)


def test_rows_with_their_own_params_step_as_the_models_of_those_params():
    """Each row on the single env's path of its own values, as the vector env steps such rows."""
    env = walked("connenv/Swing-v0")
    model = env.model
    x = np.repeat(model.pack(env.state)[None], 3, axis=0)
    a = np.zeros((3, 1))
    params = [{"g": 9.81}, {"g": 3.7}, {"g": 3.7, "mass": 2.0}]
    x_next = model.step(x, a, params=params)
    for i, p in enumerate(params):
        assert np.array_equal(x_next[i], model.with_params(p).step(x[i], a[i]))
    assert not np.array_equal(x_next[0], x_next[1])
    assert model.with_params({"g": 3.7}).params.g == 3.7 and model.params.g == 9.81


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda m: m.step(np.zeros(m.n + 1), np.zeros(1)), "state x of shape"),
        # issue 44 §2: each once accepted, a result of NaN or complex numbers, or another exception
        (lambda m: m.step(X(m) + 1e-3j, np.zeros((2, 1))), "state x complex"),
        (lambda m: m.step(X(m)[0] + 1e-3j, np.zeros(1)), "state x complex"),
        (lambda m: m.jacobians(X(m) + 1e-3j, np.zeros((2, 1))), "state x complex"),
        (lambda m: m.step(X(m)[0].tolist()[:-1] + ["0"], np.zeros(1)), "state x=.* must be real numbers"),
        (lambda m: m.jacobians(X(m)[0], ["0.3"]), r"action a=\['0.3'\] must be real numbers"),
        (lambda m: m.jacobians(X(m)[0], [0.3 + 1e-3j]), "action a=.* is complex"),
        (lambda m: m.step(X(m), np.full((2, 1), 0.3 + 0j)), "(?s)action a=.* is complex"),
        (lambda m: m.step(X(m), np.zeros((2, 1)), params=[{"g": "9"}, {"g": 9.0}]),
         "params: g='9' must be a real number in"),
        (lambda m: m.step(X(m)[:0], np.zeros((0, 1))), r"state x of shape \(0, 7\)"),
        (lambda m: m.step(X(m)[:0], np.zeros((0, 1)), params=[]), r"state x of shape \(0, 7\)"),
        (lambda m: m.jacobians(X(m)[:0], np.zeros((0, 1)), params=[]), r"state x of shape \(0, 7\)"),
        (lambda m: m.step(X(m), np.zeros(3)), r"action a has shape \(3,\); expected real numbers of shape \(2, 1\)"),
        (lambda m: m.jacobians(X(m)[0], np.zeros(3)), r"action a has shape \(3,\); expected .* shape \(1,\)"),
        (lambda m: m.jacobians(X(m)[0], None), "action a=None must be real numbers"),
        (lambda m: m.step(X(m)[0], None), "action a=None must be real numbers"),
        (lambda m: m.step(X(m), np.zeros((2, 1)), params=5), "params=5 must be a dict"),
        (lambda m: m.step(X(m)[0], np.zeros(1), params={"g": [1, 2]}), r"params: g=\[1, 2\] must be a real number in"),
        (lambda m: m.step(X(m)[0], np.zeros(1), params={"mass": True}), "params: mass=True must be a real number in"),
        (lambda m: m.with_params({"g": math.nan}), "params: g=nan must be a real number in"),
        (lambda m: m.with_params("g"), "params='g' must be a dict"),
        (lambda m: m.with_params(5), "params=5 must be a dict"),
        (lambda m: m.with_params(None), "params=None must be a dict"),
        (lambda m: m.pack({}), r"state has the fields \[\]; expected those of Swing-v0's SwingState"),
        (lambda m: m.pack("abc"), "state='abc' must be a SwingState of Swing-v0"),
        (lambda m: m.reward(X(m)[0], np.zeros(1), X(m)), r"state x of shape \(7,\) and state x_next of shape \(2, 7\)"),
        (lambda m: m.terminated(X(m)[0, :3]), r"state x of shape \(3,\)"),
        (lambda m: m.step(np.full(m.n, math.inf), np.zeros(1)), r"x\[0\] \(theta\) = inf is not finite"),
        (lambda m: m.with_params({"radius": 1.0}), "not physical parameters"),
        (lambda m: m.step(np.zeros((2, m.n)), np.zeros((2, 1)), params=[{}]), "per-row params"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises((ValueError, TypeError), match=message):
        call(make("connenv/Swing-v0").model)


def X(model):
    """Two rows of the model's env at its reset."""
    return np.repeat(model.pack(model.env.state)[None], 2, axis=0)


@pytest.mark.parametrize("env_id", IDS)
def test_a_nan_in_any_entry_is_refused_naming_it_but_where_the_task_declares_it_unmeasured(env_id):
    """NaN was taken in every entry (and came out NaN, or was absorbed); a task's "not measured" (the ball's
    distance, `State.unmeasured`) is the one place it is a value."""
    env = walked(env_id, steps=1)
    model = env.model
    x, a = model.pack(env.state), np.zeros(env.action_space.shape)
    allowed = [name for e in model.entries if e.name in type(env.state).unmeasured for name in e.names(
        model.components)]  # fmt: skip
    for j, name in enumerate(model.state_names):
        bad = x.copy()
        bad[j] = math.nan
        if name in allowed:
            assert np.isnan(model.step(bad, a)[j])
            continue
        for call in (lambda: model.step(bad, a), lambda: model.jacobians(bad[None], a[None]),
                     lambda: model.reward(x, a, bad), lambda: model.terminated(bad), lambda: model.info(bad)):
            with pytest.raises(ValueError, match=rf"state x(_next)?\[{j}\] \({re.escape(name)}\) = nan"):
                call()


@pytest.mark.parametrize(("env_id", "entry", "value"), [
    ("connenv/BeadOnBar-v1", "inside", 0.5), ("connenv/BeadOnBar-v1", "inside", 2.0),
    ("connenv/KapitzaSwingUp-v0", "upright_steps", 0.5), ("connenv/SnakeSwimmer-v0", "full", -1.0),
])
def test_a_flag_or_counter_that_is_no_whole_number_is_refused(env_id, entry, value):
    """x[inside] = 0.5 read as True and upright_steps = 0.5 as 0: a flag is 0 or 1, a counter a whole number."""
    model = make(env_id).model
    x = model.pack(model.env.state)
    j = model.state_names.index(entry)
    x[j] = value
    with pytest.raises(ValueError, match=rf"x\[{j}\] \({entry}\) = {value} .*must be"):
        model.step(x, np.zeros(model.env.action_space.shape))


@pytest.mark.parametrize("env_id", ["connenv/KapitzaPendulum-v0", "connenv/RollingBall-v0"])
def test_a_step_that_overflows_is_a_stepper_error_on_one_state_and_on_rows(env_id):
    """A momentum (an attitude's entry) of 1e300 raised OverflowError on one state, StepperError (or a warning and
    a result) on rows."""
    model = make(env_id).model
    x = model.pack(model.env.state)
    x[1 if env_id.endswith("Pendulum-v0") else model.state_names.index("R_target[0,1]")] = 1e300
    a = np.zeros(model.env.action_space.shape)
    for y, b in ((x, a), (x[None], a[None])):
        with pytest.raises(StepperError):
            model.step(y, b)


@pytest.mark.parametrize("env_id", IDS)
def test_a_model_pickles_and_its_copy_steps_to_the_bit(env_id):
    """A model goes to worker processes (Ray, a process pool) by pickle: its Params class is made at run time."""
    env = walked(env_id)
    model = env.model
    copy = pickle.loads(pickle.dumps(model))
    x, a = model.pack(env.state), 0.8 * env.action_space.sample()
    assert copy.params == model.params and copy.state_names == model.state_names
    assert np.array_equal(copy.step(x, a), model.step(x, a), equal_nan=True)
    assert pickle.loads(pickle.dumps(model.params)) == model.params


FLOAT32_STEP = 1e-3  # the central differences' step on float32 entries: their rounding (6e-8) over it is 6e-5
FLOAT32_RELATIVE = 1e-3


@pytest.mark.parametrize("env_id", [i for i in IDS if any(e.dtype == np.float32 for e in make(i).model.entries)])
def test_the_jacobian_rows_of_float32_entries_carry_the_derivative_through_the_rounding(env_id):
    """RollingBallGoal-v0's goals are float32: their rows of ∂x_next/∂a were 0 (complex64 flushed the complex step
    to 0) where central differences give 0.1 to 1. The rounding's derivative is 1: rows of float32 entries (and of
    the angle between them) against central differences with a step their rounding allows."""
    model, x, a, _ = jacobian_case(env_id)
    rows = np.array([e.dtype == np.float32 or e.name in FLOAT32_DERIVED for e in model.entries
                     for _ in range(e.size)])  # fmt: skip
    _, B = model.jacobians(x, a)
    for j in range(model.m):
        up, down = a.copy().reshape(ROWS, -1), a.copy().reshape(ROWS, -1)
        up[:, j] += FLOAT32_STEP
        down[:, j] -= FLOAT32_STEP
        central = (model.step(x, up.reshape(a.shape)) - model.step(x, down.reshape(a.shape)))[:, rows]
        central /= 2 * FLOAT32_STEP
        assert np.max(np.abs(central)) > 0.01  # a column that moves: 0 was the bug
        assert np.max(np.abs(B[:, rows, j] - central)) <= FLOAT32_RELATIVE * np.max(np.abs(central))
