"""Throughput: single-env steps/s against Gymnasium's Pendulum-v1, native vector env-steps/s against Gymnasium's
native CartPole-v1 vector env and SyncVectorEnv, and SB3 PPO training steps/s against Pendulum-v1's.

    python -m connenv.throughput [--envs ID ...] [--sizes 1 64 1024 4096] [--sync-max 1024] [--seconds 0.5]
                                 [--breakdown] [--training] [--bounds] [--write docs/throughput.md]
    python -m connenv.throughput --rigid-body [--single-steps 3000]
    python -m connenv.throughput --backend jax [--envs ID ...] [--sizes ...] [--write docs/throughput-jax.md]

Single envs: each env from ``gym.make(id)`` (its registered wrappers included) and Pendulum-v1 from
``gym.make("Pendulum-v1")`` are stepped alternately with random actions, each step timed alone, resets left out
of the timing; the figures are the medians, and the ratio is the env's median step time over Pendulum-v1's,
measured in the same loop, so that it holds on a machine busy with other work, where the absolute times do not.

Vector envs: ``gym.make_vec(id, N, vectorization_mode="vector_entry_point")`` (native) and the same with
``"sync"`` (Gymnasium's SyncVectorEnv of N single envs), and Gymnasium's native CartPole-v1 vector env at the same N
(``gym.make_vec("CartPole-v1", N, vectorization_mode="vector_entry_point")``), reset once (untimed), then stepped
with random actions in alternating blocks of about ``seconds / ROUNDS`` each; autoresets are part of the steps, as
in training. The figure is N × steps / time, the median over the blocks, and the target is a fraction of
CartPole's rate in the same run. SyncVectorEnv's cost per env hardly depends on N, and at N = 4096 its first reset
alone takes tens of seconds on the envs whose reset solves for an optimal arc, so it runs only up to ``--sync-max``
(default 1024). The timed blocks are short beside an episode, so few rows end in them: the autoresets' share in a
long run is printed by ``--breakdown``, which adds, at the largest N, where a native step's time goes: the stepper
and the rest (task code: observation, reward, info), the vector-field evaluations per step of the adaptive
steppers, and the cost of a row's reset (the single env's reset, run with the row's generator) with its share per
step when every episode runs to the time limit.

``--training``: SB3's PPO (MlpPolicy, or MultiInputPolicy for a Dict observation) on 8 copies of the env in SB3's
DummyVecEnv, n_steps 256, torch on one thread, beside Pendulum-v1 with the same settings: training steps/s after a
warm-up rollout, and the env's share of the training time (the time the same DummyVecEnv takes to step as often
with random actions, over the training time). It needs the ``train`` extra.

``--bounds``: what bounds the targets, measured: the calls a default step cannot skip (the elliptic functions of the
swing's and Kapitza's closed form, the skier's vector field) on one state against Pendulum-v1's step and on the
largest N against CartPole-v1's vector step, and the batched RK8 step of the swing with its error per step.

``--write PATH`` writes what was printed as a Markdown page (docs/throughput.md): regenerate it with the command, do
not edit it.

``--backend jax``: the JAX envs (``connenv.jax``; the ``jax`` extra) instead, each id's jit-ed rollouts beside its
numpy vector env and Gymnasium's functional JAX Pendulum in the same run (``connenv/jax/throughput.py`` says how).

``--rigid-body``: the free rigid body (connenv.systems.rigid_body, a system without an env): its default step,
``advance`` by the exact flow over dt = 0.1 s from a seeded random momentum, timed alternately with Pendulum-v1's
env step as above.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import time

import gymnasium as gym
import numpy as np
import scipy

import connenv  # noqa: F401  (registers the envs)
from connenv import cli
from connenv.core.integrators import INTEGRATORS
from connenv.envs.spec import registry, spec

PROG = "python -m connenv.throughput"
SINGLE_STEPS = 3000
REFERENCE = "CartPole-v1"  # Gymnasium's native vector env, the vector table's reference (issue 15)
ROUNDS = 5
SIZES = (1, 64, 1024, 4096)
TRAINING = {"n_envs": 8, "n_steps": 256, "rollouts": 2}  # PPO's settings for --training, env and Pendulum-v1 alike


def make_kwargs(env_id: str) -> dict:
    """The make kwargs of an id: none for the built envs; the generic ids need a system, for which they take
    connenv.examples' (the swing from its Lagrangian; Elroy's beanie)."""
    return spec(env_id).make_kwargs()


def single_step_times(env_id: str, steps: int, seed: int = 0, **kwargs):
    """Median step times (s) of env_id (made with kwargs, default make_kwargs(env_id)) and of Pendulum-v1, stepped
    alternately, each step timed alone."""
    envs = [gym.make(env_id, **(kwargs or make_kwargs(env_id))), gym.make("Pendulum-v1")]
    times = [[], []]
    for k, env in enumerate(envs):
        env.reset(seed=seed)
        env.action_space.seed(seed + k)
    actions = [[env.action_space.sample() for _ in range(256)] for env in envs]
    for i in range(steps):
        for k, env in enumerate(envs):
            action = actions[k][i % 256]
            start = time.perf_counter()
            _, _, terminated, truncated, _ = env.step(action)
            times[k].append(time.perf_counter() - start)
            if terminated or truncated:
                env.reset()
    return statistics.median(times[0]), statistics.median(times[1])


def rigid_body_step_times(steps: int, dt: float = 0.1, seed: int = 0):
    """Median step times (s) of the free rigid body's default step (the exact flow over dt) and of Pendulum-v1,
    stepped alternately, each step timed alone."""
    from connenv.systems.rigid_body import RigidBody, advance, state

    body, pendulum = RigidBody(), gym.make("Pendulum-v1")
    pendulum.reset(seed=seed)
    pendulum.action_space.seed(seed)
    y = state(np.random.default_rng(seed).normal(size=3))
    times = [[], []]
    for _ in range(steps):
        start = time.perf_counter()
        y = advance(body, y, dt)
        times[0].append(time.perf_counter() - start)
        action = pendulum.action_space.sample()
        start = time.perf_counter()
        pendulum.step(action)
        times[1].append(time.perf_counter() - start)
    return statistics.median(times[0]), statistics.median(times[1])


def vector_rates(env_id: str, n: int, seconds: float, sync: bool, seed: int = 0, reference=REFERENCE, **kwargs):
    """Median env-steps/s at N = n of the native vector env (made with kwargs), of SyncVectorEnv (None unless sync)
    and of the reference id's native vector env (None without one), stepped alternately."""
    kwargs = kwargs or make_kwargs(env_id)
    envs = [gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", **kwargs)]
    if sync:
        envs.append(gym.make_vec(env_id, n, vectorization_mode="sync", **kwargs))
    if reference is not None:
        envs.append(gym.make_vec(reference, n, vectorization_mode="vector_entry_point"))
    rng = np.random.default_rng(seed)
    ours = rng.uniform(-1.0, 1.0, (16, *envs[0].action_space.shape)).astype(np.float32)
    actions = [ours] * (1 + sync)
    if reference is not None:
        envs[-1].action_space.seed(seed)
        actions.append([envs[-1].action_space.sample() for _ in range(16)])
    rates = [[] for _ in envs]
    for k, env in enumerate(envs):
        env.reset(seed=seed)
        env.step(actions[k][0])
    for _ in range(ROUNDS):
        for k, env in enumerate(envs):
            steps, start = 0, time.perf_counter()
            while (elapsed := time.perf_counter() - start) < seconds / ROUNDS or steps == 0:
                env.step(actions[k][steps % 16])
                steps += 1
            rates[k].append(n * steps / elapsed)
    for env in envs:
        env.close()
    medians = [statistics.median(r) for r in rates]
    return medians[0], (medians[1] if sync else None), (medians[-1] if reference is not None else None)


class Counted:
    """A system whose vector_field calls are counted (the adaptive steppers' right-hand-side evaluations). Made by
    ``counted(system)``: a subclass per wrapped type, because the steppers decide a system's protocols once per type
    (``connenv.core.steppers.conforms``), and one class for every wrapped system would answer for the first."""

    def __init__(self, system):
        self.system, self.calls = system, 0

    def vector_field(self, y, u, u_dot):
        self.calls += 1
        return self.system.vector_field(y, u, u_dot)

    def __getattr__(self, name):
        return getattr(self.system, name)


def counted(system) -> Counted:
    """system wrapped in Counted, with the methods of the system's protocols (exact flows, hamiltonian) exposed."""
    names = [name for name in dir(type(system)) if not name.startswith("_") and callable(getattr(system, name))]
    methods = {name: _forward(name) for name in names if name != "vector_field"}
    return type(f"Counted{type(system).__name__}", (Counted,), methods)(system)


def _forward(name):
    return lambda self, *args, **kwargs: getattr(self.system, name)(*args, **kwargs)


def step_breakdown(env_id: str, n: int, steps: int, seed: int = 0):
    """Where a native vector step goes at N = n: (ms per step, ms in the stepper, vector-field evaluations per
    step, µs per row reset, ms per step of autoresets in the steady state of episodes at the time limit)."""
    venv = gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", **make_kwargs(env_id))
    prototype = venv.unwrapped.env
    for name in ("system", "reduced_system", "full_system"):
        if hasattr(prototype, name):
            setattr(prototype, name, counted(getattr(prototype, name)))
    systems = [getattr(prototype, name, None) for name in ("system", "reduced_system", "full_system")]
    counters = list({id(c): c for c in systems if isinstance(c, Counted)}.values())
    stepper, in_stepper = venv.unwrapped.stepper, [0.0]

    def timed_stepper(*args):
        start = time.perf_counter()
        result = stepper(*args)
        in_stepper[0] += time.perf_counter() - start
        return result

    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1.0, 1.0, (16, *venv.action_space.shape)).astype(np.float32)
    start = time.perf_counter()
    venv.reset(seed=seed)
    reset_per_row = (time.perf_counter() - start) / n
    venv.step(actions[0])
    venv.unwrapped.stepper = timed_stepper
    calls_before = sum(c.calls for c in counters)
    start = time.perf_counter()
    for i in range(steps):
        venv.step(actions[i % len(actions)])
    elapsed = time.perf_counter() - start
    calls = sum(c.calls for c in counters) - calls_before
    amortized = n / venv.unwrapped.max_episode_steps * reset_per_row
    return elapsed / steps, in_stepper[0] / steps, calls / steps, reset_per_row, amortized


