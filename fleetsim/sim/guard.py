"""Calling a planner safely: a per-call wall-clock timeout, its time measured, its faults contained.

A planner that raises anything but a :class:`RouteError`, or overruns the timeout, becomes a
:class:`PlannerFault` carrying its traceback; the run then fails with a ``planner-error`` and the
harness carries on with the next scenario. The timeout uses ``SIGALRM`` (an interval timer), which
interrupts pure-Python loops and sleeps; it is only available in the main thread of a POSIX process,
elsewhere calls run without a timeout. A call that returns after its time is a fault too, even if the
planner caught the timer's exception; a planner that catches it and never returns cannot be stopped
in-process (run such a planner as a subprocess).

A planner that answers a planning round's calls in one go (:meth:`PlannerGuard.round`, a planner
process speaking protocol 1.2) is given the per-call timeout once per call of the round, and each call's
own duration, as the planner reports it, is held to the per-call timeout as if it had been made alone.
"""

from __future__ import annotations

import functools
import math
import signal
import threading
import time
import traceback
from collections.abc import Callable, Sequence
from types import FrameType

from fleetsim.errors import FleetsimError, PlannerProcessError
from fleetsim.planning.plans import RouteError
from fleetsim.sim.interrupt import PlannerInterrupted

__all__ = ["PlannerFault", "PlannerGuard"]

_clock = time.perf_counter


class PlannerFault(FleetsimError):
    """The planner raised, overran its time, or returned something that is not a response."""

    def __init__(self, message: str, *, vehicle_id: int | None = None, details: str = "") -> None:
        self.message = message
        self.vehicle_id = vehicle_id
        self.details = details  # the planner's traceback, where there is one
        super().__init__(message)


class _Overrun(BaseException):
    """Raised inside the planner by the timer; a BaseException so a planner's ``except Exception`` cannot
    swallow it."""


def _timer_usable() -> bool:
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


def _planner_traceback(exc: BaseException) -> str:
    """The traceback from the planner's frames on (the harness's own frames say nothing to a user)."""
    frames = traceback.extract_tb(exc.__traceback__)
    inside = [frame for frame in frames if "fleetsim/sim/guard.py" not in frame.filename.replace("\\", "/")]
    lines = ["Traceback (most recent call last):\n", *traceback.format_list(inside)]
    lines += traceback.format_exception_only(type(exc), exc)
    return "".join(lines)


