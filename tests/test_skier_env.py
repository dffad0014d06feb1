"""Skier-v0 as a Gymnasium env: checkers, determinism, pickling, the task and every bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers.skier import SkierPumping

ID = "connenv/Skier-v0"
SYMBOLIC = {"trail": "0.25*x**2", "trail_params": {"domain": (-5.0, 5.0)}, "target_x": 4.0}


def test_start_is_at_rest_crouched_half_a_metre_to_two_from_the_bottom():
    env = gym.make(ID)
    sides = set()
    for seed in range(50):
        _, info = env.reset(seed=seed)
        state = info["state"]
        assert 0.5 <= abs(state["x"]) <= 2.0
        assert state["x_dot"] == 0.0 and state["p"] == 0.0 and state["h"] == 0.5 and state["t"] == 0.0
        sides.add(np.sign(state["x"]))
    assert sides == {-1.0, 1.0}


def test_info_carries_the_physical_state():
    """At the valley's bottom: σ = 1, κ = H k²/2, s = x; p = m (1 − κh)² ẋ; E = ½ m (1 − κh)² ẋ² + m g h."""
    env = gym.make(ID, mass=80.0)
    _, info = env.reset(options={"state": {"x": 0.0, "x_dot": 2.0, "h": 0.7}})
    state, kappa = info["state"], 3.0 * (2 * math.pi / 12) ** 2 / 2
    assert set(state) == {"x", "x_dot", "p", "h", "t", "s", "kappa"}
    assert state["kappa"] == pytest.approx(kappa) and state["s"] == 0.0
    assert state["p"] == pytest.approx(80.0 * (1 - kappa * 0.7) ** 2 * 2.0)
    assert info["energy"] == pytest.approx(0.5 * 80.0 * (1 - kappa * 0.7) ** 2 * 4.0 + 80.0 * 9.81 * 0.7)
    _, info = env.reset(options={"state": {"x": 3.0}})
    assert 3.0 < info["state"]["s"] < 3.0 * math.sqrt(1 + (3.0 * math.pi / 12) ** 2)  # between x and max σ · x


def test_success_at_the_rim_and_the_reward_is_the_log_of_the_progress():
    env = gym.make(ID)
    _, info = env.reset(options={"state": {"x": 5.9, "x_dot": 3.0}})
    assert info["progress"] > 1.0 and not info["is_success"]
    _, reward, terminated, _, info = env.step(np.array([-1.0], np.float32))
    assert terminated and info["is_success"] and info["state"]["x"] >= 6.0
    assert reward == pytest.approx(-0.01, abs=1e-6)  # no jump: the energy, so the progress, is conserved
    _, info = env.reset(options={"state": {"x": 0.0, "x_dot": 1.0}})
    _, reward, _, _, after = env.step(np.array([1.0], np.float32))
    assert reward == pytest.approx(math.log(after["progress"] / info["progress"]) - 0.01)


def test_a_user_trail_succeeds_at_its_target():
    env = gym.make(ID, **SYMBOLIC)
    _, info = env.reset(options={"state": {"x": 0.0, "x_dot": 12.0}})
    for _ in range(100):
        *_, terminated, _, info = env.step(np.array([0.0], np.float32))
        if terminated:
            break
    assert info["is_success"] and info["state"]["x"] >= 4.0


def test_observations_stay_in_the_space_while_pumping_out_of_the_valley_and_halfpipe():
    policy = SkierPumping()
    for kwargs in ({}, {"trail": "halfpipe"}):
        env = gym.make(ID, **kwargs)
        for seed in range(3):
            obs, _ = env.reset(seed=seed)
            done = False
            while not done:
                assert env.observation_space.contains(obs)
                obs, _, terminated, truncated, info = env.step(policy.predict(obs)[0])
                done = terminated or truncated
            assert info["is_success"]
            assert env.observation_space.contains(obs)


