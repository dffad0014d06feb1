"""Golden trajectories: every registered id, single and native vector env, on seeded random actions with resets.

``python tests/golden/record.py`` writes tests/golden/trajectories.json: for every recorded array, the SHA-256 of
its float64 bytes and shape, and three projections (the sum, a sum with fixed weights cos(1 + i), the sum of
absolute values), so that a refactor can be checked without keeping megabytes of numbers; and the fingerprint of
the floating-point platform it was recorded on. tests/test_golden.py replays the same runs and names every array
that moved. Re-record only on a change of behaviour that is meant, and say which trajectory changed and why.

The bits depend on the platform as well as the code: numpy picks its SIMD kernels for sin, exp, … by CPU (AVX2,
AVX-512, …), OpenBLAS picks its matrix kernels by CPU (Haswell, SkylakeX, …), and they round the last bit
differently. On the recording's platform (same fingerprint) the test compares digests, to the bit; elsewhere it
compares projections to a tolerance that such roundings, grown along an episode and through an adaptive stepper's
step choices, stay within.
"""

from __future__ import annotations

import hashlib
import json
import platform
from pathlib import Path

import gymnasium as gym
import numpy as np
import threadpoolctl

import connenv  # noqa: F401  (registers the envs)
from connenv.envs.spec import registry

PATH = Path(__file__).with_name("trajectories.json")
SEEDS = (0, 1)
STEPS = 300
ROWS = 3

CASES = [(name, spec.id, kwargs, options) for spec in registry.values() for name, kwargs, options in spec.golden]
"""(name, id, make kwargs, reset options) of each spec's golden cases: short episodes, so that a run holds
terminations and resets."""

def flatten(value, prefix, out):
    """{dotted key: float array} of an observation or info, strings and masks left out."""
    if isinstance(value, dict):
        for key, item in value.items():
            if not str(key).startswith("_"):
                flatten(item, f"{prefix}.{key}", out)
        return
    array = np.asarray(value)
    if array.dtype.kind in "biuf":
        out.setdefault(prefix, []).append(array.astype(np.float64))


def split(kwargs):
    kwargs = dict(kwargs)
    return kwargs.pop("max_episode_steps"), kwargs


def rollout(env, seed, options, reset_at_end):
    """STEPS uniform random actions from reset(seed, options); with reset_at_end, a reset (with options) whenever an
    episode ends (a vector env resets its rows itself)."""
    actions = np.random.default_rng(seed).uniform(-1, 1, (STEPS, *env.action_space.shape)).astype(np.float32)
    out = {}
    obs, info = env.reset(seed=seed, options=options)
    flatten({"obs": obs, "info": info}, "reset", out)
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        flatten({"obs": obs, "reward": reward, "flags": [terminated, truncated], "info": info}, "step", out)
        if reset_at_end and (terminated or truncated):
            obs, info = env.reset(options=options)
            flatten({"obs": obs, "info": info}, "reset", out)
    return out


def single_run(env_id, kwargs, options, seed):
    """The rollout of gym.make(id). The time limit is Gymnasium's own TimeLimit: rl_zoo3, once imported (by other
    tests), replaces gym.make's by one that adds an info key and reports no truncation on a step that also
    terminates."""
    limit, kwargs = split(kwargs)
    time_limit = next(c for c in gym.wrappers.TimeLimit.__mro__ if c.__module__.startswith("gymnasium"))
    return rollout(time_limit(gym.make(env_id, **kwargs).unwrapped, limit), seed, options, True)


def vector_run(env_id, kwargs, options, seed):
    """The rollout of the native vector env of ROWS rows, autoresets included."""
    limit, kwargs = split(kwargs)
    env = gym.make_vec(env_id, ROWS, vectorization_mode="vector_entry_point", max_episode_steps=limit, **kwargs)
    return rollout(env, seed, options, False)


def digest(array):
    array = np.ascontiguousarray(array, np.float64)
    return hashlib.sha256(repr(array.shape).encode() + array.tobytes()).hexdigest()


def projections(array):
    """(Σx, Σ x_i cos(1 + i), Σ|x|) over the flattened array: the first two move with any change of value or order,
    the third scales the tolerance."""
    x = np.ravel(np.asarray(array, np.float64))
    return [float(x.sum()), float(x @ np.cos(1.0 + np.arange(x.size))), float(np.abs(x).sum())]


def fingerprint():
    """The floating-point platform: what decides the last bits of a run. numpy's SIMD kernel per function (as
    dispatched now, so NPY_DISABLE_CPU_FEATURES counts), each loaded BLAS library's kernel (OpenBLAS picks one per
    CPU, and OPENBLAS_CORETYPE overrides it; seen through threadpoolctl), libc (libm), numpy and scipy. The CPU's
    model name is left out: two CPUs that dispatch the same kernels give the same bits."""
    import scipy.linalg  # noqa: F401  (loads scipy's BLAS, so that threadpoolctl sees it)

    umath = np._core._multiarray_umath
    targets = getattr(umath, "__cpu_targets_info__", None)
    if targets is None:  # numpy < 2.4: the features numpy dispatches on
        simd = sorted(k for k, v in umath.__cpu_features__.items() if v)
    else:
        simd = sorted({info["current"] for loops in targets.values() for info in loops.values()})
    blas = sorted(
        f"{lib['internal_api']} {lib['version']} {lib.get('architecture')}"
        for lib in threadpoolctl.threadpool_info()
        if lib["user_api"] == "blas"
    )
    return " | ".join(
        [platform.machine(), " ".join(simd), "; ".join(blas), "-".join(platform.libc_ver()), np.__version__, scipy.__version__]
    )


def runs(cases=CASES):
    """{case/mode/seed/key: [digest, *projections]} of every run of the cases."""
    arrays = {}
    for name, env_id, kwargs, options in cases:
        for seed in SEEDS:
            for mode, run in (("single", single_run), ("vector", vector_run)):
                for key, values in run(env_id, kwargs, options, seed).items():
                    array = np.stack(values)
                    arrays[f"{name}/{mode}/{seed}/{key}"] = [digest(array), *projections(array)]
    return arrays


if __name__ == "__main__":
    arrays = runs()
    PATH.write_text(json.dumps({"fingerprint": fingerprint(), "arrays": arrays}, indent=0, sort_keys=True) + "\n")
    print(f"{len(arrays)} arrays -> {PATH}")
