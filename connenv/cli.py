"""What every command line of the repository shares: bad input ends a command in one line, ``PROG: error: MESSAGE``
on stderr with exit status 2, and the argparse types that check the common arguments.

argparse prints its usage above a usage error; ``ArgumentParser`` prints the error line alone (``--help`` prints the
usage). ``run`` calls a command's ``main(argv)`` and turns the errors of bad input that only the command's work finds
(a file that is no model, kwargs an env refuses, an address nothing answers at: ValueError, TypeError, OSError,
StepperError) into the same line, so that a user meets one line, not a traceback, and a calling script an exit
status. Other exceptions are bugs and keep their traceback.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path

from connenv.core.steppers import StepperError

INPUT_ERRORS = (ValueError, TypeError, OSError, StepperError)
"""The exceptions that bad input raises once parsing is done; ``run`` reports them in one line."""
SEED_MAX = 2**32 - 1  # numpy's global seed, which SB3's set_random_seed sets, takes at most this


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser whose usage errors are one line, ``PROG: error: MESSAGE``, exit status 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")


def one_line(message: str) -> str:
    return " ".join(str(message).split())


def run(main: Callable, prog: str, argv: list[str] | None = None):
    """main(argv), its INPUT_ERRORS reported as ``prog: error: message`` on stderr and exit status 2."""
    try:
        return main(argv)
    except INPUT_ERRORS as error:
        sys.stderr.write(f"{prog}: error: {one_line(error)}\n")
        raise SystemExit(2) from error


def parsed(text: str, convert, valid, expected: str):
    """convert(text) if it converts and is valid, else argparse's error saying what was expected."""
    try:
        value = convert(text)
    except ValueError:
        value = None
    if value is None or not valid(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not {expected}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer > 0, also written as 1e5."""
    value = parsed(text, float, lambda v: v > 0 and v.is_integer(), "a positive integer (valid: 1, 2, ...)")
    return int(value)


def non_negative_int(text: str) -> int:
    """argparse type: an integer ≥ 0."""
    return parsed(text, int, lambda v: v >= 0, "an integer ≥ 0 (valid: 0, 1, 2, ...)")


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    return parsed(text, float, lambda v: 0 < v < math.inf, "a finite number > 0")


def seed_int(text: str) -> int:
    """argparse type: a seed, an integer in [0, 2³² − 1]."""
    return parsed(text, int, lambda v: 0 <= v <= SEED_MAX, f"a seed (valid: an integer in [0, {SEED_MAX}])")


def unwritable(path: Path, directory: bool) -> str | None:
    """Why path cannot be written as a file (directory: created as a folder) with its missing parents, or None:
    checked before the work whose results it holds."""
    if path.exists() and path.is_dir() != directory:
        return f"is {'a file' if directory else 'a directory'}"
    existing = next(parent for parent in (path, *path.parents) if parent.exists())
    if not existing.is_dir():
        return f"cannot be created: {str(existing)!r} is a file"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot be written: {str(existing)!r} is not writable"
    return None


def writable_file(text: str) -> str:
    """argparse type: a file path that can be written (its missing folders created)."""
    if reason := unwritable(Path(text), directory=False):
        raise argparse.ArgumentTypeError(f"{text!r} {reason}")
    return text


def writable_dir(text: str) -> str:
    """argparse type: a folder that exists or can be created, and can be written."""
    if reason := unwritable(Path(text), directory=True):
        raise argparse.ArgumentTypeError(f"{text!r} {reason}")
    return text
