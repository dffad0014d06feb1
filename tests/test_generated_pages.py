"""The generated docs pages: docs/speed-accuracy.md from the charts' CSVs, docs/throughput.md from the throughput
tables. Both are written by the commands that measured their figures; these tests check what the writers make of
given numbers, not timings."""

from __future__ import annotations

import csv

from connenv.bench.common import OUTPUT
from connenv.bench.page import page
from connenv.throughput import Report, verdict

PRECISION_HEADER = [
    "integrator", "options", "us_per_step", "ratio_to_pendulum", "state_error_x₀=1 (m)", "drift (max |E − E(0)|)",
    "pareto", "default", "diverged",
]  # fmt: skip


def write_chart(folder, name, rows):
    with open(folder / f"{name}_precision.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(PRECISION_HEADER)
        writer.writerows(rows)


def test_every_committed_chart_has_a_section_with_its_default_stepper():
    text = page(OUTPUT)
    charts = sorted(OUTPUT.glob("*_precision.csv"))
    maps = sorted(OUTPUT.glob("*_stability.csv"))
    assert len(charts) >= 16 and len(maps) >= 14
    for path in charts:
        name = path.name.removesuffix("_precision.csv")
        section = text.split(f"### {name}\n", 1)[1].split("\n### ", 1)[0]
        assert section.count("(default)") == 1, name
        assert f"precision/{name}_precision.png" in section
    for path in maps:
        assert f"precision/{path.name.removesuffix('.csv')}.png" in text


def test_a_default_off_the_front_is_flagged_and_the_front_listed_in_order_of_cost(tmp_path):
    write_chart(
        tmp_path,
        "toy",
        [
            ["rk4", "rk4 ×1", "10.0", "1.0", "1e-3", "1e-4", "True", "False", ""],
            ["dop853", "dop853 rtol 1e-08", "30.0", "3.0", "1e-3", "1e-6", "False", "True", ""],
            ["exact", "exact", "20.0", "2.0", "0.0", "1e-15", "True", "False", ""],
            ["euler", "euler ×1", "5.0", "0.5", "inf", "inf", "False", "False", "diverged at t = 1 s"],
        ],
    )
    text = page(tmp_path)
    lines = [line for line in text.splitlines() if line.startswith("| ")][1:]
    assert lines[0].startswith("| **dop853 rtol 1e-08** (default)") and lines[0].endswith("| **off** |")
    assert [line.split(" | ")[0] for line in lines[1:]] == ["| rk4 ×1", "| exact"]
    assert "max \\|E − E(0)\\|" in text  # a "|" inside a cell would split the table
    assert "Diverged (StepperError): euler ×1." in text


def test_the_throughput_verdicts_compare_with_the_targets():
    assert verdict(1.4, 1.5, at_most=True) == "met" and verdict(1.6, 1.5, at_most=True) == "MISSED"
    assert verdict(0.36, 0.35, at_most=False) == "met" and verdict(0.1, 0.35, at_most=False) == "MISSED"
    assert verdict(9.9, None, at_most=True) == ""


def test_the_throughput_page_holds_a_row_per_env_and_the_command(capsys):
    report = Report("machine line")
    report.table("Single env", ["env", "× Pendulum"], [["connenv/Swing-v0", "2.19"], ["connenv/Skier-v0", "7.30"]])
    report.note("Targets missed: none.")
    text = report.markdown("python -m connenv.throughput --envs connenv/Swing-v0 connenv/Skier-v0")
    assert text.startswith("# Throughput\n") and "`python -m connenv.throughput --envs connenv/Swing-v0" in text
    assert "| connenv/Swing-v0 | 2.19 |" in text and "| connenv/Skier-v0 | 7.30 |" in text
    assert "|---|---|" in text and "machine line" in text
    assert "connenv/Skier-v0" in capsys.readouterr().out
