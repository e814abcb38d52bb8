"""The master control a ``vda5050:...,exec=COMMAND`` spec starts: a child process in a session of its own.

It is started as an ``exec:`` planner is (:mod:`fleetsim.exec.process`): ``start_new_session``, so the
process and whatever it starts (the real master control behind a wrapper script, npm's children, worker
processes) form one process group, and :meth:`MasterProcess.stop` stops the whole group: SIGTERM, a grace
period for whatever still runs, then SIGKILL. The run stops it at its end and as soon as the master
control has exited (a crash), so nothing it started outlives the run.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import signal
import subprocess
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from fleetsim.errors import MasterControlError

__all__ = ["MasterProcess"]

GRACE = 5.0  # seconds the group gets after SIGTERM before SIGKILL
_POLL = 0.02  # seconds between looks at the group while it stops


class MasterProcess:
    """``command`` running with ``environment`` added to this process's, the leader of its own session."""

    def __init__(self, command: Sequence[str], environment: Mapping[str, str]) -> None:
        self.command = tuple(command)
        try:
            self.process = subprocess.Popen(
                self.command, env={**os.environ, **environment}, stdin=subprocess.DEVNULL, start_new_session=True
            )
        except OSError as error:
            msg = f"the master control {shlex.join(self.command)!r} could not be started: {error.strerror or error}"
            raise MasterControlError(msg) from None

    @property
    def pid(self) -> int:
        """The leader's process id, which is also its group's."""
        return self.process.pid

    def exit_status(self) -> int | None:
        """The leader's exit status once it has exited (negative: killed by that signal), else None."""
        return self.process.poll()

    def stop(self, grace: float = GRACE) -> None:
        """Stop the whole group: SIGTERM, up to ``grace`` seconds for every process in it to end, then
        SIGKILL for any that has not. The leader is reaped; the group may have lost it long before."""
        group = self.process.pid
        _signal_group(group, signal.SIGTERM)
        deadline = time.monotonic() + grace
        while _group_runs(group, self.process) and time.monotonic() < deadline:
            time.sleep(_POLL)
        if _group_runs(group, self.process):
            _signal_group(group, signal.SIGKILL)
        self.process.wait()


def _signal_group(group: int, sig: signal.Signals) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(group, sig)


def _group_runs(group: int, leader: subprocess.Popen[bytes]) -> bool:
    """Whether a process of ``group`` still runs. The leader is reaped when it has exited; a zombie (an
    orphan that exited and that no one reaps, as under a minimal init) does not count, where ``/proc``
    tells zombies apart."""
    leader.poll()
    try:
        os.killpg(group, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    proc = Path("/proc")
    if not proc.is_dir():
        return True
    for stat in proc.glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue  # it ended while we looked
        # pid (comm) state ppid pgrp ...: comm may hold spaces and parentheses, the last ')' ends it.
        state, _parent, its_group = text[text.rindex(")") + 2 :].split(maxsplit=3)[:3]
        if its_group == str(group) and state != "Z":
            return True
    return False
