"""RollingBall-v0, RollingBallPose-v0 and RollingBallGoal-v0 as Gymnasium envs: checkers, determinism, pickling,
the reference controllers, HER, the evaluation CLI and every bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import connenv  # noqa: F401
from agents import evaluate
from agents.controllers import controller
from connenv.core import StepperError

ORIENT, POSE, GOAL = "connenv/RollingBall-v0", "connenv/RollingBallPose-v0", "connenv/RollingBallGoal-v0"
IDS = [ORIENT, POSE, GOAL]


def flat(obs):
    return np.concatenate([obs[k] for k in sorted(obs)]) if isinstance(obs, dict) else obs


def test_targets_are_uniform_on_so3():
    """Under the Haar measure a rotation's unit quaternion is uniform on S³: E|w| = 4/(3π), E[x²] = 1/4 (400 seeds,
    standard errors 0.013)."""
    env = gym.make(ORIENT).unwrapped
    quats = []
    for seed in range(400):
        env.reset(seed=seed)
        quats.append(Rotation.from_matrix(env.state.R_target).as_quat(canonical=True))
    quats = np.array(quats)
    assert np.mean(quats[:, 3]) == pytest.approx(4 / (3 * math.pi), abs=0.04)
    assert np.mean(quats[:, :3] ** 2, axis=0) == pytest.approx([0.25] * 3, abs=0.04)


def test_info_state_and_a_straight_step():
    """A step at v = (v_max, 0) rolls the ball by v_max dt/ρ about +y, moves it by v_max dt and counts the path."""
    env = gym.make(ORIENT, radius=2.0, v_max=0.5, dt=0.2)
    _, info = env.reset(seed=0, options={"state": {"x": 1.0, "y": -2.0}, "target": np.eye(3)})
    assert set(info["state"]) == {"x", "y", "R", "t"} and info["angle_error"] == 0.0
    _, reward, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
    expected = Rotation.from_rotvec([0.0, 0.5 * 0.2 / 2.0, 0.0]).as_matrix()
    assert np.abs(info["state"]["R"] - expected).max() <= 1e-15
    assert (info["state"]["x"], info["state"]["y"], info["state"]["t"]) == pytest.approx((1.1, -2.0, 0.2))
    assert info["angle_error"] == pytest.approx(0.05) and info["path_length"] == pytest.approx(0.1)
    assert reward == pytest.approx(-0.05 - 0.01)


def test_actions_beyond_the_unit_disk_are_projected_radially():
    env = gym.make(ORIENT).unwrapped
    env.reset(seed=0, options={"target": np.eye(3)})
    env.step(np.array([3.0, 4.0], np.float32))
    assert env.state.position == pytest.approx([0.06, 0.08])  # speed v_max = 1 along (3, 4)/5 over dt = 0.1
    env.step(np.array([0.3, 0.4], np.float32))
    assert env.state.position == pytest.approx([0.09, 0.12])  # inside the disk: unchanged


@pytest.mark.parametrize("env_id, names", [(ORIENT, ["arc", "holonomy"]), (POSE, ["holonomy"]), (GOAL, ["arc"])])
@pytest.mark.parametrize("tolerance", [0.05, 1e-6])
def test_controllers_reach_every_sampled_target(env_id, names, tolerance):
    """Both reach the tolerance on 15 seeds, and 1e-6 rad (and 1e-6 m for the pose) in the exact model."""
    env = gym.make(env_id, tolerance=tolerance, **({"position_tolerance": tolerance} if env_id == POSE else {}))
    for name in names:
        policy = controller(env_id, name, env)
        for seed in range(15):
            episode = evaluate.run_episode(env, policy, seed)
            assert episode.success and episode.measures["angle_error"] <= tolerance
            assert episode.measures.get("position_error", 0.0) <= tolerance


def test_optimal_arc_rolls_no_further_than_the_distance_and_holonomy_further():
    """In the env the arc controller rolls within 1% of the optimal arc's length (its discrete arc), and never
    further than the holonomy planner on the same target."""
    env = gym.make(ORIENT, tolerance=1e-6)
    arc, holonomy = (controller(ORIENT, name, env) for name in ("arc", "holonomy"))
    for seed in range(10):
        arc_ratio = evaluate.run_episode(env, arc, seed).measures["path_ratio"]
        assert 1.0 <= arc_ratio <= 1.01
        assert arc_ratio <= evaluate.run_episode(env, holonomy, seed).measures["path_ratio"]


def test_goal_env_reward_is_compute_reward_on_single_and_batched_goals():
    env = gym.make(GOAL).unwrapped
    obs, info = env.reset(seed=0)
    rewards, achieved, infos = [], [], []
    policy = controller(GOAL, "arc", env)
    for _ in range(60):
        obs, reward, terminated, _, info = env.step(policy.predict(obs)[0])
        assert reward == env.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)
        assert terminated == env.compute_terminated(obs["achieved_goal"], obs["desired_goal"], info)
        rewards.append(reward), achieved.append(obs["achieved_goal"]), infos.append(info)
        if terminated:
            break
    assert rewards[-1] == 0.0 and set(rewards[:-1]) == {-1.0}
    batch = env.compute_reward(np.array(achieved), np.repeat(obs["desired_goal"][None], len(achieved), 0), infos)
    assert batch.shape == (len(achieved),) and np.array_equal(batch, rewards)


@pytest.mark.parametrize("env_id", [ORIENT, GOAL])
def test_sac_trains_with_its_hyperparameters_and_reloads(env_id, tmp_path, train):
    """train.py with sac.yml: SAC on RollingBall-v0, and SAC with SB3's HerReplayBuffer on the goal env (its
    compute_reward relabels goals), past learning_starts; the model reloads and is evaluated beside the arc."""
    argv = ["--env", env_id, "--algo", "sac", "--timesteps", "1100", "--runs", str(tmp_path), "--eval-episodes", "2"]
    results = train.main([*argv, "--eval-freq", "-1"])
    assert results["timesteps"] == 1100
    trained, analytic, random = results["evaluation"]["policies"]
    assert trained["policy"].startswith("sac:") and analytic["success_rate"] == 1.0 and random["success_rate"] == 0.0


def test_evaluation_cli_reports_controllers_and_random_with_the_measures(tmp_path):
    report = evaluate.compare(ORIENT, ["arc", "holonomy", "random"], episodes=4, seed=0)
    arc, holonomy, random = report["policies"]
    assert arc["success_rate"] == holonomy["success_rate"] == 1.0 and random["success_rate"] == 0.0
    assert 1.0 <= arc["measures_mean"]["path_ratio"] <= 1.01 < holonomy["measures_mean"]["path_ratio"]
    assert arc["measures_mean"]["angle_error"] <= 0.05 < random["measures_mean"]["angle_error"]
    assert "path_ratio" in evaluate.format_table(report).splitlines()[1]


def test_a_controller_of_another_env_is_refused():
    with pytest.raises(ValueError, match="no controller 'arc' for connenv/RollingBallPose-v0"):
        evaluate.make_policy("arc", POSE, 0)


def test_stepper_that_leaves_so3_raises_naming_stepper_and_dt():
    """RK4 with one substep at 0.5 rad per step errs by ~(0.5)⁵/120 per step in ‖RᵀR − I‖: past the 1e-6 bound."""
    env = gym.make(ORIENT, integrator="rk4", substeps=1, dt=0.5)
    env.reset(seed=0)
    with pytest.raises(StepperError, match=r"RK4\(substeps=1\) left SO\(3\).* dt = 0.5, radius = 1.0"):
        for _ in range(10):
            env.step(np.array([1.0, 0.0], np.float32))


NOT_ORTHOGONAL = np.diag([1.0, 1.0, 1.0 + 1e-6])
REFLECTION = np.diag([1.0, 1.0, -1.0])


@pytest.mark.parametrize(
    "options, message",
    [
        ({"start": 1}, "start"),
        ({"state": {"z": 1.0}}, "'z'"),
        ({"state": {"x": float("nan")}}, "state x=nan"),
        ({"state": {"R": NOT_ORTHOGONAL}}, r"state R=.* is not a rotation: ‖RᵀR − I‖ = 2e-06"),
        ({"state": {"R": REFLECTION}}, r"state R=.* is not a rotation: .* det R = -1"),
        ({"state": {"R": np.eye(2)}}, r"state R has shape \(2, 2\)"),
        ({"target": np.full((3, 3), np.nan)}, "target=.* is not finite"),
        ({"target": REFLECTION}, "target=.* det R = -1"),
        ({"target": [1, 0, 0]}, r"target has shape \(3,\)"),
    ],
)
def test_bad_reset_states_and_targets_are_named(options, message):
    env = gym.make(POSE)
    with pytest.raises(ValueError, match=message):
        env.reset(options=options)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"radius": 0.0}, "radius=0.0"),
        ({"v_max": -1.0}, "v_max=-1.0"),
        ({"dt": float("inf")}, "dt=inf"),
        ({"tolerance": 4.0}, "tolerance=4.0"),
        ({"tolerance": 0.0}, "tolerance=0.0"),
        ({"integrator": "leapfrog"}, "integrator='leapfrog'"),
        ({"integrator": "rk4", "substeps": 0}, "substeps=0"),
        ({"bogus": 1}, "bogus"),
        ({"render_mode": "ascii"}, "render_mode='ascii'"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")
def test_bad_parameters_are_named_with_their_range(kwargs, message):
    for env_id in IDS:
        with pytest.raises(ValueError, match=message):
            gym.make(env_id, **kwargs)


def test_bad_position_tolerance_is_named():
    with pytest.raises(ValueError, match=r"position_tolerance=-0.1 .*\[5e-08, 50000.0\]"):
        gym.make(POSE, position_tolerance=-0.1)


@pytest.mark.parametrize(
    "action, message",
    [(np.zeros(3, np.float32), r"shape \(3,\)"), (np.float32(0.5), r"shape \(\)"), (np.array([np.nan, 0]), "finite")],
)
def test_bad_actions_are_rejected(action, message):
    env = gym.make(ORIENT).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


