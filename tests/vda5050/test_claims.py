"""A VDA 5050 master control dispatches: fleetsim publishes a scenario's transport orders on its
``transportOrders`` topics, the master control (paho-mqtt and networkx, none of fleetsim's code) claims
them for its vehicles, and every claim is judged by the dispatcher's rules, a refused one told back on the
order's topic with its code and reason."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from dataclasses import replace
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from claiming_master import ClaimingMaster
from paho.mqtt.client import CallbackAPIVersion, Client, MQTTMessage, MQTTv311, topic_matches_sub

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.orders import Order, Shift, Stop
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.vda5050.broker import BrokerAddress
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings
from fleetsim.vda5050.transport import ClaimInvalid, order_level, read_claim

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
SPEED = 20.0


@cache
def _loop() -> Scenario:
    """The shipped one-way loop (segments 1-10): vehicle 1 stands on segment 1, vehicle 2 on segment 6."""
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == "loop-one-way"), suite)


def _run(broker: BrokerAddress, orders: tuple[Order, ...], **settings: Any) -> tuple[RunResult, Vda5050Fleet]:
    shift = settings.pop("shift", None)
    start_timeout = settings.pop("start_timeout", 30.0)
    loop = _loop()
    scenario = replace(
        loop, tasks=(), orders=orders, shift=shift, settings=replace(loop.settings, stop_on=(), **settings)
    )
    fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED, start_timeout=start_timeout))
    return run_scenario(scenario, fleet, planner_timeout=None), fleet


def _states(master: ClaimingMaster, order_id: str) -> list[tuple[str, str | None, int]]:
    """The order's states as the master control saw them, repeats left out."""
    said = [(m["state"], m["serialNumber"], m["servedStops"]) for m in master.seen if m["orderId"] == order_id]
    return [s for i, s in enumerate(said) if i == 0 or said[i - 1] != s]


@pytest.fixture
def dispatcher(broker: BrokerAddress) -> Iterator[ClaimingMaster]:
    control = ClaimingMaster(broker.host, broker.port)
    yield control
    control.close()


def test_a_master_control_claims_each_order_for_the_nearest_idle_vehicle_and_completes_them(
    broker: BrokerAddress, dispatcher: ClaimingMaster
) -> None:
    orders = (
        Order("a", (Stop(7, dwell=1.0), Stop(8)), release=0.0),
        Order("b", (Stop(2), Stop(3, dwell=1.0)), release=0.0, deadline=40.0, priority=2),
        Order("late", (Stop(4),), release=20.0),
    )
    result, fleet = _run(broker, orders, shift=Shift(duration=45.0))
    assert result.passed, [f.message for f in result.failures]
    assert not result.rejections and not result.collisions
    # Oldest first, each to the idle vehicle nearest its first stop: a (segment 7) to vehicle 2 (on 6),
    # b to vehicle 1, and the late one (segment 4) to vehicle 1, which ended b on segment 3.
    assert dispatcher.claimed == {"a": "2", "b": "1", "late": "1"}
    done = {o["id"]: o for o in result.orders}
    assert {k: (o["vehicle"], o["completed"] is not None) for k, o in done.items()} == {
        "a": (2, True),
        "b": (1, True),
        "late": (1, True),
    }
    assert fleet.transport is not None and fleet.transport.claimed == 3
    # Each order's life on its topic, as it went.
    assert _states(dispatcher, "a") == [
        ("RELEASED", None, 0),
        ("ASSIGNED", "2", 0),
        ("STARTED", "2", 0),
        ("STARTED", "2", 1),
        ("COMPLETED", "2", 2),
    ]
    # One stop and no dwell: reached, served and completed at once, so it is never seen STARTED.
    assert _states(dispatcher, "late") == [("RELEASED", None, 0), ("ASSIGNED", "1", 0), ("COMPLETED", "1", 1)]
    b = dispatcher.orders["b"]
    assert b["stops"] == [
        {"goalEdgeIds": ["e2"], "goalNodeIds": ["s1.last", "s2.last"], "goalProgress": None, "dwell": 0.0},
        {"goalEdgeIds": ["e3"], "goalNodeIds": ["s2.last", "s3.last"], "goalProgress": None, "dwell": 1.0},
    ]
    assert (b["release"], b["deadline"], b["vehicleTypes"], b["priority"], b["lastRefusal"]) == (
        0.0,
        40.0,
        None,
        2,
        None,
    )
    # A state is published within a step of the change the run recorded.
    released = next(m for m in dispatcher.seen if m["orderId"] == "late")
    assert released["time"] == pytest.approx(done["late"]["release"], abs=0.11)
    assigned = next(m for m in dispatcher.seen if m["orderId"] == "late" and m["state"] == "ASSIGNED")
    assert done["late"]["assigned"] <= assigned["time"] <= done["late"]["assigned"] + 0.11
    completed = next(m for m in dispatcher.seen if m["orderId"] == "a" and m["state"] == "COMPLETED")
    assert done["a"]["completed"] <= completed["time"] <= done["a"]["completed"] + 0.21


