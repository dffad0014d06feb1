"""Throughput of the JAX envs, beside the numpy vector env of the same id and Gymnasium's own JAX Pendulum
(``gymnasium.envs.phys2d.pendulum.PendulumFunctional``, float32) in the same run:

    python -m connenv.throughput --backend jax [--envs ID ...] [--sizes 1 64 1024 4096 65536] [--write PATH]

A rollout is ``jax.jit`` of ``lax.scan`` over ROLLOUT steps of ``env.step_rows`` (the N envs' step in one call:
the numbers of ``jax.vmap(env.step)``, with a branch no row takes skipped) and autoresets, with random actions
drawn from the key inside the program, as a PureJaxRL-style trainer runs an env. Its compile time is
the first call's; the rate is N × ROLLOUT / the median time of the following calls. The numpy figure is
connenv.throughput's native vector env at the same N (timed in blocks as there), and the ratio JAX / numpy is the
target's (issue 45: ≥ 2× at N = 4096, ≥ 5× at N = 64, compile < 30 s). Pendulum's rollout is the same program on
its transition, observation and reward, with a reset where an episode reaches 200 steps.
"""

from __future__ import annotations

import statistics
import time

import jax
import jax.numpy as jnp

ROLLOUT = 100
CALLS = 5
TARGETS = {64: 5.0, 4096: 2.0}  # N: the least ratio of JAX's rate to the numpy vector env's
COMPILE_MAX = 30.0  # s


def rollout_program(env, params, n: int):
    """A jitted rollout of ROLLOUT steps of n envs with random actions: (key, states) -> (key, states, Σ reward)."""
    space = env.action_space(params)

    def body(carry, _):
        key, states = carry
        key, act, run = jax.random.split(key, 3)
        actions = jax.vmap(space.sample)(jax.random.split(act, n))
        obs, states, reward, terminated, truncated, info = env.step_rows(run, states, actions, params)
        return (key, states), reward.sum()

    @jax.jit
    def rollout(key, states):
        (key, states), rewards = jax.lax.scan(body, (key, states), None, length=ROLLOUT)
        return key, states, rewards.sum()

    return rollout


def pendulum_program(n: int):
    """The same rollout of Gymnasium's functional Pendulum (float32), reset every 200 steps."""
    from gymnasium.envs.phys2d.pendulum import PendulumFunctional

    pendulum = PendulumFunctional()

    def one(state, action, key, t):
        after = pendulum.transition(state, action, None)
        reward = pendulum.reward(state, action, after, None)
        obs = pendulum.observation(after, None)
        fresh = pendulum.initial(key)
        return jnp.where(t % 200 == 199, fresh, after), reward, obs

    def body(carry, t):
        key, states = carry
        key, act, run = jax.random.split(key, 3)
        actions = jax.random.uniform(act, (n, 1), minval=-2.0, maxval=2.0)
        states, reward, obs = jax.vmap(one, (0, 0, 0, None))(states, actions, jax.random.split(run, n), t)
        return (key, states), reward.sum()

    @jax.jit
    def rollout(key, states):
        (key, states), rewards = jax.lax.scan(body, (key, states), jnp.arange(ROLLOUT))
        return key, states, rewards.sum()

    states = jax.vmap(pendulum.initial)(jax.random.split(jax.random.key(1), n))
    return rollout, states


def timed(rollout, key, states):
    """(compile s, median s per call) of a rollout program."""
    start = time.perf_counter()
    key, states, total = rollout(key, states)
    total.block_until_ready()
    compile_time = time.perf_counter() - start
    times = []
    for _ in range(CALLS):
        start = time.perf_counter()
        key, states, total = rollout(key, states)
        total.block_until_ready()
        times.append(time.perf_counter() - start)
    return compile_time, statistics.median(times)


def rates(env_id: str, n: int):
    """(compile s, JAX env-steps/s) of env_id's rollout at N = n."""
    import connenv.jax as cj

    env, params = cj.make(env_id, **cj.checked_kwargs(env_id))
    obs, states = jax.vmap(env.reset, (0, None))(jax.random.split(jax.random.key(0), n), params)
    compile_time, seconds = timed(rollout_program(env, params, n), jax.random.key(1), states)
    return compile_time, n * ROLLOUT / seconds


def pendulum_rate(n: int) -> float | None:
    """Gymnasium's functional Pendulum's env-steps/s at N = n (None where flax, which it needs, is missing)."""
    try:
        rollout, states = pendulum_program(n)
    except ImportError:
        return None
    return n * ROLLOUT / timed(rollout, jax.random.key(1), states)[1]