class PlannerGuard:
    """Invokes planner methods with a timeout; counts calls and sums the time spent inside them.

    Use it as a context manager around a run. On entry a periodic ``SIGALRM`` tick starts (a quarter of
    the timeout, at most every 0.25 s); the tick raises inside a planner call that has run longer than
    the timeout. A call itself only notes its start time, so guarding costs no system call per call.
    """

    def __init__(self, timeout: float | None = 10.0) -> None:
        self.timeout = timeout
        self._limit = timeout if timeout is not None else math.inf  # what a call's time is compared with
        self._tick_limit = self._limit  # what the tick compares the call in progress with (a round: more)
        self.calls = 0
        self.wall_time = 0.0
        self._armed = False
        self._previous: object = None
        self._call_started: float | None = None
        self._previous_timer: tuple[float, float] = (0.0, 0.0)
        self._entered = 0.0

    @property
    def in_call(self) -> bool:
        """A planner call is in progress (a stop signal may cut it short)."""
        return self._call_started is not None

    def forget_call(self) -> None:
        """No call is in progress any more (one was abandoned by an exception raised between its return
        and its accounting), so the timer must not fire for it."""
        self._call_started = None

    def _tick(self, signum: int, frame: FrameType | None) -> None:
        started = self._call_started
        if started is not None and self.timeout is not None and time.perf_counter() - started > self._tick_limit:
            self._call_started = None
            raise _Overrun

    def __enter__(self) -> PlannerGuard:
        if self.timeout is not None and _timer_usable():
            self._previous = signal.signal(signal.SIGALRM, self._tick)
            tick = min(self.timeout / 4.0, 0.25)
            # Someone else's timer (pytest-timeout, say) is put back on exit, less the time spent here.
            self._previous_timer = signal.setitimer(signal.ITIMER_REAL, tick, tick)
            self._entered = time.monotonic()
            self._armed = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._armed:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, self._previous)  # type: ignore[arg-type]
            delay, interval = self._previous_timer
            if delay > 0.0:
                left = max(delay - (time.monotonic() - self._entered), 1e-3)
                signal.setitimer(signal.ITIMER_REAL, left, interval)
            self._armed = False

    def __call__(
        self, method: str, call: Callable[..., object], vehicle_id: int, task: object, fleet: object, layout: object
    ) -> object:
        """``call(task, fleet, layout)``, timed and guarded; ``method`` and ``vehicle_id`` are for messages."""
        start = self._call_started = _clock()
        try:
            response = call(task, fleet, layout)
        except (RouteError, PlannerInterrupted):
            self._account(start)
            raise
        except (_Overrun, Exception) as exc:
            self._account(start)
            where = f"{method}() for vehicle {vehicle_id}"
            overrun = functools.partial(self._overrun, method, vehicle_id, call, timer=True)
            raise self._fault(exc, where, vehicle_id, overrun) from None
        elapsed = _clock() - start
        self._call_started = None
        self.calls += 1
        self.wall_time += elapsed
        if elapsed > self._limit:
            raise self._overrun(method, vehicle_id, call)  # it caught the timer's exception and returned late
        return response

    def dispatch(self, call: Callable[..., object], board: object, fleet: object, layout: object) -> object:
        """A dispatcher's ``call(board, fleet, layout)``, timed and guarded as a planner call is (the same
        per-call timeout; its faults are ``PlannerFault`` naming ``dispatch()``). Not counted among the
        planner's calls."""
        start = self._call_started = _clock()
        try:
            answer = call(board, fleet, layout)
        except PlannerInterrupted:
            self._call_started = None
            raise
        except (_Overrun, Exception) as exc:
            self._call_started = None
            if isinstance(exc, _Overrun):
                raise PlannerFault(
                    f"dispatch() did not return within the per-call timeout of {self.timeout:g} s"
                ) from None
            if isinstance(exc, PlannerProcessError):  # it names dispatch() and its request; stderr says more
                raise PlannerFault(str(exc), details=exc.details) from None
            msg = f"dispatch() raised {type(exc).__name__}: {exc}"
            raise PlannerFault(msg, details=_planner_traceback(exc)) from None
        elapsed = _clock() - start
        self._call_started = None
        if elapsed > self._limit:
            raise PlannerFault(f"dispatch() did not return within the per-call timeout of {self.timeout:g} s")
        return answer

    def round(
        self,
        call_round: Callable[..., Sequence[tuple[object, float | None]]],
        calls: Sequence[tuple[str, int, object]],
        fleet: object,
        layout: object,
    ) -> list[object]:
        """``call_round(calls, fleet, layout)``: the answers to the first calls of a planning round (each
        call ``(method, vehicle id, task)``), timed and guarded like that many calls. The round may take the
        per-call timeout once per call; each answer comes with its call's own duration (``None``: unknown),
        which must be within the per-call timeout. Counted as one call per answer."""
        count = len(calls)
        method, vehicle_id, _task = calls[0]
        self._tick_limit = self._limit * count
        start = self._call_started = _clock()
        try:
            answers = call_round(calls, fleet, layout)
        except PlannerInterrupted:
            self._account(start)
            raise
        except (_Overrun, Exception) as exc:
            self._account(start)
            overrun = functools.partial(self._round_overrun, method, vehicle_id, count, call_round, timer=True)
            where = f"{method}() for vehicle {vehicle_id}" if count == 1 else _round_words(method, vehicle_id, count)
            raise self._fault(exc, where, vehicle_id, overrun) from None
        finally:
            self._tick_limit = self._limit
        elapsed = _clock() - start
        self._call_started = None
        self.calls += len(answers)
        self.wall_time += elapsed
        limit = self._limit
        for (call_method, call_vehicle, _), (_, seconds) in zip(calls, answers, strict=False):
            if seconds is not None and seconds > limit:  # this call alone took longer than a call may
                raise self._overrun(call_method, call_vehicle, call_round)
        if elapsed > limit * count:
            raise self._round_overrun(method, vehicle_id, count, call_round)
        return [response for response, _ in answers]

    @staticmethod
    def _fault(exc: BaseException, where: str, vehicle_id: int, overrun: Callable[[], PlannerFault]) -> PlannerFault:
        """What a call (or a round) that ended in ``exc`` is reported as."""
        if isinstance(exc, _Overrun):
            return overrun()
        if isinstance(exc, PlannerProcessError):
            # A planner process failed: its error names the message it failed on (the init message, a
            # request, a round's requests) and its stderr says more than our frames.
            return PlannerFault(str(exc), vehicle_id=vehicle_id, details=exc.details)
        msg = f"{where} raised {type(exc).__name__}: {exc}"
        return PlannerFault(msg, vehicle_id=vehicle_id, details=_planner_traceback(exc))

    def _round_overrun(
        self, method: str, vehicle_id: int, count: int, call: Callable[..., object], *, timer: bool = False
    ) -> PlannerFault:
        if count == 1:
            return self._overrun(method, vehicle_id, call, timer=timer)
        what = f"{_round_words(method, vehicle_id, count)} did not return within {count} x the per-call timeout"
        return self._overrun(method, vehicle_id, call, what, count=count, timer=timer)

    def _overrun(
        self,
        method: str,
        vehicle_id: int,
        call: Callable[..., object],
        what: str = "",
        *,
        count: int = 1,
        timer: bool = False,
    ) -> PlannerFault:
        what = what or f"{method}() for vehicle {vehicle_id} did not return within the per-call timeout"
        msg = f"{what} of {self.timeout:g} s"
        # A planner may say more about itself: the tail of a planner process's stderr, and (cut short by
        # the timer) what it was waiting for: its init message, say, rather than the call that started it.
        owner = getattr(call, "__self__", None)
        diagnostics = getattr(owner, "diagnostics", None)
        details = diagnostics() if callable(diagnostics) else ""
        overrun_message = getattr(owner, "overrun_message", None)
        if timer and callable(overrun_message):
            limit = f"{count} x the per-call timeout" if count > 1 else "the per-call timeout"
            said = overrun_message(f"{limit} of {self.timeout:g} s")
            msg = said if isinstance(said, str) and said else msg
        return PlannerFault(msg, vehicle_id=vehicle_id, details=details if isinstance(details, str) else "")

    def _account(self, start: float) -> None:
        self._call_started = None
        self.calls += 1
        self.wall_time += _clock() - start


def _round_words(method: str, vehicle_id: int, count: int) -> str:
    """A planning round's calls, in words (for error messages)."""
    return f"a round of {count} planner calls (the first {method}() for vehicle {vehicle_id})"
