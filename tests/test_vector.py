"""Native vector envs: row i is env i of a SyncVectorEnv of single envs, episodes and resets included; the per-row
adaptive stepper is scipy's DOP853 row by row; bad input is refused as in the single envs."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import connenv  # noqa: F401  (registers the envs)
from connenv.core import StepperError, make_stepper
from connenv.core.batched import EmbeddedRK, RowByRow, batched
from connenv.core.segments import bounded_segments, bounded_segments_batch
from connenv.systems.skier import Skier
from connenv.systems.trails import make_trail


def test_swing_rows_match_over_whole_default_episodes(run_both):
    """Swing-v0 as registered: two full 500-step episodes per row on the exact flow."""
    assert run_both("connenv/Swing-v0", 3, 1002, 0, {}).sum() >= 6


def test_skier_rows_match_on_the_default_valley(run_both):
    """The default valley with its two rims, 100 steps a row on the per-row DOP853."""
    assert run_both("connenv/Skier-v0", 3, 110, 2, {"max_episode_steps": 100})[1] == 3


def test_shell_rows_in_the_full_model_match_and_mix_with_reduced_rows(run_both):
    """Reset with a momentum puts every row in the full (Kirchhoff) model; autoresets put rows back at rest in the
    reduced one, so the batch steps both models at once."""
    options = {"state": {"momentum": (0.3, -0.2, 0.1), "u": (0.1, 0.05)}}
    kwargs = {"max_episode_steps": 25, "success_radius": 0.45}
    assert run_both("connenv/KozlovShell-v0", 3, 60, 3, kwargs, options=options).sum() > 0


@pytest.mark.parametrize("integrator", [{"integrator": "rk4", "substeps": 2}, {"integrator": "lsoda"}])
def test_other_steppers_keep_rows_on_the_single_path(integrator, run_both, short_episodes):
    kwargs = {**short_episodes["connenv/Swing-v0"], **integrator, "max_episode_steps": 15}
    run_both("connenv/Swing-v0", 3, 20, 1, kwargs)


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("connenv/Swing-v0", {"max_radial_speed": 2.0}),  # the ramp on the exact stepper's per-row DOP853 fallback
        ("connenv/Swing-v0", {"max_radial_speed": 2.0, "integrator": "rk4", "substeps": 3}),
        ("connenv/Skier-v0", {"max_height_speed": 3.0}),
    ],
)
def test_ramped_controls_match_with_a_ramp_time_per_row(env_id, kwargs, run_both, short_episodes):
    assert run_both(env_id, 3, 50, 6, {**short_episodes[env_id], **kwargs}).sum() > 0


def test_ball_rows_on_dop853_match(run_both, short_episodes):
    """The ball's matrix ODE on per-row DOP853 (at a loose tolerance, where one step size for all rows would show)."""
    kwargs = {**short_episodes["connenv/RollingBall-v0"], "integrator": "dop853", "rtol": 1e-5, "atol": 1e-7}
    assert run_both("connenv/RollingBall-v0", 3, 40, 2, kwargs).sum() > 0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"pivot": "planar", "max_episode_steps": 100},  # up to three segments a step, cut at each row's end stops
        {"damping": 0.2, "max_episode_steps": 50},  # no closed form: per-row DOP853 on segments of per-row length
        {"integrator": "rk4", "substeps": 3, "max_episode_steps": 50},
    ],
)
def test_kapitza_rows_with_their_own_end_stops_match(kwargs, run_both):
    assert run_both("connenv/KapitzaPendulum-v0", 3, 120, 4, kwargs).sum() > 0


def skier_system():
    return Skier(make_trail("valley", None))


def test_per_row_dop853_is_scipys_dop853_on_each_row():
    """EmbeddedRK takes scipy's decisions for each row: each row equals solve_ivp(method="DOP853") on that row
    alone, while solve_ivp on the flattened batch, with one step size for all rows, does not."""
    system, rtol, atol, tau = skier_system(), 1e-8, 1e-10, 0.5
    rng = np.random.default_rng(0)
    y = np.column_stack([rng.uniform(-5.0, 5.0, 6), rng.uniform(-300.0, 300.0, 6)])
    h, hold = rng.uniform(0.5, 1.0, (6, 1)), np.zeros((6, 1))
    batch = EmbeddedRK("DOP853", rtol, atol)(system, y, h, hold, tau)
    for i in range(6):
        field = lambda s, yi, i=i: system.vector_field(yi, h[i], hold[i])
        alone = solve_ivp(field, (0, tau), y[i], "DOP853", rtol=rtol, atol=atol)
        assert np.allclose(batch[i], alone.y[:, -1], rtol=1e-14, atol=1e-13)
    coupled = make_stepper("dop853", rtol=rtol, atol=atol)(system, y, h, hold, tau)
    assert np.max(np.abs(coupled - batch)) > 1e-8  # why the batch needs per-row step control