def bound_note(env_id: str, n: int) -> str:
    """What bounds a traced step, measured at N = n: the whole vmapped transition beside its closed form's special
    function (the swing's and Kapitza's Jacobi elliptic functions), traced and scipy's, on the same rows."""
    import numpy as np
    import scipy.special

    import connenv.jax as cj
    from connenv.jax.namespace import ellipj

    rng = np.random.default_rng(0)
    u, m = rng.uniform(0.0, 1.0, n), rng.uniform(0.0, 0.9, n)
    env, params = cj.make(env_id)
    X = np.tile(np.asarray(env.reset(jax.random.key(0), params)[1].x), (n, 1))
    A = jnp.zeros((n, *env.action_space(params).shape))
    step = jax.jit(jax.vmap(lambda x, a: env.transition(x, a)[0]))
    traced = jax.jit(ellipj)

    def median(call):
        call()
        times = []
        for _ in range(20):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
        return statistics.median(times)

    whole = median(lambda: step(X, A).block_until_ready())
    special = median(lambda: traced(u, m)[0].block_until_ready())
    numpy_special = median(lambda: scipy.special.ellipj(u, m))
    return (f"Bound of {env_id.removeprefix('connenv/')} at N = {n}: the vmapped transition takes "
            f"{whole * 1e3:.2f} ms, "
            f"of which the traced Jacobi elliptic functions alone take {special * 1e3:.2f} ms, against "
            f"{numpy_special * 1e3:.2f} ms for scipy's ellipj on the same rows (cephes' AGM stops at its level; "
            "the traced one computes every level and both series, and XLA's float64 transcendental functions on the "
            "CPU).")


def table(report, env_ids, sizes, misses: list, numpy_rate):
    """The JAX table on connenv.throughput's Report: per id and N, the compile time, JAX's rate, the numpy vector
    env's (``numpy_rate(id, n)``, connenv.throughput's, passed in) and Pendulum's in the same run, and the ratio
    against its target."""
    from connenv.envs.spec import spec

    jax.config.update("jax_enable_x64", True)  # the benchmark's own process: float64, as connenv.jax asks
    rows = []
    for env_id in env_ids:
        if not spec(env_id).jax:
            rows.append([env_id.removeprefix("connenv/"), "–", "no JAX version yet", "", "", "", ""])
            continue
        for n in sizes:
            try:
                compile_time, ours = rates(env_id, n)
            except Exception as error:  # noqa: BLE001  (a rollout that does not trace at this N is a row that says so)
                first = str(error).splitlines()[0][:120]
                rows.append([env_id.removeprefix("connenv/"), str(n), "–", f"failed: {type(error).__name__}: {first}",
                             "", "", ""])
                misses.append(f"{env_id} at N = {n}: the rollout failed ({type(error).__name__})")
                print(" | ".join(rows[-1]), flush=True)
                continue
            numpy = numpy_rate(env_id, n)
            pendulum = pendulum_rate(n)
            ratio = ours / numpy
            target = TARGETS.get(n)
            cell = f"{ratio:.2f}×" + ("" if not target else " met" if ratio >= target else " MISSED")
            if target and ratio < target:
                misses.append(f"{env_id} JAX/numpy at N = {n}: {ratio:.2f}× < {target}×")
            if compile_time > COMPILE_MAX:
                misses.append(f"{env_id} compile {compile_time:.1f} s > {COMPILE_MAX} s")
            rows.append([env_id.removeprefix("connenv/"), str(n), f"{compile_time:.1f}", f"{ours / 1e6:.3g}",
                         f"{numpy / 1e6:.3g}", "–" if pendulum is None else f"{pendulum / 1e6:.3g}", cell])
            print(" | ".join(rows[-1]), flush=True)
    report.table(
        f"JAX: jit + vmap + lax.scan rollouts of {ROLLOUT} steps, random actions, autoresets (float64)",
        ["env", "N", "compile s", "JAX M steps/s", "numpy vector M steps/s", "phys2d Pendulum (JAX, float32) M steps/s",
         "JAX / numpy"],
        rows,
    )
    for env_id in env_ids:
        if env_id == "connenv/Swing-v0":
            report.note(bound_note(env_id, 4096))
    report.note(f"JAX backend: {jax.default_backend()} ({jax.devices()[0].device_kind}). " + (
        "Not measured on a GPU yet: on one, `python -m connenv.throughput --backend jax --sizes 64 4096 65536 "
        "1048576 --write docs/throughput-jax-gpu.md` runs the same benchmark up to N = 2²⁰."
        if jax.default_backend() == "cpu" else ""))
