"""KapitzaPendulum-v0 and KapitzaSwingUp-v0 as Gymnasium envs: checkers, determinism, pickling, the pivot's
travel, the tasks, the reference controllers and every bad input."""

import math

import gymnasium as gym
import numpy as np
import pytest

import connenv  # noqa: F401
from agents import evaluate
from agents.controllers import controller
from agents.controllers.kapitza import KapitzaVibration

HOLD, SWING_UP = "connenv/KapitzaPendulum-v0", "connenv/KapitzaSwingUp-v0"


def test_starts_near_inverted_or_hanging_at_rest():
    hold, swing_up = gym.make(HOLD), gym.make(SWING_UP)
    for seed in range(30):
        state = hold.reset(seed=seed)[1]["state"]
        assert abs(state["theta"] - math.pi) <= 0.2 and state["theta_dot"] == 0.0
        state = swing_up.reset(seed=seed)[1]["state"]
        assert 0.05 <= abs(state["theta"]) <= 0.1 and state["theta_dot"] == 0.0
        assert state["u"] == (0.0, 0.0) and state["u_dot"] == (0.0, 0.0) and state["t"] == 0.0


def test_pivot_stays_in_its_travel_and_moves_continuously():
    env = gym.make(HOLD, pivot="planar", tolerance=3.1)
    env.reset(seed=0)
    env.action_space.seed(0)
    u = np.zeros(2)
    for _ in range(500):
        info = env.step(env.action_space.sample())[4]
        new = np.array(info["state"]["u"])
        assert np.all(np.abs(new) <= 0.1) and np.all(np.abs(new - u) <= 10.0 * 0.005 + 1e-15)
        u = new
    env.reset(options={"state": {"u": (0.0, 0.09)}})
    info = env.step(np.array([0.0, 1.0], np.float32))[4]  # 5 cm asked for, 1 cm of travel left
    assert info["state"]["u"] == (0.0, 0.1) and info["state"]["u_dot"] == (0.0, 0.0)


def test_energy_in_the_pivots_frame_is_conserved_at_constant_velocity_and_jumps_as_computed():
    env = gym.make(HOLD, tolerance=3.1)
    _, info = env.reset(options={"state": {"theta": 2.0, "theta_dot": 1.0, "u": (0.0, -0.1), "u_dot": (0.0, 0.0)}})
    theta, energy = info["state"]["theta"], info["energy"]
    action = np.array([0.2], np.float32)
    energies = [env.step(action)[4]["energy"] for _ in range(10)]  # 2 m/s for 0.1 m: no stop
    # the jump 0 → 2 m/s at the first step's start: ΔE = −m l θ̇ Δu̇ sin θ + ½ m (Δu̇ sin θ)²
    along = 10.0 * float(action[0]) * math.sin(theta)
    assert energies[0] == pytest.approx(energy - 1.0 * along + 0.5 * along**2, rel=1e-12)
    assert max(energies) - min(energies) < 1e-12 * abs(energies[0])


def test_hold_terminates_when_the_pendulum_falls_and_rewards_closeness():
    env = gym.make(HOLD)
    env.reset(options={"state": {"theta": math.pi + 0.29, "theta_dot": 2.0}})
    _, reward, terminated, _, info = env.step(np.array([0.0], np.float32))
    assert terminated and not info["is_success"] and info["deviation"] > 0.3
    env.reset(options={"state": {"theta": math.pi}})
    _, reward, terminated, _, info = env.step(np.array([0.0], np.float32))
    assert not terminated and info["is_success"] and reward == pytest.approx(1.0)


def test_swing_up_succeeds_only_after_holding_inverted_for_hold_time():
    env = gym.make(SWING_UP, hold_time=0.02)  # 4 steps
    env.reset(options={"state": {"theta": math.pi}})
    results = [env.step(np.array([0.0], np.float32)) for _ in range(4)]
    assert [r[2] for r in results] == [False, False, False, True]
    assert results[-1][4]["upright_time"] == pytest.approx(0.02)


def test_swing_up_reward_is_the_log_lift_gain_less_time():
    """ℓ = (E/(m g l) + 1)/2; at rest at θ, ℓ = (1 − cos θ)/2. Held still, the energy is conserved."""
    env = gym.make(SWING_UP)
    env.reset(options={"state": {"theta": 0.5, "u": (0.0, -0.1)}})
    _, reward, *_ = env.step(np.array([0.0], np.float32))
    assert reward == pytest.approx(-0.2 * 0.005, rel=1e-9)
    # the pivot's velocity jumps from 0 to 4 m/s up at θ = π/2, θ̇ = −1 rad/s: ΔE = −m l θ̇ (4 sin θ) + ½ m (4 sin θ)²
    env.reset(options={"state": {"theta": math.pi / 2, "theta_dot": -1.0}})
    _, reward, *_ = env.step(np.array([0.4], np.float32))
    lift_before = 0.5 * (0.5 * 1.0 / 9.81 + 1.0)
    along = 10.0 * float(np.float32(0.4))
    lift_after = 0.5 * ((0.5 * 1.0 + along + 0.5 * along**2) / 9.81 + 1.0)
    assert reward == pytest.approx(math.log(min(lift_after, 1.0) / lift_before) - 0.001, rel=1e-9)


