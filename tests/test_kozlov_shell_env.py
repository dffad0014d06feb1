"""KozlovShell-v0 as a Gymnasium env: checkers, determinism, pickling, the task, the gait planner, training and
every bad input."""

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents.controllers import controller
from agents.controllers.kozlov_shell import BASE, gaits

ENV_ID = "connenv/KozlovShell-v0"
TIME_LIMIT = 300


def make(**kwargs):
    return gym.make(ENV_ID, **kwargs)


def test_start_is_at_rest_at_the_origin_with_a_target_half_a_metre_to_a_metre_away():
    env = make()
    angles = []
    for seed in range(100):
        obs, info = env.reset(seed=seed)
        assert info["state"] == {
            "x": 0.0,
            "y": 0.0,
            "theta": 0.0,
            "u": (0.0, 0.0),
            "momentum": (0.0, 0.0, 0.0),
            "t": 0.0,
        }
        assert 0.5 <= info["distance"] <= 1.0 and info["model"] == "reduced"
        assert np.array_equal(obs[:2], np.float32(info["target"])) and np.array_equal(obs[2:], [1, 0, 0, 0, 0, 0, 0])
        angles.append(math.atan2(info["target"][1], info["target"][0]))
    assert np.histogram(angles, bins=4, range=(-math.pi, math.pi))[0].min() >= 10  # any direction


def test_info_and_observation_carry_the_state_in_the_body_frame():
    env = make()
    state = {"x": 0.2, "y": -0.1, "theta": math.pi / 2, "u": (0.25, -0.125), "momentum": (0.4, 0.0, 0.1)}
    obs, info = env.reset(options={"state": state, "target": (0.2, 0.9)})
    assert info["state"] == {**state, "t": 0.0} and info["model"] == "full"
    assert info["distance"] == pytest.approx(1.0)
    # the target is 1 m along space y, which is body x when θ = π/2; P₁ along body x is space y
    shell = env.unwrapped.full_system
    expected = [
        1.0,
        0.0,
        0.0,
        1.0,
        0.5,
        -0.5,
        0.4 / (2 + shell.added_masses[0]),
        0.0,
        0.1 / (shell.J + shell.added_masses[2]),
    ]
    assert obs == pytest.approx(expected, abs=1e-6)
    assert info["spatial_momentum"] == pytest.approx((0.0, 0.4, 0.1 + 0.2 * 0.4), abs=1e-12)
    _, _, _, _, info = env.step(np.array([0.5, -0.5], np.float32))
    assert info["state"]["t"] == pytest.approx(0.1) and info["state"]["u"] == (0.25, -0.125)


def test_reward_pays_the_progress_in_success_radii_and_success_terminates():
    env = make()
    _, info = env.reset(options={"target": (0.3, 0.0)})
    total, n, distance = 0.0, 0, info["distance"]
    for action in [(1, -1), (1, 1), (-1, -1), (-1, 1), (0, 0)] * 3:
        _, reward, terminated, _, info = env.step(np.array(action, np.float32))
        total, n = total + reward, n + 1
    assert total == pytest.approx((distance - info["distance"]) / 0.05 - 0.01 * n, rel=1e-12)
    _, info = env.reset(options={"target": (0.06, 0.0)})
    _, _, terminated, _, info = env.step(np.array([0.0, 0.0], np.float32))  # the mass stays: the shell too
    assert not terminated and not info["is_success"]
    _, info = env.reset(options={"target": (-0.15, 0.0)})
    _, reward, terminated, _, info = env.step(np.array([1.0, 0.0], np.float32))  # the mass goes +x, the shell −x
    assert terminated and info["is_success"] and info["distance"] <= 0.05
    assert reward == pytest.approx((0.15 - info["distance"]) / 0.05 - 0.01, rel=1e-12)


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
    results = [run(env, planner, seed) for seed in range(20)]
    assert all(success for success, _ in results)
    assert max(steps for _, steps in results) <= TIME_LIMIT / 2


def test_gait_planner_measures_its_gaits_on_the_model():
    """Every gait is a closed loop from BASE that never sends the mass to the centre, where a reset puts it; the
    figure-eights do not turn; the loops do."""
    planner = gaits(make().unwrapped)
    for gait in planner.gaits:
        assert gait.waypoints[-1] == BASE and (0.0, 0.0) not in gait.waypoints
        assert (abs(gait.holonomy[2]) <= 1e-8) == gait.name.startswith("X")  # the default stepper's accuracy
    x = next(g for g in planner.gaits if g.name == "X@1")
    assert math.hypot(*x.holonomy[:2]) > 0.03


