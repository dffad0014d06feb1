"""ChaplyginSleigh-v0 as a task: the start, the mass held at C, the reference controller, and bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401  (registers the envs)
from agents.controllers.chaplygin_sleigh import ShakePlanner, TailFirst

ID = "connenv/ChaplyginSleigh-v0"


def test_start_is_at_rest_with_the_target_one_to_two_metres_away():
    env = gym.make(ID)
    for seed in range(20):
        obs, info = env.reset(seed=seed)
        state = info["state"]
        assert all(state[k] == 0.0 for k in ("x", "y", "phi", "v", "omega", "u", "u_dot", "u_along", "u_along_dot"))
        assert 1.0 <= info["distance"] <= 2.0 and obs.shape == (8,)


def test_action_zero_with_the_mass_at_C_keeps_the_mass_there_and_the_sleigh_on_its_course():
    env = gym.make(ID)
    env.reset(seed=0, options={"state": {"v": 0.5}})
    for _ in range(40):
        _, _, _, _, info = env.step(np.zeros(2, np.float32))
    state = info["state"]
    assert state["u"] == 0.0 and state["u_along"] == 0.0 and state["u_dot"] == 0.0
    assert state["x"] == pytest.approx(0.5 * 40 * 0.05, abs=1e-12) and state["y"] == 0.0 and state["omega"] == 0.0


def test_reset_sets_the_state_and_the_target():
    env = gym.make(ID)
    state = {"x": 1.0, "y": -2.0, "phi": 0.5, "v": 0.3, "omega": -0.4, "u": 0.1, "u_dot": 1.0, "u_along": -0.2,
             "u_along_dot": 0.5}
    _, info = env.reset(options={"state": state, "target": (3.0, 1.0)})
    assert info["state"] == pytest.approx({**state, "t": 0.0}, abs=1e-12)
    assert info["distance"] == pytest.approx(math.hypot(2.0, 3.0))


@pytest.mark.parametrize(
    "law, seed",
    [(ShakePlanner, 8), (ShakePlanner, 11), (TailFirst, 7)],  # targets 175°, 0° (straight ahead) and 143° off the nose
)
def test_the_controllers_reach_the_target(law, seed):
    env = gym.make(ID)
    controller = law(env.unwrapped)
    obs, _ = env.reset(seed=seed)
    for step in range(1000):
        obs, _, terminated, truncated, info = env.step(controller.predict(obs, episode_start=np.array([step == 0]))[0])
        if terminated or truncated:
            break
    assert info["is_success"] and info["distance"] <= 0.1


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"sled_mass": 0.0}, "sled_mass"),
        ({"offset": -0.1}, "offset"),
        ({"rail": 0.0}, "rail"),
        ({"box": -1.0}, "box"),
        ({"tolerance": 1.5}, "tolerance"),
        ({"max_mass_speed": None}, "max_mass_speed=None"),
        ({"max_mass_speed": -1.0}, "max_mass_speed"),
        ({"dt": 2.0}, "dt"),
        ({"substep": 3}, "substep"),
    ],
)
def test_bad_parameters_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(ID, **kwargs)


@pytest.mark.parametrize(
    "options, match",
    [
        ({"state": {"u": 0.5}}, "state u"),
        ({"state": {"t": 1.0}}, "t"),
        ({"state": {"phi": 10.0}}, "phi"),
        ({"state": {"v": math.nan}}, "state v"),
        ({"target": (1.0,)}, "target"),
        ({"start": 1}, "start"),
    ],
)
def test_bad_reset_options_are_refused(options, match):
    with pytest.raises(ValueError, match=match):
        gym.make(ID).reset(options=options)


def test_bad_actions_are_refused():
    env = gym.make(ID)
    env.reset(seed=0)
    for action in ([0.0], [np.nan, 0.0], "a"):
        with pytest.raises(ValueError, match="action"):
            env.step(action)
