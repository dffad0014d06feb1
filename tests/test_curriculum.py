"""Start curricula (agents.curriculum): training episodes started by reset options, seeded like the env, and never
the evaluation's."""

import math

import gymnasium as gym
import numpy as np
import pytest
import yaml

import connenv  # noqa: F401
from agents import curriculum


def test_kapitza_release_starts_at_rest_from_any_angle_and_repeats_with_the_seed():
    env = curriculum.StartCurriculum(gym.make("connenv/KapitzaSwingUp-v0"), curriculum.kapitza_release, share=1.0)
    thetas = []
    for seed in range(40):
        state = env.reset(seed=seed)[1]["state"]
        assert 0.1 <= abs(state["theta"]) <= math.pi and state["theta_dot"] == 0.0 and state["u_dot"] == (0.0, 0.0)
        thetas.append(state["theta"])
    assert max(map(abs, thetas)) > 2.5  # up to near inverted, not only near hanging
    assert env.reset(seed=7)[1]["state"] == env.reset(seed=7)[1]["state"]


def test_curriculum_episodes_are_cut_at_max_steps_and_the_rest_are_the_envs_own():
    own = gym.make("connenv/KapitzaSwingUp-v0")
    never = curriculum.StartCurriculum(gym.make("connenv/KapitzaSwingUp-v0"), curriculum.kapitza_release, share=0.0)
    np.testing.assert_array_equal(never.reset(seed=3)[0], own.reset(seed=3)[0])
    always = curriculum.StartCurriculum(own, curriculum.kapitza_release, share=1.0, max_steps=3)
    always.reset(seed=0)
    flags = [always.step(np.zeros(1, np.float32))[3] for _ in range(3)]
    assert flags == [False, False, True]


def test_bead_targets_lie_near_the_bead_inside_the_starting_reach():
    env = curriculum.StartCurriculum(gym.make("connenv/BeadOnBar-v0"), curriculum.bead_near_target, share=1.0)
    for seed in range(40):
        info = env.reset(seed=seed)[1]
        assert 0.02 - 1e-12 <= abs(info["target"] - info["state"]["r"]) <= 0.2 + 1e-12
        assert abs(info["target"]) <= 0.8 + 1e-12 and info["state"]["r_dot"] == 0.0


def test_an_unknown_curriculum_is_named():
    with pytest.raises(ValueError, match=r"curriculum 'swing' is not one of \['bead_near_target', 'kapitza_release'\]"):
        curriculum.wrapper("swing")


def test_train_wraps_the_training_env_in_the_curriculum_and_evaluates_on_the_tasks_start(tmp_path, monkeypatch):
    """The periodic and final evaluations must see the task as registered: only the training env is wrapped."""
    from agents import train

    made = []
    monkeypatch.setattr(curriculum, "StartCurriculum", lambda env, *a, **k: made.append(env) or env)
    hyperparams = {"n_timesteps": 64, "policy": "MlpPolicy", "learning_starts": 32, "curriculum": "bead_near_target",
                   "policy_kwargs": "dict(net_arch=[8])"}  # fmt: skip
    path = tmp_path / "sac.yml"
    path.write_text(yaml.safe_dump({"connenv/BeadOnBar-v0": hyperparams}))
    argv = ["--env", "connenv/BeadOnBar-v0", "--algo", "sac", "--runs", str(tmp_path), "--hyperparams", str(path)]
    train.main([*argv, "--eval-freq", "32", "--eval-episodes", "1"])
    assert len(made) == 1  # the training env; the periodic evaluation's env is not wrapped
    config = yaml.load((tmp_path / "BeadOnBar-v0_sac_s0" / "connenv-BeadOnBar-v0" / "config.yml").read_text(),
                       Loader=yaml.UnsafeLoader)  # fmt: skip
    assert dict(config)["curriculum"] == "bead_near_target"
