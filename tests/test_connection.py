"""ConnectionEnv and the Magnus stepper: closed forms, equivalences with the hand-built models, Stokes, contracts."""

import math
import re

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

import connenv
from connenv.core.integrators import make_stepper
from connenv.core.lie import GROUPS, Connection, magnus_flow
from connenv.core.steppers import StepperError
from connenv.systems.kozlov_shell import ReducedKozlovShell

ID = "connenv/Connection-v0"


def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def twisted(s):
    """A non-flat connection on a 2-D shape space, shape (3, 2)."""
    return np.array([[1.0 + s[1] ** 2, 0.5], [math.sin(s[0]), 1.0], [0.3, s[0] * s[1]]])


def make(**kwargs):
    return gym.make(ID, **{"shape_low": [-1.0, -1.0], "shape_high": [1.0, 1.0], **kwargs})


# -- closed forms and equivalences ------------------------------------------------------------------


def test_elroys_beanie_turns_the_body_by_the_inertia_ratio():
    """A body (I₁) with a rotor (I₂) at zero angular momentum: θ̇₁ = −I₂/(I₁+I₂) ψ̇, so one turn of the rotor turns
    the body by −2π I₂/(I₁+I₂) (Marsden & Ratiu's Elroy's beanie)."""
    I1, I2 = 3.0, 0.7
    env = gym.make(ID, group="SO2", connection=lambda s: np.array([[I2 / (I1 + I2)]]), shape_low=[-np.inf],
                   shape_high=[np.inf], dt=2 * math.pi / 40)  # fmt: skip
    env.reset(seed=0)
    for _ in range(40):
        _, _, _, _, info = env.step(np.array([1.0], np.float32))
    turn = -2 * math.pi * I2 / (I1 + I2)
    expected = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    assert np.max(np.abs(info["state"]["g"] - expected)) <= 1e-12
    assert info["state"]["s"][0] == pytest.approx(2 * math.pi, abs=1e-12)


def rolling_ball_connection(radius):
    """Rolling without slipping or spin: ω = e_z × ṡ/ρ for the contact point s, so A = −(1/ρ) [[0, −1], [1, 0], [0, 0]]
    in the space frame."""
    return lambda s: -np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 0.0]]) / radius


def test_rolling_ball_is_the_space_frame_connection_of_its_contact_point():
    """RollingBall-v0's attitude under velocity commands equals g of the SO(3) space-frame connection ξ = e_z × ṡ/ρ."""
    radius, v_max, dt = 0.7, 1.3, 0.1
    ball = gym.make("connenv/RollingBall-v0", radius=radius, v_max=v_max, dt=dt)
    env = gym.make(ID, group="SO3", frame="space", connection=rolling_ball_connection(radius),
                   shape_low=[-np.inf] * 2, shape_high=[np.inf] * 2, dt=dt, max_shape_speed=v_max)  # fmt: skip
    start = Rotation.from_rotvec([0.3, -1.1, 0.4]).as_matrix()
    ball.reset(seed=0, options={"state": {"R": start}})
    env.reset(seed=0, options={"state": {"g": start}})
    rng = np.random.default_rng(1)
    for _ in range(100):
        a = rng.uniform(-1.0, 1.0, 2)
        a = (0.999 * a / max(1.0, np.hypot(*a))).astype(np.float32)  # inside the unit disk: the ball does not project
        _, _, _, _, ball_info = ball.step(a)
        _, _, _, _, info = env.step(a)
    assert np.max(np.abs(info["state"]["g"] - ball_info["state"]["R"])) <= 1e-12