def _retained(broker: BrokerAddress, topic: str, wait: float = 1.0) -> dict[str, dict[str, Any]]:
    """What the broker keeps on ``topic`` (a filter), by topic, as a client that connects now sees it."""
    kept: dict[str, dict[str, Any]] = {}

    def keep(client: Client, userdata: Any, message: MQTTMessage) -> None:
        if topic_matches_sub(topic, message.topic):  # amqtt also sends what others subscribed to
            kept[message.topic] = json.loads(message.payload)

    client = Client(callback_api_version=CallbackAPIVersion.VERSION2, client_id="late-reader", protocol=MQTTv311)
    client.on_message = keep
    client.connect(broker.host, broker.port)
    client.subscribe(topic, qos=1)
    client.loop_start()
    time.sleep(wait)
    client.loop_stop()
    client.disconnect()
    return kept


def test_refused_claims_are_rejections_with_their_codes_and_are_told_back_on_the_orders_topic(
    embedded_broker: BrokerAddress,
) -> None:
    orders = (
        Order("a", (Stop(7),), release=0.0),
        Order("later", (Stop(4),), release=30.0),
        Order("tug", (Stop(9),), release=0.0, vehicle_types=("tugger",)),
    )
    claims: list[tuple[str, dict[str, Any] | bytes]] = [
        ("nope", {"serialNumber": "1"}),
        ("later", {"serialNumber": "1"}),
        ("tug", {"serialNumber": "1"}),
        ("a", {"serialNumber": "7"}),
        ("a", b"not json"),
        ("a", {"serialNumber": "2"}),  # narrowly right: this one is taken
    ]
    master = ClaimingMaster(embedded_broker.host, embedded_broker.port, claims=claims)
    try:
        result, _ = _run(embedded_broker, orders, time_limit=3.0)
        assert master.wait_until(lambda: master.orders.get("a", {}).get("state") == "ASSIGNED", timeout=5.0)
    finally:
        master.close()
    codes = [(r.rejection.code.value, r.rejection.vehicle_id) for r in result.rejections]
    assert codes == [
        ("order-unknown", 1),
        ("order-unreleased", 1),
        ("order-vehicle-type", 1),
        ("assignment-unknown-vehicle", 7),
    ]
    assert [o["vehicle"] for o in result.orders if o["id"] == "a"] == [2]
    refusals = {(m["orderId"], m["state"]): m["lastRefusal"] for m in master.seen if m["lastRefusal"] is not None}
    assert refusals[("nope", "UNKNOWN")]["code"] == "order-unknown"
    assert refusals[("nope", "UNKNOWN")]["serialNumber"] == "1"
    unreleased = refusals[("later", "UNKNOWN")]
    assert unreleased["code"] == "order-unreleased" and "not released yet" in unreleased["reason"]
    tug = refusals[("tug", "RELEASED")]
    assert tug["code"] == "order-vehicle-type" and "tugger" in tug["reason"] and "'agv'" in tug["reason"]
    # Told back in the order the claims came, each in its turn: the last one taken.
    assert [(m["state"], (m["lastRefusal"] or {}).get("code")) for m in master.seen if m["orderId"] == "a"] == [
        ("RELEASED", None),
        ("RELEASED", "assignment-unknown-vehicle"),
        ("RELEASED", "claim-invalid"),
        ("ASSIGNED", "claim-invalid"),
    ]
    # An order the master control cannot have seen is not described: no stops, no release time.
    assert not any("stops" in m for m in master.seen if m["orderId"] in ("nope", "later"))
    assert not any(m["orderId"] == "later" and m["state"] != "UNKNOWN" for m in master.seen)
    # The claim that is not one is told back, and is no rejection of the run.
    invalid = next(m["lastRefusal"] for m in master.seen if (m["lastRefusal"] or {}).get("code") == "claim-invalid")
    assert invalid["serialNumber"] is None and "not JSON" in invalid["reason"]
    # The broker keeps the orders' messages, with their last refusal; the unknown ones it does not keep.
    kept = _retained(embedded_broker, "uagv/fleetsim/transportOrders/+")
    assert set(kept) == {"uagv/fleetsim/transportOrders/a", "uagv/fleetsim/transportOrders/tug"}
    assert kept["uagv/fleetsim/transportOrders/tug"]["lastRefusal"]["code"] == "order-vehicle-type"
    assert kept["uagv/fleetsim/transportOrders/a"]["state"] == "ASSIGNED"
    assert kept["uagv/fleetsim/transportOrders/a"]["lastRefusal"]["code"] == "claim-invalid"


