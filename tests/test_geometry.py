"""connenv.geometry (issue 34, §1): the curvature of each env's connection against its closed form, the holonomy of
loops against the curvature's area integral, minimum-perturbation coordinates, and the curvature map's command."""

from __future__ import annotations

import math

import gymnasium as gym
import matplotlib.image
import numpy as np
import pytest

from agents import curvature_map
import connenv  # noqa: F401  (registers the envs)
from connenv import cli, geometry
from connenv.core.lie import Connection
from connenv.systems import falling_cat, rolling_coin

RNG = np.random.default_rng(34)


def circle(radius, centre=(0.0, 0.0), samples=200):
    """A counterclockwise circle based on its rim, at centre + (radius, 0)."""
    t = np.linspace(0.0, 2 * math.pi, samples + 1)
    loop = np.asarray(centre) + radius * np.stack([np.cos(t), np.sin(t)], -1)
    loop[-1] = loop[0]
    return loop


def keyhole(radius, samples=200):
    """Out from the origin to the rim, once around counterclockwise, and back: a loop based at the centre of the
    disc it encloses."""
    return np.concatenate([[[0.0, 0.0]], circle(radius, samples=samples), [[0.0, 0.0]]])


def order(sizes, errors) -> float:
    """The slope of log error against log size (least squares)."""
    return float(np.polyfit(np.log(sizes), np.log(errors), 1)[0])


def test_the_beanies_connection_is_flat_and_its_holonomy_the_winding_alone():
    """A 1-D shape space encloses no area, so F = 0 and the curvature predicts nothing; yet ψ winds, and each turn
    of the beanie turns the body by −2π I₂/(I₁ + I₂) whatever the speed profile and back-and-forth on the way."""
    env = gym.make("connenv/ElroysBeanie-v0", body_inertia=1.3, beanie_inertia=0.4).unwrapped
    F = geometry.curvature(env, RNG.uniform(-20.0, 20.0, (50, 1))).F
    assert F.shape == (50, 1, 1, 1) and not np.any(F)
    t = np.linspace(0.0, 1.0, 301)
    for winding in (-1, 1, 2):
        psi = 0.7 + 2 * math.pi * winding * t + 1.5 * np.sin(6 * math.pi * t)  # there and back on the way
        holonomy = geometry.loop_holonomy(env, psi[:, None], period=2 * math.pi)
        np.testing.assert_allclose(holonomy.net, [-2 * math.pi * winding * 0.4 / 1.7], rtol=1e-12)
        assert holonomy.predicted.tolist() == [0.0]


def test_the_cats_curvature_is_its_closed_form():
    """F₁₂ about the spine is f′(β)/β (connenv.systems.falling_cat.curvature), by complex step, to 1e-10, and the
    cat turns about nothing else; at the straight cat too, where the connection's formula divides by β²."""
    env = gym.make("connenv/FallingCat-v0").unwrapped
    s = np.concatenate([[[0.0, 0.0], [1e-9, 0.0]], RNG.uniform(-1.2, 1.2, (100, 2))])
    result = geometry.curvature(env, s)
    expected = falling_cat.curvature(np.hypot(s[:, 0], s[:, 1]), **env.inertias)
    assert result.method == "complex step"
    np.testing.assert_allclose(result.F[:, 0, 0, 1], expected, rtol=1e-10)
    np.testing.assert_array_equal(result.F[:, 1:], 0.0)
    np.testing.assert_array_equal(result.F[:, 0, 1, 0], -result.F[:, 0, 0, 1])