def test_gait_planner_starts_over_on_a_new_episode():
    """An episode cut short mid-gait does not change the next one."""
    env = make()
    fresh = run(env, controller(ENV_ID, "gaits", env), 5)
    planner = controller(ENV_ID, "gaits", env)
    obs, _ = env.reset(seed=4)
    for _ in range(7):
        obs, *_ = env.step(planner.predict(obs)[0])
    assert run(env, planner, 5) == fresh


def test_gait_planner_predicts_a_batch_like_sb3():
    env = make()
    obs = np.stack([env.reset(seed=seed)[0] for seed in range(3)])
    planner = controller(ENV_ID, "gaits", env)
    action, state = planner.predict(obs, deterministic=True)
    assert action.shape == (3, 2) and action.dtype == np.float32 and state is None
    single = [controller(ENV_ID, "gaits", env).predict(row)[0] for row in obs]
    assert np.array_equal(action, np.stack(single))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"a": 0.0}, "a=0.0"),
        ({"b": 1.2}, r"b=1.2 .*a=1.0.*along body x"),
        ({"b": -0.5}, "b=-0.5"),
        ({"a": float("nan")}, "a=nan"),
        ({"shell_mass": 0.0}, "shell_mass=0.0"),
        ({"shell_inertia": -1.0}, "shell_inertia=-1.0"),
        ({"rho": -1.0}, "rho=-1.0"),
        ({"mass": float("inf")}, "mass=inf"),
        ({"u1_max": 0.0}, "u1_max=0.0"),
        ({"u1_max": 0.9}, r"u1_max=0.9, u2_max=0.25: .*outside the shell"),
        ({"u2_max": 0.5}, r"u2_max=0.5: .*outside the shell"),
        ({"dt": 0.0}, "dt=0.0"),
        ({"dt": "fast"}, "dt='fast'"),
        ({"success_radius": 0.0}, "success_radius=0.0"),
        ({"success_radius": 0.6}, "success_radius=0.6"),
        ({"integrator": "exact"}, "needs a closed-form flow"),
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
        make(**kwargs)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"start": 1}, "start"),
        ({"state": {"omega": 1.0}}, "omega"),
        ({"state": {"u": (0.6, 0.0)}}, r"state u\[0\]=0.6 .*\[-0.5, 0.5\]"),
        ({"state": {"u": (0.0, -0.3)}}, r"state u\[1\]=-0.3 .*\[-0.25, 0.25\]"),
        ({"state": {"u": (0.1,)}}, r"state u=\(0.1,\) must be a sequence of 2"),
        ({"state": {"x": float("nan")}}, "state x=nan"),
        ({"state": {"theta": "up"}}, "state theta='up'"),
        ({"state": {"momentum": (0.0, float("inf"), 0.0)}}, "state momentum=.*finite"),
        ({"state": {"momentum": (1.0, 2.0)}}, "state momentum=.*sequence of 3"),
        ({"target": (float("nan"), 0.0)}, "target=.*finite"),
        ({"target": 1.0}, "target=1.0 must be a sequence of 2"),
    ],
)
def test_bad_reset_options_are_named(options, message):
    env = make()
    with pytest.raises(ValueError, match=message):
        env.reset(options=options)


@pytest.mark.parametrize(
    "action, message",
    [
        (np.zeros(3, np.float32), r"shape \(3,\)"),
        (np.float32(0.5), r"shape \(\)"),
        (np.array([0.0, np.nan]), "not finite"),
    ],
)
def test_bad_actions_are_rejected(action, message):
    env = make().unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_actions_outside_the_box_are_clipped_to_it():
    env = make().unwrapped
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([-7.0, 3.0], np.float32))
    assert info["state"]["u"] == (-0.5, 0.25)


def test_trains_with_its_hyperparameters_and_the_gait_planner_swims(tmp_path, train):
    """train.py and the evaluation on KozlovShell-v0: a tiny PPO run, and the gait planner against random."""
    argv = ["--env", ENV_ID, "--timesteps", "300", "--runs", str(tmp_path), "--eval-episodes", "2", "--eval-freq", "-1"]
    results = train.main(argv)
    assert Path(results["model"]).name == "connenv-KozlovShell-v0.zip"
    analytic, random = results["evaluation"]["policies"][1:]
    assert analytic["success_rate"] == 1.0 and random["success_rate"] == 0.0
