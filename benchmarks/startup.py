"""What installing fleetsim costs every pytest session, and what pytest adds to running one scenario.

    python benchmarks/startup.py [--rounds 10]

1. A project of one plain test and no fleetsim suite is run with pytest, alternately with the plugin
   loaded (as in any environment where fleetsim is installed) and with ``-p no:fleetsim``.
2. One shipped scenario (the examples' ``crossing``, copied into a scratch project with its folder) is run
   with ``pytest FILE::crossing --planner P`` and with ``fleetsim run FILE::crossing --planner P``, in
   turn, with Python writing its bytecode caches and again with ``PYTHONDONTWRITEBYTECODE=1`` (common in
   CI containers; pytest then rewrites the assertions of every module it is asked to on every start).
   Each setting is timed once more with ``-p no:hypothesispytest``, Hypothesis's own pytest plugin, which
   imports Hypothesis in every session where it is installed, whether fleetsim is there or not.

Commands of one comparison alternate, so that both see the same moments of a noisy machine; each figure
is the median of the paired differences. ``fleetsim --help`` and ``fleetsim --version`` are timed the same
number of times (medians).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

SUITES = Path(__file__).resolve().parents[1] / "scenario_suites"
PLANNER = "fleetsim.planners:ReservingPlanner"
MS = 1000.0


def _seconds(command: Sequence[str], cwd: Path, env: Mapping[str, str] | None = None) -> float:
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def _paired(
    rounds: int, a: Sequence[str], b: Sequence[str], cwd: Path, env: Mapping[str, str] | None = None
) -> tuple[float, float, float]:
    """Medians of A, of B and of the paired differences A - B, A and B run in turn."""
    _seconds(a, cwd, env)  # warm the caches once (and, with bytecode caches on, write them)
    _seconds(b, cwd, env)
    times_a, times_b = [], []
    for _ in range(rounds):
        times_a.append(_seconds(a, cwd, env))
        times_b.append(_seconds(b, cwd, env))
    added = [x - y for x, y in zip(times_a, times_b, strict=True)]
    return statistics.median(times_a), statistics.median(times_b), statistics.median(added)


def _scenario_project(root: Path) -> str:
    """The examples suite, its lock file and its folders in ``root``; returns the one scenario's target."""
    for folder in ("examples", "tiled"):
        shutil.copytree(SUITES / folder, root / folder)
    shutil.copy(SUITES / "examples.fleetsim.yaml", root)
    shutil.copy(SUITES / "examples.fleetsim.lock.json", root)
    return "examples.fleetsim.yaml::crossing"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args(argv)
    pytest = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"]
    fleetsim = [sys.executable, "-m", "fleetsim"]
    environment = {key: value for key, value in os.environ.items() if key not in ("CI", "PYTHONDONTWRITEBYTECODE")}
    with tempfile.TemporaryDirectory() as tmp:
        plain = Path(tmp, "plain")
        plain.mkdir()
        (plain / "test_plain.py").write_text("def test_plain():\n    assert 1 + 1 == 2\n", encoding="utf-8")
        with_plugin, without, added = _paired(args.rounds, pytest, [*pytest, "-p", "no:fleetsim"], plain, environment)
        print(f"pytest, one plain test, {args.rounds} alternating rounds (medians):")
        print(f"  with the fleetsim plugin   {with_plugin * MS:7.1f} ms")
        print(f"  with -p no:fleetsim        {without * MS:7.1f} ms")
        print(f"  added by the plugin        {added * MS:7.1f} ms (median of the paired differences)")

        project = Path(tmp, "scenario")
        project.mkdir()
        target = _scenario_project(project)
        run = [*fleetsim, "run", target, "--planner", PLANNER]
        print(f"\none scenario ({target}, {PLANNER}), {args.rounds} alternating rounds (medians):")
        for label, extra in (("bytecode caches", {}), ("PYTHONDONTWRITEBYTECODE=1", {"PYTHONDONTWRITEBYTECODE": "1"})):
            env = {**environment, **extra}
            for plugins in ((), ("-p", "no:hypothesispytest")):
                session = [*pytest, *plugins, target, "--planner", PLANNER]
                under_pytest, alone, extra_time = _paired(args.rounds, session, run, project, env)
                shown = " ".join(plugins) or "all plugins"
                print(
                    f"  {label:26} {shown:24} pytest {under_pytest * MS:7.1f} ms  fleetsim run {alone * MS:7.1f} ms"
                    f"  pytest adds {extra_time * MS:+7.1f} ms"
                )

        helps = [_seconds([*fleetsim, "--help"], plain) for _ in range(args.rounds)]
        versions = [_seconds([*fleetsim, "--version"], plain) for _ in range(args.rounds)]
    print(f"\nfleetsim --help              {statistics.median(helps) * MS:7.1f} ms")
    print(f"fleetsim --version           {statistics.median(versions) * MS:7.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