def test_controller_predict_handles_a_batch_like_sb3():
    obs = np.array([[0, 0.1, 1, 0.5, 0, 0], [0, 0.1, 1, -0.5, 0, 0], [0, -0.1, 1, -0.5, 0, 0]], np.float32)
    action, state = SkierPumping().predict(obs, deterministic=True)
    assert action.shape == (3, 1) and state is None
    assert action[:, 0].tolist() == [1.0, -1.0, 1.0]


def test_bounded_height_speed_moves_h_at_that_speed():
    env = gym.make(ID, max_height_speed=2.0).unwrapped
    env.reset(seed=0)
    env.step(np.array([1.0], np.float32))
    assert env.state.h == pytest.approx(0.6)
    env.step(np.array([1.0], np.float32))
    env.step(np.array([1.0], np.float32))
    assert env.state.h == pytest.approx(0.8)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"h_min": 0.0}, "h_min=0.0"),
        ({"h_min": 1.0}, "h_max=1.0"),
        ({"h_max": float("nan")}, "h_max=nan"),
        ({"mass": -70.0}, "mass=-70.0"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"max_height_speed": -1.0}, "max_height_speed=-1.0"),
        ({"integrator": "leapfrog"}, "integrator='leapfrog'"),
        ({"integrator": "exact"}, "exact"),
        ({"trail": "moguls"}, "trail='moguls'"),
        ({"trail": 3.0}, "trail=3.0"),
        ({"trail_params": {"depth": 2.0}}, "depth"),
        ({"trail_params": {"H": -3.0}}, "H=-3.0"),
        ({"trail": "halfpipe", "trail_params": {"max_angle": 2.0}}, "max_angle=2.0"),
        ({"trail": "log(x)", "trail_params": {"domain": (-1.0, 1.0)}, "target_x": 0.5}, r"f\(x\) is not finite"),
        ({"trail": "x**2 + a", "trail_params": {"domain": (-1.0, 1.0)}, "target_x": 0.5}, r"symbol\(s\) \['a'\]"),
        ({"trail": "0.1*x**2", "trail_params": {"domain": (1.0, -1.0)}, "target_x": 0.5}, "domain hi=-1.0"),
        ({"trail": "0.1*x**2", "trail_params": {"domain": (-2.0, 2.0)}}, "no rims: give target_x"),
        ({"trail": "0.1*x**2", "trail_params": {"domain": (-2.0, 2.0)}, "target_x": 3.0}, "target_x=3.0"),
        ({"trail": "0.1*x**2", "trail_params": {"domain": (-2.0, 2.0)}, "target_x": 0.0}, "at the bottom"),
        (
            {"trail": (np.sin, np.cos, np.sin, np.cos), "trail_params": {"domain": (-2.0, 2.0)}, "target_x": 1.0},
            "f'' disagrees with the derivative of f'",
        ),
        ({"trail": (np.sin, np.cos), "trail_params": {"domain": (-2.0, 2.0)}}, "four callables"),
        ({"bogus": 1}, "bogus"),
    ],
)
def test_bad_parameters_and_trails_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"state": {"theta": 1.0}}, "theta"),
        ({"state": {"x": 7.0}}, r"state x=7.0 .*\[-6.0, 6.0\]"),
        ({"state": {"h": 1.5}}, r"state h=1.5 .*\[0.5, 1.0\]"),
        ({"state": {"x": float("nan")}}, "state x=nan"),
        ({"state": {"x_dot": 1.0, "p": 1.0}}, "both x_dot and p"),
        ({"state": {"p": float("inf")}}, "state p=inf"),
    ],
)
def test_bad_reset_states_are_named(options, message):
    with pytest.raises(ValueError, match=message):
        gym.make(ID).reset(options=options)


@pytest.mark.parametrize(
    "action, message",
    [(np.zeros(2, np.float32), r"shape \(2,\)"), (np.array([np.nan]), "not finite")],
)
def test_bad_actions_are_rejected(action, message):
    env = gym.make(ID).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


