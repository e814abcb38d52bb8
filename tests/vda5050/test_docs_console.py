"""The console example in docs/vda5050.md shows only what a paced run repeats: tests/docs runs it on a
machine that may be loaded, where the wall clock paces the run otherwise. Its expected output must match
the summary table (as fleetsim prints it) whatever the paced figures are: makespan, clearance, hash and
realtime factor, as seen on an idle machine and on a loaded one."""

from __future__ import annotations

import shlex

import pytest
from runs import ROOT

from fleetsim.sim.report import format_table
from tests.docs.examples import blocks, commands, normalise, output_pattern

DOCS = ROOT / "docs" / "vda5050.md"
TASKS = {"crossing": "2/2", "loop-one-way": "4/4", "corridor-passing-bay": "2/2", "mixed-shapes": "3/3"}
# Per scenario (in TASKS' order): makespan, clearance, hash, realtime factor.
IDLE = [
    ("27.1 s", "> 2 m", "37c10e321aa1", "20x"),
    ("66.1 s", "> 2 m", "335bc20861e6", "20x"),
    ("42.5 s", "1.40 m", "12506216791b", "20x"),
    ("40.7 s", "> 2 m", "aacc162d3786", "20x"),
]
LOADED = [  # the corridor's clearance and the factors from a run beside the rest of the test suite
    ("27.1 s", "> 2 m", "8f0d2ab31c55", "11x"),
    ("66.3 s", "> 2 m", "0b9e4475d2a0", "15x"),
    ("42.6 s", "1.33 m", "f3c1e0a9b8d7", "13x"),
    ("40.9 s", "> 2 m", "61d2c09be4a3", "13x"),
]
CRAWLING = [
    ("31.4 s", "1.92 m", "5e5e9a0c1d2b", "3x"),
    ("104.9 s", "1.75 m", "a0b1c2d3e4f5", "2x"),
    ("48.0 s", "0.98 m", "0f1e2d3c4b5a", "4x"),
    ("44.2 s", "12.50 m", "99aa88bb77cc", "9x"),
]


@pytest.mark.parametrize("paced", [IDLE, LOADED, CRAWLING], ids=["idle", "loaded", "crawling"])
def test_the_console_example_matches_whatever_the_wall_clock_paced(paced: list[tuple[str, str, str, str]]) -> None:
    [block] = [b for b in blocks(DOCS.read_text(encoding="utf-8")) if b.lang == "console" and "vda5050:" in b.text]
    [(command, expected)] = list(commands(block))
    words = shlex.split(command)
    planner = words[words.index("--planner") + 1]
    rows = [
        (name, "passed", tasks, makespan, "0", "0", clearance, "0", "0", trace_hash, factor)
        for (name, tasks), (makespan, clearance, trace_hash, factor) in zip(TASKS.items(), paced, strict=True)
    ]
    output = "\n".join(
        [
            "fleetsim: 2 VDA 5050 2.0 vehicles on mqtt://127.0.0.1:41234 (topics uagv/v2/fleetsim/<serialNumber>/...)",
            "[1/4] crossing: passed (tasks 2/2, t=27.1 s)",
            *format_table(rows),
            "",
            f"4 scenario(s) with {planner}: 4 passed",
        ]
    )
    assert output_pattern(normalise(expected)).fullmatch(normalise(output)), output