def test_per_row_rk45_and_row_by_row_lsoda_match_the_single_state_steps():
    system = skier_system()
    y, h, hold = np.array([[2.0, 0.0], [-1.0, 150.0], [4.0, -80.0]]), np.full((3, 1), 0.8), np.zeros((3, 1))
    for name in ("rk45", "lsoda"):
        single = make_stepper(name, rtol=1e-9, atol=1e-11)
        rows = batched(single)
        assert isinstance(rows, EmbeddedRK if name == "rk45" else RowByRow)
        alone = np.array([single(system, y[i], h[i], hold[i], 0.05) for i in range(3)])
        assert np.allclose(rows(system, y, h, hold, 0.05), alone, rtol=1e-14, atol=1e-13)


def test_per_row_stepper_that_cannot_meet_its_tolerance_raises():
    """A vector field that blows up within the segment: the step size collapses and the row is named."""

    class Blowup:
        def vector_field(self, y, u, u_dot):
            return y * y

    with pytest.raises(StepperError, match=r"step size is less than spacing .* rows \[1\]"):
        EmbeddedRK("DOP853", 1e-8, 1e-10)(Blowup(), np.array([[0.1], [100.0]]), np.zeros((2, 1)), np.zeros((2, 1)), 1.0)


def test_seeded_vector_runs_are_bit_identical_and_seeds_map_to_rows():
    def run(seed):
        env = gym.make_vec("connenv/Skier-v0", 3, vectorization_mode="vector_entry_point")
        obs = [env.reset(seed=seed)[0]]
        for _ in range(5):
            obs.append(env.step(np.full((3, 1), 0.5, np.float32))[0])
        return np.array(obs)

    assert np.array_equal(run(4), run(4))
    assert np.array_equal(run([6, 5, 4])[:, 2], run(4)[:, 0])  # a list seeds row i with its i-th entry


@pytest.mark.parametrize(
    ("action", "message"),
    [(np.zeros((3, 2)), r"shape \(3, 2\); expected \(3, 1\)"), (np.zeros(3), r"expected \(3, 1\)"),
     (np.array([[0.0], [math.nan], [0.0]]), "not finite")],
)
def test_bad_actions_are_refused(action, message):
    env = gym.make_vec("connenv/Swing-v0", 3, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_envs": 0}, "num_envs=0 must be an integer ≥ 1"),
        ({"num_envs": 2, "max_episode_steps": 0}, "max_episode_steps=0"),
        ({"num_envs": 2, "r_min": 3.0}, "r_max"),  # the single env's checks
        ({"num_envs": 2, "render_mode": "human"}, "does not render"),
    ],
)
def test_bad_make_kwargs_are_refused(kwargs, message):
    from connenv.envs.swing import SwingVectorEnv

    with pytest.raises(ValueError, match=message):
        SwingVectorEnv(**kwargs)


def test_a_diverging_stepper_raises_in_the_batch_as_in_the_single_env(diverging):
    """The single envs' divergence cases (tests/conftest.py's diverging), on 3 rows: the same StepperError, never NaN.
    The swing's bound is lowered (r_max = 0.2 m, bound 0.1 m g r_max): at 2 m its Euler run succeeds first, and the
    vector env resets the row where the single env of that test steps on."""
    env_id, kwargs, reset, action, message = diverging
    kwargs = {**kwargs, "r_max": 0.2} if env_id == "connenv/Swing-v0" else kwargs
    env = gym.make_vec(env_id, 3, vectorization_mode="vector_entry_point", **kwargs)
    env.reset(seed=0, options={"state": reset})
    sign = np.broadcast_to(np.asarray(action, np.float32), env.action_space.shape)
    alternating = env_id in ("connenv/KozlovShell-v0", "connenv/KapitzaPendulum-v0")
    with pytest.raises(StepperError, match=message):
        for k in range(2000):
            assert np.all(np.isfinite(env.step(sign * (-1) ** k if alternating else sign)[0]))


