"""ActiveConstraint-v0: a user's system from its Lagrangian, checked against hand-built envs and closed forms."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
import sympy as sp
from gymnasium.utils.env_checker import check_env

from connenv import ActiveConstraintEnv, examples
from connenv.core import JumpClass, classify
from connenv.core.lagrangian import LagrangianSystem
from connenv.core.segments import bounded_segments, bounded_segments_batch

ID = "connenv/ActiveConstraint-v0"
G = 9.81
theta, theta_dot, r, r_dot, u, u_dot = sp.symbols("theta theta_dot r r_dot u u_dot")
I, J = 2.0, 0.5  # the rotor body's moments of inertia, body and rotor


def swing_system(mass=1.0):
    return LagrangianSystem(mass * (r_dot**2 + r**2 * theta_dot**2) / 2, -mass * G * r * sp.cos(theta), [theta], [r])


def rotor_system():
    return LagrangianSystem(I * theta_dot**2 / 2 + J * (theta_dot + u_dot) ** 2 / 2, 0, [theta], [u])


def bead_system():
    return LagrangianSystem((r_dot**2 + r**2 * theta_dot**2) / 2, G * r * sp.sin(theta), [r], [theta])


@pytest.mark.parametrize(
    "make, expected, q_range, u_range",
    [
        (swing_system, JumpClass.STRONGLY_FIT, (-2, 2), (1, 2)),
        (rotor_system, JumpClass.FIT, (-2, 2), (-2, 2)),
        (bead_system, JumpClass.GENERAL, (-2, 2), (-1, 1)),
    ],
)
def test_symbolic_class_agrees_with_sampling(make, expected, q_range, u_range):
    system = make()
    assert system.jump_class is expected
    q, uu = np.linspace(*q_range, 4)[:, None], np.linspace(*u_range, 3)[:, None]
    assert classify(system, q, uu) is expected


def test_swing_from_its_lagrangian_reproduces_swing_v0():
    """Same commands, same (θ, p): the generic DOP853 flow against Swing-v0's closed-form elliptic flow."""
    swing = gym.make("connenv/Swing-v0", integrator="exact").unwrapped
    generic = ActiveConstraintEnv(swing_system(), 1.6, 2.0, integrator="dop853", rtol=1e-12, atol=1e-14)
    assert generic.jump_class is JumpClass.STRONGLY_FIT and generic.control == "position"
    swing.reset(options={"state": {"theta": 0.4, "p": 0.0, "r": 2.0}})
    generic.reset(options={"state": {"q": [0.4], "p": [0.0], "u": [2.0]}})
    rng = np.random.default_rng(0)
    for _ in range(60):
        action = rng.uniform(-1, 1, 1).astype(np.float32)
        *_, info = swing.step(action)
        *_, generic_info = generic.step(action)
        state = generic_info["state"]
        assert state["u"][0] == pytest.approx(info["state"]["r"], abs=1e-15)
        assert abs(state["q"][0] - info["state"]["theta"]) < 1e-10
        assert abs(state["p"][0] - info["state"]["p"]) < 1e-10


@pytest.mark.parametrize("delta_u", [0.3, -2.0])
def test_rotor_jump_turns_the_body_by_the_connection(delta_u):
    """At p = 0 a jump Δu of the rotor turns the body by −J Δu/(I + J); p stays 0 (K constant)."""
    env = ActiveConstraintEnv.from_lagrangian(
        I * theta_dot**2 / 2 + J * (theta_dot + u_dot) ** 2 / 2, 0, [theta], [u], u_low=-3.0, u_high=3.0
    )
    assert env.jump_class is JumpClass.FIT
    env.reset(options={"state": {"q": [0.7], "u": [1.0]}})
    action = np.array([(1.0 + delta_u + 3.0) / 3.0 - 1.0])  # commands u = 1 + Δu
    *_, info = env.step(action)
    assert info["state"]["u"][0] == pytest.approx(1.0 + delta_u, abs=1e-15)
    assert abs(info["state"]["q"][0] - (0.7 - J * delta_u / (I + J))) < 1e-12
    assert info["state"]["p"][0] == 0.0