def test_the_coins_curvature_and_holonomy_are_its_docstrings():
    """dA = (−R cos θ, R sin θ) dθ ∧ dφ; on the abelian ℝ² the holonomy is −∬dA exactly (Stokes), for a rectangle of
    any size the closed form `rectangle_displacement`."""
    env = gym.make("connenv/RollingCoin-v0", radius=0.7).unwrapped
    s = RNG.uniform(-4.0, 4.0, (100, 2))
    F = geometry.curvature(env, s).F[:, :, 0, 1]
    np.testing.assert_allclose(F, 0.7 * np.stack([-np.cos(s[:, 0]), np.sin(s[:, 0])], -1), rtol=1e-13, atol=1e-15)
    theta0, delta_theta, delta_phi = 0.4, 2.5, 3.0
    corners = [(theta0, 0.0), (theta0, delta_phi), (theta0 + delta_theta, delta_phi), (theta0 + delta_theta, 0.0)]
    loop = np.concatenate([np.linspace(a, b, 20, endpoint=False) for a, b in zip(corners, corners[1:] + corners[:1])])
    holonomy = geometry.loop_holonomy(env, np.concatenate([loop, loop[:1]]))
    expected = rolling_coin.rectangle_displacement(theta0, delta_theta, delta_phi, 0.7)
    np.testing.assert_allclose(holonomy.net, expected, rtol=1e-12)
    np.testing.assert_allclose(holonomy.predicted, expected, rtol=1e-12)


def test_the_balls_holonomy_is_curvature_times_area_to_second_order():
    """The ball's connection is constant, so its curvature is the bracket alone, F = [A₁, A₂] = e_z/ρ² (space
    frame), and a small loop of area a turns the ball by −a/ρ² about the vertical. Based at the centre of the disc it
    encloses, the loop's error falls as a² (the next Magnus term, third order in its size, is the area's first moment
    about the base point: zero there)."""
    env = gym.make("connenv/RollingBall-v0", radius=1.5).unwrapped
    np.testing.assert_allclose(geometry.curvature(env, [0.3, -2.0]).F[0, :, 0, 1], [0.0, 0.0, 1 / 1.5**2], atol=1e-12)
    radii = np.array([0.4, 0.2, 0.1, 0.05]) * 1.5
    areas = 100 * radii**2 * math.sin(2 * math.pi / 200)  # of the 200-gon
    errors = []
    for r, area in zip(radii, areas):
        holonomy = geometry.loop_holonomy(env, keyhole(r))
        np.testing.assert_allclose(holonomy.predicted, [0.0, 0.0, -area / 1.5**2], rtol=1e-12, atol=1e-15)
        errors.append(np.linalg.norm(holonomy.net - holonomy.predicted))
    assert order(areas, errors) >= 1.8


def test_the_snakes_first_order_prediction_improves_as_the_loop_shrinks():
    """On SE(2) both parts of F act (dA and the bracket); the prediction's error, relative to the loop's area (the
    size of the motion), falls as the loop shrinks, and θ's row, abelian, is predicted exactly."""
    env = gym.make("connenv/SnakeSwimmer-v0").unwrapped
    relative = []
    for r in (0.8, 0.4, 0.2):
        holonomy = geometry.loop_holonomy(env, circle(r, centre=(0.3, -0.2)))
        error = np.abs(holonomy.net - holonomy.predicted)
        assert error[2] <= 1e-12
        relative.append(np.linalg.norm(error[:2]) / (math.pi * r * r))
    assert relative[0] > relative[1] > relative[2]
    assert relative[2] < 0.3 * relative[0]


def test_minimum_perturbation_coordinates_predict_the_snakes_gaits_better():
    """In the frame that moves least with the shape the curvature's area integral predicts the circular gaits'
    translation better (the turn is the same in both frames, and exact); the frame's curvature is Ad_{β⁻¹} F, and
    stepping its connection A' = Ad_{β⁻¹} A − β⁻¹ dβ gives the holonomy conjugated by β at the base shape."""
    local = geometry.local_connection("connenv/SnakeSwimmer-v0")
    (row,) = geometry.gait_errors(local, amplitudes=(0.6,), samples=200)
    default, minimum = (np.hypot(*(h.net - h.predicted)[:2]) for h in (row.default, row.minimum))
    assert minimum < 0.5 * default
    assert abs(row.default.net[2] - row.default.predicted[2]) <= 1e-12
    frame = geometry.minimum_perturbation(local)
    moved = Connection("SE2", "body", lambda s: frame.transformed(s, geometry.evaluate(local.connection, s)), True)
    s = RNG.uniform(-1.5, 1.5, (20, 2))
    result = geometry.curvature(moved, s)  # the splines carry no complex shapes: by Richardson
    expected = frame.adjoint_inverse(s, geometry.curvature(local, s).F[:, :, 0, 1])
    assert result.method == "richardson"
    np.testing.assert_allclose(result.F[:, :, 0, 1], expected, atol=20 * np.max(result.error) + 1e-9)
    loop = circle(0.6 * 2 * math.pi / 3, samples=200)
    stepped = geometry.loop_holonomy(moved, loop).net
    np.testing.assert_allclose(stepped, geometry.loop_holonomy(local, loop, frame_change=frame).net, atol=1e-9)