def test_vector_ball_infos_are_finite_and_leave_out_the_unmeasured_distance():
    env = gym.make_vec("connenv/RollingBall-v0", 4, vectorization_mode="vector_entry_point")
    _, info = env.reset(seed=0)
    _, _, _, _, stepped = env.step(np.ones((4, 2), np.float32))
    for info in (info, stepped):
        assert "distance" not in info and "path_ratio" not in info
        assert all(np.all(np.isfinite(info[key])) for key in ("angle_error", "path_length"))


def test_a_diverging_stepper_raises_in_the_batch():
    """RK4 with one substep at dt = 0.5 leaves SO(3): the vector env raises as the single env does."""
    env = gym.make_vec("connenv/RollingBall-v0", 4, vectorization_mode="vector_entry_point", dt=0.5, integrator="rk4")
    env.reset(seed=0)
    with pytest.raises(StepperError, match=r"RK4\(substeps=1\) left SO\(3\).* dt = 0.5, radius = 1.0"):
        for _ in range(20):
            env.step(np.ones((4, 2), np.float32))


def test_partial_reset_restarts_only_the_masked_rows():
    """Gymnasium's reset_mask: row 1 restarts from its own generator's next start, rows 0 and 2 keep their state."""
    env = gym.make_vec("connenv/KozlovShell-v0", 3, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    stepped, _, _, _, _ = env.step(np.full((3, 2), 0.5, np.float32))
    single = gym.make("connenv/KozlovShell-v0")
    single.reset(seed=1)
    second_start, _ = single.reset()
    obs, info = env.reset(options={"reset_mask": np.array([False, True, False])})
    assert np.array_equal(obs[[0, 2]], stepped[[0, 2]]) and np.allclose(obs[1], second_start, atol=1e-7)
    assert list(info["_distance"]) == [False, True, False]
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": np.zeros(3, bool)})


@pytest.mark.parametrize("low, high", [(-0.1, 0.1), ([-0.1, -0.05], [0.1, np.inf])], ids=["pivot", "asymmetric"])
def test_bounded_segments_of_a_batch_are_each_rows_own(low, high):
    """Coordinates at, near and away from their bounds (the Kapitza pivot's ±0.1, or asymmetric and infinite),
    moving at any speed: the batch cuts each row's step where bounded_segments cuts it alone, to the bit, and ends
    it at the same (u, u̇)."""
    rng = np.random.default_rng(0)
    u = np.clip(rng.choice([-0.1, -0.0999, 0.0, 0.05, 0.099, 0.1], (2000, 2)), low, high)
    u_dot = rng.choice([-10.0, -3.3, 0.0, 5.0, 10.0], (2000, 2)) * rng.uniform(0.2, 1.0, (2000, 2))
    batch, u_end, u_dot_end = bounded_segments_batch(u, u_dot, low, high, 0.005)
    starts, velocities, durations = (np.stack(parts) for parts in zip(*batch))
    assert np.all((low <= u_end) & (u_end <= high)) and np.allclose(durations.sum(axis=0), 0.005, rtol=0, atol=1e-18)
    for i in range(len(u)):
        segments, u_alone, u_dot_alone = bounded_segments(u[i], u_dot[i], low, high, 0.005)
        mine = [(s[i], v[i], d[i]) for s, v, d in zip(starts, velocities, durations) if d[i] > 0.0]
        assert len(mine) == len(segments)
        for (s, v, d), (s_alone, v_alone, d_alone) in zip(mine, segments):
            assert np.array_equal(s, s_alone) and np.array_equal(v, v_alone) and d == d_alone
        assert np.array_equal(u_end[i], u_alone) and np.array_equal(u_dot_end[i], u_dot_alone)


def test_per_row_stepper_keeps_scipys_evaluation_budget(monkeypatch):
    """As Scipy's stepper, EmbeddedRK gives up on a row after MAX_EVALUATIONS vector-field evaluations in a segment
    (lowered here to 50, which a long segment of the skier needs more than), naming the rows."""
    import connenv.core.batched as batched_module

    monkeypatch.setattr(batched_module, "MAX_EVALUATIONS", 50)
    y, h, hold = np.array([[2.0, 0.0], [-4.0, 200.0]]), np.full((2, 1), 0.8), np.zeros((2, 1))
    with pytest.raises(StepperError, match=r"cannot meet its tolerance: 50 evaluations .* rows \[0, 1\]"):
        EmbeddedRK("DOP853", 1e-10, 1e-12)(skier_system(), y, h, hold, 5.0)