def shell_steppers(integrators, n: int, steps: int, seconds: float, seed: int = 0):
    """The shell's reduced model (KozlovShellEnv's default episode) stepped by each integrator as the env steps it,
    a straight mass motion to a random command per step of 0.1 s: one state against Pendulum-v1's env step, and N = n
    rows by the batched stepper against Gymnasium's native CartPole-v1 vector env, each pair alternated in one loop
    (issue 15's targets: ≤ 5× and ≥ 0.1×). The system is stepped directly, without the env's task code."""
    from connenv.core.batched import batched
    from connenv.core.integrators import make_stepper
    from connenv.envs.kozlov_shell import KozlovShellEnv
    from connenv.systems.kozlov_shell import ReducedKozlovShell

    system, dt, u_max = ReducedKozlovShell(), 0.1, np.array([0.5, 0.25])
    rng = np.random.default_rng(seed)
    commands = rng.uniform(-1.0, 1.0, (256, 2)) * u_max
    print("\nthe shell's reduced model by integrator, stepped directly: one state × Pendulum-v1's env step (target")
    print(f"≤ 5), N={n} rows × CartPole-v1's native vector env (target ≥ 0.1)")
    print("and the pose error after 300 steps from rest against DOP853 at rtol 1e-13 (max-norm of x, y, θ; m, rad)")
    print(
        f"{'integrator':12} {'µs/step':>9} {'× Pendulum':>11} {'M/s':>9} {'CartPole M/s':>13} {'× CartPole':>11} "
        f"{'pose error':>11}"
    )
    reference = make_stepper("dop853", system, rtol=1e-13, atol=1e-15)
    for name in integrators:
        integrator, _, atol = name.partition(":")  # "magnus:1e-9": the Magnus step with atol 1e-9
        options = {"rtol": 1e-8, "atol": 1e-10} if integrator == "dop853" else {"atol": float(atol)} if atol else {}
        if integrator == "default":  # the env's own: the Lie-group step with the rule fixed at construction
            stepper = KozlovShellEnv().stepper
        else:
            stepper = make_stepper(integrator, system, **options)
        y, y_ref, u = np.zeros(3), np.zeros(3), np.zeros(2)
        for u_cmd in np.random.default_rng(seed).uniform(-1.0, 1.0, (300, 2)) * u_max:
            u_dot = (u_cmd - u) / dt
            y, y_ref, u = stepper(system, y, u, u_dot, dt), reference(system, y_ref, u, u_dot, dt), u_cmd
        error = np.max(np.abs(y - y_ref))
        pendulum = gym.make("Pendulum-v1")
        pendulum.reset(seed=seed)
        times, y, u = [[], []], np.zeros(3), np.zeros(2)
        for i in range(steps):
            u_cmd = commands[i % 256]
            start = time.perf_counter()
            y = stepper(system, y, u, (u_cmd - u) / dt, dt)
            times[0].append(time.perf_counter() - start)
            u, action = u_cmd, pendulum.action_space.sample()
            start = time.perf_counter()
            pendulum.step(action)
            times[1].append(time.perf_counter() - start)
        single, pendulum_time = statistics.median(times[0]), statistics.median(times[1])
        rows = batched(stepper)
        cartpole = gym.make_vec("CartPole-v1", n, vectorization_mode="vector_entry_point")
        cartpole.reset(seed=seed)
        y, u, rates = np.zeros((n, 3)), np.zeros((n, 2)), [[], []]
        for _ in range(ROUNDS):
            count, start = 0, time.perf_counter()
            while (elapsed := time.perf_counter() - start) < seconds / ROUNDS or count == 0:
                u_cmd = rng.uniform(-1.0, 1.0, (n, 2)) * u_max
                y, u, count = rows(system, y, u, (u_cmd - u) / dt, dt), u_cmd, count + 1
            rates[0].append(n * count / elapsed)
            count, start = 0, time.perf_counter()
            while (elapsed := time.perf_counter() - start) < seconds / ROUNDS or count == 0:
                cartpole.step(cartpole.action_space.sample())
                count += 1
            rates[1].append(n * count / elapsed)
        native, cartpole_rate = statistics.median(rates[0]), statistics.median(rates[1])
        print(
            f"{name:12} {single * 1e6:9.1f} {single / pendulum_time:11.2f} {native / 1e6:9.4f} "
            f"{cartpole_rate / 1e6:13.3f} {native / cartpole_rate:11.3f} {error:11.1e}"
        )


