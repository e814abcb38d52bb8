"""A master control started with ``exec=`` runs in a session of its own, as an ``exec:`` planner does:
whatever it starts (the real master control behind a wrapper script, a worker) is stopped with it, at
the end of the run and when it crashes. A master control that exits, or cannot start, fails the run with
the sentence the docs give, never a traceback (through ``fleetsim run`` as a user sees it)."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from runs import ROOT, run_command

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

MASTER = Path(__file__).resolve().parent / "scripted_master.py"
SPEED = 20.0


def _crossing() -> Scenario:
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)


def _runs(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, exited and not reaped by the init, does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


def _gone(pid: int, timeout: float = 2.0) -> bool:
    """Whether ``pid`` stops running within ``timeout`` seconds (a signal takes a moment to land)."""
    deadline = time.monotonic() + timeout
    while _runs(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


@pytest.fixture
def started(tmp_path: Path) -> Iterator[Path]:
    """The file a wrapper writes its background process's pid to; that process is killed afterwards if a
    failing test left it running."""
    pid_file = tmp_path / "started.pid"
    yield pid_file
    if pid_file.exists():
        with contextlib.suppress(ProcessLookupError, ValueError):
            os.kill(int(pid_file.read_text()), signal.SIGKILL)


def test_the_real_master_control_behind_a_wrapper_is_stopped_when_the_run_ends(tmp_path: Path, started: Path) -> None:
    wrapper = tmp_path / "master.sh"
    wrapper.write_text(
        '#!/bin/sh\n# the real master control in the background, as deployments wrap it\n"$1" "$2" &\necho $! > "$3"\nwait\n'
    )
    fleet = Vda5050Fleet(
        Vda5050Settings(speed=SPEED), master_command=["sh", str(wrapper), sys.executable, str(MASTER), str(started)]
    )
    result = run_scenario(_crossing(), fleet, planner_timeout=None)
    assert result.passed, [f.message for f in result.failures]  # the real master control drove it
    assert _gone(int(started.read_text())), "the master control behind the wrapper outlived the run"


def test_a_master_control_that_exits_fails_the_run_with_the_documented_sentence_and_takes_its_child_along(
    started: Path,
) -> None:
    command = ["sh", "-c", f'sleep 300 & echo $! > "{started}"; exit 3']
    result = run_scenario(_crossing(), Vda5050Fleet(Vda5050Settings(speed=SPEED), master_command=command))
    assert result.ended == "planner-error"
    [failure] = result.failures
    assert failure.kind == "planner-error"
    assert failure.message == "the master control exited with status 3 at t = 0.0 s"
    assert "traceback" not in failure.details
    assert _gone(int(started.read_text())), "the master control's child outlived its crash"


def test_a_master_control_that_cannot_start_fails_the_run_with_a_sentence(tmp_path: Path) -> None:
    missing = tmp_path / "no-such-master"
    result = run_scenario(_crossing(), Vda5050Fleet(Vda5050Settings(speed=SPEED), master_command=[str(missing)]))
    [failure] = result.failures
    assert failure.kind == "planner-error"
    assert failure.message == f"the master control '{missing}' could not be started: No such file or directory"
    assert "traceback" not in failure.details


def test_fleetsim_run_says_the_master_control_exited_in_one_sentence_without_a_traceback() -> None:
    command = run_command("crossing", f"vda5050:speed={SPEED:g},exec=sh -c 'exit 3'")
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 1, done.stderr
    [result] = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    [failure] = result["failures"]
    assert failure["kind"] == "planner-error"
    assert failure["message"] == "the master control exited with status 3 at t = 0.0 s"
    assert "traceback" not in json.dumps(failure).lower()
    # The report under the table (on stderr with --json): the sentence, and nothing after it.
    report = done.stderr.split("FAILED crossing\n", 1)[1]
    assert report.splitlines() == [
        "  planner-error at t=0.10 s:",
        "    the master control exited with status 3 at t = 0.0 s",
    ]
    assert "Traceback" not in done.stderr and "begin_step raised" not in done.stderr
