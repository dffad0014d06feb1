"""SnakeSwimmer-v0 as a Gymnasium env: the start, the observation, the joints' motion, the reward, the gait planner
and every bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers import controller
from agents.controllers.snake_swimmer import BASE

ENV_ID = "connenv/SnakeSwimmer-v0"
TIME_LIMIT = 1000
LIMIT = 2 * math.pi / 3


def make(**kwargs):
    return gym.make(ENV_ID, **kwargs)


def test_start_is_straight_at_rest_with_a_target_one_to_two_body_lengths_away_in_any_direction():
    env = make()
    angles = []
    for seed in range(60):
        obs, info = env.reset(seed=seed)
        assert info["state"] == {"x": 0.0, "y": 0.0, "theta": 0.0, "alpha": 0.0, "beta": 0.0,
                                 "momentum": (0.0, 0.0, 0.0), "t": 0.0}  # fmt: skip
        assert 3.0 <= info["distance"] <= 6.0 and info["model"] == "reduced"  # body length 6a = 3 m
        assert obs[:2] == pytest.approx(np.array(info["target"]) / 3.0, abs=1e-6)
        angles.append(math.atan2(info["target"][1], info["target"][0]))
    assert np.histogram(angles, bins=4, range=(-math.pi, math.pi))[0].min() >= 6  # any direction


def test_info_and_observation_carry_the_state_in_the_middle_links_frame():
    env = make()
    state = {"x": 0.2, "y": -0.1, "theta": math.pi / 2, "alpha": 0.5, "beta": -1.0, "momentum": (0.4, 0.0, 0.1)}
    obs, info = env.reset(options={"state": state, "target": (0.2, 2.9)})
    assert info["state"] == {**state, "t": 0.0} and info["model"] == "full"
    assert info["distance"] == pytest.approx(3.0)
    scale = np.diag(env.unwrapped.full_system.locked_inertia(np.zeros(2)))
    expected = [1.0, 0.0, 0.0, 1.0, 0.5 / LIMIT, -1.0 / LIMIT, 0.4 / scale[0], 0.0, 0.1 / scale[2]]
    assert obs == pytest.approx(expected, abs=1e-6)
    assert info["spatial_momentum"] == pytest.approx((0.0, 0.4, 0.1 + 0.2 * 0.4), abs=1e-12)


def test_joints_move_along_the_straight_segment_with_the_faster_at_max_joint_speed_then_hold():
    env = make().unwrapped
    env.reset(seed=0)
    command = np.array([0.5, -0.25])  # (π/3, −π/6): 7 steps at 0.15 rad per step for α
    alphas, betas = [], []
    for _ in range(8):
        _, _, _, _, info = env.step(command)
        alphas.append(info["state"]["alpha"])
        betas.append(info["state"]["beta"])
    assert alphas[0] == pytest.approx(3.0 * 0.05) and betas[0] == pytest.approx(-0.5 * 3.0 * 0.05)
    assert alphas[6:] == [LIMIT / 2] * 2 and betas[6:] == [-LIMIT / 4] * 2
    assert np.all(np.diff(alphas[:7]) > 0)
    _, _, _, _, info = env.step(np.array([-7.0, 3.0]))  # clipped to the range, one step toward it
    assert info["state"]["alpha"] == pytest.approx(LIMIT / 2 - 0.15)


def test_reward_pays_the_progress_in_success_radii_and_success_terminates():
    env = make()
    _, info = env.reset(options={"target": (-1.0, 0.0)})
    total, n, distance = 0.0, 0, info["distance"]
    for action in [(0.5, 0.5), (-0.5, 0.5), (-0.5, -0.5), (0.5, -0.5)] * 8:
        _, reward, terminated, _, info = env.step(np.array(action, np.float32))
        total, n = total + reward, n + 1
    assert total == pytest.approx((distance - info["distance"]) / 0.3 - 0.01 * n, rel=1e-12)
    _, info = env.reset(options={"target": (0.31, 0.0)})
    _, _, terminated, _, info = env.step(np.zeros(2, np.float32))  # the joints stay: the chain too
    assert not terminated and not info["is_success"] and info["distance"] == pytest.approx(0.31)
    _, info = env.reset(options={"target": (0.0, -0.35)})
    _, reward, terminated, _, info = env.step(np.array([0.1, 0.1], np.float32))  # bending into a C moves it −y
    assert terminated and info["is_success"] and info["distance"] <= 0.3


def run(env, policy, seed):
    obs, _ = env.reset(seed=seed)
    done, steps = False, 0
    while not done:
        assert env.observation_space.contains(obs)
        obs, _, terminated, truncated, info = env.step(policy.predict(obs, deterministic=True)[0])
        done, steps = terminated or truncated, steps + 1
    return info["is_success"], steps


def test_gait_planner_reaches_every_target_within_half_the_time_limit():
    env = make()
    planner = controller(ENV_ID, "gaits", env)
    results = [run(env, planner, seed) for seed in range(4)]
    assert all(success for success, _ in results)
    assert max(steps for _, steps in results) <= TIME_LIMIT / 2


def test_gait_planner_measures_its_gaits_on_the_model():
    """Every gait is a closed loop from the straight shape; the squares, the diamonds and the S-shaped quadrants
    (their own images under (α, β) ↦ (−α, −β) or (α, β) ↦ (−β, −α)) do not turn; the C-shaped quadrants do."""
    planner = controller(ENV_ID, "gaits", make())
    for gait in planner.gaits:
        assert gait.waypoints[-1] == BASE == gait.shapes[-1]
        turns = abs(gait.holonomy[2]) > 1e-9
        assert turns == gait.name.startswith(("Q1", "Q3"))
    square = next(g for g in planner.gaits if g.name == "S@0.5")
    assert math.hypot(*square.holonomy[:2]) > 0.5


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"a": 0.0}, "a=0.0"),
        ({"b": 0.5}, r"b=0.5 .*a=0.5"),
        ({"b": -0.5}, "b=-0.5"),
        ({"link_density": 0.0}, "link_density=0.0"),
        ({"a": 1e200}, r"a=1e\+200 .*\[1e-06, 1000.0\]"),
        ({"a": 1e-200, "b": 1e-201}, r"a=1e-200 .*\[1e-06, 1000.0\]"),
        ({"b": 1e-201}, r"b=1e-201 .*\[0.005, a=0.5\)"),  # the aspect ratio a/b at most 100
        ({"b": 0.0049}, r"b=0.0049 .*\[0.005, a=0.5\)"),
        ({"rho": 0.0, "link_density": 1e-300}, r"link_density=1e-300 .*\[1e-06, 1000.0\]"),
        ({"link_density": 1e300}, r"link_density=1e\+300 .*\[1e-06, 1000.0\]"),
        ({"rho": 1e300}, r"rho=1e\+300 .*\[0.0, 1000.0\]"),
        ({"max_joint_speed": 1e300}, r"max_joint_speed=1e\+300 .*\[3e-06, 1000.0\]"),
        ({"max_joint_speed": 1e-300}, r"max_joint_speed=1e-300 .*\[3e-06, 1000.0\]"),
        ({"success_radius": 1e-300}, r"success_radius=1e-300 .*\[3e-07, 3.0\)"),
        ({"rho": -1.0}, "rho=-1.0"),
        ({"max_joint_speed": float("inf")}, "max_joint_speed=inf"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"dt": 0.3}, "dt=0.3"),
        ({"success_radius": 0.0}, "success_radius=0.0"),
        ({"success_radius": 3.0}, "success_radius=3.0"),
        ({"integrator": "exact"}, "needs a closed-form flow"),
        ({"integrator": "rk4", "substeps": 0}, "substeps=0"),
        ({"bogus": 1}, "bogus"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")
def test_bad_parameters_are_named_with_their_range(kwargs, message):
    with pytest.raises(ValueError, match=message):
        make(**kwargs)


def test_the_smallest_links_in_vacuum_still_have_mass_and_step_finitely():
    """At the least a, b and link_density the link mass link_density · πab is positive, so rho = 0 (a snake in
    vacuum, no added mass) is a valid model: it steps to finite observations."""
    env = make(a=2e-6, b=1e-6, link_density=1e-6, rho=0.0).unwrapped
    assert env.full_system.link_mass > 0.0
    env.reset(seed=0)
    for _ in range(3):
        obs, *_ = env.step(np.array([1.0, -0.5]))
    assert np.all(np.isfinite(obs))


@pytest.mark.parametrize(
    "options, message",
    [
        ({"start": 1}, "start"),
        ({"state": {"u": (0.0, 0.0)}}, "u"),
        ({"state": {"alpha": 2.1}}, r"state alpha=2.1 .*2.09"),
        ({"state": {"beta": float("nan")}}, "state beta=nan"),
        ({"state": {"theta": "up"}}, "state theta='up'"),
        ({"state": {"momentum": (0.0, float("inf"), 0.0)}}, "state momentum=.*finite"),
        ({"state": {"momentum": (100.0, 0.0, 0.0)}}, r"state momentum\[0\]=100.0"),
        ({"target": (float("nan"), 0.0)}, "target=.*finite"),
    ],
)
def test_bad_reset_options_are_named(options, message):
    env = make()
    with pytest.raises(ValueError, match=message):
        env.reset(options=options)


def test_bad_actions_are_rejected():
    env = make().unwrapped
    env.reset(seed=0)
    for action, message in [(np.zeros(3), r"shape \(3,\)"), (np.array([0.0, np.nan]), "not finite")]:
        with pytest.raises(ValueError, match=message):
            env.step(action)
