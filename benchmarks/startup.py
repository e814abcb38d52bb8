"""What installing fleetsim costs every pytest session, and how fast the command line answers.

    python benchmarks/startup.py [--rounds 10]

A project of one plain test and no fleetsim suite is run with pytest, alternately with the plugin loaded
(as in any environment where fleetsim is installed) and with ``-p no:fleetsim``, so that both see the
same moments of a noisy machine; the figure is the median of the paired differences. ``fleetsim --help``
and ``fleetsim --version`` are timed the same number of times (medians).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path


def _seconds(command: Sequence[str], cwd: Path) -> float:
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args(argv)
    pytest = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"]
    fleetsim = [sys.executable, "-m", "fleetsim"]
    with tempfile.TemporaryDirectory() as tmp:
        project = Path(tmp)
        (project / "test_plain.py").write_text("def test_plain():\n    assert 1 + 1 == 2\n", encoding="utf-8")
        _seconds(pytest, project)  # warm the file system cache once
        with_plugin, without, helps, versions = [], [], [], []
        for _ in range(args.rounds):
            with_plugin.append(_seconds(pytest, project))
            without.append(_seconds([*pytest, "-p", "no:fleetsim"], project))
            helps.append(_seconds([*fleetsim, "--help"], project))
            versions.append(_seconds([*fleetsim, "--version"], project))
    added = [a - b for a, b in zip(with_plugin, without, strict=True)]
    ms = 1000.0
    print(f"pytest, one plain test, {args.rounds} alternating rounds (medians):")
    print(f"  with the fleetsim plugin   {statistics.median(with_plugin) * ms:7.1f} ms")
    print(f"  with -p no:fleetsim        {statistics.median(without) * ms:7.1f} ms")
    print(f"  added by the plugin        {statistics.median(added) * ms:7.1f} ms (median of the paired differences)")
    print(f"fleetsim --help              {statistics.median(helps) * ms:7.1f} ms")
    print(f"fleetsim --version           {statistics.median(versions) * ms:7.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
