"""A live run: the simulation paced at a speed against the wall clock and streamed to viewer pages.

The loop hands each trace line to :meth:`LiveRun.watch` the moment the step ends (``run_scenario(...,
watch=...)``); that is the only touch point, so a watched run computes exactly what an unwatched one does
and its trace hash is the same at any speed. ``watch`` first waits until the step's moment on the wall
clock (step k ends at ``(k + 1) * dt / speed`` seconds after the start, counted again from every change
of speed and every resumption), then passes the line on, then — if a page paused the run — waits until it
is resumed or stepped. While it waits the loop waits: a paused run does not advance and its planner is
not called.

Lines become step records (:mod:`fleetsim.view.document`) in a thread of their own, from the trace
format alone (:func:`fleetsim.recording.replay.replay`), and go to every page watching: each page gets
the scene, every step so far, then the steps as they come, batched, from a queue of its own, so a slow
or closed page never slows the run. Any page may pause, step or change the speed, and every page is told.
"""

from __future__ import annotations

import contextlib
import json
import queue
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from fleetsim.recording.replay import replay
from fleetsim.scenario import Scenario
from fleetsim.view.document import StepRecords, scene_part

__all__ = ["FASTEST", "LiveRun", "Pacer", "parse_speed"]

FASTEST = "max"  # the speed word for "as fast as it goes"
SLOWEST, QUICKEST = 0.01, 1000.0  # the speeds a run may be paced at
_POLL = 0.1  # seconds between looks at the stop request while waiting
_END = object()


def parse_speed(text: str) -> float | None:
    """A speed as the command line gives it: a multiple of real time, or ``max`` (``None``: unpaced)."""
    if text.strip() == FASTEST:
        return None
    try:
        speed = float(text)
    except ValueError:
        speed = float("nan")
    if not SLOWEST <= speed <= QUICKEST:
        msg = f"speed={text!r} must be a multiple of real time from {SLOWEST:g} to {QUICKEST:g}, or {FASTEST!r}"
        raise ValueError(msg)
    return speed


class Pacer:
    """Pacing of a run's steps against the wall clock: speed (``None``: as fast as possible), pause, step."""

    def __init__(self, speed: float | None, stopped: Callable[[], bool] = lambda: False) -> None:
        self._changed = threading.Condition()
        self.speed = speed
        self.paused = False
        self._allowed = 0  # steps a page asked for while paused
        self._anchor: tuple[float, float] | None = None  # (wall clock, sim time) the pace counts from
        self.stopped = stopped
        self.shown = 0.0  # sim time of the last step let through
        self.started_at = speed  # the speed the run began at (its result's ``paced``)
        self.lag = 0.0  # the most wall seconds a step came behind its moment
        self.late_steps = 0  # steps more than a step's wall time behind

    def start(self) -> None:
        """A run begins: the pace counts from now."""
        with self._changed:
            self._anchor = (time.monotonic(), 0.0)
            self.shown, self.lag, self.late_steps, self.started_at = 0.0, 0.0, 0, self.speed

    def wait_for_moment(self, sim_time: float) -> None:
        """Until the wall clock reaches the moment of ``sim_time`` at the current speed (returns at once
        when paused, stopped or as fast as possible)."""
        with self._changed:
            while not self.paused and self.speed is not None and not self.stopped():
                if self._anchor is None:
                    self._anchor = (time.monotonic(), 0.0)
                wall, sim = self._anchor
                left = wall + (sim_time - sim) / self.speed - time.monotonic()
                if left <= 0:
                    self.lag = max(self.lag, -left)
                    if -left > (sim_time - self.shown) / self.speed:
                        self.late_steps += 1
                    break
                self._changed.wait(min(left, _POLL))
            self.shown = sim_time

    def hold_while_paused(self) -> None:
        """While paused and no step was asked for; a step asked for is used up here."""
        with self._changed:
            if not self.paused:
                return  # the pace counts on from where it was: no drift step by step
            while self.paused and self._allowed == 0 and not self.stopped():
                self._changed.wait(_POLL)
            if self.paused and self._allowed > 0:
                self._allowed -= 1
            self._anchor = (time.monotonic(), self.shown)  # held: the pace counts from here

    def pause(self) -> None:
        with self._changed:
            self.paused = True
            self._changed.notify_all()

    def resume(self) -> None:
        with self._changed:
            self.paused = False
            self._allowed = 0
            self._anchor = (time.monotonic(), self.shown)
            self._changed.notify_all()

    def step(self) -> None:
        with self._changed:
            if self.paused:
                self._allowed += 1
                self._changed.notify_all()

    def set_speed(self, speed: float | None) -> None:
        with self._changed:
            self.speed = speed
            self._anchor = (time.monotonic(), self.shown)
            self._changed.notify_all()


def _batched(items: list[Any]) -> Iterator[Any]:
    """Queued items as messages: each run of step records as one ``steps`` message, others as they are."""
    steps: list[Any] = []
    for item in items:
        if isinstance(item, list):
            steps.append(item)
            continue
        if steps:
            yield {"type": "steps", "steps": steps}
            steps = []
        yield item
    if steps:
        yield {"type": "steps", "steps": steps}


class _Page:
    """One watching page: its queue of messages to send."""

    def __init__(self) -> None:
        self.outbox: queue.SimpleQueue[Any] = queue.SimpleQueue()