def test_abelian_flow_is_the_line_integral_of_the_connection_with_stops():
    """On ℝ² the flow is g = −∫ A(s) ds along the shape's path; a coordinate stopped at its bound ends the path there.
    With A = [[s₂, 0], [0, s₁]] and the straight path from s to s + Δ the integral is (s₂Δ₁ + Δ₁Δ₂/2, s₁Δ₂ + Δ₁Δ₂/2)."""
    env = gym.make(ID, group="R2", connection=lambda s: np.array([[s[1], 0.0], [0.0, s[0]]]), shape_low=[-1.0, -5.0],
                   shape_high=[0.25, 5.0], dt=0.5)  # fmt: skip
    env.reset(seed=0, options={"state": {"s": [0.0, 0.1]}})
    _, _, _, _, info = env.step(np.array([1.0, 1.0], np.float32))  # s₁ stops at 0.25 after 0.25 s, s₂ goes on
    assert np.allclose(info["state"]["s"], [0.25, 0.6], atol=1e-15)
    # path: (0, 0.1) → (0.25, 0.35) straight, then s₂ alone from 0.35 to 0.6 at s₁ = 0.25
    x = -(0.1 * 0.25 + 0.25 * 0.25 / 2)
    y = -(0.0 * 0.25 + 0.25 * 0.25 / 2) - 0.25 * 0.25
    assert np.max(np.abs(info["state"]["g"] - [x, y])) <= 1e-15


@pytest.mark.parametrize("frame", ["body", "space"])
@pytest.mark.parametrize("order", [4, 6])
def test_magnus_error_falls_as_its_order(frame, order):
    """On a non-constant connection on SO(3) the error of n Magnus steps falls as n^-order (ratio 2^order per
    doubling), against DOP853 at rtol 1e-13 on the matrix equation; every result is on SO(3) to 1e-14."""
    s0, s_dot, tau = np.array([0.2, -0.4]), np.array([1.5, 2.0]), 1.0

    def f(t, flat):
        W, R = hat(-twisted(s0 + t * s_dot) @ s_dot), flat.reshape(3, 3)
        return (R @ W if frame == "body" else W @ R).ravel()

    reference = solve_ivp(f, (0, tau), np.eye(3).ravel(), method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    system = Connection("SO3", frame, twisted)
    errors = []
    for n in (4, 8, 16):
        g, _, _ = magnus_flow(GROUPS["SO3"], frame, system.group_velocity, tuple(np.eye(3).ravel()), s0, s_dot, tau,
                              n, order)  # fmt: skip
        errors.append(np.max(np.abs(np.array(g) - reference)))
        assert GROUPS["SO3"].off_group(np.reshape(g, (3, 3))) <= 1e-14
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(np.log2(ratios) - order) < 0.3), (errors, ratios)


def test_magnus_stepper_meets_its_tolerance_on_the_shell():
    """The shell's reduced model (ξ = −I⁻¹C u̇ on SE(2)): each Magnus step of a random straight mass motion is within
    its atol (1e-10) of DOP853 at rtol 1e-13, and 60 steps stay within 5e-9, the error of the env's DOP853 default."""
    system, rng = ReducedKozlovShell(), np.random.default_rng(0)
    magnus, reference = make_stepper("magnus", system), make_stepper("dop853", system, rtol=1e-13, atol=1e-15)
    y, y_ref, u = np.zeros(3), np.zeros(3), np.zeros(2)
    for _ in range(60):
        u_cmd = rng.uniform(-1.0, 1.0, 2) * [0.5, 0.25]
        u_dot = (u_cmd - u) / 0.1
        one_step = magnus(system, y_ref, u, u_dot, 0.1)
        y, y_ref, u = magnus(system, y, u, u_dot, 0.1), reference(system, y_ref, u, u_dot, 0.1), u_cmd
        assert np.max(np.abs(one_step - y_ref)) <= 1e-10
    assert np.max(np.abs(y - y_ref)) <= 5e-9


def test_shell_connection_is_the_locked_inertia_solve():
    """The shell's closed-form ξ (the Schur complement) equals −A u̇ with A = I⁻¹ C from a linear solve."""
    system, rng = ReducedKozlovShell(a=1.2, b=0.4, mass=0.7), np.random.default_rng(2)
    u, u_dot = rng.uniform(-0.3, 0.3, (5, 2)), rng.normal(size=(5, 2))
    closed = np.stack(system.group_velocity(u, u_dot), -1)
    solved = -np.einsum("nij,nj->ni", system.connection(u), u_dot)
    assert np.max(np.abs(closed - solved)) <= 1e-14


