"""Refactors keep behaviour: every registered id replays its golden trajectories (tests/golden), to the bit on the
platform they were recorded on, to RTOL elsewhere (see tests/golden/record.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from golden.record import CASES, PATH, fingerprint, runs

RECORDED = json.loads(PATH.read_text())
RTOL = 1e-9
"""Tolerance on a projection, relative to the array's Σ|x|: far above the last-bit roundings of other SIMD kernels
(test_other_kernels_stay_within_the_tolerance), far below any change of model, stepper or task."""
FLOOR = 1e-3
"""Σ|x| below which an array is compared to RTOL · FLOOR: a quantity that is all roundoff (the drift of a conserved
quantity under an exact step) has no relative precision."""
BASELINE_KERNELS = {"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX2 FMA3 AVX512F AVX512_SKX AVX512_ICL AVX512_SPR"}


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_trajectories_match_the_recorded_ones(case):
    recorded = {key: value for key, value in RECORDED["arrays"].items() if key.startswith(case[0] + "/")}
    replayed = runs([case])
    assert replayed.keys() == recorded.keys()
    if fingerprint() == RECORDED["fingerprint"]:
        moved = sorted(key for key in recorded if replayed[key][0] != recorded[key][0])
        assert not moved, f"{len(moved)} of {len(recorded)} arrays differ from the golden ones: {moved[:10]}"
    moved = sorted(key for key in recorded if not within(replayed[key], recorded[key]))
    assert not moved, f"{len(moved)} of {len(recorded)} arrays differ beyond {RTOL}: {moved[:10]}"


def test_other_kernels_stay_within_the_tolerance():
    """numpy's baseline kernels (AVX2 and AVX-512 dispatch turned off, as on an older CPU) round differently, yet
    every projection of every case stays within RTOL of the recording."""
    code = "import json; from golden.record import runs; print(json.dumps(runs()))"
    tests = Path(__file__).parent
    env = {**os.environ, **BASELINE_KERNELS, "PYTHONPATH": str(tests)}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True, cwd=tests)
    replayed = json.loads(out.stdout.splitlines()[-1])
    assert replayed.keys() == RECORDED["arrays"].keys()
    moved = sorted(key for key, value in RECORDED["arrays"].items() if not within(replayed[key], value))
    assert not moved, f"{len(moved)} arrays differ beyond {RTOL} under the baseline kernels: {moved[:10]}"


def within(replayed, recorded):
    """Both value projections within RTOL · max(Σ|x|, FLOOR) of the recording's ([digest, Σx, Σx·w, Σ|x|])."""
    scale = RTOL * max(recorded[3], FLOOR)
    return abs(replayed[1] - recorded[1]) <= scale and abs(replayed[2] - recorded[2]) <= scale
