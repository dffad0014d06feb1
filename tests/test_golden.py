"""Refactors keep behaviour to the bit: every registered id replays its golden trajectories (tests/golden)."""

from __future__ import annotations

import json

import pytest
from golden.record import CASES, PATH, runs


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_trajectories_are_identical_to_the_recorded_ones(case):
    recorded = {key: value for key, value in json.loads(PATH.read_text()).items() if key.startswith(case[0] + "/")}
    replayed = runs([case])
    assert replayed.keys() == recorded.keys()
    moved = sorted(key for key in recorded if replayed[key] != recorded[key])
    assert not moved, f"{len(moved)} of {len(recorded)} arrays differ from the golden ones: {moved[:10]}"
