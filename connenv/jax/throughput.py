"""Throughput of the JAX envs, beside the numpy vector env of the same id and Gymnasium's own JAX Pendulum
(``gymnasium.envs.phys2d.pendulum.PendulumFunctional``, float32) in the same run:

    python -m connenv.throughput --backend jax [--envs ID ...] [--sizes 1 64 1024 4096 65536] [--write PATH]

A rollout is ``jax.jit`` of ``lax.scan`` over ROLLOUT steps of ``env.step_rows`` (the N envs' step in one call:
the numbers of ``jax.vmap(env.step)``, with a branch no row takes skipped) and autoresets, with random actions
drawn from the key inside the program (one uniform draw of the N rows' actions, as Pendulum's), as a PureJaxRL-style
trainer runs an env. Its compile time is
the first call's; the rate is N × ROLLOUT / the median time of the following calls. The numpy figure is
connenv.throughput's native vector env at the same N (timed in blocks as there), and the ratio JAX / numpy is the
target's (issue 45: ≥ 2× at N = 4096, ≥ 5× at N = 64, compile < 30 s). Pendulum's rollout is the same program on
its transition, observation and reward, with a reset where an episode reaches 200 steps.

Where an id misses a target, the page names what bounds it, measured in the same run (`bound_note`): step_rows'
time split into the next state, the observation, reward and info, and the autoreset, and the transcendental
functions of its transition, counted in its jaxpr and timed on N rows, summed per function of connenv that calls
them. On a GPU, GPU_COMMAND runs the benchmark up to N = 2²⁰ within 8 minutes.
"""

from __future__ import annotations

import functools
import math
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

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
        actions = jax.random.uniform(act, (n, *space.shape), jnp.float32 if space.dtype == np.float32 else float,
                                     jnp.asarray(space.low), jnp.asarray(space.high)).astype(space.dtype)
        obs, states, reward, terminated, truncated, info = env.step_rows(run, states, actions, params)
        return (key, states), reward.sum()

    @jax.jit
    def rollout(key, states):
        (key, states), rewards = jax.lax.scan(body, (key, states), None, length=ROLLOUT)
        return key, states, rewards.sum()

    return rollout


@functools.cache
def pendulum_program(n: int):
    """The same rollout of Gymnasium's functional Pendulum (float32), reset every 200 steps; made (and compiled) once
    per N, timed beside each id."""
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
    _, states = jax.vmap(env.reset, (0, None))(jax.random.split(jax.random.key(0), n), params)
    compile_time, seconds = timed(rollout_program(env, params, n), jax.random.key(1), states)
    return compile_time, n * ROLLOUT / seconds


def pendulum_rate(n: int) -> float | None:
    """Gymnasium's functional Pendulum's env-steps/s at N = n (None where flax, which it needs, is missing)."""
    try:
        rollout, states = pendulum_program(n)
    except ImportError:
        return None
    return n * ROLLOUT / timed(rollout, jax.random.key(1), states)[1]


TIMED = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
         "exp", "exp2", "expm1", "log", "log1p", "sqrt", "rsqrt", "cbrt", "pow", "div", "erf_inv")
"""The primitives whose cost bound_note measures: XLA's float64 transcendental functions and division (on the CPU
many times an addition's; the arithmetic between them is left out, and so is a division by a number written in the
code, which XLA may turn into a product)."""


def _least(*calls, rounds: int = 15) -> list[float]:
    """The least time of each call over rounds in which they run in turn (after one untimed call each): on a shared
    machine the least is the call's own cost, the others' being what load adds."""
    for call in calls:
        call()
    least = [math.inf] * len(calls)
    for _ in range(rounds):
        for k, call in enumerate(calls):
            start = time.perf_counter()
            call()
            least[k] = min(least[k], time.perf_counter() - start)
    return least


@functools.cache
def primitive_time(name: str, n: int) -> float:
    """Seconds one call of the lax primitive ``name`` takes on n float64 rows: a jitted sum of 16 calls, less the same
    sum without them, over 16."""
    import numpy as np

    chain = 16
    rng = np.random.default_rng(0)
    x, y = (jnp.asarray(rng.uniform(0.1, 0.9, n)) for _ in range(2))
    function = getattr(jax.lax, name)
    binary = name in ("atan2", "pow", "div")
    shift = 1.0 if name == "acosh" else 0.0

    def program(apply):
        return jax.jit(lambda x, y: sum(apply(x * (1.0 + 1e-3 * i) + shift, y) for i in range(chain)))

    with_it = program(lambda a, b: function(a, b) if binary else function(a))
    without = program(lambda a, b: a + b if binary else a)
    timed, bare = _least(lambda: with_it(x, y).block_until_ready(), lambda: without(x, y).block_until_ready())
    return max(0.0, timed - bare) / chain