@pytest.mark.parametrize("frame", ["body", "space"])
def test_small_loop_holonomy_is_curvature_times_area(frame):
    """Stokes for a connection: a small square loop of side ε in shape space, run counterclockwise from s₀, moves g by
    exp(ε² F(s₀) + O(ε³)), F = −(∂₁A₂ − ∂₂A₁) ± [A₁, A₂] (+ body, − space frame). For A₁ = (1, s₂, 0),
    A₂ = (0, 1, s₁): ∂₁A₂ − ∂₂A₁ = (0, −1, 1)."""
    s0 = np.array([0.3, -0.2])

    def connection(s):
        return np.array([[1.0, 0.0], [s[1], 1.0], [0.0, s[0]]])

    A = connection(s0)
    curvature = -np.array([0.0, -1.0, 1.0]) + (1.0 if frame == "body" else -1.0) * np.cross(A[:, 0], A[:, 1])
    misses = []
    for eps in (1e-2, 1e-3):
        env = gym.make(ID, group="SO3", frame=frame, connection=connection, shape_low=[-1, -1], shape_high=[1, 1],
                       dt=eps)  # fmt: skip
        env.reset(seed=0, options={"state": {"s": s0}})
        for a in ([1, 0], [0, 1], [-1, 0], [0, -1]):
            _, _, _, _, info = env.step(np.array(a, np.float32))
        holonomy = Rotation.from_matrix(info["state"]["g"]).as_rotvec() / eps**2
        misses.append(np.linalg.norm(holonomy - curvature) / np.linalg.norm(curvature))
    assert misses[1] <= 2e-3 and misses[1] <= misses[0] / 5, misses


def test_g_stays_on_so3_over_a_long_episode():
    env = make(group="SO3", connection=twisted, dt=0.2)
    env.reset(seed=0)
    rng = np.random.default_rng(3)
    for _ in range(300):
        _, _, _, _, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
    assert GROUPS["SO3"].off_group(info["state"]["g"]) <= 1e-12


def test_constant_connection_is_one_exponential():
    """Where A is constant along the path, the step is exp(−τ A ṡ): SE(2)'s closed form, no substeps."""
    A = np.array([[1.0, 0.2], [0.0, -0.5], [0.7, 1.0]])
    env = make(group="SE2", connection=lambda s: A, dt=0.3)
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.4, -0.8], np.float32))
    xi = -A @ np.array([0.4, -0.8], np.float32) * 0.3
    X = np.array([[0.0, -xi[2], xi[0]], [xi[2], 0.0, xi[1]], [0.0, 0.0, 0.0]])
    assert np.max(np.abs(info["state"]["g"] - expm(X))) <= 1e-15


def test_a_constant_connection_given_as_an_array_steps_exactly_alone_and_in_a_batch():
    """A given as an array: the exact step (one exponential) by default. The rolling ball's A in the space frame
    gives RollingBall-v0's attitude (Rodrigues by scipy) to rounding, and the vector env's rows the single env's."""
    radius, dt = 0.7, 0.1
    kwargs = {"group": "SO3", "frame": "space", "connection": rolling_ball_connection(radius)(None),
              "shape_low": [-np.inf] * 2, "shape_high": [np.inf] * 2, "dt": dt}  # fmt: skip
    env, ball = gym.make(ID, **kwargs), gym.make("connenv/RollingBall-v0", radius=radius, dt=dt)
    assert type(env.unwrapped.stepper).__name__ == "Exact"
    native = gym.make_vec(ID, 2, vectorization_mode="vector_entry_point", **kwargs)
    env.reset(seed=0)
    ball.reset(seed=0)
    native.reset(seed=0)
    rng = np.random.default_rng(3)
    for _ in range(50):
        a = (0.7 * rng.uniform(-1.0, 1.0, (2, 2))).astype(np.float32)
        info = env.step(a[0])[4]
        ball_info = ball.step(a[0])[4]
        rows = native.step(a)[4]
    assert np.max(np.abs(info["state"]["g"] - ball_info["state"]["R"])) <= 1e-13
    assert np.array_equal(rows["state"]["g"][0], info["state"]["g"])


# -- the env's contract ---------------------------------------------------------------------------


@pytest.mark.parametrize("group", ["SO2", "SE2", "SO3", "R2"])
def test_checkers_pass(group):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    dim = GROUPS[group].dim
    kwargs = {"group": group, "connection": lambda s: np.ones((dim, 2)) * (1.0 + s[0] * s[1])}
    check_env(make(**kwargs).unwrapped, skip_render_check=True)
    sb3_check_env(make(**kwargs))


