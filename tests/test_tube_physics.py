"""TubeTwist-v0's physics: the twist of a closed loop of the tangent is the area it encloses on the unit sphere
(the octant, any spherical polygon by Girard's spherical excess, Foucault's circles), the twist of an open path is
that of the path closed by a geodesic, the step is the exact exponential, and the tube is the rolling ball read
backwards."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import connenv  # noqa: F401  (registers the envs)
from connenv.systems.tube import bend_toward, circle_frame, circle_rate, polygon_area, tangent_angle, twist, wrap

ID = "connenv/TubeTwist-v0"


def drive_along(env, vertices):
    """Step the env once per vertex, each step bending T along the great circle to the vertex (dt · max_bend_rate
    must reach the longest side); the last info."""
    tube = env.unwrapped
    for v in vertices:
        R = tube.state.g.reshape(3, 3)
        info = env.step(bend_toward(R, v) / (tube.max_shape_speed * tube.dt))[4]
    return info


def loop_env(**kwargs):
    """One step bends up to π: a side of any polygon is one step."""
    return gym.make(ID, max_bend_rate=math.pi, dt=1.0, tolerance=1e-3, max_episode_steps=None, **kwargs)


def test_octant_loop_twists_the_tip_by_a_quarter_turn():
    """T from e_z to e_x to e_y and back to e_z along great circles encloses an eighth of the sphere, π/2: the tip
    comes back turned about T by π/2, R = Rz(π/2)."""
    env = loop_env()
    env.reset(seed=0, options={"target": math.pi / 2})
    info = drive_along(env, np.eye(3)[[0, 1, 2]])
    assert abs(info["twist"] - math.pi / 2) <= 1e-12 and info["tangent_error"] <= 1e-12
    assert np.max(np.abs(info["state"]["R"] - Rotation.from_rotvec([0, 0, math.pi / 2]).as_matrix())) <= 1e-12
    assert info["is_success"]


def circle_polygon(rng, sides):
    """A convex spherical polygon: `sides` points at increasing azimuths on a circle of random radius about a random
    centre, counterclockwise seen from outside."""
    centre = Rotation.random(rng=rng).as_matrix()
    radius = rng.uniform(0.4, 1.3)
    azimuths = np.sort(rng.uniform(0.0, 2 * math.pi, sides))
    local = np.stack([math.sin(radius) * np.cos(azimuths), math.sin(radius) * np.sin(azimuths),
                      np.full(sides, math.cos(radius))], -1)  # fmt: skip
    return local @ centre.T


def girard_excess(vertices):
    """Σ interior angles − (n − 2)π of a convex spherical polygon, each angle between the great circles to the two
    neighbours, from their tangent directions at the vertex."""
    n, total = len(vertices), 0.0
    for i, v in enumerate(vertices):
        a, b = vertices[i - 1], vertices[(i + 1) % n]
        ta, tb = a - (a @ v) * v, b - (b @ v) * v
        total += math.acos(np.clip(ta @ tb / (np.linalg.norm(ta) * np.linalg.norm(tb)), -1.0, 1.0))
    return total - (n - 2) * math.pi


@pytest.mark.parametrize("sides", [3, 4, 5, 8])
def test_any_spherical_polygon_twists_the_tip_by_its_spherical_excess(sides):
    """T bent from T₀ to a polygon's first vertex, round the polygon and back to T₀ the way it came (a spur, which
    encloses nothing), from any start frame R₀: counterclockwise the tip turns by the polygon's spherical excess
    (Girard), clockwise by minus it; the excess computed from the polygon's angles."""
    rng = np.random.default_rng(sides)
    env = loop_env()
    for _ in range(3):
        R0 = Rotation.random(rng=rng).as_matrix()
        polygon = circle_polygon(rng, sides)
        excess = girard_excess(polygon)
        for sign, loop in ((1, polygon), (-1, polygon[::-1])):
            env.reset(options={"state": {"R": R0}})
            info = drive_along(env, [*loop, loop[0], R0[:, 2]])
            assert info["tangent_error"] <= 1e-12
            assert abs(wrap(info["twist"] - sign * excess)) <= 1e-11


def test_the_twist_of_an_open_path_is_that_of_the_path_closed_by_the_geodesic():
    """Along a path of great-circle arcs round T₀, the twist is the area of the polygon of the vertices so far
    closed straight back to T₀ (solid angles of its fan, Van Oosterom & Strackee), and the tangent's angle is the
    last vertex's from T₀."""
    rng = np.random.default_rng(11)
    env = loop_env()
    env.reset(seed=0)
    azimuths, colatitudes = np.cumsum(rng.uniform(0.2, 0.9, 6)), rng.uniform(0.3, 1.3, 6)
    path = [np.array([0.0, 0.0, 1.0])]
    for phi, c in zip(azimuths, colatitudes):
        v = np.array([math.sin(c) * math.cos(phi), math.sin(c) * math.sin(phi), math.cos(c)])
        info = drive_along(env, [v])
        path.append(v)
        if len(path) >= 3:
            assert abs(info["twist"] - polygon_area(path)) <= 1e-12
        assert abs(info["tangent_error"] - c) <= 1e-12


