"""A planner in another process, in any language: the JSON-lines protocol over its stdin and stdout.

:class:`SubprocessPlanner` is an ordinary planner to the simulation. Its first call starts the process
(so a process that cannot start fails the run like any planner error, not the harness), sends the init
message and waits for ``ready``; each call then sends one request and reads one answer, which must be
valid JSON matching ``schemas/planner-response.schema.json``. A process whose ``ready`` says ``"rounds":
true`` is asked a planning round's calls in one message instead (:meth:`SubprocessPlanner.plan_round`,
``fleetsim/exec/rounds.py``). A process whose ``ready`` says ``"dispatches": true`` is a dispatcher too:
then, and only then, the planner has a ``dispatch(board, fleet, layout)`` method, which sends a
``dispatch`` request (``fleetsim/exec/dispatching.py``); a run with transport orders and no other
dispatcher starts the process before its first step to know (:meth:`SubprocessPlanner.begin_run`).
Everything the process writes to stderr goes to a temporary file whose tail is shown when something goes
wrong.

Faults — the process cannot start, exits early or crashes, does not answer within the per-call timeout,
answers with invalid JSON, an answer that violates the schema (the field and value are named), an
answer to another request or a round answered past its first change — raise :class:`PlannerProcessError`, which fails the run with a
``planner-error`` carrying the stderr tail. :meth:`SubprocessPlanner.close` (called when the run ends,
and by a finaliser if it never is) closes stdin, waits briefly, then terminates and kills the process
group, so no planner process outlives its run.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import shlex
import signal
import subprocess
import tempfile
import time
import weakref
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.errors import PlannerProcessError
from fleetsim.exec.dispatching import DISPATCH, BoardEncoder, decode_assignments
from fleetsim.exec.protocol import FleetEncoder, LegBook, decode_response, dumps, encode_task, init_message, loads
from fleetsim.exec.rounds import (
    CALL,
    NOTHING_TO_CHANGE,
    ROUND,
    RoundAnswerError,
    describe_round,
    nothing_changed,
    nothing_to_change,
    read_round_answer,
)
from fleetsim.exec.schemas import SCHEMAS, load_schema, violation
from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import Response, RouteError
from fleetsim.planning.protocol import RoundCall
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario, Task, VehicleType

__all__ = ["SCHEMAS", "PlannerProcessError", "SubprocessPlanner", "load_schema"]

_STDERR_TAIL = 4000  # characters of stderr shown with an error
_GRACE = 1.0  # seconds a process gets to exit after stdin closes, and again after SIGTERM
# A request: its type, id, vehicle, task and (when the fleet changed) ',"fleet":' and the update.
_REQUEST = b'{"type":"%b","id":%d,"vehicle":%d,"task":%b%b}\n'
_METHODS = {"plan_routes": b"plan_routes", "fix_legs": b"fix_legs"}
_PLAN_HANDED_BACK = b'{"id":%d,"plans":[%b],"route_errors":[]}'
_CALL_OF_ID = CALL.replace(b'"id":%d', b'"id":%%d')  # a round's call with all but its id filled in


def _kill_group(process: subprocess.Popen[bytes]) -> None:
    """Terminate, then kill, the process and everything it started (its own session)."""
    for sig, wait in ((signal.SIGTERM, _GRACE), (signal.SIGKILL, None)):
        if process.poll() is not None:
            return
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, sig)
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(wait)


class SubprocessPlanner:
    """A planner that runs ``command`` and speaks the JSON-lines protocol with it (one process per run)."""

    def __init__(
        self,
        command: str | Sequence[str],
        *,
        timeout: float | None = 10.0,
        startup_timeout: float = 30.0,
        cwd: str | os.PathLike[str] | None = None,
        planner_options: Mapping[str, Any] | None = None,
        scenario_dir: str | os.PathLike[str] | None = None,
    ) -> None:
        self.command = shlex.split(command) if isinstance(command, str) else list(command)
        if not self.command:
            msg = f"command={command!r} must name a program to run"
            raise ValueError(msg)
        self.timeout = timeout
        self.startup_timeout = startup_timeout
        self.cwd = cwd
        # What the init message tells the process it is made with: the suite entry's options, its folder.
        self.planner_options = dict(planner_options or {})
        self.scenario_dir = None if scenario_dir is None else str(Path(scenario_dir).resolve())
        self.requests = 0
        self.rounds: bool | None = None  # the process answers rounds (None: not started yet)
        self.dispatches: bool | None = None  # the process dispatches (None: not started yet)
        self._process: subprocess.Popen[bytes] | None = None
        self._stderr: IO[bytes] | None = None
        self._buffer = b""
        self._pipes = (-1, -1)  # the process's stdin and stdout, while it runs
        self._fleet: FleetSnapshot | None = None  # the fleet the process last saw
        self._encoder = FleetEncoder()
        self._boards = BoardEncoder()
        self._board_time = 0.0  # the time of the board of the dispatch request being answered
        self._legs = LegBook()  # the answers' legs, each decoded once
        # task id -> the task, its JSON, and its fix_legs and plan_routes calls of a round (formats of the id)
        self._tasks: dict[int, tuple[Task, bytes, bytes, bytes]] = {}
        self._asking: tuple[int, str, int] | None = None  # the request being answered (None: the init message)
        self._round: tuple[int, Sequence[RoundCall]] | None = None  # the round being answered: first id, calls
        self._finalizer: weakref.finalize[..., SubprocessPlanner] | None = None

    def __repr__(self) -> str:
        return f"SubprocessPlanner({shlex.join(self.command)!r})"

    # -- the planner protocol ----------------------------------------------------------------------

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._call("plan_routes", task, fleet, layout)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._call("fix_legs", task, fleet, layout)

    def plan_round(
        self, calls: Sequence[RoundCall], fleet: FleetSnapshot, layout: Layout
    ) -> list[tuple[Response | RouteError, float | None]]:
        """The answers to the first of ``calls`` (a planning round's calls left), with each call's duration
        by the process's clock: all of them when none changes anything, else up to the first that does.
        A process that does not answer rounds is asked the first call alone."""
        if self._process is None:
            self._start_at(layout, fleet)
        if not self.rounds:
            method, _vehicle, task = calls[0]
            try:
                return [(self._call(method, task, fleet, layout), None)]
            except RouteError as error:
                return [(error, None)]
        first = self.requests + 1
        self._asking, self._round = None, (first, calls)
        # A round holds up to a few calls per vehicle a step: each is its task's call, formatted with its id.
        tasks, known = self._tasks, self._known_task
        parts = []
        number = first
        for method, vehicle, task in calls:
            entry = tasks.get(task.id)
            if entry is None or entry[0] is not task:
                entry = known(task)
            if vehicle == task.vehicle_id:  # always, for a vehicle's own head task
                parts.append((entry[2] if method == "fix_legs" else entry[3]) % number)
            else:
                parts.append(CALL % (_METHODS[method], number, vehicle, entry[1]))
            number += 1
        requests = b",".join(parts)
        self._send(ROUND % (requests, self._update(fleet)))
        # Each call may take the per-call timeout: the round, as many times as it has calls.
        line = self._read_line(None if self.timeout is None else self.timeout * len(calls))
        durations = nothing_changed(line, first, len(calls))
        if durations is not None:  # the commonest answer, recognised by its bytes
            self.requests += len(calls)
            return [([], seconds) for seconds in durations]
        try:
            answers = read_round_answer(self._decode(line), first, calls, fleet, self._legs)
        except RoundAnswerError as error:
            raise self._fail(f"answered {self._request()} with {error}") from None
        self.requests += len(answers)
        return list(answers)

    # -- the dispatcher (protocol 1.5) ---------------------------------------------------------------

    def begin_run(self, scenario: Scenario) -> None:
        """Start the process for ``scenario`` now, not at the first call, so that whether it dispatches is
        known before the run: the loop asks this of the planner of a run with transport orders and no other
        dispatcher. A process that cannot start raises :class:`PlannerProcessError`."""
        if self._process is None and not self.requests:
            self._start(scenario.layout, {vehicle.id: vehicle.type for vehicle in scenario.vehicles}, scenario.tasks)

    @property
    def dispatch(self) -> Callable[[OrderBoard, FleetSnapshot, Layout], list[Assignment]]:
        """``dispatch(board, fleet, layout)``, there only when the process said in its ready message that it
        dispatches (``"dispatches": true``): a process not started yet has said nothing."""
        if self.dispatches:
            return self._dispatch
        said = "has not started" if self.dispatches is None else 'did not answer init with "dispatches": true'
        msg = f"{self!r} has no dispatch: the process {said}"
        raise AttributeError(msg)

    def _dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> list[Assignment]:
        """A ``dispatch`` request: the board and the fleet update; the answer's assignments."""
        if self._process is None:
            raise self._fail("was closed")  # it said it dispatches: it was started
        self.requests += 1
        number = self.requests
        self._asking, self._round, self._board_time = (number, "dispatch", 0), None, board.time
        self._send(DISPATCH % (number, self._boards.encode(board), self._update(fleet)))
        answer = self._decode(self._read_line(self.timeout))
        problem = violation(load_schema("dispatch-answer"), answer)
        if problem is not None:
            raise self._fail(f"answered {self._request()} with an invalid answer: {problem}")
        if answer["id"] != number:
            raise self._fail(f"answered {self._request()} with the answer to request {answer['id']!r}")
        return decode_assignments(answer)

    def diagnostics(self) -> str:
        """The tail of what the process wrote to stderr (shown with any planner error)."""
        if self._stderr is None:
            return ""
        with contextlib.suppress(OSError, ValueError):
            self._stderr.flush()
            size = self._stderr.seek(0, os.SEEK_END)
            self._stderr.seek(max(0, size - _STDERR_TAIL))
            text = self._stderr.read().decode("utf-8", errors="replace")
            return f"stderr of {shlex.join(self.command)} (last {_STDERR_TAIL} characters):\n{text}" if text else ""
        return ""

    def overrun_message(self, limit: str) -> str:
        """What a call cut short by the run's timer (``limit``: the timeout, in words) was waiting for:
        the message the process did not answer (the init message, a request, a round's requests)."""
        return f"planner process {shlex.join(self.command)}: did not answer {self._request()} within {limit}"

    def close(self) -> None:
        """End the process: close its stdin, give it a moment, then terminate and kill its group."""
        process, self._process = self._process, None
        if process is None:
            return
        with contextlib.suppress(OSError, ValueError):
            if process.stdin is not None:
                process.stdin.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(_GRACE)
        _kill_group(process)
        if process.stdout is not None:
            process.stdout.close()
        if self._finalizer is not None:
            self._finalizer.detach()

    # -- the conversation --------------------------------------------------------------------------

    def _fail(self, message: str) -> PlannerProcessError:
        return PlannerProcessError(f"planner process {shlex.join(self.command)}: {message}", self.diagnostics())

    def _start_at(self, layout: Layout, fleet: FleetSnapshot) -> None:
        """Start the process at its first call (on the fleet as it is then), unless it was closed."""
        if self.requests:
            raise self._fail("was closed")
        tasks = [task for queue in fleet.tasks.values() for task in queue]
        self._start(layout, {vid: state.type for vid, state in fleet.vehicles.items()}, tasks)

    def _start(self, layout: Layout, vehicles: Mapping[int, VehicleType], tasks: Iterable[Task]) -> None:
        tasks = list(tasks)
        if self._stderr is None:
            self._stderr = tempfile.TemporaryFile()  # noqa: SIM115 -- kept for diagnostics, closed by GC
        try:
            process = subprocess.Popen(
                self.command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr,
                cwd=self.cwd, start_new_session=True,
            )  # fmt: skip
        except OSError as error:
            raise self._fail(f"cannot start: {error.strerror or error}") from None
        self._process = process
        assert process.stdin is not None and process.stdout is not None
        self._pipes = (process.stdin.fileno(), process.stdout.fileno())  # looked up once, used every call
        self._finalizer = weakref.finalize(self, _kill_group, process)
        self._asking = self._round = None
        self._send(dumps(init_message(layout, vehicles, tasks, self.planner_options, self.scenario_dir)) + b"\n")
        answer = self._receive(self.startup_timeout)
        problem = violation(load_schema("ready"), answer)
        if problem is not None:
            raise self._fail(f'answered the init message with {_short(answer)}, not {{"type": "ready"}} ({problem})')
        self.rounds = answer.get("rounds") is True
        self.dispatches = answer.get("dispatches") is True
        self._fleet = None
        self._encoder = FleetEncoder(tasks)
        self._boards = BoardEncoder()
        self._legs = LegBook()

    def _call(self, method: str, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if self._process is None:
            self._start_at(layout, fleet)
        self.requests += 1
        number = self.requests
        self._asking, self._round = (number, method, task.vehicle_id), None
        # The request is put together from bytes: its task is encoded once per run, its fleet only when
        # it changed since the last request (and then only what changed).
        update = self._update(fleet)
        self._send(_REQUEST % (_METHODS[method], number, task.vehicle_id, self._encoded_task(task), update))
        line = self._read_line(self.timeout)
        # The two commonest answers, as fleetsim's own clients spell them, need no decoding or checking:
        # nothing to change, and the vehicle's plan handed back unchanged (it is the plan in force, as the
        # process last saw it).
        if line == NOTHING_TO_CHANGE % number:
            return []
        sent = self._encoder.plans.get(task.vehicle_id)
        if sent is not None and line == _PLAN_HANDED_BACK % (number, sent[1]):
            return [sent[0]]
        answer = self._decode(line)
        if nothing_to_change(answer, number):
            return []  # the same, spelt otherwise
        problem = violation(load_schema("response"), answer)
        if problem is not None:
            raise self._fail(f"answered {self._request()} with an invalid response: {problem}")
        if answer["id"] != number:
            raise self._fail(f"answered {self._request()} with the answer to request {answer['id']!r}")
        return decode_response(answer, self._legs)

    def _update(self, fleet: FleetSnapshot) -> bytes:
        """``,"fleet":`` and what changed since the fleet the process last saw, or nothing if it is the same."""
        if fleet is self._fleet:
            return b""
        update = b',"fleet":' + self._encoder.encode(fleet, self._fleet)
        self._fleet = fleet
        return update

    def _encoded_task(self, task: Task) -> bytes:
        """The task's JSON, encoded at its first request (a task is asked about again and again)."""
        known = self._tasks.get(task.id)
        if known is None or known[0] is not task:
            known = self._known_task(task)
        return known[1]

    def _known_task(self, task: Task) -> tuple[Task, bytes, bytes, bytes]:
        """The task's JSON and its two calls of a round, kept for the requests to come."""
        encoded = dumps(encode_task(task))
        escaped = encoded.replace(b"%", b"%%")  # the call is formatted again, with its id
        fix, plan = (
            _CALL_OF_ID % (_METHODS[method], task.vehicle_id, escaped) for method in ("fix_legs", "plan_routes")
        )
        entry = self._tasks[task.id] = (task, encoded, fix, plan)
        return entry

    def _request(self) -> str:
        """The message being answered, in words (for error messages)."""
        if self._round is not None:
            return describe_round(*self._round)
        if self._asking is None:
            return "the init message"
        number, method, vehicle = self._asking
        if method == "dispatch":
            return f"request {number} (dispatch() at t={self._board_time:g} s)"
        return f"request {number} ({method} for vehicle {vehicle})"

    def _send(self, message: bytes) -> None:
        """Write one message: a line, newline included."""
        descriptor = self._pipes[0]
        try:
            # Straight to the pipe, no buffer to fill and flush; a long message may take several writes.
            written = os.write(descriptor, message)
            if written < len(message):
                rest = memoryview(message)[written:]
                while rest:
                    rest = rest[os.write(descriptor, rest) :]
        except (BrokenPipeError, ConnectionResetError):
            raise self._fail(f"{self._ended()} before reading {self._request()}") from None

    def _receive(self, timeout: float | None) -> Any:
        return self._decode(self._read_line(timeout))

    def _decode(self, line: bytes) -> Any:
        try:
            return loads(line)
        except ValueError as error:  # orjson's JSONDecodeError, invalid UTF-8 included
            raise self._fail(
                f"answered {self._request()} with invalid JSON ({getattr(error, 'msg', error)}): {_clip(line)}"
            ) from None

    def _read_line(self, timeout: float | None) -> bytes:
        deadline = None if timeout is None else time.monotonic() + timeout
        descriptor = self._pipes[1]
        while b"\n" not in self._buffer:
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise self._fail(f"did not answer {self._request()} within {self._limit_words(timeout)}")
            ready, _, _ = select.select([descriptor], [], [], left)
            if not ready:
                continue
            chunk = os.read(descriptor, 1 << 16)
            if not chunk:
                raise self._fail(f"{self._ended()} before answering {self._request()}")
            self._buffer += chunk
        line, _, self._buffer = self._buffer.partition(b"\n")
        return line

    def _limit_words(self, timeout: float | None) -> str:
        if self._round is not None and len(self._round[1]) > 1 and self.timeout is not None:
            return f"{len(self._round[1])} x the per-call timeout of {self.timeout:g} s"
        return f"the per-call timeout of {timeout:g} s"

    def _ended(self) -> str:
        assert self._process is not None
        with contextlib.suppress(subprocess.TimeoutExpired):
            self._process.wait(_GRACE)
        code = self._process.returncode
        if code is None:
            return "closed its stdout"
        if code < 0:
            with contextlib.suppress(ValueError):
                return f"was killed by {signal.Signals(-code).name}"
        return f"exited with status {code}"


def _clip(line: bytes, limit: int = 200) -> str:
    text = line.decode("utf-8", errors="replace")
    return repr(text if len(text) <= limit else text[:limit] + "...")


def _short(value: Any, limit: int = 200) -> str:
    text = json.dumps(value)
    return text if len(text) <= limit else text[:limit] + "..."
