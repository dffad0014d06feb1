"""Refactors keep behaviour: every registered id replays its golden trajectories (tests/golden), to the bit on the
platform they were recorded on, to RTOL elsewhere (see tests/golden/record.py)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest
from golden.record import CASES, PATH, fingerprint, runs

RECORDED = json.loads(PATH.read_text())
RTOL = 1e-12
"""Tolerance on a projection, relative to the array's Σ|x|. Another kernel rounds an operation's last bit (1.1e-16)
differently; along an episode of a few hundred steps, and through an adaptive stepper's step choices, such
roundings grow by up to a few hundred times, which stays within 1e-12 (test_other_kernels_replay_the_recorded_
trajectories checks it on another platform's kernels). Any change of model, stepper, tolerance or task moves a projection by
orders of magnitude more."""
FLOOR = 1.0
"""Σ|x| below which an array is compared absolutely, to RTOL · FLOOR: a quantity that is all roundoff (the drift of
a conserved quantity under an exact step) has no relative precision, and states and rewards are of order one in SI."""
KERNELS = {
    "openblas-haswell+numpy-baseline": {
        "OPENBLAS_CORETYPE": "Haswell",
        "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX2 FMA3 AVX512F AVX512_SKX AVX512_ICL AVX512_SPR",
    },
}
"""Another floating-point platform an x86-64 machine can play: OpenBLAS's kernel for a Haswell-class CPU (as on an
AMD EPYC) and numpy's baseline kernels (AVX2 and AVX-512 dispatch turned off, as on an older CPU), both at once: each
rounds its operations' last bits otherwise, and their differences add up along a trajectory."""

x86 = pytest.mark.skipif(platform.machine() != "x86_64", reason="the kernels named are x86-64's")


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_trajectories_match_the_recorded_ones(case):
    recorded = {key: value for key, value in RECORDED["arrays"].items() if key.startswith(case[0] + "/")}
    assert_matches(runs([case]), recorded, fingerprint())


@x86
@pytest.mark.parametrize("kernels", KERNELS.values(), ids=KERNELS.keys())
def test_other_kernels_replay_the_recorded_trajectories(kernels):
    """The replay under another kernel: to the bit where that kernel is the recording's, else within RTOL."""
    platform, replayed = run_with(kernels, "[fingerprint(), runs()]")
    assert_matches(replayed, RECORDED["arrays"], platform)


@x86
def test_the_fingerprint_sees_the_blas_kernel():
    """Two OpenBLAS kernels that every x86-64 CPU of ours runs round differently, so they are two platforms."""
    assert run_with({"OPENBLAS_CORETYPE": "Haswell"}, "fingerprint()") != run_with(
        {"OPENBLAS_CORETYPE": "Prescott"}, "fingerprint()"
    )


def run_with(variables, expression):
    """An expression of golden.record's, evaluated in a fresh interpreter with these environment variables."""
    code = f"import json; from golden.record import fingerprint, runs; print(json.dumps({expression}))"
    tests = Path(__file__).parent
    path = [str(tests), str(tests.parent), os.environ.get("PYTHONPATH", "")]  # this checkout's connenv, not another's
    env = {**os.environ, **variables, "PYTHONPATH": os.pathsep.join(path)}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True, cwd=tests)
    return json.loads(out.stdout.splitlines()[-1])


def assert_matches(replayed, recorded, platform):
    assert replayed.keys() == recorded.keys()
    if platform == RECORDED["fingerprint"]:
        moved = sorted(key for key in recorded if replayed[key][0] != recorded[key][0])
        assert not moved, f"{len(moved)} of {len(recorded)} arrays differ from the golden ones: {moved[:10]}"
    moved = sorted(key for key in recorded if not within(replayed[key], recorded[key]))
    assert not moved, f"{len(moved)} of {len(recorded)} arrays differ beyond {RTOL}: {moved[:10]}"


def within(replayed, recorded):
    """Both value projections within RTOL · max(Σ|x|, FLOOR) of the recording's ([digest, Σx, Σx·w, Σ|x|])."""
    scale = RTOL * max(recorded[3], FLOOR)
    return abs(replayed[1] - recorded[1]) <= scale and abs(replayed[2] - recorded[2]) <= scale
