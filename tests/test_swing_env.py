"""Swing-v0 as a Gymnasium env: checkers, determinism, pickling, the task and every bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers.swing import PiccoliKulkarni


def test_start_is_near_rest_at_r_max():
    env = gym.make("connenv/Swing-v0")
    for seed in range(50):
        _, info = env.reset(seed=seed)
        assert 0.05 <= abs(info["state"]["theta"]) <= 0.1
        assert info["state"]["theta_dot"] == 0.0 and info["state"]["r"] == 2.0 and info["state"]["t"] == 0.0


def test_info_carries_the_physical_state():
    env = gym.make("connenv/Swing-v0", mass=2.0)
    _, info = env.reset(options={"state": {"theta": 0.5, "theta_dot": -1.0, "r": 1.8}})
    state = info["state"]
    assert set(state) == {"theta", "theta_dot", "p", "r", "t"}
    assert state["p"] == pytest.approx(2.0 * 1.8**2 * -1.0)
    assert info["energy"] == pytest.approx(0.5 * 2.0 * 1.8**2 * 1.0 - 2.0 * 9.81 * 1.8 * math.cos(0.5))
    _, _, _, _, info = env.step(np.array([0.0], np.float32))
    assert info["state"]["t"] == pytest.approx(0.05) and info["state"]["r"] == pytest.approx(1.8)


def test_success_terminates_when_the_energy_implies_the_target_amplitude():
    env = gym.make("connenv/Swing-v0")
    # squatting at the bottom with the speed of amplitude π/2 at r = r_max: a jump to r_min reaches it
    speed = math.sqrt(2 * 9.81 / 2.0)
    env.reset(options={"state": {"theta": 0.0, "theta_dot": speed * 0.999, "r": 2.0}})
    *_, terminated, _, info = env.step(np.array([1.0], np.float32))
    assert not terminated and not info["is_success"]
    env.reset(options={"state": {"theta": 0.0, "theta_dot": speed * 0.999, "r": 2.0}})
    _, reward, terminated, _, info = env.step(np.array([-1.0], np.float32))
    assert terminated and info["is_success"] and info["amplitude"] >= math.pi / 2
    # reward = ln(h′/h) − 0.01, and the jump at the bottom multiplies h by (r_max/r_min)³
    assert reward == pytest.approx(3 * math.log(2.0 / 1.6) - 0.01, rel=1e-9)


def test_observations_stay_in_the_space_while_pumping_over_the_top():
    env = gym.make("connenv/Swing-v0", target_amplitude=math.pi)
    policy = PiccoliKulkarni()
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            assert env.observation_space.contains(obs)
            obs, _, terminated, truncated, info = env.step(policy.predict(obs)[0])
            done = terminated or truncated
        assert info["is_success"]


def test_controller_predict_handles_a_batch_like_sb3():
    obs = np.array([[1, 0.1, 0.5, 1], [1, 0.1, -0.5, 1], [1, -0.1, -0.5, -1]], np.float32)
    action, state = PiccoliKulkarni().predict(obs, deterministic=True)
    assert action.shape == (3, 1) and state is None
    assert action[:, 0].tolist() == [-1.0, 1.0, -1.0]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"r_min": 0.0}, "r_min=0.0"),
        ({"r_min": -1.0}, "r_min=-1.0"),
        ({"r_max": 1.5}, "r_max=1.5"),
        ({"r_min": float("nan")}, "r_min=nan"),
        ({"g": 0.0}, "g=0.0"),
        ({"mass": -1.0}, "mass=-1.0"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"dt": "fast"}, "dt='fast'"),
        ({"target_amplitude": 3.5}, "target_amplitude=3.5"),
        ({"target_amplitude": 0.0}, "target_amplitude=0.0"),
        ({"max_radial_speed": 0.0}, "max_radial_speed=0.0"),
        ({"integrator": "leapfrog"}, "integrator='leapfrog'"),
        ({"integrator": "rk4", "substeps": 0}, "substeps=0"),
        ({"integrator": "dop853", "rtol": -1e-9}, "rtol=-1e-09"),
        ({"bogus": 1}, "bogus"),
        ({"render_mode": "ascii"}, "render_mode='ascii'"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")  # gymnasium's own warning comes first
def test_bad_parameters_are_named_with_their_range(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make("connenv/Swing-v0", **kwargs)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"start": 1}, "start"),
        ({"state": {"omega": 1.0}}, "omega"),
        ({"state": {"r": 2.5}}, r"state r=2.5 .*\[1.6, 2.0\]"),
        ({"state": {"theta": float("nan")}}, "state theta=nan"),
        ({"state": {"theta_dot": 1.0, "p": 1.0}}, "both theta_dot and p"),
        ({"state": {"theta_dot": 100.0}}, "state theta_dot=100.0"),
        ({"state": {"p": float("inf")}}, "state p=inf"),
    ],
)
def test_bad_reset_states_are_named(options, message):
    env = gym.make("connenv/Swing-v0")
    with pytest.raises(ValueError, match=message):
        env.reset(options=options)


@pytest.mark.parametrize(
    "action, message",
    [(np.zeros(2, np.float32), r"shape \(2,\)"), (np.float32(0.5), r"shape \(\)"), (np.array([np.nan]), "not finite")],
)
def test_bad_actions_are_rejected(action, message):
    env = gym.make("connenv/Swing-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_actions_outside_the_box_are_clipped_to_the_radius_range():
    env = gym.make("connenv/Swing-v0").unwrapped
    env.reset(seed=0)
    env.step(np.array([-7.0], np.float32))
    assert env.state.r == 1.6


