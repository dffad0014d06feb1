"""The rolling ball: exactness of the step on SO(3), holonomy as enclosed area, the arcs and their optimality."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import connenv.systems.rolling_ball as rolling_ball
from connenv.core.integrators import make_stepper
from connenv.systems.rolling_ball import Arc, RollingBall, split_legs

BALL = RollingBall(1.0)


def random_rotations(count, seed=0):
    return Rotation.random(count, rng=np.random.default_rng(seed))


def roll_by_steps(ball, displacements, stepper=None, dt=0.1, R=None):
    """R after rolling the straight steps through a stepper (default: the exact one), each over dt."""
    stepper = stepper or make_stepper("exact", ball)
    y = np.eye(3).ravel() if R is None else R.ravel()
    for d in displacements:
        y = stepper(ball, y, np.zeros(2), np.asarray(d, float) / dt, dt)
    return y.reshape(3, 3)


def angle_between(A, B):
    return float(Rotation.from_matrix(A @ B.T).magnitude())


def test_exact_step_stays_on_so3_over_a_million_random_steps():
    """‖RᵀR − I‖ ≤ 1e-12 and det R = 1 to 1e-12 after 10⁶ exact steps at random velocities (|v| ≤ 1, dt = 0.1).

    The step matrices are made in one batched call of exact_segment on I (scipy's Rotation) and composed. One
    state takes Rodrigues' formula on floats instead: 10⁴ such steps stay on SO(3) as well, and each agrees with
    the batched step to rounding."""
    steps, dt = 1_000_000, 0.1
    v = np.random.default_rng(1).uniform(-1.0, 1.0, (steps, 2))
    S = BALL.exact_segment(np.broadcast_to(np.eye(3).ravel(), (steps, 9)), np.zeros(2), v, dt).reshape(steps, 3, 3)
    R = np.eye(3)
    for k in range(10_000):
        single = BALL.exact_segment(R.ravel(), np.zeros(2), v[k], dt).reshape(3, 3)
        np.testing.assert_allclose(single, S[k] @ R, rtol=0, atol=1e-14)
        R = single
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-12
    R = np.eye(3)
    for k in range(steps):
        R = S[k] @ R
    assert np.linalg.norm(R.T @ R - np.eye(3)) <= 1e-12
    assert abs(np.linalg.det(R) - 1.0) <= 1e-12


@pytest.mark.parametrize("radius", [1.0, 2.5])
@pytest.mark.parametrize("d", [0.7, -1.3])
def test_seed_maneuver_turns_by_d_about_the_vertical(radius, d):
    """Lawton's slide 8: roll +x by ρπ/2, −y by ρd, −x by ρπ/2: R = Rz(d), the centre at (0, −ρd)."""
    ball = RollingBall(radius)
    legs = np.array([[radius * math.pi / 2, 0.0], [0.0, -radius * d], [-radius * math.pi / 2, 0.0]])
    steps = split_legs(legs, 0.1)
    R = roll_by_steps(ball, steps)
    assert np.abs(R - Rotation.from_rotvec([0, 0, d]).as_matrix()).max() <= 1e-12
    assert np.abs(steps.sum(axis=0) - [0.0, -radius * d]).max() <= 1e-12


@pytest.mark.parametrize("lune", [math.pi / 2, 0.4, 2.5])
def test_holonomy_equals_the_enclosed_spherical_area(lune):
    """Roll π/2 along +x, `lune` along +y, then π/2 along −x (ρ = 1): the contact point traces on the sphere two
    meridians joined along the equator, a lune of area `lune` (an octant, π/2, for the issue's example), and the
    ball turns by −area about the vertical."""
    R = BALL.roll([[math.pi / 2, 0.0], [0.0, lune], [-math.pi / 2, 0.0]])
    assert (R * Rotation.from_rotvec([0, 0, -lune]).inv()).magnitude() <= 1e-12


def test_small_square_turns_by_its_area():
    """Rolling a closed square of side ℓ counter-clockwise turns the ball by −ℓ²/ρ² about the vertical, to O(ℓ³)."""
    for side in (0.02, 0.01):
        legs = side * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
        turn = BALL.roll(legs).as_rotvec()
        assert abs(turn[2] + side**2) <= 2 * side**3
        assert np.linalg.norm(turn[:2]) <= 2 * side**3


@pytest.mark.parametrize("arc", [Arc(0.3, 0.8, 2.0), Arc(-2.0, -2.5, 3.5), Arc(1.0, 0.0, 1.5)])
def test_closed_form_arc_equals_integrating_along_the_arc(arc):
    """R(s) = Rz(ks) exp(s(ω₀ − k e_z)^) R(0) against DOP853 on Ṙ = ω̂(s)R with the heading α + ks, and the
    centre against the integral of the heading."""

    def rhs(s, y):
        heading = arc.heading + arc.curvature * s
        v = np.array([math.cos(heading), math.sin(heading)])
        return np.concatenate([BALL.vector_field(y[:9], None, v), v])

    sol = solve_ivp(rhs, (0, arc.length), np.r_[np.eye(3).ravel(), 0, 0], method="DOP853", rtol=1e-13, atol=1e-14)
    R_integrated = sol.y[:9, -1].reshape(3, 3)
    assert np.abs(BALL.arc_rotation(arc).as_matrix() - R_integrated).max() <= 1e-10
    assert np.abs(BALL.arc_position(arc) - sol.y[9:, -1]).max() <= 1e-10


def test_discrete_arc_is_exact_in_steps_and_converges_to_the_arc():
    """Rz(nδ)(Rz(−δ)exp(ℓω₀^))ⁿ is the rotation of rolling its n steps one by one, and the discrete arc with the
    chords of an arc differs from the arc by O(1/n²)."""
    arc = Arc(0.4, 1.2, 3.0)
    errors = []
    for n in (20, 40, 80):
        step = arc.length / n
        chords = rolling_ball.DiscreteArc(arc.heading + arc.curvature * step / 2, arc.curvature * step, step, n)
        R = roll_by_steps(BALL, chords.displacements())
        assert np.abs(BALL.discrete_arc_rotation(chords).as_matrix() - R).max() <= 1e-13
        errors.append(angle_between(R, BALL.arc_rotation(arc).as_matrix()))
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.05)


