"""RollingCoinSurface-v0 as a Gymnasium env: the start, the task (chord success, reward, arena), the controller
and every bad input."""

import math
import pickle

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers import controller
from connenv.core.steppers import RK4, Exact, Scipy

ID = "connenv/RollingCoinSurface-v0"


def test_start_is_at_rest_with_a_random_heading_and_the_target_four_metres_down_within_the_cone():
    env = gym.make(ID)
    headings = []
    for seed in range(30):
        _, info = env.reset(seed=seed)
        state, target = info["state"], env.unwrapped.state.target
        assert set(state) == {"x", "y", "theta", "phi", "phi_dot", "t"}
        assert (state["x"], state["y"], state["phi"], state["phi_dot"], state["t"]) == (0.0, 0.0, 0.0, 0.0, 0.0)
        assert math.hypot(*target) == pytest.approx(4.0) and abs(math.atan2(target[0], target[1])) <= 0.25
        assert info["distance"] == pytest.approx(4.0)
        assert info["energy"] == pytest.approx(9.81 * env.unwrapped.surface.height(0.0, 0.0)[0])  # m = 1, at rest
        headings.append(state["theta"])
    assert min(headings) < -2.0 and max(headings) > 2.0


def test_info_energy_is_three_quarters_m_r2_phi_dot2_plus_m_g_z():
    env = gym.make(ID, surface="plane", slope=(0.1, -0.2), mass=2.0, radius=0.4)
    _, info = env.reset(options={"state": {"x": 1.0, "y": 2.0, "theta": 0.3, "phi": 1.0, "phi_dot": 3.0},
                                 "target": (1.0, 5.0)})
    assert info["energy"] == pytest.approx(0.75 * 2.0 * 0.4**2 * 9.0 + 2.0 * 9.81 * (0.1 - 0.4))
    assert info["state"]["phi"] == 1.0 and info["distance"] == pytest.approx(3.0)


def test_default_steppers_exact_on_a_plane_and_rk4_with_8_substeps_elsewhere():
    assert isinstance(gym.make(ID, surface="plane").unwrapped.stepper, Exact)
    assert gym.make(ID).unwrapped.stepper == RK4(8)
    assert isinstance(gym.make(ID, integrator="dop853").unwrapped.stepper, Scipy)


def test_success_when_the_steps_chord_passes_within_tolerance_though_neither_end_does():
    """Rolling at 4 m/s straight through the target: the step's ends are 0.1 m either side of it."""
    env = gym.make(ID, surface="plane")
    env.reset(options={"state": {"x": 0.0, "y": 1.9, "theta": 0.0, "phi_dot": 8.0}, "target": (0.05, 2.0)})
    _, reward, terminated, _, info = env.step(np.array([0.0]))
    assert info["state"]["y"] == pytest.approx(2.1, abs=1e-2) and info["distance"] > 0.1
    assert info["miss"] == pytest.approx(0.05) and info["is_success"] and terminated
    assert reward == pytest.approx(math.hypot(0.05, 0.1) - info["distance"] - 0.01)


def test_the_rewards_sum_to_the_distance_gained_less_the_time_cost():
    env = gym.make(ID)
    _, info = env.reset(seed=3)
    total, steps, d0 = 0.0, 0, info["distance"]
    rng = np.random.default_rng(3)
    for _ in range(40):
        _, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 1))
        total, steps = total + reward, steps + 1
        if terminated or truncated:
            break
    assert total == pytest.approx(d0 - info["distance"] - 0.01 * steps, abs=1e-12)


def test_leaving_the_arena_ends_the_episode_without_success():
    env = gym.make(ID, surface="plane")
    env.reset(options={"state": {"x": 0.0, "y": 5.9, "theta": 0.0, "phi_dot": 4.0}, "target": (-3.0, 0.0)})
    _, _, terminated, _, info = env.step(np.array([0.0]))
    assert terminated and info["left_arena"] and not info["is_success"]


@pytest.mark.parametrize(
    "kwargs, seeds",
    [({}, range(8)), ({"surface": "plane"}, range(3)), ({"surface": "bowl"}, range(3))],
    ids=["hill", "plane", "bowl"],
)
def test_the_reference_controller_reaches_the_target(kwargs, seeds):
    """Pure pursuit of the target, around the hill by a waypoint where the line to the target climbs too high."""
    env = gym.make(ID, **kwargs)
    law = controller(ID, env=env)
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        for _ in range(200):
            obs, _, terminated, truncated, info = env.step(law.predict(obs)[0])
            if terminated or truncated:
                break
        assert info["is_success"], (kwargs, seed, info)