class LiveRun:
    """The live view of one or more runs in turn (``begin`` each), paced by one :class:`Pacer`."""

    def __init__(self, speed: float | None) -> None:
        self.pacer = Pacer(speed)
        self._lock = threading.Lock()
        self._pages: list[_Page] = []
        self._scene: dict[str, Any] | None = None
        self._history: list[list[Any]] = []  # the step records so far
        self._outcome: dict[str, Any] | None = None
        self._lines: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._converter: threading.Thread | None = None
        self._time_step = 0.1

    # -- the loop's side ---------------------------------------------------------------------------

    def begin(self, scenario: Scenario, about: Mapping[str, Any], stopped: Callable[[], bool] = lambda: False) -> None:
        """A new run is about to start: every page is shown its scene. ``stopped``: whether a stop was
        asked for (a paused run's loop is then let go on, to end at its step)."""
        self.finish_steps()
        self.pacer.stopped = stopped
        scene = {**scene_part(scenario, about), "live": True}
        with self._lock:
            self._scene, self._history, self._outcome = scene, [], None
            self._time_step = scenario.settings.time_step
            self._broadcast({"type": "scene", "scene": scene})
            self._broadcast(self._status())
        self._lines = queue.SimpleQueue()
        self._converter = threading.Thread(
            target=self._convert, args=(scenario, self._lines), name="fleetsim-live-steps", daemon=True
        )
        self._converter.start()
        self.pacer.start()

    def watch(self, line: str) -> None:
        """A trace line, the moment it is written (the header, then one per step)."""
        if line.startswith("{"):  # the header: the pace counts from here
            self._lines.put(line)
            self.pacer.start()
            return
        step = int(line[1 : line.index(",")])
        self.pacer.wait_for_moment((step + 1) * self._time_step)
        self._lines.put(line)
        self.pacer.hold_while_paused()

    def end(self, outcome: Mapping[str, Any]) -> None:
        """The run ended: every page is told how (after the last step)."""
        self.finish_steps()
        with self._lock:
            self._outcome = dict(outcome)
            self._broadcast({"type": "end", "outcome": self._outcome})

    def finish_steps(self) -> None:
        """Wait until every line handed over is a step record sent to the pages."""
        if self._converter is not None:
            self._lines.put(_END)
            self._converter.join()
            self._converter = None

    def close(self) -> None:
        """The command is done: every page's connection is closed (the pages keep what they received)."""
        self.finish_steps()
        with self._lock:
            for page in self._pages:
                page.outbox.put(_END)

    def _convert(self, scenario: Scenario, lines: queue.SimpleQueue[Any]) -> None:
        last = [""]  # the line replay took last: the one of the frame it yields

        records = StepRecords()

        def taken() -> Iterator[str]:
            while (line := lines.get()) is not _END:
                if line.startswith("{"):
                    records.header(line)  # the run's orders, if it has any
                last[0] = line
                yield line

        for frame in replay(scenario, taken()):
            record = records.record(frame, last[0])
            with self._lock:
                self._history.append(record)
                for page in self._pages:
                    page.outbox.put(record)

    # -- the pages' side ---------------------------------------------------------------------------

    def _status(self) -> dict[str, Any]:
        pacer = self.pacer
        return {"type": "status", "paused": pacer.paused, "speed": pacer.speed, "time": pacer.shown}

    def _broadcast(self, message: Mapping[str, Any]) -> None:
        for page in self._pages:
            page.outbox.put(dict(message))

    def serve(self, connection: Any) -> None:
        """Serve one page's WebSocket until it closes (the server's thread for it)."""
        page = _Page()
        with self._lock:
            if self._scene is not None:
                page.outbox.put({"type": "scene", "scene": self._scene})
                page.outbox.put({"type": "steps", "steps": list(self._history)})
                if self._outcome is not None:
                    page.outbox.put({"type": "end", "outcome": self._outcome})
            page.outbox.put(self._status())
            self._pages.append(page)
        reader = threading.Thread(target=self._read, args=(connection, page), name="fleetsim-live-page", daemon=True)
        reader.start()
        try:
            self._write(connection, page)
        finally:
            with self._lock:
                self._pages.remove(page)

    def _write(self, connection: Any, page: _Page) -> None:
        from websockets.exceptions import ConnectionClosed

        while True:
            queued = [page.outbox.get()]  # wait for one, then take whatever else is queued
            with contextlib.suppress(queue.Empty):
                while True:
                    queued.append(page.outbox.get_nowait())
            ended = _END in queued
            try:
                for message in _batched(queued[: queued.index(_END)] if ended else queued):
                    connection.send(json.dumps(message, separators=(",", ":")))
            except ConnectionClosed:
                return
            if ended:
                return

    def _read(self, connection: Any, page: _Page) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            with contextlib.suppress(ConnectionClosed):  # the page went: nothing more to read
                for text in connection:
                    self._control(text)
        finally:
            page.outbox.put(_END)

    def _control(self, text: str | bytes) -> None:
        """A page's request: pause, resume, step, speed (a number > 0, or null: as fast as possible)."""
        try:
            message = json.loads(text)
            kind = message["type"]
        except (ValueError, TypeError, KeyError):
            return  # not a request this page sends: ignored
        pacer = self.pacer
        if kind == "pause":
            pacer.pause()
        elif kind == "resume":
            pacer.resume()
        elif kind == "step":
            pacer.step()
        elif kind == "speed":
            value = message.get("value")
            if value is None:
                pacer.set_speed(None)
            elif isinstance(value, int | float) and not isinstance(value, bool) and SLOWEST <= value <= QUICKEST:
                pacer.set_speed(float(value))
            else:
                return
        else:
            return
        with self._lock:
            self._broadcast(self._status())
