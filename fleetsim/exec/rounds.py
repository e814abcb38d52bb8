"""Planning rounds in one message (protocol 1.2): the harness's ``round`` message and the checks on its
answer.

A client that says ``{"type": "ready", "rounds": true}`` is sent, instead of one request per call,
``{"type": "round", "calls": [CALL...], "fleet": FLEET}``: the calls of a planning round left to make,
in order (each ``{"type": "plan_routes" | "fix_legs", "id": N, "vehicle": V, "task": TASK}``, a request
without its fleet), and the fleet update as a request would carry it. The client makes the calls in
order against that fleet and stops after the first whose answer changes something (a plan other than the
vehicle's plan in force handed back, a route error, a whole-request route error); it answers
``{"answers": [ANSWER...], "durations": [SECONDS...]}``, the answers to the calls it made (each one a
request's answer, ``schemas/planner-response.schema.json``; all but the last change nothing) and how long
each call took, by its own clock. fleetsim applies them as if the calls had come one by one and sends
the calls left in a new round, with the fleet as changed. A call's ``id`` is its number in the run, as
one call at a time: a call left unanswered is sent again in the next round with the same ``id``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fleetsim.exec.protocol import LegBook, decode_response, loads
from fleetsim.exec.schemas import load_schema, violation
from fleetsim.planning.plans import Response, RouteError, hands_back
from fleetsim.planning.protocol import RoundCall
from fleetsim.planning.snapshot import FleetSnapshot

__all__ = [
    "NOTHING_TO_CHANGE",
    "RoundAnswerError",
    "describe_round",
    "nothing_changed",
    "nothing_to_change",
    "read_round_answer",
]

ROUND = b'{"type":"round","calls":[%b]%b}\n'  # the calls, then (when the fleet changed) ',"fleet":' and it
CALL = b'{"type":"%b","id":%d,"vehicle":%d,"task":%b}'
# An answer with nothing to change (to the request with id %d), as fleetsim's own clients write it.
NOTHING_TO_CHANGE = b'{"id":%d,"plans":[],"route_errors":[]}'

# The commonest answer to a round, every call answered with nothing to change, as both of fleetsim's clients
# write it (compact JSON, keys in this order): the part before the durations, for a round of N calls.
_NOTHING_ANSWERED: dict[int, bytes] = {}


class RoundAnswerError(ValueError):
    """The answer to a round breaks the protocol (the message says how)."""


def nothing_to_change(answer: Any, number: int) -> bool:
    """Exactly ``{"id": number, "plans": [], "route_errors": []}``."""
    return (
        type(answer) is dict
        and len(answer) == 3
        and answer.get("id") == number
        and type(answer["id"]) is int
        and answer.get("plans") == []
        and answer.get("route_errors") == []
    )


def nothing_changed(line: bytes, first: int, count: int) -> list[float] | None:
    """The durations of an answer ``line`` to a round of ``count`` calls (numbered from ``first``) that
    answers every call with nothing to change, spelt as fleetsim's clients spell it (the commonest answer:
    recognised by its bytes, without decoding the answers); ``None`` for any other answer or spelling,
    which :func:`read_round_answer` then reads and checks."""
    template = _NOTHING_ANSWERED.get(count)
    if template is None:
        nothing = b",".join([NOTHING_TO_CHANGE] * count)
        template = _NOTHING_ANSWERED[count] = b'{"answers":[%b],"durations":[' % nothing
    head = template % tuple(range(first, first + count))
    if not (line.startswith(head) and line.endswith(b"]}")):
        return None
    try:
        durations = loads(line[len(head) - 1 : -1])  # from the durations' "[" to their "]"
    except ValueError:
        return None
    # (The slice starts with "[": what parses is a list.)
    return durations if len(durations) == count and _all_seconds(durations) else None


def _all_seconds(durations: list[Any]) -> bool:
    """Every duration a float of seconds, not negative (a float: the schema allows any number)."""
    return all(type(seconds) is float and seconds >= 0.0 for seconds in durations)


def describe_round(first: int, calls: Sequence[RoundCall], shown: int = 3) -> str:
    """The round's requests, in words (for error messages)."""
    numbers = f"request {first}" if len(calls) == 1 else f"requests {first}-{first + len(calls) - 1}"
    words = [f"{method} for vehicle {vehicle}" for method, vehicle, _ in calls[:shown]]
    more = ", ..." if len(calls) > shown else ""
    return f"{numbers} in one round ({', '.join(words)}{more})"


def read_round_answer(
    answer: Any, first: int, calls: Sequence[RoundCall], fleet: FleetSnapshot, book: LegBook | None = None
) -> list[tuple[Response | RouteError, float]]:
    """The decoded answers to the first calls of a round (numbered from ``first``), each with its duration;
    a whole-request route error is a ``RouteError`` object; legs from ``book`` when given. Anything wrong
    raises :class:`RoundAnswerError`."""
    is_object = type(answer) is dict
    answers = answer.get("answers") if is_object else None
    durations = answer.get("durations") if is_object else None
    well_formed = (
        is_object
        and len(answer) == 2
        and type(answers) is list
        and len(answers) > 0
        and type(durations) is list
        and _all_seconds(durations)
    )
    if not well_formed:
        problem = violation(load_schema("round-answer"), answer)
        if problem is not None:
            msg = f"an invalid answer: {problem}"
            raise RoundAnswerError(msg)
    assert isinstance(answers, list) and isinstance(durations, list)  # the schema says so
    if len(answers) != len(durations):
        msg = f"{len(answers)} answers and {len(durations)} durations (one of each per call answered)"
        raise RoundAnswerError(msg)
    if len(answers) > len(calls):
        msg = f"{len(answers)} answers to a round of {len(calls)} calls"
        raise RoundAnswerError(msg)
    last = len(answers) - 1
    decoded: list[tuple[Response | RouteError, float]] = []
    for index, item in enumerate(answers):
        number = first + index
        if nothing_to_change(item, number):  # the commonest answer, by far
            decoded.append(([], durations[index]))
            continue
        problem = violation(load_schema("response"), item, f"answers[{index}]")
        if problem is not None:
            msg = f"an invalid answer: {problem}"
            raise RoundAnswerError(msg)
        if item["id"] != number:
            msg = f"the answer to request {item['id']!r} in place of request {number}'s (answers[{index}])"
            raise RoundAnswerError(msg)
        response: Response | RouteError
        try:
            response = decode_response(item, book)
        except RouteError as error:
            response = error
        if index < last and _changes(response, fleet):
            msg = (
                f"answers[{index}] (request {number}) changing something before the round's last answer"
                " (a round's answers end with the first that changes something)"
            )
            raise RoundAnswerError(msg)
        decoded.append((response, durations[index]))
    return decoded


def _changes(response: Response | RouteError, fleet: FleetSnapshot) -> bool:
    """The answer changes something: anything but nothing, or one plan that is the plan in force."""
    if isinstance(response, RouteError):
        return True
    return bool(response) and not hands_back(list(response), fleet.plans)