def test_kapitza_controller_holds_every_start_and_the_exact_stepper_matches_dop853():
    env = gym.make(HOLD)
    policy = controller(HOLD, "kapitza", env)
    for seed in range(5):
        episode = evaluate.run_episode(env, policy, seed)
        assert episode.success and episode.length == 2000 and episode.measures["max_deviation"] <= 0.2
    exact, dop853 = (gym.make(HOLD, integrator=name) for name in ("exact", "dop853"))
    obs, _ = exact.reset(seed=1)
    dop853.reset(seed=1)
    for _ in range(400):
        action = policy.predict(obs)[0]
        obs, *_, info = exact.step(action)
        info_dop853 = dop853.step(action)[4]
    assert info["state"]["theta"] == pytest.approx(info_dop853["state"]["theta"], abs=1e-8)


def test_modulated_vibration_damps_the_slow_swing_that_open_loop_vibration_keeps():
    env = gym.make(HOLD)
    open_loop, damped = controller(HOLD, "kapitza", env), controller(HOLD, "damped", env)
    for seed in range(3):
        kept, damped_out = (evaluate.run_episode(env, policy, seed) for policy in (open_loop, damped))
        assert damped_out.success and env.unwrapped.deviation(env.unwrapped.state.y) < 1e-3
        assert damped_out.ret > kept.ret


def test_swing_up_controller_swings_up_and_holds():
    env = gym.make(SWING_UP)
    policy = controller(SWING_UP, "analytic", env)
    for seed in range(3):
        episode = evaluate.run_episode(env, policy, seed)
        assert episode.success and episode.time < 20.0


def test_damping_has_no_closed_form_and_falls_back_to_dop853():
    damped = {"damping": 0.1, "tolerance": 3.1}
    exact, dop853 = (gym.make(HOLD, integrator=name, **damped) for name in ("exact", "dop853"))
    for env in (exact, dop853):
        env.reset(options={"state": {"theta": 1.0}})
    for _ in range(50):
        a, b = exact.step(np.array([0.4], np.float32))[4], dop853.step(np.array([0.4], np.float32))[4]
    assert a["state"]["theta"] == pytest.approx(b["state"]["theta"], abs=1e-8)
    assert a["energy"] < -9.81 * math.cos(1.0)  # it loses energy


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"pivot": "diagonal"}, "pivot='diagonal'"),
        ({"length": 0.0}, "length=0.0"),
        ({"mass": -1.0}, "mass=-1.0"),
        ({"g": float("nan")}, "g=nan"),
        ({"v_max": 0.0}, "v_max=0.0"),
        ({"a_max": 1.0}, "a_max=1.0"),
        ({"dt": -0.1}, "dt=-0.1"),
        ({"tolerance": 4.0}, "tolerance=4.0"),
        ({"damping": -0.1}, "damping=-0.1"),
        ({"integrator": "leapfrog"}, "integrator='leapfrog'"),
        ({"omega": 3.0}, "omega"),
    ],
)
def test_bad_parameters_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        gym.make(HOLD, **kwargs)


def test_bad_hold_time_is_named():
    with pytest.raises(ValueError, match="hold_time=0"):
        gym.make(SWING_UP, hold_time=0)


@pytest.mark.parametrize(
    "action, message",
    [(np.array([0.1, 0.2], np.float32), "shape"), (np.array([np.nan], np.float32), "not finite")],
)
def test_bad_actions_are_named(action, message):
    env = gym.make(HOLD)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


@pytest.mark.parametrize(
    "state, message",
    [
        ({"u": (0.0, 0.2)}, r"state u\[1\]"),
        ({"u": (0.05, 0.0)}, r"state u\[0\] \(pivot='vertical'\)"),
        ({"u_dot": (0.0, 11.0)}, r"state u_dot\[1\]"),
        ({"u": (0.0,)}, "must be a sequence of 2"),
        ({"theta": math.inf}, "state theta=inf"),
        ({"theta_dot": 1.0, "p": 1.0}, "both theta_dot and p"),
        ({"omega": 1.0}, "unknown key"),
    ],
)
def test_bad_reset_states_are_named(state, message):
    with pytest.raises(ValueError, match=message):
        gym.make(HOLD).reset(options={"state": state})


def test_controller_rejects_a_vibration_the_pivot_cannot_follow():
    env = gym.make(HOLD, v_max=2.0).unwrapped
    with pytest.raises(ValueError, match="v_max=2.0"):
        controller(HOLD, "kapitza", env)
    with pytest.raises(ValueError, match="pivot='horizontal'"):
        controller(SWING_UP, "swingup", gym.make(SWING_UP, pivot="horizontal"))
    with pytest.raises(ValueError, match="modulation=0.5"):
        KapitzaVibration(gym.make(HOLD).unwrapped, modulation=0.5)  # 0.08 × 1.5 m: beyond the travel