def test_bead_at_constant_bar_speed_follows_the_closed_form():
    """θ̇ = ω from rest: r(t) = A cosh ωt + B sinh ωt + (g/2ω²) sin(θ₀ + ωt)."""
    omega, r0, theta0 = 0.6, 0.3, 0.2
    env = ActiveConstraintEnv(bead_system(), -np.inf, np.inf, max_control_speed=1.0)
    assert env.jump_class is JumpClass.GENERAL and env.control == "velocity"
    env.reset(options={"state": {"q": [r0], "u": [theta0]}})
    c = G / (2 * omega**2)
    A, B = r0 - c * math.sin(theta0), -c * math.cos(theta0)
    for _ in range(40):
        *_, info = env.step(np.array([omega]))
        t = info["state"]["t"]
        closed = A * math.cosh(omega * t) + B * math.sinh(omega * t) + c * math.sin(theta0 + omega * t)
        speed = omega * (A * math.sinh(omega * t) + B * math.cosh(omega * t) + c * math.cos(theta0 + omega * t))
        assert abs(info["state"]["q"][0] - closed) < 1e-9
        assert abs(info["state"]["p"][0] - speed) < 1e-9
        assert info["state"]["u"][0] == pytest.approx(theta0 + omega * t, rel=1e-14)


class TwoByTwo:
    """A system given by its metric: n = m = 1 with G11, G12, G22 as given (constant)."""

    n, m = 1, 1

    def __init__(self, G11, G12, G22, n=1, m=1):
        self.blocks, self.n, self.m = [np.asarray(b, float) for b in (G11, G12, G22)], n, m

    def metric(self, q, u):
        return tuple(np.broadcast_to(b, q.shape[:-1] + b.shape) for b in self.blocks)

    def potential(self, q, u):
        return 0.0 * q[..., 0]


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: ActiveConstraintEnv.from_lagrangian(sp.Symbol("M") * theta_dot**2 / 2, 0, [theta], [u], u_low=0,
                                                     u_high=1), r"\['M'\].*not in q"),
        (lambda: ActiveConstraintEnv.from_lagrangian(theta_dot**2 / 2 + u_dot**2, u_dot, [theta], [u], u_low=0,
                                                     u_high=1), r"\['u_dot'\].*not in q"),
        (lambda: ActiveConstraintEnv.from_lagrangian(theta_dot**4 + u_dot**2, 0, [theta], [u], u_low=0, u_high=1),
         "not a quadratic form"),
        (lambda: ActiveConstraintEnv.from_lagrangian(theta_dot**2 + u_dot**2, sp.sign(theta), [theta], [u], u_low=0,
                                                     u_high=1), "derivative sympy cannot evaluate"),
        (lambda: ActiveConstraintEnv(TwoByTwo([[1, 0.5], [0.2, 1]], [[0], [0]], [[1]], n=2), 0, 1),
         "G11 .* not symmetric"),
        (lambda: ActiveConstraintEnv(TwoByTwo([[-1]], [[0]], [[1]]), 0, 1), "G11 .* not positive definite"),
        (lambda: ActiveConstraintEnv(TwoByTwo([[1]], [[2]], [[1]]), 0, 1), "not positive semidefinite"),
        (lambda: ActiveConstraintEnv(TwoByTwo([[1]], [[0, 0]], [[1]]), 0, 1), r"G12 has shape \(1, 2\).*\(1, 1\)"),
        (lambda: ActiveConstraintEnv(object(), 0, 1), "must have integer attributes n, m"),
        (lambda: ActiveConstraintEnv(bead_system(), -1, 1, control="position"), "'general'.*speed.*'velocity'"),
        (lambda: ActiveConstraintEnv(bead_system(), -1, 1), "default for a system of class 'general'.*speed"),
        (lambda: ActiveConstraintEnv(rotor_system(), -np.inf, np.inf), "needs finite bounds"),
        (lambda: ActiveConstraintEnv(rotor_system(), 1, -1), "u_low=1 must be below u_high=-1"),
        (lambda: ActiveConstraintEnv(rotor_system(), 0, 1, control="velocity"), "needs max_control_speed"),
    ],
)
def test_bad_systems_are_refused_at_construction(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_a_swing_whose_radius_may_reach_zero_is_refused_without_a_numpy_warning():
    """At r = 0 the swing's G11 = r² vanishes, the zero matrix: θ̇ costs no kinetic energy, and the metric check
    names the point (a zero matrix has no scale to compare its lowest eigenvalue with)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"G11 = \[\[0\.0\]\] .* u = \[0\.\] is not positive definite"):
            gym.make("connenv/ActiveConstraint-v0", **{**examples.swing(), "u_low": 0.0})


def test_reset_state_is_set_exactly_and_checked():
    env = ActiveConstraintEnv(rotor_system(), -1.0, 2.0)
    _, info = env.reset()
    assert info["state"]["u"][0] == 0.5 and info["state"]["q"][0] == 0.0 and info["state"]["t"] == 0.0
    _, info = env.reset(options={"state": {"q": [0.25], "p": [-1.5]}})
    assert (info["state"]["q"][0], info["state"]["p"][0], info["state"]["u"][0]) == (0.25, -1.5, 0.5)
    with pytest.raises(ValueError, match=r"state u\[0\]=.*out of range"):
        env.reset(options={"state": {"u": [3.0]}})
    with pytest.raises(ValueError, match="state q=.*1 finite"):
        env.reset(options={"state": {"q": [np.nan]}})


class StopAtQuarterTurn:
    """A task: from a random angle, turn the rotor body to θ = π/2."""

    def reset(self, np_random):
        return {"q": np_random.uniform(-0.5, 0.5, 1), "p": np_random.uniform(-0.2, 0.2, 1)}

    def reward(self, state, next_state):
        return -abs(next_state["q"][0] - math.pi / 2)

    def terminated(self, state):
        return abs(state["q"][0] - math.pi / 2) < 0.05


KWARGS = {
    "rotor": dict(u_low=-math.pi, u_high=math.pi, task=StopAtQuarterTurn()),
    "rotor_ramp": dict(u_low=-1.0, u_high=1.0, max_control_speed=3.0),
    "bead": dict(u_low=-0.5, u_high=0.8, max_control_speed=2.0, task=StopAtQuarterTurn()),
}


def make_kwargs(name):
    return {"system": bead_system() if name == "bead" else rotor_system(), **KWARGS[name]}


@pytest.mark.parametrize("name", sorted(KWARGS))
def test_checkers_pass(name):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(ID, max_episode_steps=50, **make_kwargs(name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the unbounded observation Box is by design
        check_env(env.unwrapped)
        sb3_check_env(env.unwrapped)


@pytest.mark.parametrize("name", sorted(KWARGS))
def test_vector_env_rows_equal_single_envs(name):
    N, steps = 3, 25
    vector = gym.make_vec(ID, N, vectorization_mode="vector_entry_point", max_episode_steps=10, **make_kwargs(name))
    singles = [gym.make(ID, max_episode_steps=10, **make_kwargs(name)) for _ in range(N)]
    obs, _ = vector.reset(seed=7)
    single_obs = [env.reset(seed=7 + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    rng = np.random.default_rng(1)
    for _ in range(steps):
        actions = rng.uniform(-1, 1, (N, vector.single_action_space.shape[0]))
        restarting = vector.prev_done.copy()  # these rows reset in this step, with the generators they have
        obs, reward, terminated, truncated, info = vector.step(actions)
        for i, env in enumerate(singles):
            if restarting[i]:
                o, inf = env.reset()
                rew, term, trunc = 0.0, False, False
            else:
                o, rew, term, trunc, inf = env.step(actions[i])
            for key in ("q", "p", "u"):
                np.testing.assert_allclose(info["state"][key][i], inf["state"][key], rtol=0, atol=1e-12)
            assert (reward[i], terminated[i], truncated[i]) == pytest.approx((rew, term, trunc), abs=1e-12)


def test_bounded_segments_stop_each_coordinate_at_its_own_bound():
    u, u_dot, low, high = np.array([0.0, 0.5, 1.0]), np.array([2.0, -1.0, 1.0]), np.array([-1, 0.2, -np.inf]), \
        np.array([0.1, 1.0, np.inf])
    segments, u_end, u_dot_end = bounded_segments(u, u_dot, low, high, 1.0)
    np.testing.assert_allclose(u_end, [0.1, 0.2, 2.0], atol=1e-15)
    assert list(u_dot_end) == [0.0, 0.0, 1.0]
    assert sum(tau for *_, tau in segments) == pytest.approx(1.0, abs=1e-15)
    rows, batch_end, _ = bounded_segments_batch(np.stack([u, u]), np.stack([u_dot, -u_dot]), low, high, 1.0)
    np.testing.assert_array_equal(batch_end[0], u_end)
    single = [s for s in bounded_segments(u, -u_dot, low, high, 1.0)[0]]
    batch = [(a[1], b[1], tau[1]) for a, b, tau in rows if tau[1] > 0]
    for (ua, va, ta), (ub, vb, tb) in zip(single, batch):
        np.testing.assert_array_equal(ua, ub), np.testing.assert_array_equal(va, vb)
        assert ta == tb


def test_render_plots_the_coordinates_or_the_users_picture():
    env = ActiveConstraintEnv(rotor_system(), -1.0, 1.0, render_mode="rgb_array")
    env.reset()
    first = env.render()
    env.step(np.array([1.0]))
    assert first.shape == (500, 500, 3) and np.any(env.render() != first)
    drawn = []
    env = ActiveConstraintEnv(
        rotor_system(), -1.0, 1.0, render_mode="rgb_array", draw=lambda state, canvas: drawn.append(state["t"])
    )
    env.reset()
    assert env.render().shape == (500, 500, 3) and drawn == [0.0]


def test_connenv_import_stays_free_of_sympy():
    import subprocess
    import sys

    code = "import sys, connenv; print('sympy' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"


def test_a_blow_up_in_finite_time_raises_stepper_error():
    """H = p²/2 − q⁴ reaches q = ∞ in finite time from q = 1, p = √2 (E = 0: q(t) = 1/(1 − √2 t)), within the
    first step at dt = 1: the stepper raises instead of returning a non-finite state."""
    from connenv.core import StepperError

    q, q_dot = sp.symbols("q q_dot")
    env = ActiveConstraintEnv.from_lagrangian(q_dot**2 / 2 + u_dot**2 / 2, -(q**4), [q], [u], u_low=0, u_high=1, dt=1.0)
    env.reset(options={"state": {"q": [1.0], "p": [math.sqrt(2.0)]}})
    with pytest.raises(StepperError, match="ActiveConstraintEnv in the step from t = 0"):
        env.step(np.array([0.0]))


def test_pickle_and_deepcopy_keep_the_derived_system():
    import copy
    import pickle

    env = ActiveConstraintEnv(rotor_system(), -1.0, 1.0, task=StopAtQuarterTurn())
    env.reset(seed=3)
    for clone in (pickle.loads(pickle.dumps(env)), copy.deepcopy(env)):
        assert clone.jump_class is JumpClass.FIT
        a = np.array([0.4])
        np.testing.assert_array_equal(clone.step(a)[0], copy.deepcopy(env).step(a)[0])


def test_rotor_ramp_and_jump_turn_the_body_alike():
    """At p = 0, θ + J u/(I + J) is conserved along any path of u: a ramp at bounded speed ends where the jump
    lands (the ramp through the vector field, the jump through the jump equations)."""
    jump = ActiveConstraintEnv(rotor_system(), -3.0, 3.0)
    ramp = ActiveConstraintEnv(rotor_system(), -3.0, 3.0, max_control_speed=4.0)
    for env in (jump, ramp):
        env.reset(options={"state": {"q": [0.2], "u": [-1.0]}})
        for _ in range(20):  # the ramp covers Δu = 2.5 in 0.625 s: 13 steps
            *_, info = env.step(np.array([0.5]))
        assert info["state"]["u"][0] == pytest.approx(1.5, abs=1e-15)
        assert abs(info["state"]["q"][0] - (0.2 - J * 2.5 / (I + J))) < 1e-12


def test_explicit_euler_on_the_held_swing_trips_the_energy_check():
    """Explicit Euler multiplies a pendulum's energy error each step; at dt = 0.3 s the held swing's energy, which
    the flow conserves, drifts past the bound within a few steps: StepperError, not a wrong answer."""
    from connenv.core import StepperError

    accurate = ActiveConstraintEnv(swing_system(), 1.6, 2.0, dt=0.3)
    accurate.reset(options={"state": {"q": [1.0]}})
    for _ in range(20):
        accurate.step(np.array([1.0]))  # the default stepper keeps E
    env = ActiveConstraintEnv(swing_system(), 1.6, 2.0, dt=0.3, integrator="euler")
    env.reset(options={"state": {"q": [1.0]}})
    with pytest.raises(StepperError, match=r"Euler\(substeps=1\) diverged: \|energy error\|"):
        for _ in range(20):
            env.step(np.array([1.0]))


class TurnTo(StopAtQuarterTurn):
    """StopAtQuarterTurn that also judges: a success where the body turned to π/2 within 0.05 rad and stopped
    there (|p| < 0.1)."""

    def is_success(self, state):
        return self.terminated(state) and abs(state["p"][0]) < 0.1


@pytest.mark.parametrize("task", [StopAtQuarterTurn(), TurnTo()], ids=["without is_success", "with is_success"])
def test_is_success_is_the_tasks_own_and_false_without_it_apart_from_the_end(task):
    """info["is_success"] is task.is_success(state) where the task has it, else False (an end is not always a
    success), while task.terminated ends the episode either way: a jump of the rotor by Δu = −π turns the body
    from rest at θ = π/2 − J π/(I + J) by −J Δu/(I + J), to θ = π/2, and leaves it there, at p = 0."""
    env = ActiveConstraintEnv(rotor_system(), -math.pi, math.pi, task=task)
    theta0 = math.pi / 2 - J * math.pi / (I + J)
    _, info = env.reset(options={"state": {"q": [theta0], "p": [0.0], "u": [0.0]}})
    assert info["is_success"] is False
    _, _, terminated, _, info = env.step(np.array([-1.0]))
    assert terminated and abs(info["state"]["q"][0] - math.pi / 2) < 1e-9
    assert info["is_success"] is isinstance(task, TurnTo)
