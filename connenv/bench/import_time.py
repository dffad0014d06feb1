"""How long ``import connenv`` takes: fresh interpreters run ``python -X importtime -c "import connenv"``, and the
median of their cumulative times (connenv's own line, and its heaviest imports) is printed beside the median of
``import gymnasium`` alone, the floor that registering with Gymnasium costs. Run it on a quiet machine:

    python -m connenv.bench import [--runs N] [--module NAME]
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys

from connenv import cli


def parse_args(argv=None):
    parser = cli.ArgumentParser(prog="python -m connenv.bench import", description=__doc__.split(":")[0] + ".")
    parser.add_argument("--runs", type=cli.positive_int, default=15, help="fresh interpreters per module (15)")
    parser.add_argument("--module", default="connenv", help="the module to time (connenv)")
    parser.add_argument("--top", type=cli.positive_int, default=5, help="heaviest top-level imports listed (5)")
    return parser.parse_args(argv)


def parse(line: str) -> tuple[str, float]:
    _, total_us, name = line.removeprefix("import time:").split("|")
    return name.strip(), int(total_us) * 1e-6


def one_run(module: str) -> dict[str, float]:
    """{imported module: cumulative import time (s)} of a fresh interpreter importing module."""
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", f"import {module}"], capture_output=True, text=True)
    if done.returncode:
        raise ValueError(f"--module {module!r}: import {module} fails: {cli.one_line(done.stderr.splitlines()[-1])}")
    seen = {}
    for line in done.stderr.splitlines():
        if line.startswith("import time:") and "cumulative" not in line:
            name, total = parse(line)
            seen.setdefault(name, total)  # the first line of a name is its import
    return seen


def medians(modules: tuple[str, ...], runs: int) -> list[dict[str, float]]:
    """For each module, {imported module: median of its cumulative import time (s)} over runs fresh interpreters,
    the modules' runs taking turns (a load that comes and goes weighs on each alike)."""
    samples: list[dict[str, list[float]]] = [{} for _ in modules]
    for _ in range(runs):
        for module, found in zip(modules, samples):
            for name, total in one_run(module).items():
                found.setdefault(name, []).append(total)
    return [{name: statistics.median(values + [0.0] * (runs - len(values))) for name, values in found.items()}
            for found in samples]  # fmt: skip


def main(argv=None):
    args = parse_args(argv)
    if not re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*", args.module):
        raise ValueError(f"--module {args.module!r} is no module name (valid: a dotted name, connenv.geometry)")
    found, floor = medians((args.module, "gymnasium"), args.runs)
    floor = floor["gymnasium"]
    print(f"import {args.module}: median {found[args.module] * 1e3:.0f} ms over {args.runs} fresh interpreters "
          f"(import gymnasium alone: {floor * 1e3:.0f} ms)")  # fmt: skip
    shown = [n for n in found if n != args.module and ("." not in n or n.startswith("scipy.") and n.count(".") == 1)]
    heaviest = sorted(((found[n], n) for n in shown), reverse=True)  # top-level packages, and scipy's sub-packages
    for total, name in heaviest[: args.top]:
        print(f"  {name:<40} {total * 1e3:7.0f} ms")
    for heavy in ("scipy", "sympy", "jax", "torch", "agents"):
        if heavy in found:
            print(f"  imports {heavy}")


if __name__ == "__main__":
    cli.run(main, "python -m connenv.bench import")
