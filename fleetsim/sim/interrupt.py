"""Stopping cleanly on SIGINT (Ctrl-C) and SIGTERM (a CI job cancelled or out of time).

While :class:`StopSignals` is active, the first SIGINT or SIGTERM does not end the process: it asks the
run in progress to stop at the end of its current step (``ended: "interrupted"``), so its result, trace,
picture and recording are written like any failed run's, and the front end (``fleetsim run``, the pytest
plugin) stops after it. A planner call in progress is cut short at once (the handler raises
:class:`PlannerInterrupted` inside it), so a slow planner does not hold the stop up. A second signal
raises :class:`RunAborted` (a ``KeyboardInterrupt``) wherever the process is, abandoning the clean-up;
files already complete stay, half-written ones are removed by their writers.

Signal handlers can only be set in the main thread; elsewhere :class:`StopSignals` changes nothing. A
signal the process was started with ignored (``nohup``, a shell's background job) stays ignored.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType
from typing import Any, Protocol

__all__ = ["STOP_SIGNALS", "PlannerInterrupted", "RunAborted", "StopSignals", "signal_name"]

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def signal_name(signum: int) -> str:
    """``SIGINT``, ``SIGTERM``, ...; the number for a signal Python has no name for."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


class PlannerInterrupted(BaseException):
    """Raised inside a planner call by a stop signal; a BaseException, so a planner's ``except
    Exception`` cannot swallow it. The run ends at the end of the step, without the call's answer."""


class RunAborted(KeyboardInterrupt):
    """A second stop signal: the clean-up of the first is given up at once. ``signum`` is the first
    signal's, which the exit status reports (128 + signum)."""

    def __init__(self, signum: int, again: int) -> None:
        self.signum = signum
        super().__init__(f"{signal_name(again)} during the clean-up after {signal_name(signum)}: aborted")


class _InCall(Protocol):
    @property
    def in_call(self) -> bool: ...


class StopSignals:
    """A context manager: SIGINT and SIGTERM ask for a clean stop while it is active (see the module).

    ``signum`` is the first stop signal received, or ``None``. A planner guard registered as ``guard``
    (the run in progress does this) lets the first signal cut a planner call short.
    """

    def __init__(self) -> None:
        self.signum: int | None = None
        self.guard: _InCall | None = None
        self._previous: dict[int, Any] = {}

    @property
    def requested(self) -> bool:
        return self.signum is not None

    @property
    def exit_status(self) -> int:
        """128 + the signal's number, as a shell reports a process ended by it (130, 143)."""
        return 128 + (self.signum or 0)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is not None:
            raise RunAborted(self.signum, signum)
        self.signum = signum
        guard = self.guard
        if guard is not None and guard.in_call:
            raise PlannerInterrupted

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                # An ignored signal stays ignored (``nohup``, a shell's background job), as Python leaves it.
                if signal.getsignal(signum) is not signal.SIG_IGN:
                    self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        for signum, handler in self._previous.items():
            if handler is not None:  # None: a handler set outside Python, which cannot be put back
                signal.signal(signum, handler)
        self._previous.clear()