@pytest.mark.parametrize("group", ["SE2", "SO3"])
def test_vector_rows_are_single_envs(group):
    """Row i of the native vector env follows SyncVectorEnv's env i, through stops at the bounds and autoresets."""
    kwargs = {"group": group, "connection": twisted if group != "SE2" else lambda s: twisted(s)[[0, 2, 1]],
              "shape_low": [-0.5, -1.0], "shape_high": [0.3, np.inf], "max_episode_steps": 20}  # fmt: skip
    native = gym.make_vec(ID, 3, vectorization_mode="vector_entry_point", **kwargs)
    sync = gym.make_vec(ID, 3, vectorization_mode="sync", **kwargs)
    native.reset(seed=5)
    sync.reset(seed=5)
    rng = np.random.default_rng(0)
    for _ in range(45):
        a = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        obs, _, _, truncated, info = native.step(a)
        sync_obs, _, _, sync_truncated, sync_info = sync.step(a)
        assert np.max(np.abs(obs - sync_obs)) <= 1e-12 and np.array_equal(truncated, sync_truncated)
        assert np.max(np.abs(info["state"]["g"] - sync_info["state"]["g"])) <= 1e-12


def test_task_drives_start_reward_and_end():
    """A task: start at a random s, pay the turn of θ, end when the body has turned by a quarter."""

    class Turn:
        def reset(self, np_random):
            return {"s": [np_random.uniform(-1, 1)]}

        def reward(self, state, next_state):
            return math.atan2(next_state["g"][1, 0], next_state["g"][0, 0]) - math.atan2(state["g"][1, 0],
                                                                                         state["g"][0, 0])

        def terminated(self, state):
            return math.atan2(state["g"][1, 0], state["g"][0, 0]) >= math.pi / 4

    env = gym.make(ID, group="SO2", connection=lambda s: np.array([[-1.0]]), shape_low=[-np.inf], shape_high=[np.inf],
                   task=Turn())  # fmt: skip
    _, info = env.reset(seed=0)
    assert -1 <= info["state"]["s"][0] <= 1
    total, steps, terminated = 0.0, 0, False
    while not terminated:
        _, reward, terminated, _, info = env.step(np.array([1.0], np.float32))
        total, steps = total + reward, steps + 1
    assert steps == 8 and total == pytest.approx(0.8, abs=1e-12)  # ω = ṡ = 1, dt = 0.1: 0.8 rad ≥ π/4 after 8


def test_reset_sets_the_state_and_renders():
    drawn = []
    env = make(group="SE2", connection=lambda s: np.ones((3, 2)), render_mode="rgb_array")
    g = np.array([[0.0, -1.0, 2.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    _, info = env.reset(options={"state": {"g": g, "s": [0.5, -0.25]}})
    assert np.max(np.abs(info["state"]["g"] - g)) <= 1e-16 and np.array_equal(info["state"]["s"], [0.5, -0.25])
    assert env.render().shape == (500, 500, 3)
    custom = make(group="R2", connection=lambda s: np.ones((2, 2)), render_mode="rgb_array",
                  draw=lambda state, canvas: drawn.append(state["t"]))  # fmt: skip
    custom.reset(seed=0)
    assert custom.render().shape == (500, 500, 3) and drawn == [0.0]


# -- bad input ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"group": "SE3"}, "group='SE3'"),
        ({"frame": "world"}, "frame='world'"),
        ({"connection": lambda s: np.ones((2, 2))}, "shape (3, 2)"),
        ({"connection": lambda s: np.full((3, 2), np.nan)}, "finite"),
        ({"connection": np.ones((2, 2))}, "or a constant A"),
        ({"connection": "curved"}, "callable"),
        ({"shape_low": [1.0, 0.0]}, "below"),
        ({"shape_low": [-1.0]}, "one shape"),
        ({"shape_high": [1.0, np.nan]}, "NaN"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"max_shape_speed": -1.0}, "max_shape_speed=-1.0"),
    ],
)
def test_bad_construction_is_refused(kwargs, words):
    kwargs = {"group": "SE2", "connection": lambda s: np.ones((3, 2)), **kwargs}
    with pytest.raises(ValueError, match=re.escape(words)):
        make(**kwargs)