def test_without_claims_the_orders_stay_open_and_the_time_limit_names_them(embedded_broker: BrokerAddress) -> None:
    orders = (Order("a", (Stop(7),)), Order("b", (Stop(2),)))
    silent = ClaimingMaster(embedded_broker.host, embedded_broker.port, claims=[], announce="idle-master")
    try:
        result, _ = _run(embedded_broker, orders, time_limit=3.0)
    finally:
        silent.close()
    assert result.ended == "time-limit" and not result.rejections
    [failure] = result.failures
    assert failure.kind == "timeout"
    assert "2 orders open: 'a', 'b'" in failure.message
    assert {(m["orderId"], m["state"], m["serialNumber"]) for m in silent.seen} == {
        ("a", "RELEASED", None),
        ("b", "RELEASED", None),
    }


def test_a_master_control_that_neither_claims_nor_announces_itself_fails_the_start(
    embedded_broker: BrokerAddress,
) -> None:
    mute = ClaimingMaster(embedded_broker.host, embedded_broker.port, claims=[])
    try:
        result, _ = _run(embedded_broker, (Order("a", (Stop(7),)),), time_limit=3.0, start_timeout=1.0)
    finally:
        mute.close()
    assert result.ended == "planner-error" and result.steps == 1
    assert "claimed no order and announced nothing on uagv/fleetsim/master/connection within 1 s" in (
        result.failures[0].message
    )
    assert mute.orders["a"]["state"] == "RELEASED"  # it was shown the order


@pytest.mark.parametrize(
    ("payload", "problem"),
    [
        (b'{"serialNumber": "12"}', None),
        (b'{"serialNumber": "-3", "timestamp": "2026-01-01T00:00:00.00Z"}', None),
        (b'{"serialNumber": "012"}', "serialNumber='012'"),
        (b'{"serialNumber": 12}', "serialNumber=12"),
        (b'{"serialNumber": "agv-1"}', "serialNumber='agv-1'"),
        (b"{}", "serialNumber=None"),
        (b'["12"]', "it must be an object"),
        (b"\xff", "is not JSON"),
    ],
)
def test_a_claim_names_a_vehicle_by_its_serial_number(payload: bytes, problem: str | None) -> None:
    if problem is None:
        claim = read_claim("o/1", payload)
        assert (claim.order_id, claim.vehicle_id, claim.serial) == ("o/1", int(claim.serial), claim.serial)
        return
    with pytest.raises(ClaimInvalid, match="the claim for order 'o/1'") as raised:
        read_claim("o/1", payload)
    assert problem in str(raised.value)


def test_an_order_id_is_one_topic_level() -> None:
    assert order_level("a-1_b.c~") == "a-1_b.c~"
    assert order_level("pick/7 #2+") == "pick%2F7%20%232%2B"