def test_a_float64_action_is_used_at_its_precision():
    env = gym.make(ID, surface="plane")
    env.reset(seed=0)
    a = np.array([0.1 + 1e-12])
    theta0 = env.unwrapped.state.theta
    info = env.step(a)[4]
    assert info["state"]["theta"] == theta0 + a[0] * 2.0 * 0.05


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"surface": "moon"}, "surface='moon'"),
        ({"surface": "bowl", "slope": (0.1, 0.0)}, "slope"),
        ({"surface": "plane", "slope": (0.1,)}, "slope"),
        ({"surface": "hill", "surface_params": {"depth": 1.0}}, "depth"),
        ({"surface": "x + y*b"}, "['b']"),
        ({"surface": "x + (", "surface_params": {}}, "sympy"),
        ({"surface": "1/x"}, "not finite"),
        ({"surface": "hill", "integrator": "exact"}, "exact"),
        ({"radius": -1.0}, "radius"),
        ({"max_steer_rate": 0.0}, "max_steer_rate"),
        ({"dt": 2.0}, "dt"),
        ({"tolerance": float("nan")}, "tolerance"),
        ({"target_distance": 7.0}, "outside the arena"),
        ({"target_angle": 2.0}, "target_angle"),
        ({"surface": "-0.25*y + 0.3*y**2"}, "not below the start"),
        ({"surface": "x**2 + y**2"}, "flat at the start"),
        ({"substep": 4}, "substep"),
        ({"radius": 1e300}, "radius=1e+300 is out of range: must be finite and in [0.001, 1000.0]"),
        ({"radius": 1e-300}, "radius=1e-300 is out of range"),
        ({"mass": 0.0}, "mass=0.0 is out of range: must be finite and in [1e-06, 1000.0]"),
        ({"g": 1e300}, "g=1e+300 is out of range: must be finite and in [1e-06, 1000.0]"),
        ({"max_steer_rate": 1e300}, "max_steer_rate=1e+300 is out of range"),
        ({"tolerance": 1e300}, "tolerance=1e+300 is out of range"),
        ({"surface": "bowl", "surface_params": {"radius": 1e-300}},
         "surface_params radius=1e-300 is out of range: must be finite and in [0.001, 1000.0]"),
        ({"surface_params": {"width": 1e-300}}, "surface_params width=1e-300"),
        ({"surface_params": {"height": 1e300}}, "surface_params height=1e+300"),
        ({"surface": "-a*y", "surface_params": {"a": 1e300}}, "surface_params a=1e+300"),
        ({"surface": "moon"}, "give surface_params for its symbol(s) ['moon']"),
        ({"surface": "x + I*y"}, "complex"),
    ],
)
def test_bad_parameters_are_refused_naming_them(kwargs, words):
    with pytest.raises(ValueError) as error:
        gym.make(ID, **kwargs)
    assert words in str(error.value)


@pytest.mark.parametrize(("surface", "downhill"), [("x", -math.pi / 2), ("y", -math.pi), ("-y", 0.0)])
def test_a_single_symbol_surface_is_a_sympy_plane(surface, downhill):
    """A surface that is one symbol ("x", "y") is the sympy plane z = x or z = y, not a misspelt built-in: the start
    heads down its gradient, z_x = 1 or z_y = 1, and the coin rolls downhill on it."""
    env = gym.make(ID, surface=surface).unwrapped
    assert math.remainder(env.downhill - downhill, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    env.reset(seed=0)
    z0 = env.surface.height(0.0, 0.0)[0]
    for _ in range(5):
        info = env.step(np.zeros(1))[4]
    assert env.surface.height(info["state"]["x"], info["state"]["y"])[0] < z0


@pytest.mark.parametrize(
    "options, words",
    [
        ({"state": {"x": 7.0}}, "state x"),
        ({"state": {"theta": 10.0}}, "state theta"),
        ({"state": {"phi_dot": 1e6}}, "state phi_dot"),
        ({"state": {"v": 1.0}}, "'v'"),
        ({"target": (0.0, 9.0)}, "target"),
        ({"target": (0.0,)}, "target"),
        ({"goal": (0.0, 1.0)}, "'goal'"),
    ],
)
def test_bad_reset_options_are_refused_naming_them(options, words):
    env = gym.make(ID)
    with pytest.raises(ValueError) as error:
        env.reset(options=options)
    assert words in str(error.value)


@pytest.mark.parametrize("action", [np.array([np.nan]), np.array([0.1, 0.2]), "left"])
def test_bad_actions_are_refused(action):
    env = gym.make(ID)
    env.reset(seed=0)
    with pytest.raises(ValueError):
        env.step(action)


def test_an_env_on_a_sympy_surface_pickles_and_continues_identically():
    env = gym.make(ID, surface="0.02*x**2 - 0.25*y + a*x*y", surface_params={"a": 0.01})
    env.reset(seed=0)
    twin = pickle.loads(pickle.dumps(env))
    for a in np.linspace(-1, 1, 10):
        assert np.array_equal(env.step(np.array([a]))[0], twin.step(np.array([a]))[0])