def _tally(jaxpr, n: int, weight: float, counts: dict, loops: list, outer: str = "?"):
    """counts[(primitive, function)] += its calls on n rows (outputs of n × k elements count k) in jaxpr and the
    jaxprs inside it: a scan's body times its length, a cond's first branch (the skipped one: connenv's branches run
    only where some row takes them), a while loop's body once (its trip count read off the rows: noted in loops). A
    primitive whose traceback names no function (inside a custom derivative's jaxpr) counts to the enclosing one's
    (outer)."""
    for eqn in jaxpr.eqns:
        name, caller = eqn.primitive.name, _caller(eqn)
        caller = outer if caller == "?" else caller
        if name == "cond":
            _tally(eqn.params["branches"][0].jaxpr, n, weight, counts, loops, caller)
            continue
        if name == "while":
            loops.append(caller)
        for value in eqn.params.values():
            inner = getattr(value, "jaxpr", value)
            if hasattr(inner, "eqns"):
                _tally(inner, n, weight * (eqn.params["length"] if name == "scan" else 1), counts, loops, caller)
        if name in TIMED and not (name == "div" and type(eqn.invars[1]).__name__ == "Literal"):
            size = math.prod(eqn.outvars[0].aval.shape)
            if size >= n:
                counts[(name, caller)] = counts.get((name, caller), 0.0) + weight * size / n


WRAPPERS = ("atan2", "hypot", "_where", "_sort_last", "single_precision", "one_sided.<locals>.function")
"""connenv.jax.namespace's functions that only wrap one of jax.numpy's (for its derivative): a primitive they call
is counted to their caller."""


def _caller(eqn) -> str:
    """The function (and its file) whose line made the primitive eqn: the innermost frame of its traceback outside JAX
    and WRAPPERS (JAX's own source_info_util, private: "?" where it is missing or has changed)."""
    try:
        from jax._src import source_info_util

        frames = source_info_util.user_frames(eqn.source_info.traceback)
        frame = next((f for f in frames if not (f.file_name.endswith("connenv/jax/namespace.py")
                                                and f.function_name in WRAPPERS)), None)
    except (ImportError, AttributeError, TypeError):
        return "?"
    if frame is None:
        return "?"
    path = frame.file_name
    return f"{frame.function_name} ({path[path.rindex('connenv/'):] if 'connenv/' in path else path.rsplit('/', 1)[-1]})"


def bound_note(env_id: str, n: int) -> str:
    """What bounds env_id's rollout at N = n, measured in this run: the time of step_rows split into the next state
    (the physics' stepper and the task's state), the observation, reward and info, and the autoreset with the rest;
    and the transcendental primitives of the transition (counted in its jaxpr, each timed on n rows here), summed per
    function of connenv that calls them, the costliest three named."""
    import connenv.jax as cj

    env, params = cj.make(env_id, **cj.checked_kwargs(env_id))
    _, states = env.reset_rows(jax.random.key(0), n, params)
    A = jax.vmap(env.action_space(params).sample)(jax.random.split(jax.random.key(1), n))
    step = jax.jit(lambda key, states, A: env.step_rows(key, states, A, params))
    after = jax.jit(lambda X, A: env._advance_rows(X, A)[0])
    transition = jax.jit(lambda X, A: env._advance_rows(X, A))
    whole, physics, both = _least(lambda: jax.block_until_ready(step(jax.random.key(2), states, A)),
                                  lambda: after(states.x, A).block_until_ready(),
                                  lambda: jax.block_until_ready(transition(states.x, A)))
    task = max(0.0, both - physics)
    counts, loops = {}, []
    _tally(jax.make_jaxpr(lambda X, A: env._advance_rows(X, A))(states.x, A).jaxpr, n, 1.0, counts, loops)
    per_call = {name: primitive_time(name, n) for name in {name for name, _ in counts}}
    functions = {}
    for (name, where), calls in counts.items():
        cost, parts = functions.get(where, (0.0, {}))
        parts[name] = parts.get(name, 0.0) + calls
        functions[where] = (cost + calls * per_call[name], parts)
    total = sum(cost for cost, _ in functions.values())
    ranked = sorted(functions.items(), key=lambda item: -item[1][0])[:3]
    named = "; ".join(
        f"{where} {cost * 1e3:.2f} ms (" + ", ".join(f"{name} ×{calls:g}" for name, calls in
                                                    sorted(parts.items(), key=lambda p: -p[1] * per_call[p[0]])[:4]) + ")"
        for where, (cost, parts) in ranked)
    loop_text = (f" It runs {len(loops)} while loop(s) whose trip count is read off the rows "
                 f"({', '.join(sorted(set(loops)))}), counted once."
                 if loops else "")
    share = f"{total / both:.0%} of the transition's" if both > 0 else "the"
    return (f"Bound of {env_id.removeprefix('connenv/')} at N = {n}: step_rows takes {whole * 1e3:.2f} ms, of which "
            f"the next state (the stepper and the task's state) {physics * 1e3:.2f} ms, the observation, reward and "
            f"info {task * 1e3:.2f} ms, and the autoreset and the rest {max(0.0, whole - physics - task) * 1e3:.2f} ms. "
            f"Its transcendental functions and divisions come to ≈ {total * 1e3:.2f} ms ({share} time; counted in "
            f"its jaxpr, before XLA merges repeated ones, each timed on {n} rows in this run), the costliest by the "
            f"function that calls them: "
            f"{named}.{loop_text}")


