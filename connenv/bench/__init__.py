"""Benchmarks of the steppers: speed against accuracy, and where methods fail. Not run in CI (the tests run a
smoke version of each); every figure the README or docs/ quote is printed by one of these commands.

    python -m connenv.bench all [--env NAME ...] [--quick]         both of the next two: every chart in docs/precision/
    python -m connenv.bench precision [--env NAME ...] [--quick]   work–precision charts, docs/precision/
    python -m connenv.bench stability [--env NAME ...] [--quick]   stability maps, docs/precision/
    python -m connenv.bench steppers [--env swing|skier|ball]      the energy-drift table that chose the defaults
    python -m connenv.bench generic [--quick]                      ActiveConstraint-v0's steppers on two Lagrangians
    python -m connenv.bench [--env swing|skier|ball]               the same (the command the older docs quote)

Times are medians of env.step on unwrapped envs, each step timed right after a step of Gymnasium's Pendulum-v1
in the same process; the ratio of the two medians is the figure to read on a shared machine.
"""

from __future__ import annotations

import sys

COMMANDS = ("all", "precision", "stability", "steppers", "generic")


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    command = argv.pop(0) if argv and argv[0] in COMMANDS else "steppers"
    if command == "all":
        from connenv.bench import precision, stability

        precision.main(argv)
        stability.main(argv)
        return
    if command == "precision":
        from connenv.bench.precision import main as run
    elif command == "stability":
        from connenv.bench.stability import main as run
    elif command == "generic":
        from connenv.bench.generic import main as run
    else:
        from connenv.bench.steppers import main as run
    run(argv)