def test_twist_is_the_swing_twist_decomposition_about_the_start_tangent():
    """ψ carried back along the geodesic is the twist of the swing–twist decomposition Q = S Rz(ψ), S about an axis
    ⊥ e_z: 2 atan2(q_z, q_w) of Q's quaternion (scipy)."""
    rotations = Rotation.random(2000, rng=4)
    q = rotations.as_quat()  # (x, y, z, w)
    Q = rotations.as_matrix()
    away = tangent_angle(Q) < math.pi - 1e-3  # at T = −T₀ no geodesic is singled out
    assert np.max(np.abs(wrap(twist(Q) - 2 * np.arctan2(q[:, 2], q[:, 3]))[away])) <= 1e-12


def foucault_frame(colatitude, curvature):
    """The frame after one turn of the bend κ(t) = k (cos Ωt, sin Ωt): Ṙ = R ω̂ integrated by DOP853 at rtol
    1e-13 from R₀ = I with the tube's own vector field (the env system's), and the turn's period."""
    env = gym.make(ID).unwrapped
    rate = circle_rate(colatitude, curvature)
    period = 2 * math.pi / math.hypot(curvature, rate)

    def rhs(t, y):
        kappa = curvature * np.array([math.cos(rate * t), math.sin(rate * t)])
        return env.system.vector_field(y, np.zeros(2), kappa)

    solution = solve_ivp(rhs, (0.0, period), np.eye(3).ravel(), "DOP853", rtol=1e-13, atol=1e-15, dense_output=True)
    return solution, period, rate


@pytest.mark.parametrize("colatitude", [0.2, 0.7, 1.2, 2.0, 2.8])
def test_foucault_transport_round_a_circle_of_colatitude_c_turns_by_2pi_1_minus_cos_c(colatitude):
    """A tube bent at constant curvature k whose bending plane turns at Ω = k cot c carries T once round a circle
    of colatitude c; N, parallel transported, comes back turned by 2π(1 − cos c) mod 2π, as a Foucault pendulum's
    plane in a day at colatitude c. Along the way the frame is the closed form R₀ exp(t (k e₁ + Ω e₃)^) Rz(−Ωt)."""
    curvature = 1.3
    solution, period, rate = foucault_frame(colatitude, curvature)
    Q = solution.y[:, -1].reshape(3, 3)
    assert tangent_angle(Q) <= 1e-10
    assert abs(wrap(twist(Q) - 2 * math.pi * (1 - math.cos(colatitude)))) <= 1e-10
    t = np.linspace(0.0, period, 7)
    closed = circle_frame(np.eye(3), curvature, rate, t)
    assert np.max(np.abs(solution.sol(t).T.reshape(-1, 3, 3) - closed)) <= 1e-10
    axis = np.array([curvature, 0.0, rate]) / math.hypot(curvature, rate)  # T stays at colatitude c about it
    assert np.max(np.abs(closed[:, :, 2] @ axis - math.cos(colatitude))) <= 1e-12


def test_a_step_is_the_exponential_of_the_bend_at_the_precision_given():
    """One step at the rates κ = a · max_bend_rate is R exp(dt (κ₁, κ₂, 0)^) (scipy's rotation vector), with a
    float64 action used as given: rounding it to float32 moves R."""
    env = gym.make(ID, max_bend_rate=1.7, dt=0.3)
    R0 = Rotation.from_rotvec([0.4, -1.0, 0.2]).as_matrix()
    a = np.array([0.123456789012345, -0.987654321098765])
    for action in (a, a.astype(np.float32)):
        env.reset(options={"state": {"R": R0}})
        R = env.step(action)[4]["state"]["R"]
        expected = R0 @ Rotation.from_rotvec([*(1.7 * 0.3 * np.asarray(action, float)), 0.0]).as_matrix()
        assert np.max(np.abs(R - expected)) <= 1e-15
    assert np.max(np.abs(R - R0 @ Rotation.from_rotvec([*(0.51 * a), 0.0]).as_matrix())) > 1e-9


def test_the_tube_is_the_rolling_ball_read_backwards():
    """Rᵀ of the tube obeys the rolling ball's equation (radius 1) at the velocity v = (−κ₂, κ₁): the two envs,
    driven alike, give Rᵀ = R_ball to rounding; and R stays on SO(3)."""
    tube, ball = gym.make(ID, dt=0.1), gym.make("connenv/RollingBall-v0", dt=0.1)
    R0 = Rotation.from_rotvec([0.2, 0.9, -0.5]).as_matrix()
    tube.reset(options={"state": {"R": R0}})
    ball.reset(options={"state": {"R": R0.T}})
    rng = np.random.default_rng(2)
    for _ in range(150):
        a = 0.7 * rng.uniform(-1.0, 1.0, 2)
        info = tube.unwrapped.step(a)[4]
        ball_info = ball.unwrapped.step(np.array([-a[1], a[0]]))[4]
    R = info["state"]["R"]
    assert np.max(np.abs(R.T - ball_info["state"]["R"])) <= 1e-13
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-13


def test_the_builders_magnus_step_agrees_with_the_exact_one():
    """ConnectionEnv's default Magnus step sees a constant ξ over each step and takes one exponential too."""
    envs = [gym.make(ID, integrator=name) for name in ("exact", "magnus")]
    rng = np.random.default_rng(5)
    for env in envs:
        env.reset(seed=3)
    for _ in range(100):
        a = rng.uniform(-1.0, 1.0, 2)
        R_exact, R_magnus = (env.unwrapped.step(a)[4]["state"]["R"] for env in envs)
    assert np.max(np.abs(R_exact - R_magnus)) <= 1e-13
