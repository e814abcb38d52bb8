"""MQTT brokers for the VDA 5050 tests: fleetsim's embedded one (amqtt) and Debian's mosquitto, each a fresh
process or thread on a free loopback port, and connected clients that are closed after the test.

``broker`` runs a test against both brokers; ``embedded_broker`` against the embedded one only; ``mqtt_link``
makes connected :class:`MqttLink` clients. mosquitto missing: its tests skip, or fail under
FLEETSIM_REQUIRE_TOOLS=1 (CI must not pass by skipping).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from tooling import mosquitto_executable

from fleetsim.vda5050.broker import BrokerAddress, BrokerError, EmbeddedBroker, Mosquitto
from fleetsim.vda5050.link import MqttLink, Will

__all__ = ["MakeLink"]


MakeLink = Callable[..., MqttLink]


@pytest.fixture
def embedded_broker() -> Iterator[BrokerAddress]:
    """A fresh embedded broker (amqtt in a thread), stopped after the test."""
    with EmbeddedBroker() as running:
        yield running.address


@pytest.fixture
def mosquitto_broker(tmp_path: Path) -> Iterator[BrokerAddress]:
    """A fresh mosquitto process on loopback, terminated after the test."""
    try:
        running = Mosquitto(mosquitto_executable(), tmp_path).__enter__()
    except BrokerError as error:
        pytest.fail(str(error))
    try:
        yield running.address
    finally:
        running.__exit__(None, None, None)


@pytest.fixture(params=["embedded", "mosquitto"])
def broker(request: pytest.FixtureRequest) -> BrokerAddress:
    """Each broker in turn: the test runs once against the embedded broker and once against mosquitto."""
    address: BrokerAddress = request.getfixturevalue(f"{request.param}_broker")
    return address


@pytest.fixture
def mqtt_link(broker: BrokerAddress) -> Iterator[MakeLink]:
    """Makes connected clients of ``broker``: ``mqtt_link(client_id=None, *, will=None, inbound_limit=...)``.
    Every client is disconnected after the test (a no-op for one the test closed already)."""
    links: list[MqttLink] = []
    numbers = itertools.count(1)

    def make(client_id: str | None = None, *, will: Will | None = None, inbound_limit: int = 10_000) -> MqttLink:
        link = MqttLink(broker, client_id or f"test-client-{next(numbers)}", will=will, inbound_limit=inbound_limit)
        link.connect(timeout=5.0)
        links.append(link)
        return link

    yield make
    for link in links:
        link.disconnect()
