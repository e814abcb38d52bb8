"""The transcript in docs/vda5050.md is a real one: the shipped example master control drives the shipped
crossing, a client of the broker records vehicle 1's orders and the states that answer them, and the
docs' block must be what this run says (each line without its time, which the wall clock moves).

    FLEETSIM_UPDATE_DOCS=1 python -m pytest tests/vda5050/test_transcript.py

writes the block anew. Every recorded message is also checked against the official schemas."""

from __future__ import annotations

import json
import os
import re
import sys
import threading
from datetime import datetime
from pathlib import Path
from typing import Any

import official
from paho.mqtt.client import Client, MQTTMessage, MQTTv311
from paho.mqtt.enums import CallbackAPIVersion

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.sim.loop import run_scenario
from fleetsim.vda5050.broker import BrokerAddress
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "vda5050.md"
MASTER = ROOT / "examples" / "vda5050" / "master_control.py"
BEGIN, END = "<!-- transcript: tests/vda5050/test_transcript.py -->", "<!-- /transcript -->"
SERIAL = "1"


class _Recorder:
    """Every order to vehicle 1 and every state from it, in arrival order."""

    def __init__(self, broker: BrokerAddress) -> None:
        self.messages: list[tuple[str, dict[str, Any]]] = []
        self.lock = threading.Lock()
        self.offline = threading.Event()  # the vehicle said OFFLINE: it publishes nothing more
        self.client = Client(callback_api_version=CallbackAPIVersion.VERSION2, client_id="recorder", protocol=MQTTv311)
        self.client.on_message = self._on_message
        self.client.connect(broker.host, broker.port)
        self.client.subscribe([(f"uagv/v2/fleetsim/{SERIAL}/{name}", 1) for name in ("order", "state", "connection")])
        self.client.loop_start()

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        name, document = message.topic.rsplit("/", 1)[-1], json.loads(message.payload)
        if name == "connection":
            if document["connectionState"] == "OFFLINE":
                self.offline.set()
            return
        with self.lock:
            self.messages.append((name, document))

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def _item(entry: dict[str, Any]) -> str:
    return f"{entry.get('nodeId') or entry.get('edgeId')}({entry['sequenceId']})"


def _route(nodes: list[dict[str, Any]], edges: list[dict[str, Any]]) -> str:
    """Nodes and edges in sequence, the base first, `|` before the horizon."""
    ordered = sorted([*nodes, *edges], key=lambda e: e["sequenceId"])
    base = " ".join(_item(e) for e in ordered if e["released"])
    horizon = " ".join(_item(e) for e in ordered if not e["released"])
    return f"{base} | {horizon}" if horizon else base


def _lines(messages: list[tuple[str, dict[str, Any]]]) -> list[str]:
    """One line per order and per state that differs from the one before (a state on the timer repeats)."""
    lines, last_state = [], ""
    epoch: datetime | None = None
    for name, m in messages:
        if name == "order":
            lines.append(
                f"{'':>7}  -> order  {m['orderId']} update {m['orderUpdateId']}: {_route(m['nodes'], m['edges'])}"
            )
            continue
        moment = datetime.fromisoformat(m["timestamp"].replace("Z", "+00:00"))
        epoch = epoch or moment
        at = f"t={(moment - epoch).total_seconds():.1f}"
        ahead = _route(m["nodeStates"], m["edgeStates"]) or "-"
        order = f"{m['orderId']} update {m['orderUpdateId']}" if m["orderId"] else "no order"
        state = (
            f"<- state  {order}, last {m['lastNodeId']}({m['lastNodeSequenceId']}), "
            f"{'driving' if m['driving'] else 'standing'}, ahead: {ahead}"
        )
        if state != last_state:
            lines.append(f"{at:>7}  {state}")
            last_state = state
    return lines


def _untimed(lines: list[str]) -> list[str]:
    return [re.sub(r"^\s*(t=\S+)?\s+", "", line) for line in lines]


def _block(text: str) -> tuple[int, int]:
    start, end = text.index(BEGIN), text.index(END)
    return start + len(BEGIN), end


def test_the_docs_transcript_is_what_the_example_master_control_and_the_vehicle_say(
    embedded_broker: BrokerAddress,
) -> None:
    suite = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    scenario = load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)
    recorder = _Recorder(embedded_broker)
    try:
        fleet = Vda5050Fleet(
            Vda5050Settings(broker=embedded_broker, speed=5.0), master_command=[sys.executable, str(MASTER)]
        )
        result = run_scenario(scenario, fleet, planner_timeout=None)
        # The last states may still be on their way when the run returns: OFFLINE comes after them (the
        # broker keeps one client's messages of one QoS in order).
        assert recorder.offline.wait(10.0), "vehicle 1 never said OFFLINE"
    finally:
        recorder.close()
    assert result.passed, [f.message for f in result.failures]
    with recorder.lock:
        messages = list(recorder.messages)
    for name, message in messages:
        assert official.validate("2.0", name, message) == [], (name, message)
    lines = _lines(messages)
    orders = [m for name, m in messages if name == "order"]
    first_state = next(m for name, m in messages if name == "state" and m["orderId"])
    fresh = "\n".join(
        [
            "",
            "```text",
            *lines,
            "```",
            "",
            "The first order in full, and the first state that answers it:",
            "",
            "```json",
            json.dumps(orders[0], indent=2),
            "```",
            "",
            "```json",
            json.dumps(first_state, indent=2),
            "```",
            "",
        ]
    )
    text = DOCS.read_text(encoding="utf-8")
    start, end = _block(text)
    if os.environ.get("FLEETSIM_UPDATE_DOCS") == "1":
        DOCS.write_text(text[:start] + fresh + text[end:], encoding="utf-8")
        return
    shown = text[start:end]
    shown_lines = shown.split("```text\n", 1)[1].split("\n```", 1)[0].splitlines()
    assert _untimed(shown_lines) == _untimed(lines), (
        "docs/vda5050.md's transcript is not what the run says; FLEETSIM_UPDATE_DOCS=1 python -m pytest "
        "tests/vda5050/test_transcript.py writes it anew"
    )