def test_the_command_draws_a_map_and_answers_an_env_without_a_connection(tmp_path, capsys):
    path = tmp_path / "cat.png"
    geometry.main(["connenv/FallingCat-v0", "--write", str(path)])
    image = matplotlib.image.imread(path)
    assert image.shape[:2] == (round(geometry.FIGURE[1] * geometry.DPI), round(geometry.FIGURE[0] * geometry.DPI))
    assert np.ptp(image[..., :3]) > 0.5  # drawn: dark arrows on a light ground
    gaited = tmp_path / "cat-gait.png"
    curvature_map.main(["connenv/FallingCat-v0", "--write", str(gaited)])  # with the analytic controller's gait
    assert np.sum(np.abs(matplotlib.image.imread(gaited) - image)) > 0
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_:
        cli.run(geometry.main, geometry.PROG, ["connenv/Swing-v0"])
    error = capsys.readouterr().err
    assert exit_.value.code == 2 and error.count("\n") == 1 and "no mechanical connection" in error


def has_connection(env_id) -> bool:
    try:
        geometry.local_connection(env_id)
    except ValueError:  # an active-constraint env
        return False
    return True


CONNECTION_ENVS = [env_id for env_id in sorted(gym.registry) if env_id.startswith("connenv/") and has_connection(env_id)]


@pytest.mark.parametrize("env_id", CONNECTION_ENVS)
def test_every_connections_small_loops_move_the_body_by_the_enclosed_curvature(env_id):
    """The curvature's area integral predicts a small loop's holonomy, with an error that falls faster than the loop:
    halving a loop about a random shape (based at its centre) divides the error by at least 2^3.5 (fourth order; the
    prediction is exact, to rounding, where the directions that move commute: the cat's roll, the coin's plane). On
    a 1-D shape space a loop goes there and back and moves nothing."""
    local = geometry.local_connection(env_id)
    low, high = np.where(np.isfinite(local.low), local.low, -1.0), np.where(np.isfinite(local.high), local.high, 1.0)
    centre = RNG.uniform(0.25, 0.75, low.size) * (high - low) + low  # a shape space without bounds: about 0
    span = 0.1 * np.min(high - low)
    errors = []
    for radius in (span, span / 2):
        if local.low.size == 1:
            loop = centre + radius * np.array([[0.0], [1.0], [-1.0], [0.0]])
        else:
            loop = centre + keyhole(radius)
        holonomy = geometry.loop_holonomy(env_id, loop)
        errors.append(np.max(np.abs(holonomy.net - holonomy.predicted)))
    if local.low.size == 1:
        assert errors[0] <= 1e-12
    else:
        assert errors[1] <= errors[0] / 2**3.5 + 1e-13


SQUARE = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1], [0.0, 0.0]]


def with_point(point):
    loop = [list(p) for p in SQUARE]
    loop[1] = point
    return loop


