"""Benchmarks of the steppers: speed against accuracy, and where methods fail. Not run in CI (the tests run a
smoke version of each); every figure the README or docs/ quote is printed by one of these commands.

    python -m connenv.bench all [--env NAME ...] [--quick]         the next two, then page
    python -m connenv.bench page                                   docs/speed-accuracy.md from the charts' CSVs
    python -m connenv.bench precision [--env NAME ...] [--quick]   work–precision charts, docs/precision/
    python -m connenv.bench stability [--env NAME ...] [--quick]   stability maps, docs/precision/
    python -m connenv.bench steppers [--env swing|skier|ball]      the energy-drift table that chose the defaults
    python -m connenv.bench generic [--quick]                      ActiveConstraintEnv's steppers on two Lagrangians
    python -m connenv.bench import [--runs N]                      the median time of `import connenv`
    python -m connenv.bench [--env swing|skier|ball]               the same (the command the older docs quote)
    python -m connenv.bench [--help]                               the list of commands

Times are medians of env.step on unwrapped envs, each step timed right after a step of Gymnasium's Pendulum-v1
in the same process; the ratio of the two medians is the figure to read on a shared machine.
"""

from __future__ import annotations

import argparse
import sys

from connenv import cli
from connenv.bench.common import bench_spec

PROG = "python -m connenv.bench"

COMMANDS = {
    "all": "precision, then stability, then page: every chart in docs/precision/ and docs/speed-accuracy.md",
    "page": "docs/speed-accuracy.md, generated from the charts' CSVs",
    "precision": "work-precision charts of every env's steppers, docs/precision/",
    "stability": "stability maps of the explicit steppers, docs/precision/",
    "steppers": "the energy-drift table that chose the defaults (also with no command and --env)",
    "generic": f"{bench_spec('generic').name}'s steppers on two Lagrangians",
    "import": "the median time of `import connenv` in fresh interpreters (python -X importtime)",
}


def parser() -> argparse.ArgumentParser:
    """The top-level command line: the subcommands with their descriptions; each parses its own options."""
    top = cli.ArgumentParser(
        prog=PROG,
        description=__doc__.split(". ")[0] + ".",
        formatter_class=lambda prog: argparse.HelpFormatter(prog, width=120),
    )
    commands = top.add_subparsers(dest="command", metavar="COMMAND", title="commands (COMMAND --help: its options)")
    for name, description in COMMANDS.items():
        commands.add_parser(name, help=description, add_help=False)
    return top


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        parser().print_help()
        return
    if argv[0].startswith("-") and argv[0] not in ("-h", "--help"):
        argv.insert(0, "steppers")  # the older form: python -m connenv.bench --env NAME
    args, argv = parser().parse_known_args(argv)
    if args.command == "all":
        from connenv.bench import page, precision, stability

        for command in (precision, stability):  # both take argv: check it before either runs
            command.parse_args(argv)
        precision.main(argv)
        stability.main(argv)
        page.main([])
        return
    if args.command == "precision":
        from connenv.bench.precision import main as run
    elif args.command == "stability":
        from connenv.bench.stability import main as run
    elif args.command == "page":
        from connenv.bench.page import main as run
    elif args.command == "generic":
        from connenv.bench.generic import main as run
    elif args.command == "import":
        from connenv.bench.import_time import main as run
    else:
        from connenv.bench.steppers import main as run
    run(argv)
