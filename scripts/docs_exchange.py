"""The transcript of docs/protocol-exchange.md: a real run with a planner process, as the lines went.

The run is the shipped ``mixed-shapes`` example (scenario_suites/examples.fleetsim.yaml) with
scripts/exchange_planner.py as an ``exec:`` planner, which logs every line it reads and writes. The
page shows those lines between ``<!-- exchange -->`` and ``<!-- end exchange -->``, each message laid out
over several lines to be read (on the wire each is one line of compact JSON), and the rejection as the
run's result reports it.
"""

from __future__ import annotations

import json
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

SUITE = "scenario_suites/examples.fleetsim.yaml"
SCENARIO = "mixed-shapes"
PLANNER = "scripts/exchange_planner.py"
SECTION = re.compile(r"^<!-- exchange -->\n.*?^<!-- end exchange -->$", re.M | re.S)
_WIDTH = 120  # a JSON value that fits in this many characters stays on one line


@dataclass(frozen=True)
class Exchange:
    """What went over the pipes, in order (``>`` from fleetsim, ``<`` from the planner), and how the run ended."""

    lines: list[tuple[str, str]]
    rejections: list[dict[str, Any]]
    status: str
    ended: str


def record(repo: Path) -> Exchange:
    """Run the scenario with the logging planner process and read back what it exchanged."""
    from fleetsim import load_scenario, load_suite, run_scenario
    from fleetsim.exec import SubprocessPlanner

    suite = load_suite(repo / SUITE)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == SCENARIO), suite)
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "exchange.log"
        result = run_scenario(scenario, SubprocessPlanner([sys.executable, str(repo / PLANNER), str(log)]))
        logged = log.read_text(encoding="utf-8").splitlines()
    lines = [(line[0], line[2:]) for line in logged]
    return Exchange(lines, [event.to_dict() for event in result.rejections], result.status, result.ended)


def pretty(value: Any, indent: int = 0, before: int = 0) -> str:
    """JSON laid out to be read: a value that fits on its line (``before`` characters of which are taken)
    stays on one line, else it takes one member or item per line."""
    flat = json.dumps(value, ensure_ascii=False)
    if indent + before + len(flat) <= _WIDTH or not isinstance(value, (dict, list)) or not value:
        return flat
    inner = " " * (indent + 2)
    if isinstance(value, dict):
        items = [
            f"{inner}{json.dumps(key)}: {pretty(item, indent + 2, len(json.dumps(key)) + 2)}"
            for key, item in value.items()
        ]
    else:
        items = [inner + pretty(item, indent + 2) for item in value]
    brackets = "{}" if isinstance(value, dict) else "[]"
    return brackets[0] + "\n" + ",\n".join(items) + "\n" + " " * indent + brackets[1]


def render(exchange: Exchange) -> str:
    """The transcript as Markdown: each message under a line saying who sends what."""
    out: list[str] = []
    number = 0
    for direction, line in exchange.lines:
        if line == "EOF":
            out.append(
                f"**fleetsim closes the planner's stdin**: the run has ended ({exchange.status}, "
                f"`ended: {exchange.ended}`), and the planner process exits.\n"
            )
            continue
        number += 1
        message = json.loads(line)
        size = len(line.encode("utf-8"))
        if direction == ">":
            what = f"`{message['type']}`" + (
                f" (`id` {message['id']}, vehicle {message['vehicle']})" if "id" in message else ""
            )
            out.append(f"**{number}. fleetsim → planner**: {what}, one line of {size:,} bytes:\n")
        else:
            what = f"`{message['type']}`" if "type" in message else f"the answer to `id` {message['id']}"
            out.append(f"**{number}. planner → fleetsim**: {what}, one line of {size:,} bytes:\n")
        out.append(f"```json\n{pretty(message)}\n```\n")
        for rejection in _rejections_of(message, exchange.rejections) if direction == "<" else []:
            out.append(
                f"fleetsim checks the plan and **rejects** it (check code `{rejection['code']}`); nothing is "
                "sent back: the vehicle keeps the plan it had, and the run reports the rejection (in its "
                "result: `fleetsim run --json`, `result.json`):\n"
            )
            out.append(f"```json\n{pretty(rejection)}\n```\n")
    return "\n".join(out)


def _rejections_of(answer: dict[str, Any], rejections: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rejections of the plans in ``answer`` (a rejection shows the plan it refused, null fields left out)."""
    plans = [(plan["vehicle_id"], _legs(plan["legs"])) for plan in answer.get("plans", [])]
    return [rejection for rejection in rejections if (rejection["vehicle"], _legs(rejection["plan"])) in plans]


def _legs(legs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{key: value for key, value in leg.items() if value is not None} for leg in legs]


def fill(text: str, exchange: Exchange) -> str:
    """The page's text with its transcript section replaced by ``exchange``."""
    if not SECTION.search(text):
        msg = "docs/protocol-exchange.md has no <!-- exchange --> ... <!-- end exchange --> section"
        raise ValueError(msg)
    return SECTION.sub(lambda _: f"<!-- exchange -->\n{render(exchange)}<!-- end exchange -->", text)
