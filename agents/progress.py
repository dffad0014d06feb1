"""Progress of a long evaluation on stderr, as training shows it: done of total, elapsed time and the estimated time
left, by tqdm (the library of SB3's bar in train.py), so that a run of minutes is never silent."""

from __future__ import annotations

import sys
from collections.abc import Iterable


def progress(iterable: Iterable, total: int, unit: str, desc: str | None = None):
    """iterable, with a bar on stderr: ``desc: 3/10 episodes [00:41<01:36]`` (elapsed < left), gone when done."""
    from tqdm import tqdm

    return tqdm(iterable, total=total, unit=f" {unit}", desc=desc, file=sys.stderr, leave=False, dynamic_ncols=True)