@pytest.mark.parametrize("env_id", ["RollingCoin-v0", "ElroysBeanie-v0", "TubeTwist-v0"])
@pytest.mark.parametrize(
    "kwarg",
    ["group", "connection", "shape_low", "shape_high", "frame", "max_shape_speed", "task", "draw", "vectorized",
     "exact_segment", "bogus"],
)
def test_a_subclass_refuses_connection_env_kwargs_by_its_own_name(env_id, kwarg):
    """An env built on ConnectionEnv sets the builder's kwargs itself: passing one to it (or an unknown one) is a
    ValueError naming the kwarg and the env, not a silent override nor a TypeError."""
    with pytest.raises(ValueError, match=re.escape(f"['{kwarg}'] for {env_id}")):
        gym.make(f"connenv/{env_id}", **{kwarg: 1})


@pytest.mark.parametrize(
    ("state", "words"),
    [
        ({"g": np.diag([1.0, 1.0, 2.0])}, "off SO3"),
        ({"g": np.eye(2)}, "shape (3, 3)"),
        ({"s": [2.0, 0.0]}, "out of range"),
        ({"s": [0.0]}, "sequence of 2"),
        ({"x": 1.0}, "unknown key"),
    ],
)
def test_bad_reset_state_is_refused(state, words):
    env = make(group="SO3", connection=twisted)
    with pytest.raises(ValueError, match=re.escape(words)):
        env.reset(options={"state": state})


def test_a_stepper_that_cannot_meet_its_tolerance_raises(monkeypatch):
    """A tolerance the step cannot meet within MAX_SUBSTEPS substeps (here 2): StepperError, not a silent step. (A
    tolerance below what floats resolve is refused at make: make_stepper's MAGNUS_ATOL_MIN.)"""
    monkeypatch.setattr(connenv.core.lie.magnus, "MAX_SUBSTEPS", 2)
    env = make(group="SO3", connection=twisted, atol=1e-15)
    env.reset(seed=0)
    with pytest.raises(StepperError, match="substeps"):
        env.step(np.array([1.0, 0.5], np.float32))


def test_a_connection_that_turns_non_finite_raises():
    """A is NaN past s₁ = 0.45: the step that crosses it raises StepperError naming the env."""
    env = make(group="SE2", connection=lambda s: np.ones((3, 2)) * np.sqrt(0.45 - s[0]))
    env.reset(seed=0, options={"state": {"s": [0.4, 0.0]}})
    with np.errstate(invalid="ignore"), pytest.raises(StepperError, match="ConnectionEnv"):
        env.step(np.array([1.0, 0.0], np.float32))


def test_magnus_falls_back_for_systems_without_a_connection():
    """The shell's full model (Kirchhoff, μ ≠ 0) has no connection: make_stepper('magnus') steps it by DOP853."""
    from connenv.systems.kozlov_shell import KozlovShell

    system, y = KozlovShell(), np.array([0.1, 0.2, 0.3, 0.3, 0.1, 0.05])
    u, u_dot = np.array([0.1, -0.1]), np.array([2.0, 1.0])
    magnus = make_stepper("magnus", system, rtol=1e-9, atol=1e-11)
    dop853 = make_stepper("dop853", rtol=1e-9, atol=1e-11)
    assert np.array_equal(magnus(system, y, u, u_dot, 0.1), dop853(system, y, u, u_dot, 0.1))
    assert isinstance(gym.make(ID, group="R2", connection=lambda s: np.eye(2), shape_low=[-1, -1],
                               shape_high=[1, 1]).unwrapped, connenv.ConnectionEnv)  # fmt: skip


@pytest.mark.parametrize("group", ["SO2", "SE2", "R2"])
@pytest.mark.parametrize("frame", ["body", "space"])
def test_magnus_agrees_with_dop853_on_the_reconstruction_equation(group, frame):
    """Two independent integrations of the same connection agree: the Lie-group step and DOP853 (rtol 1e-12) on ġ in
    coordinates, over 10 random steps that stop at the bounds."""
    dim = GROUPS[group].dim
    kwargs = {"group": group, "frame": frame, "connection": lambda s: twisted(s)[:dim], "dt": 0.2}
    envs = [make(**kwargs), make(**kwargs, integrator="dop853", rtol=1e-12, atol=1e-14)]
    rng = np.random.default_rng(4)
    for env in envs:
        env.reset(seed=0, options={"state": {"s": [0.2, -0.3]}})
    for _ in range(10):
        a = rng.uniform(-1, 1, 2).astype(np.float32)
        (_, _, _, _, info), (_, _, _, _, reference) = (env.step(a) for env in envs)
    assert np.max(np.abs(info["state"]["g"] - reference["state"]["g"])) <= 1e-9