def test_optimal_arc_reaches_every_target_and_is_shortest_of_the_planners():
    """Over 200 uniform targets: the arc closes to 1e-9, is no shorter than ρ × the rotation angle (|ω| = |v|/ρ),
    and never longer than the holonomy planner's legs."""
    for rotation in random_rotations(200):
        arc = BALL.optimal_arc(rotation)
        assert BALL.misses(arc, rotation) <= 1e-9
        holonomy = np.linalg.norm(BALL.holonomy_legs(rotation), axis=1).sum()
        assert rotation.magnitude() - 1e-12 <= arc.length <= holonomy


def test_no_shorter_arc_on_wider_branches():
    """Searching twice as many branches of the rotation vector, on a four times finer grid, finds no shorter arc."""
    rotations = random_rotations(40, seed=2)
    lengths = [BALL.optimal_arc(r).length for r in rotations]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(rolling_ball, "ARC_BRANCHES", 2 * rolling_ball.ARC_BRANCHES)
        patch.setattr(rolling_ball, "ARC_GRID", 4 * rolling_ball.ARC_GRID)
        wider = [BALL.optimal_arc(r).length for r in rotations]
    assert np.abs(np.array(lengths) - wider).max() <= 1e-12


@pytest.mark.parametrize("gamma", [0.3, math.pi / 2, -2.0, math.pi])
def test_shortest_turn_about_the_vertical_is_a_whole_loop(gamma):
    """Rz(γ) takes a whole turn of exp(s(ω₀ − k e_z)^): ρ√(4π² − φ²) with |φ| = max(|γ|, 2π − |γ|)."""
    arc = BALL.optimal_arc(Rotation.from_rotvec([0.0, 0.0, gamma]))
    phi = max(abs(gamma), 2 * math.pi - abs(gamma))
    assert arc.length == pytest.approx(math.sqrt(4 * math.pi**2 - phi**2), rel=1e-12)


@pytest.mark.parametrize("angle", [0.5, 2.0, math.pi - 1e-3])
def test_tilt_about_a_horizontal_axis_is_a_straight_roll(angle):
    """The shortest way to a rotation about a horizontal axis is the straight roll of length ρ·angle."""
    axis = np.array([math.cos(0.7), math.sin(0.7), 0.0])
    arc = BALL.optimal_arc(Rotation.from_rotvec(angle * axis))
    assert arc.length == pytest.approx(angle, rel=1e-12)
    assert abs(arc.curvature) <= 1e-9


def test_holonomy_legs_reach_the_attitude_and_return_the_centre():
    """Tilt ∘ turns equals the target rotation to 1e-12; with a start position the legs sum to bring it home."""
    rng = np.random.default_rng(3)
    for rotation in random_rotations(100, seed=3):
        start = rng.uniform(-3.0, 3.0, 2)
        for position in (None, start):
            legs = BALL.holonomy_legs(rotation, position)
            assert (BALL.roll(legs) * rotation.inv()).magnitude() <= 1e-12
            if position is not None:
                assert np.abs(position + legs.sum(axis=0)).max() <= 1e-12


@pytest.mark.parametrize("integrator, options, bound", [("dop853", {"rtol": 1e-10, "atol": 1e-12}, 1e-8)])
def test_scipy_stepper_on_the_matrix_ode_agrees_with_the_exact_step(integrator, options, bound):
    """DOP853 on Ṙ = ω̂R over 200 random steps stays within its tolerance's reach of the exact step."""
    steps = np.random.default_rng(4).uniform(-0.1, 0.1, (200, 2))
    exact = roll_by_steps(BALL, steps)
    numeric = roll_by_steps(BALL, steps, make_stepper(integrator, BALL, **options))
    assert angle_between(exact, numeric) <= bound
