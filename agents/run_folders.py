"""A run folder holds one run: what train.py (both backends) decides about a folder before training into it."""

from __future__ import annotations

import itertools
import time
from pathlib import Path


def latest_checkpoint(run: Path) -> int | None:
    """The steps of the run folder's last completed checkpoint, or None."""
    latest = run / "checkpoints" / "latest"
    return int(latest.read_text()) if latest.is_file() else None


def holds_run(run: Path) -> bool:
    """Whether the folder holds a run: rl-zoo3 writes {env}/config.yml before any model, evaluation or checkpoint."""
    return any(run.glob("*/config.yml"))


def move_aside(run: Path) -> Path:
    """Rename the run folder to {run}.{date-time} (with a counter if that is taken); return the new path."""
    name = f"{run.name}.{time.strftime('%Y%m%d-%H%M%S')}"
    aside = run.with_name(name)
    for n in itertools.count(1):
        if not aside.exists():
            return run.rename(aside)
        aside = run.with_name(f"{name}-{n}")


def claim_run_folder(run: Path, resume: bool, overwrite: bool) -> int | None:
    """The step to resume from, or None to train from step 0, once the run folder is free for this run: an earlier
    run in it is continued from its last checkpoint with `resume`, moved aside with `overwrite` and refused without
    either. Raises FileExistsError naming the folder and the ways out."""
    steps = latest_checkpoint(run)
    if not holds_run(run) or (resume and steps is not None):
        if resume and steps is None:
            print(f"{run}: no checkpoint to resume from, training from step 0")
        return steps if resume else None
    if overwrite:
        print(f"{run} held a run: moved aside to {move_aside(run)}")
        return None
    aside = f"--overwrite moves it aside to {run}.<date-time> and trains anew"
    if steps is None:
        raise FileExistsError(f"{run} holds a run with no checkpoint to resume from: {aside}")
    raise FileExistsError(f"{run} holds a run: --resume continues it from its checkpoint at step {steps}, {aside}")
