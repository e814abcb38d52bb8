"""The command line as a shell user meets it: output piped into a reader that stops early."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from fleetsim.load.tiled.writer import write_map
from fleetsim.strategies.geometry import grid


def inspect_command(map_path: Path) -> list[str]:
    """``fleetsim inspect MAP`` run by this interpreter."""
    return [sys.executable, "-c", "from fleetsim.cli import main; raise SystemExit(main())", "inspect", str(map_path)]


def test_a_reader_that_stops_early_ends_fleetsim_quietly_with_the_sigpipe_status(tmp_path: Path) -> None:
    write_map(tmp_path / "map.json", grid(21))  # 840 segments: far more output than a pipe buffers
    command = inspect_command(tmp_path / "map.json")
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdout is not None and process.stderr is not None
    first = process.stdout.readline()  # `| head -1`
    process.stdout.close()
    status = process.wait(timeout=120)
    errors = process.stderr.read().decode()
    assert first.startswith(str(tmp_path / "map.json").encode())
    assert (status, errors) == (141, "")


def test_a_reader_that_reads_everything_sees_status_0(tmp_path: Path) -> None:
    write_map(tmp_path / "map.json", grid(3))
    command = inspect_command(tmp_path / "map.json")
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert (done.returncode, done.stderr) == (0, "") and "12 segments" in done.stdout