@pytest.mark.parametrize("frame", ["body", "space"])
def test_quadrature_flow_on_se2_converges_at_least_at_order_8(frame):
    """SE(2) is solvable: θ = ∫ω and the translation is ∫R(θ)v, so the flow is two nested quadratures. With 8
    Gauss–Legendre nodes per piece the error falls by ≥ 2⁸ per halving of the pieces (against DOP853 at rtol 1e-13)."""
    from connenv.core.lie import quadrature_flow

    s0, s_dot, tau = np.array([0.2, -0.4]), np.array([3.0, 4.0]), 1.0
    system = Connection("SE2", frame, lambda s: twisted(3 * s)[[0, 2, 1]])
    g0 = np.array([0.3, -0.2, 0.5])
    reference = solve_ivp(lambda t, y: system.vector_field(y, s0 + t * s_dot, s_dot), (0, tau), g0, method="DOP853",
                          rtol=1e-13, atol=1e-15).y[:, -1]  # fmt: skip
    errors = [np.max(np.abs(np.array(quadrature_flow(GROUPS["SE2"], frame, system.group_velocity, tuple(g0), s0,
                                                     s_dot, tau, n)[0]) - reference)) for n in (1, 2)]  # fmt: skip
    assert errors[0] > 1e-9 and errors[1] <= errors[0] / 2**8, errors


def test_a_closed_form_exact_segment_is_the_default_step_and_the_flow_magnus_integrates():
    """Connection-v0 with the coin's exact_segment: integrator "exact" by default, on a bounded shape space whose
    stops cut the step into segments, and Magnus's quadrature of the same connection agrees to its tolerance; a
    non-callable exact_segment is refused."""
    import functools

    from connenv.systems import rolling_coin

    kwargs = {"group": "R2", "connection": functools.partial(rolling_coin.connection, radius=0.5),
              "shape_low": [-1.0, -2.0], "shape_high": [1.0, 2.0], "vectorized": True}  # fmt: skip
    exact = gym.make(ID, exact_segment=functools.partial(rolling_coin.exact_segment, radius=0.5), **kwargs).unwrapped
    magnus = gym.make(ID, integrator="magnus", atol=1e-12, **kwargs).unwrapped
    assert type(exact.stepper).__name__ == "Exact"
    for env in (exact, magnus):
        env.reset(seed=0)
        for a in np.random.default_rng(1).uniform(-1, 1, (60, 2)):
            env.step(a)
    assert np.max(np.abs(exact.state.g - magnus.state.g)) <= 1e-11
    with pytest.raises(ValueError, match="exact_segment"):
        gym.make(ID, exact_segment=3.0, **kwargs)


@pytest.mark.parametrize(
    ("exact_segment", "error", "words"),
    [
        (lambda g, s, s_dot, tau: np.zeros(3), ValueError, "of shape (2,)"),  # SE2's size, not R2's
        (lambda g, s, s_dot, tau: g + s_dot[0] / s_dot[1], ValueError, "finite"),  # NaN at ṡ = 0
        (lambda g, s, s_dot, tau: g + np.tanh(s_dot) * np.inf, ValueError, "finite"),  # ±inf once ṡ ≠ 0
        (lambda g, s, s_dot, tau: "moved", TypeError, "of shape (2,)"),  # no numbers at all
    ],
)
def test_an_exact_segment_that_does_not_return_a_finite_g_of_its_group_is_refused_at_make(exact_segment, error, words):
    """The user's exact_segment is tried at construction (g = identity, the start shape, τ = dt, ṡ = 0 and ṡ at top
    speed): a wrong shape or a non-finite g is a ValueError naming exact_segment (a TypeError where it returns no
    numbers), before any step uses it."""
    kwargs = {"group": "R2", "connection": lambda s: np.eye(2), "shape_low": [-1.0, -1.0], "shape_high": [1.0, 1.0]}
    with np.errstate(all="ignore"), pytest.raises(error, match=r"exact_segment=.*" + re.escape(words)):
        gym.make(ID, exact_segment=exact_segment, **kwargs)