GPU_COMMAND = ("python -m connenv.throughput --backend jax --sizes 4096 65536 1048576 --numpy-max 4096 --budget 420 "
               "--write docs/throughput-jax-gpu.md")
"""The benchmark on a GPU up to N = 2²⁰ (see the module): the numpy vector env beside it up to N = 4096 only (on the
host's CPU, where its rate does not depend on the GPU), and no new measurement started past 420 s, so that the run
ends within 8 minutes whatever the compile times; rows left out say so."""


def table(report, env_ids, sizes, misses: list, numpy_rate, numpy_max: int | None = None, budget: float | None = None):
    """The JAX table on connenv.throughput's Report: per id and N, the compile time, JAX's rate, the numpy vector
    env's (``numpy_rate(id, n)``, connenv.throughput's, passed in; up to N = numpy_max) and Pendulum's in the same run,
    and the ratio against its target; then, on the CPU, for each id that misses a target, what bounds it
    (`bound_note`, measured in the same run). budget: seconds after which no new (id, N) is measured (the rows left
    say so), for a run that must end in time (GPU_COMMAND)."""
    from connenv.envs.spec import spec

    jax.config.update("jax_enable_x64", True)  # the benchmark's own process: float64, as connenv.jax asks
    deadline = None if budget is None else time.perf_counter() + budget
    rows, missed = [], {}
    for env_id in env_ids:
        if not spec(env_id).jax:
            rows.append([env_id.removeprefix("connenv/"), "–", "no JAX version yet", "", "", "", ""])
            continue
        for n in sizes:
            if deadline is not None and time.perf_counter() > deadline:
                rows.append([env_id.removeprefix("connenv/"), str(n), "–", f"not run: past the {budget:g} s budget",
                             "", "", ""])
                misses.append(f"{env_id} at N = {n}: not run (past the budget)")
                continue
            try:
                compile_time, ours = rates(env_id, n)
            except Exception as error:  # noqa: BLE001  (a rollout that does not trace at this N is a row that says so)
                first = str(error).splitlines()[0][:120]
                rows.append([env_id.removeprefix("connenv/"), str(n), "–", f"failed: {type(error).__name__}: {first}",
                             "", "", ""])
                misses.append(f"{env_id} at N = {n}: the rollout failed ({type(error).__name__})")
                print(" | ".join(rows[-1]), flush=True)
                continue
            numpy = numpy_rate(env_id, n) if numpy_max is None or n <= numpy_max else None
            pendulum = pendulum_rate(n)
            ratio = None if numpy is None else ours / numpy
            target = TARGETS.get(n)
            cell = "–" if ratio is None else f"{ratio:.2f}×" + (
                "" if not target else " met" if ratio >= target else " MISSED")
            if target and ratio is not None and ratio < target:
                misses.append(f"{env_id} JAX/numpy at N = {n}: {ratio:.2f}× < {target}×")
                missed[env_id] = n if n == 4096 or env_id not in missed else missed[env_id]
            if compile_time > COMPILE_MAX:
                misses.append(f"{env_id} compile {compile_time:.1f} s > {COMPILE_MAX} s")
            rows.append([env_id.removeprefix("connenv/"), str(n), f"{compile_time:.1f}", f"{ours / 1e6:.3g}",
                         "–" if numpy is None else f"{numpy / 1e6:.3g}", "–" if pendulum is None else f"{pendulum / 1e6:.3g}",
                         cell])
            print(" | ".join(rows[-1]), flush=True)
    report.table(
        f"JAX: jit + vmap + lax.scan rollouts of {ROLLOUT} steps, random actions, autoresets (float64)",
        ["env", "N", "compile s", "JAX M steps/s", "numpy vector M steps/s", "phys2d Pendulum (JAX, float32) M steps/s",
         "JAX / numpy"],
        rows,
    )
    on_cpu = jax.default_backend() == "cpu"
    if missed and on_cpu:
        report.note("What bounds each id that misses a target, measured in the same run at the N named (at N = 4096 "
                    "where it misses there): medians of jitted calls on that machine, which move with its load as the "
                    "rates above do; their split and the functions named are what to read.")
        for env_id, n in missed.items():
            report.note(bound_note(env_id, n))
    report.note(f"JAX backend: {jax.default_backend()} ({jax.devices()[0].device_kind}). " + (
        f"Not measured on a GPU yet: on one, `{GPU_COMMAND}` runs the same benchmark up to N = 2²⁰ within 8 minutes "
        "(the numpy vector env beside it up to N = 4096; no new measurement past 420 s)." if on_cpu else ""))