def training_rates(env_id: str, seed: int = 0):
    """(PPO training steps/s on env_id, the same on Pendulum-v1, env_id's share of its training time, Pendulum-v1's
    share), with TRAINING's settings and torch on one thread; the share is the time the same DummyVecEnv takes to
    step as often with random actions over the training time."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    torch.set_num_threads(1)
    results = []
    for name, kwargs in ((env_id, make_kwargs(env_id)), ("Pendulum-v1", {})):
        venv = make_vec_env(name, n_envs=TRAINING["n_envs"], seed=seed, env_kwargs=kwargs)
        policy = "MultiInputPolicy" if isinstance(venv.observation_space, gym.spaces.Dict) else "MlpPolicy"
        model = PPO(policy, venv, n_steps=TRAINING["n_steps"], seed=seed, device="cpu")
        rollout = TRAINING["n_envs"] * TRAINING["n_steps"]
        model.learn(rollout)  # warm-up: one rollout and one update
        start = time.perf_counter()
        model.learn(TRAINING["rollouts"] * rollout, reset_num_timesteps=False)
        training = time.perf_counter() - start
        actions = [np.stack([venv.action_space.sample() for _ in range(venv.num_envs)]) for _ in range(16)]
        start = time.perf_counter()
        for i in range(TRAINING["rollouts"] * TRAINING["n_steps"]):
            venv.step(actions[i % 16])
        stepping = time.perf_counter() - start
        venv.close()
        results.append((TRAINING["rollouts"] * rollout / training, stepping / training))
    (rate, share), (pendulum_rate, pendulum_share) = results
    return rate, pendulum_rate, share, pendulum_share


def verdict(value: float, target: float | None, at_most: bool) -> str:
    """ "met"/"MISSED" against a target (value ≤ target with at_most, else ≥), "" without one."""
    if target is None:
        return ""
    return "met" if (value <= target if at_most else value >= target) else "MISSED"


class Report:
    """Tables printed as they fill, and kept to be written as a Markdown page."""

    def __init__(self, header: str):
        self.parts = [header]
        print(header)

    def table(self, title: str, columns: list[str], rows: list[list[str]]):
        widths = [max(len(c), *(len(r[i]) for r in rows)) if rows else len(c) for i, c in enumerate(columns)]
        print(f"\n{title}")
        for line in [columns, *rows]:
            print(
                "  ".join(cell.ljust(w) if i == 0 else cell.rjust(w) for i, (cell, w) in enumerate(zip(line, widths)))
            )
        body = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
        self.parts.append(f"{title}\n\n" + "\n".join(body + ["| " + " | ".join(r) + " |" for r in rows]))

    def note(self, text: str):
        print(f"\n{text}")
        self.parts.append(text)

    def markdown(self, command: str) -> str:
        intro = (
            "# Throughput\n\n"
            f"Generated by `{command}`; regenerate it with the same command rather than editing it. How each figure is "
            "measured is in the docstring of `connenv/throughput.py`. Absolute times on a shared machine move by 2× "
            "from hour to hour: read the ratios to Gymnasium's Pendulum-v1 and CartPole-v1, measured in the same run.\n"
        )
        return intro + "\n" + "\n\n".join(self.parts) + "\n"


def single_table(report: Report, env_ids, steps: int, misses: list):
    rows = []
    for env_id in env_ids:
        env_time, pendulum_time = single_step_times(env_id, steps)
        ratio, target = env_time / pendulum_time, spec(env_id).single_target
        result = verdict(ratio, target, at_most=True)
        misses += [f"{env_id} single {ratio:.2f}× (target ≤ {target}×)"] if result == "MISSED" else []
        rows.append(
            [env_id, f"{env_time * 1e6:.1f}", f"{1 / env_time:.0f}", f"{pendulum_time * 1e6:.1f}", f"{ratio:.2f}",
             f"≤ {target}: {result}" if target else ""]
        )  # fmt: skip
    columns = ["env", "µs/step", "steps/s", "Pendulum µs", "× Pendulum", "target"]
    report.table("Single env: median of env.step of gym.make(id); Pendulum-v1 stepped alternately", columns, rows)


def vector_table(report: Report, env_ids, sizes, seconds: float, sync_max: int, misses: list):
    rows = []
    for env_id in env_ids:
        for n in sizes:
            native, sync, cartpole = vector_rates(env_id, n, seconds, n <= sync_max)
            fraction, target = native / cartpole, spec(env_id).vector_target if n == 4096 else None
            result = verdict(fraction, target, at_most=False)
            misses += [f"{env_id} N={n} {fraction:.3f}× CartPole (target ≥ {target}×)"] if result == "MISSED" else []
            rows.append(
                [env_id, str(n), f"{native / 1e6:.4f}", f"{sync / 1e6:.4f}" if sync else "-",
                 f"{native / sync:.1f}" if sync else "-", f"{cartpole / 1e6:.3f}", f"{fraction:.3f}",
                 f"≥ {target}: {result}" if target else ""]
            )  # fmt: skip
    columns = ["env", "N", "native M/s", "sync M/s", "native/sync", "CartPole M/s", "× CartPole", "target at N=4096"]
    title = (
        "Vector envs: M env-steps/s, median of blocks, autoresets included; Gymnasium's native CartPole-v1 vector env "
        "stepped alternately at the same N"
    )
    report.table(title, columns, rows)


def breakdown_table(report: Report, env_ids, n: int, seconds: float):
    rows = []
    for env_id in env_ids:
        step, stepper, calls, reset, amortized = step_breakdown(env_id, n, max(3, int(seconds * 20)))
        rows.append(
            [env_id, f"{step * 1e3:.2f}", f"{stepper * 1e3:.2f}", f"{(step - stepper) * 1e3:.2f}", f"{calls:.1f}",
             f"{reset * 1e6:.1f}", f"{amortized * 1e3:.2f}"]
        )  # fmt: skip
    title = (
        f"Where a native vector step goes at N={n}, random actions: ms per step, in the stepper and in the rest (task "
        "code); vector-field calls per step (adaptive steppers); a row's reset (µs), and the autoresets' ms per step "
        "when every episode runs to the time limit"
    )
    report.table(title, ["env", "step ms", "stepper ms", "rest ms", "rhs calls", "reset µs", "autoreset ms"], rows)


def training_table(report: Report, env_ids):
    rows = []
    for env_id in env_ids:
        rate, pendulum_rate, share, pendulum_share = training_rates(env_id)
        rows.append(
            [env_id, f"{rate:.0f}", f"{pendulum_rate:.0f}", f"{rate / pendulum_rate:.2f}", f"{share:.0%}",
             f"{pendulum_share:.0%}"]
        )  # fmt: skip
    settings = ", ".join(f"{k} {v}" for k, v in TRAINING.items())
    title = f"SB3 PPO training steps/s ({settings}, one torch thread), beside Pendulum-v1 with the same settings"
    columns = ["env", "steps/s", "Pendulum steps/s", "× Pendulum", "env's share", "Pendulum's share"]
    report.table(title, columns, rows)


def task_layer(env_id: str, seed: int):
    """gym.make(env_id) twice, reset: as made, and with the identity for its stepper, whose step costs what the task
    layer costs (the action's check, the segments, the state, observation, reward and info), the physics left out."""
    pair = gym.make(env_id), gym.make(env_id)
    pair[1].unwrapped.stepper = lambda system, y, u, u_dot, tau: y.copy()
    for env in pair:
        env.reset(seed=seed)
        env.action_space.seed(seed)
    return pair


REFERENCES = ("Pendulum-v1's env step", "CartPole-v1's native vector step")


def bounds_table(report: Report, n: int, seed: int = 0):
    """What bounds the missed targets, measured: the physics a default step cannot skip, on one state against
    Pendulum-v1's env step and on n rows against CartPole-v1's native vector step; the task layer alone (each env
    with a single-env target stepped with the identity for its stepper); and the batched RK8 step of the swing, the alternative to its
    elliptic functions, with its largest error per step against them."""
    from scipy.special import ellipj

    from connenv.core.integrators import make_stepper
    from connenv.core.steppers import RK8
    from connenv.envs.skier import SkierEnv
    from connenv.systems.swing import Swing, ellipj_one

    rng = np.random.default_rng(seed)
    skier = SkierEnv()
    swing, r = Swing(), rng.uniform(1.6, 2.0, (n, 1))
    theta_dot = rng.uniform(-4.0, 4.0, n) * np.sqrt(swing.g / r[:, 0])  # up to twice the separatrix's speed
    rows = np.stack([rng.uniform(-np.pi, np.pi, n), swing.mass * r[:, 0] ** 2 * theta_dot], axis=-1)
    held, exact = np.zeros((n, 1)), make_stepper("exact", swing)
    closed_form = exact(swing, rows, r, held, 0.05)
    rk8_error = float(
        np.max(np.abs(RK8()(swing, rows, r, held, 0.05) - closed_form) / np.maximum(1.0, np.abs(closed_form)))
    )
    x = np.stack([rng.uniform(-5.0, 5.0, n), rng.uniform(-300.0, 300.0, n)], axis=-1)
    h, m, u = np.ones((n, 1)), rng.uniform(0.0, 0.99, n), rng.uniform(0.0, 3.0, n)
    pendulum, cartpole = (
        gym.make("Pendulum-v1"),
        gym.make_vec("CartPole-v1", n, vectorization_mode="vector_entry_point"),
    )
    task_layers = {env_id: task_layer(env_id, seed) for env_id in registry if spec(env_id).single_target}
    for env in (pendulum, cartpole):
        env.reset(seed=seed)
    one, push = np.zeros(1, np.float32), np.zeros(n, int)
    cases = [
        ("Pendulum-v1's env step (reference)", 1, lambda: pendulum.step(one)),
        ("ellipj on one float, scipy's ufunc", 1, lambda: ellipj(0.3, 0.2)),
        ("ellipj on one float, as the swing's and Kapitza's closed form call it", 1, lambda: ellipj_one(0.3, 0.2)),
        *((f"{env_id.split('/')[1]}'s env step, {kind}", 1, functools.partial(env.step, env.action_space.sample()))
          for env_id, pair in task_layers.items()
          for kind, env in zip(("its default stepper", "the identity for its stepper (the task layer)"), pair)),
        ("the skier's vector field on one state, ×13 (its default step)", 13,
         lambda: skier.system.vector_field(x[0], h[0], held[0])),
        (f"CartPole-v1's native vector step, N={n} (reference)", 1, lambda: cartpole.step(push)),
        (f"ellipj over N={n} rows", 1, lambda: ellipj(u, m)),
        (f"the swing's closed-form step (ellipj and its addition theorem) over N={n} rows", 1,
         lambda: swing.exact_flow(rows, r, 0.05)),
        (f"RK8, one step of 0.05 s on the swing's N={n} rows (error {rk8_error:.1e} of the closed form)", 1,
         lambda: RK8()(swing, rows, r, held, 0.05)),
        (f"the skier's vector field over N={n} rows, ×13", 13, lambda: skier.system.vector_field(x, h, held)),
    ]  # fmt: skip
    table = []
    for label, count, call in cases:
        times = []
        for _ in range(200 if count == 1 and "N=" not in label else 30):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
        table.append((label, count * statistics.median(times)))
    single_reference, vector_reference = (
        next(t for label, t in table if label.startswith(name)) for name in REFERENCES
    )
    rows_out = [
        [label, f"{t * 1e6:.1f}", f"{t / (vector_reference if 'N=' in label else single_reference):.2f}"]
        for label, t in table
    ]
    title = "What bounds the targets: medians of the calls a default step makes, against the reference in the same run"
    report.table(title, ["call", "µs", "× reference (Pendulum-v1 step; CartPole-v1 vector step)"], rows_out)


def shell_stepper(text: str) -> str:
    """argparse type of --shell-steppers: 'default' or an integrator of connenv.core.steppers, with :ATOL > 0."""
    integrator, colon, atol = text.partition(":")
    try:
        atol_ok = not colon or 0 < float(atol) < float("inf")
    except ValueError:
        atol_ok = False
    if integrator not in ("default", *INTEGRATORS) or not atol_ok:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not INTEGRATOR[:ATOL], INTEGRATOR one of {('default', *INTEGRATORS)}, ATOL a number > 0"
        )
    return text