@pytest.mark.parametrize("frame", ["body", "space"])
def test_magnus_meets_its_tolerance_on_a_long_segment_of_a_curved_connection(frame):
    """Over 4 s of a strongly curved connection (twisted at 6 s) the estimate from one and two substeps is not yet
    in its asymptotic regime, and the substeps it chose missed atol by orders of magnitude on SO(3); checked against
    twice as many, the step meets its atol of 1e-10 (against DOP853 at rtol 1e-13 on Ṙ = R ξ^ or ξ^ R)."""
    system = Connection("SO3", frame, lambda s: twisted(6.0 * np.asarray(s)))
    s0, s_dot, tau, R0 = np.array([0.3, -0.5]), np.array([-0.4, 0.6]), 4.0, np.eye(3).ravel()
    reference = solve_ivp(lambda t, y: system.vector_field(y, s0 + t * s_dot, s_dot), (0.0, tau), R0, method="DOP853",
                          rtol=1e-13, atol=1e-15).y[:, -1]  # fmt: skip
    assert np.max(np.abs(make_stepper("magnus")(system, R0, s0, s_dot, tau) - reference)) <= 1e-10


class Reach:
    """A task: end when s reaches 0.5; a success only where g has turned by less than a quarter turn then."""

    def __init__(self, judge=True):
        if judge:
            self.is_success = lambda state: abs(math.atan2(state["g"][1, 0], state["g"][0, 0])) < math.pi / 4

    def reset(self, np_random):
        return {"s": [0.0]}

    def reward(self, state, next_state):
        return 0.0

    def terminated(self, state):
        return state["s"][0] >= 0.5


@pytest.mark.parametrize(("turn", "judge", "success"), [(1.0, True, True), (3.0, True, False), (1.0, False, False)])
def test_is_success_is_the_tasks_own_and_false_without_it_apart_from_the_end(turn, judge, success):
    """info["is_success"] is in every info (agents.evaluate reads it): task.is_success(state) where the task has it,
    else False, while task.terminated ends the episode either way; alone and in the vector env."""
    kwargs = {"group": "SO2", "connection": np.array([[turn]]), "shape_low": [-1.0], "shape_high": [1.0],
              "task": Reach(judge)}  # fmt: skip
    env = gym.make(ID, **kwargs)
    _, info = env.reset(seed=0)
    assert info["is_success"] is judge  # at g = identity: no turn yet, a success where the task judges it
    for _ in range(5):
        _, _, terminated, _, info = env.step(np.array([1.0], np.float32))
    assert terminated and info["is_success"] == success
    vector = gym.make_vec(ID, 2, vectorization_mode="vector_entry_point", **kwargs)
    vector.reset(seed=0)
    for _ in range(5):
        _, _, terminated, _, info = vector.step(np.ones((2, 1), np.float32))
    assert terminated.all() and info["is_success"].tolist() == [success, success]


def test_evaluate_runs_an_episode_of_the_beanie_with_a_random_policy():
    """Issue 30: agents.evaluate on Connection-v0 (examples.beanie(), random policy) raised KeyError 'is_success'."""
    from agents.evaluate import RandomPolicy, run_episode
    from connenv import examples

    env = gym.make(ID, **examples.beanie(), max_episode_steps=20)
    episode = run_episode(env, RandomPolicy(env.action_space, 0), seed=0)
    assert episode.length == 20 and episode.success is False


@pytest.mark.parametrize("env_id", ["connenv/ActiveConstraint-v0", "connenv/Connection-v0"])
def test_the_builders_docstrings_state_the_registrations_time_limit(env_id):
    """Connection-v0's docstring said its registration had no time limit; the registration has 1000 steps, as
    ActiveConstraint-v0's, and both docstrings say so."""
    from connenv.envs.spec import spec

    env = gym.make(env_id, **spec(env_id).make_kwargs())
    limit = gym.spec(env_id).max_episode_steps
    assert limit == 1000 and f"truncates after {limit} steps" in " ".join(type(env.unwrapped).__doc__.split())
