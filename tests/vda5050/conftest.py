"""MQTT brokers for the VDA 5050 tests: fleetsim's embedded one (amqtt) and Debian's mosquitto, each a fresh
process or thread on a free loopback port, and connected clients that are closed after the test.

``broker`` runs a test against both brokers; ``embedded_broker`` against the embedded one only; ``mqtt_link``
makes connected :class:`MqttLink` clients. mosquitto missing: its tests skip, or fail under
FLEETSIM_REQUIRE_TOOLS=1 (CI must not pass by skipping).
"""

from __future__ import annotations

import itertools
import os
import shutil
import socket
import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from fleetsim.vda5050.broker import BrokerAddress, BrokerError, EmbeddedBroker, check_reachable
from fleetsim.vda5050.link import MqttLink, Will

__all__ = ["MakeLink", "mosquitto_executable"]

_MOSQUITTO = "/usr/sbin/mosquitto"  # Debian installs it outside a user's PATH
_START_TIMEOUT = 5.0
_PORT_ATTEMPTS = 3

MakeLink = Callable[..., MqttLink]


def mosquitto_executable() -> str:
    """The mosquitto broker; a test needing it is skipped when it is missing, or fails when
    FLEETSIM_REQUIRE_TOOLS=1."""
    executable = shutil.which("mosquitto") or (_MOSQUITTO if os.access(_MOSQUITTO, os.X_OK) else None)
    if executable is None:
        reason = "the MQTT broker 'mosquitto' is not installed (Debian/Ubuntu: apt install mosquitto)"
        if os.environ.get("FLEETSIM_REQUIRE_TOOLS") == "1":
            pytest.fail(reason + "; FLEETSIM_REQUIRE_TOOLS=1 requires it")
        pytest.skip(reason)
    return executable


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def _start_mosquitto(executable: str, folder: Path) -> tuple[subprocess.Popen[bytes], BrokerAddress]:
    """mosquitto on a free loopback port, reachable; retried when another process took the port first."""
    log = folder / "mosquitto.log"
    attempt = 0
    while True:
        attempt += 1
        address = BrokerAddress("127.0.0.1", _free_port())
        config = folder / "mosquitto.conf"
        config.write_text(f"listener {address.port} 127.0.0.1\nallow_anonymous true\npersistence false\n")
        # Its log goes to a file: a pipe nobody reads would block mosquitto once full.
        with log.open("wb") as output:
            process = subprocess.Popen([executable, "-c", str(config)], stdout=output, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + _START_TIMEOUT
        while process.poll() is None and time.monotonic() < deadline:
            try:
                check_reachable(address, timeout=0.5)
            except BrokerError:
                time.sleep(0.02)
                continue
            return process, address
        _stop(process)
        text = log.read_text(errors="replace")
        if "Address already in use" not in text or attempt == _PORT_ATTEMPTS:
            pytest.fail(f"mosquitto did not start on {address.url} within {_START_TIMEOUT} s:\n{text}")


def _stop(process: subprocess.Popen[bytes]) -> None:
    process.terminate()
    try:
        process.wait(5)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(5)


@pytest.fixture
def embedded_broker() -> Iterator[BrokerAddress]:
    """A fresh embedded broker (amqtt in a thread), stopped after the test."""
    with EmbeddedBroker() as running:
        yield running.address


@pytest.fixture
def mosquitto_broker(tmp_path: Path) -> Iterator[BrokerAddress]:
    """A fresh mosquitto process on loopback, terminated after the test."""
    process, address = _start_mosquitto(mosquitto_executable(), tmp_path)
    try:
        yield address
    finally:
        _stop(process)


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