@pytest.mark.parametrize(
    ("call", "message"),
    [  # issue 44 §2: each once a NaN, an accepted shape or another exception than a ValueError naming the input
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", [np.nan, 0.0]), r"s=\[nan, 0.0\] is not finite"),
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", [np.inf, 0.0]), r"s=\[inf, 0.0\] is not finite"),
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", [0.1 + 1e-3j, 0.0]), "s=.* is complex"),
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", np.array([0.1, 0.2]) + 0j), "(?s)s=.* is complex"),
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", ["0.1", "0.2"]), "s=.* must be finite real"),
        (lambda: geometry.curvature("connenv/SnakeSwimmer-v0", np.zeros((0, 2))), r"s=.* has shape \(0, 2\)"),
        (lambda: geometry.curvature("connenv/RollingBall-v0", [0.1, 0.2, 0.3]), r"s=.* has shape \(3,\).*k = 2"),
        (lambda: geometry.curvature("connenv/Connection-v0", [0.1, 0.2]), r"s=.* has shape \(2,\).*k = 1"),
        (lambda: geometry.curvature(lambda s: np.zeros((len(s), 1, 2)), [0.1, 0.2, 0.3], group="SO2"),
         "s=.* has 3 shape coordinates, and the connection A"),
        (lambda: geometry.enclosed("connenv/SnakeSwimmer-v0", with_point([np.nan, 0.0])), "loop=.* is not finite"),
        (lambda: geometry.enclosed("connenv/SnakeSwimmer-v0", SQUARE, apex=[np.nan, 0.0]), "apex=.* is not finite"),
        (lambda: geometry.enclosed("connenv/SnakeSwimmer-v0", SQUARE, apex=[0.0]), r"apex=\[0.0\] has shape \(1,\)"),
        (lambda: geometry.loop_holonomy("connenv/SnakeSwimmer-v0", with_point([np.inf, 0.0])),
         "loop=.* is not finite"),
        (lambda: geometry.loop_holonomy("connenv/SnakeSwimmer-v0", np.array(SQUARE) * 1j), "(?s)loop=.* is complex"),
        (lambda: geometry.loop_holonomy("connenv/ElroysBeanie-v0", [[0.0], [1.0], [0.0]], period=math.nan),
         "period=nan"),
        (lambda: geometry.minimum_perturbation("connenv/SnakeSwimmer-v0", grid=1), r"grid=1: .*\[3, 1025\]"),
        (lambda: geometry.minimum_perturbation("connenv/SnakeSwimmer-v0", grid=0), r"grid=0: .*\[3, 1025\]"),
        (lambda: geometry.minimum_perturbation("connenv/SnakeSwimmer-v0", grid=5.5), r"grid=5.5"),
        (lambda: geometry.minimum_perturbation("connenv/SnakeSwimmer-v0", grid=True), r"grid=True"),
    ],
)
def test_bad_shapes_loops_and_grids_are_value_errors_naming_them(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_the_map_names_the_shapes_and_units_and_explains_its_marks(monkeypatch, tmp_path):
    """The curvature map's axes are the system's shape coordinates with their units, each colour bar says F's unit
    (the direction's unit per shape unit²), and a legend names the arrows, the gait and its start, whose
    arrowheads show the way it runs."""
    from matplotlib.figure import Figure

    drawn = []
    monkeypatch.setattr(Figure, "savefig", lambda figure, *args, **kwargs: drawn.append(figure))
    gait = np.array([[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5], [0.0, 0.0]])
    geometry.draw("connenv/SnakeSwimmer-v0", str(tmp_path / "map.png"), points=9, gait=gait, gait_label="a square")
    (figure,) = drawn
    panels = [axes for axes in figure.axes if axes.get_label() != "<colorbar>"]
    bars = [axes for axes in figure.axes if axes.get_label() == "<colorbar>"]
    assert [(p.get_xlabel(), p.get_ylabel()) for p in panels] == [("alpha (rad)", "beta (rad)")] * 3
    assert [bar.get_ylabel() for bar in bars] == ["F₁₂ (x) [m/rad²]", "F₁₂ (y) [m/rad²]", "F₁₂ (θ) [1/rad]"]
    (legend,) = figure.legends
    assert [text.get_text() for text in legend.get_texts()][1:] == ["a square", "its start"]
    assert all(sum(hasattr(child, "arrow_patch") for child in p.get_children()) >= 3 for p in panels)