def main(argv=None):
    ids = sorted(env_id for env_id in gym.registry if env_id.startswith("connenv/"))
    parser = cli.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", nargs="+", default=ids, choices=ids, metavar="ID")
    parser.add_argument("--sizes", nargs="+", type=cli.positive_int, default=list(SIZES), help="N of the vector envs")
    parser.add_argument(
        "--sync-max", type=cli.non_negative_int, default=1024, help="largest N at which SyncVectorEnv runs"
    )
    parser.add_argument("--seconds", type=cli.positive_float, default=0.5, help="timed seconds per vector env and N")
    parser.add_argument("--single-steps", type=cli.positive_int, default=SINGLE_STEPS)
    parser.add_argument("--skip-single", action="store_true")
    parser.add_argument("--skip-vector", action="store_true")
    parser.add_argument("--breakdown", action="store_true", help="also where a native step goes at the largest N")
    parser.add_argument("--training", action="store_true", help="also SB3 PPO training steps/s (the train extra)")
    parser.add_argument("--bounds", action="store_true", help="also the measured cost of what bounds the targets")
    parser.add_argument(
        "--write",
        type=cli.writable_file,
        metavar="PATH",
        help="write the tables as a Markdown page (docs/throughput.md)",
    )
    parser.add_argument(
        "--shell-steppers",
        nargs="*",
        type=shell_stepper,
        metavar="INTEGRATOR",
        help="only the shell's reduced model under these "
        "integrators (default: dop853 magnus default; magnus:ATOL for another atol; default: the env's own stepper) "
        "against Pendulum-v1 and CartPole-v1's native vector env, at the largest N",
    )
    parser.add_argument("--rigid-body", action="store_true", help="only the free rigid body's step against Pendulum-v1")
    parser.add_argument("--backend", choices=["numpy", "jax"], default="numpy",
                        help="numpy: the envs; jax: connenv.jax's rollouts beside the numpy vector env (the jax extra)")
    parser.add_argument("--numpy-max", type=cli.positive_int, metavar="N",
                        help="--backend jax: the largest N at which the numpy vector env runs beside (default: every N)")
    parser.add_argument("--budget", type=cli.positive_float, metavar="SECONDS",
                        help="--backend jax: measure no new (id, N) after this many seconds (the rows left say so)")
    args = parser.parse_args(argv)
    if args.rigid_body:
        body, pendulum = rigid_body_step_times(args.single_steps)
        print(f"free rigid body, exact flow, dt = 0.1 s: {body * 1e6:.1f} µs/step, Pendulum-v1 {pendulum * 1e6:.1f} "
              f"µs/step: {body / pendulum:.2f}× Pendulum-v1")  # fmt: skip
        return
    if args.shell_steppers is not None:
        integrators = args.shell_steppers or ["dop853", "magnus", "default"]
        shell_steppers(integrators, max(args.sizes), args.single_steps, args.seconds)
        return
    report = Report(
        f"{datetime.datetime.now():%Y-%m-%d %H:%M}, {platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"gymnasium {gym.__version__}, commit {commit()}"
    )
    misses = []
    if args.backend == "jax":
        from connenv.jax import checked_kwargs
        from connenv.jax.throughput import table

        sizes = args.sizes if args.sizes != list(SIZES) else [1, 64, 1024, 4096, 65536]
        table(report, args.envs, sizes, misses,
              lambda env_id, n: vector_rates(env_id, n, args.seconds, sync=False, reference=None,
                                             **checked_kwargs(env_id))[0], args.numpy_max, args.budget)
        args.skip_single = args.skip_vector = True
        report.note("Targets missed: " + ("; ".join(misses) if misses else "none") + ".")
    if not args.skip_single:
        single_table(report, args.envs, args.single_steps, misses)
    if not args.skip_vector:
        vector_table(report, args.envs, args.sizes, args.seconds, args.sync_max, misses)
    if args.breakdown:
        breakdown_table(report, args.envs, max(args.sizes), args.seconds)
    if args.training:
        training_table(report, args.envs)
    if args.bounds:
        bounds_table(report, max(args.sizes))
    if not (args.skip_single and args.skip_vector):
        report.note("Targets missed: " + ("; ".join(misses) if misses else "none") + ".")
    if args.write:
        command = "python -m connenv.throughput " + " ".join(argv if argv is not None else sys.argv[1:])
        pathlib.Path(args.write).write_text(report.markdown(command.strip()))
        print(f"wrote {args.write}")


def commit() -> str:
    """The checkout's commit (with "+" where the work tree differs), or "unknown" outside a git checkout."""
    here = pathlib.Path(__file__).parent
    try:

        def run(*args):
            return subprocess.run(["git", *args], cwd=here, capture_output=True, text=True, check=True).stdout

        return run("rev-parse", "--short", "HEAD").strip() + (
            "+" if run("status", "--porcelain", "-uno").strip() else ""
        )
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    cli.run(main, PROG)
