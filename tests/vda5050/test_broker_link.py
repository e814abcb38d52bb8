"""The MQTT transport of the VDA 5050 vehicles against real brokers (the embedded amqtt one and mosquitto),
with real clients on both ends: delivery, retained messages, last wills, the bounded inbound buffer,
unreachable brokers, broker URLs, and the embedded broker's loopback-only listener and clean stop."""

from __future__ import annotations

import contextlib
import errno
import logging
import socket
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from tooling import mosquitto_executable

from fleetsim.specs.python import PlannerSpecError
from fleetsim.vda5050 import broker as broker_module
from fleetsim.vda5050.broker import (
    BrokerAddress,
    BrokerError,
    EmbeddedBroker,
    Mosquitto,
    check_reachable,
    parse_broker_url,
)
from fleetsim.vda5050.link import Inbound, MqttLink, Will

MakeLink = Callable[..., MqttLink]  # the mqtt_link fixture of conftest.py
FORM = "mqtt://[user[:password]@]host[:port]"


def wait_for(link: MqttLink, topic: str, timeout: float = 5.0) -> list[Inbound]:
    """Everything ``link`` receives up to and including the first message on ``topic`` (a marker: a
    broker keeps one publisher's messages in order, so what was sent before the marker came before it)."""
    received: list[Inbound] = []
    deadline = time.monotonic() + timeout
    while not any(item.topic == topic for item in received):
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not link.wait(remaining):
            pytest.fail(f"nothing on {topic!r} within {timeout} s; received {received!r}")
        received += link.drain()
    return received


def topics(items: list[Inbound]) -> list[str]:
    return [item.topic for item in items]


# -- delivery ---------------------------------------------------------------------------------------------


def test_a_published_message_reaches_the_subscriber_of_its_topic_only(mqtt_link: MakeLink) -> None:
    receiver, sender = mqtt_link("receiver"), mqtt_link("sender")
    receiver.subscribe("fleet/v1/order", "fleet/v1/marker")
    before = time.monotonic()
    sender.publish("fleet/v2/order", b"for another vehicle")
    sender.publish("fleet/v1/order", b'{"orderId": "o1"}')
    sender.publish("fleet/v1/marker", b"")

    received = wait_for(receiver, "fleet/v1/marker")

    assert topics(received) == ["fleet/v1/order", "fleet/v1/marker"]
    assert received[0].payload == b'{"orderId": "o1"}'
    assert before <= received[0].received <= received[1].received <= time.monotonic()
    assert receiver.drain() == []
    assert receiver.dropped == 0


def test_a_retained_message_reaches_a_late_subscriber_and_a_plain_one_does_not(mqtt_link: MakeLink) -> None:
    sender = mqtt_link("sender")
    sender.publish("fleet/v1/connection", b"ONLINE", qos=1, retain=True)
    sender.publish("fleet/v1/state", b"not kept", qos=1)

    late = mqtt_link("late")
    late.subscribe("fleet/v1/#")
    sender.publish("fleet/v1/marker", b"")

    received = wait_for(late, "fleet/v1/marker")
    assert [(item.topic, item.payload) for item in received] == [
        ("fleet/v1/connection", b"ONLINE"),
        ("fleet/v1/marker", b""),
    ]


def test_a_client_ignores_retained_messages_of_topics_it_did_not_subscribe_to(mqtt_link: MakeLink) -> None:
    other_vehicle = mqtt_link("other-vehicle")
    other_vehicle.subscribe("fleet/v2/connection")
    master = mqtt_link("master")
    master.publish("fleet/v2/connection", b"ONLINE", qos=1, retain=True)

    vehicle = mqtt_link("vehicle")  # amqtt 0.12 sends it the retained message other-vehicle subscribed to
    vehicle.subscribe("fleet/v1/#")
    master.publish("fleet/v1/marker", b"")

    assert topics(wait_for(vehicle, "fleet/v1/marker")) == ["fleet/v1/marker"]
    assert topics(wait_for(other_vehicle, "fleet/v2/connection")) == ["fleet/v2/connection"]


# -- last will ----------------------------------------------------------------------------------------------

WILL = Will("fleet/v1/connection", b'{"connectionState": "CONNECTIONBROKEN"}')


def test_an_aborted_client_gets_its_last_will_published_and_retained(mqtt_link: MakeLink) -> None:
    watcher = mqtt_link("watcher")
    watcher.subscribe("fleet/v1/connection")
    vehicle = mqtt_link("vehicle", will=WILL)

    vehicle.abort()

    received = wait_for(watcher, "fleet/v1/connection")
    assert [item.payload for item in received] == [WILL.payload]
    assert not vehicle.connected
    assert vehicle.lost is None  # an abort of our own is not a loss
    late = mqtt_link("late")
    late.subscribe("fleet/v1/connection")
    assert [item.payload for item in wait_for(late, "fleet/v1/connection")] == [WILL.payload]


def test_a_cleanly_disconnected_client_gets_no_last_will(mqtt_link: MakeLink) -> None:
    watcher = mqtt_link("watcher")
    watcher.subscribe("fleet/v1/#")
    vehicle = mqtt_link("vehicle", will=WILL)

    vehicle.disconnect()
    time.sleep(0.2)  # a will would be published as the broker handles the closed connection
    mqtt_link("other").publish("fleet/v1/marker", b"")

    assert topics(wait_for(watcher, "fleet/v1/marker")) == ["fleet/v1/marker"]
    assert not vehicle.connected
    assert vehicle.lost is None


# -- the bounded inbound buffer -------------------------------------------------------------------------------


# amqtt handles about 5,000 messages a second (mosquitto ten times as many): 50,000 would cost it 10 s a run.
FLOOD = {"mosquitto": 50_000, "embedded": 10_000}


def test_a_flood_keeps_the_newest_messages_up_to_the_limit_and_counts_the_dropped(
    mqtt_link: MakeLink, request: pytest.FixtureRequest
) -> None:
    receiver = mqtt_link("receiver", inbound_limit=1000)
    receiver.subscribe("flood")
    sender = mqtt_link("sender")

    for number in range(1000):  # exactly the limit: nothing dropped
        sender.publish("flood", str(number).encode())
    _wait_until(lambda: receiver.pending == 1000, "1000 messages buffered")
    assert receiver.dropped == 0
    assert [int(item.payload) for item in receiver.drain()] == list(range(1000))

    flood = FLOOD[request.node.callspec.params["broker"]]
    for number in range(flood):
        sender.publish("flood", str(number).encode())
    _wait_until(lambda: receiver.dropped + receiver.pending >= flood, f"{flood} messages arrived", timeout=20.0)

    kept = receiver.drain()
    assert len(kept) == 1000
    assert receiver.dropped == flood - 1000
    assert [int(item.payload) for item in kept] == list(range(flood - 1000, flood))
    assert receiver.pending == 0
    assert not receiver.wait(0.0)


def _wait_until(condition: Callable[[], bool], what: str, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"not within {timeout} s: {what}")
        time.sleep(0.01)


def test_a_bad_topic_or_qos_and_a_closed_link_are_errors_naming_the_topic(embedded_broker: BrokerAddress) -> None:
    link = MqttLink(embedded_broker, "vehicle")
    link.connect()
    with pytest.raises(ValueError, match=r"^cannot publish to topic='fleet/\+/state' with qos=0: "):
        link.publish("fleet/+/state", b"")
    with pytest.raises(ValueError, match=r"^cannot subscribe to topics=\['fleet/v1/order'\] with qos=3: "):
        link.subscribe("fleet/v1/order", qos=3)
    link.publish("fleet/v1/state", b"")  # the same link, a valid topic: sent
    link.disconnect()
    with pytest.raises(
        BrokerError, match=rf"^cannot publish to 'fleet/v1/state' on the MQTT broker at {embedded_broker.url}: "
    ):
        link.publish("fleet/v1/state", b"")


def test_an_inbound_limit_below_one_is_rejected() -> None:
    with pytest.raises(ValueError, match=r"inbound_limit=0 must be >= 1"):
        MqttLink(BrokerAddress("127.0.0.1", 1883), "vehicle", inbound_limit=0)


# -- unreachable and stopped brokers ----------------------------------------------------------------------------


def _closed_port() -> int:
    with socket.socket() as probe:  # bound, never listening: a connect is refused
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def test_an_unreachable_broker_is_a_broker_error_naming_it_within_the_timeout() -> None:
    address = BrokerAddress("127.0.0.1", _closed_port())
    link = MqttLink(address, "vehicle")
    start = time.monotonic()
    with pytest.raises(BrokerError, match=rf"^cannot reach the MQTT broker at mqtt://127\.0\.0\.1:{address.port}: "):
        link.connect(timeout=2.0)
    assert time.monotonic() - start < 2.0
    assert not link.connected

    with pytest.raises(BrokerError, match=rf"^cannot reach the MQTT broker at mqtt://127\.0\.0\.1:{address.port}: "):
        check_reachable(address, timeout=2.0)


def test_a_reachable_broker_passes_the_check(broker: BrokerAddress) -> None:
    check_reachable(broker, timeout=2.0)


def test_a_link_records_a_lost_connection_when_its_broker_stops() -> None:
    with EmbeddedBroker() as running:
        link = MqttLink(running.address, "vehicle")
        link.connect()
        assert link.connected
        assert link.lost is None
    _wait_until(lambda: link.lost is not None, "the loss recorded", timeout=2.0)
    assert not link.connected
    assert str(link.lost).startswith(f"lost the connection to the MQTT broker at {link.address.url} ")
    link.disconnect()
    assert link.lost is not None  # a later disconnect does not forget the loss


# -- broker URLs -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("mqtt://localhost", BrokerAddress("localhost", 1883)),
        ("mqtt://broker.example:1884", BrokerAddress("broker.example", 1884)),
        ("mqtts://broker.example", BrokerAddress("broker.example", 8883, tls=True)),
        ("mqtt://fleet@broker.example", BrokerAddress("broker.example", 1883, username="fleet")),
        ("mqtt://us%40er:p%3Ass@h:1", BrokerAddress("h", 1, username="us@er", password="p:ss")),
        ("mqtt://[::1]:1883", BrokerAddress("::1", 1883)),
        (" mqtt://h:2 ", BrokerAddress("h", 2)),
    ],
)
def test_a_broker_url_gives_its_address(text: str, expected: BrokerAddress) -> None:
    assert parse_broker_url(text) == expected


def test_the_url_and_repr_of_an_address_never_show_the_password() -> None:
    address = parse_broker_url("mqtts://fleet:s3cret@[::1]:8884")
    assert address.url == "mqtts://[::1]:8884"
    assert str(address) == address.url
    assert "s3cret" not in repr(address)
    assert address.password == "s3cret"


def test_tls_settings_belong_to_an_mqtts_url() -> None:
    address = parse_broker_url("mqtts://h", ca_file="ca.pem", cert_file="c.pem", key_file="k.pem", insecure=True)
    assert (str(address.ca_file), str(address.cert_file), str(address.key_file)) == ("ca.pem", "c.pem", "k.pem")
    assert address.insecure and address.tls
    with pytest.raises(BrokerError, match=r"'mqtt://h' is not mqtts:// but ca_file \(TLS\) given"):
        parse_broker_url("mqtt://h", ca_file="ca.pem")
    with pytest.raises(BrokerError, match=r"'mqtts://h' needs cert_file for key_file='k.pem'"):
        parse_broker_url("mqtts://h", key_file="k.pem")


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("localhost:1883", "has no scheme"),
        ("", "has no scheme"),
        ("http://broker.example", "has the scheme 'http'"),
        ("mqtt://", "has no host"),
        ("mqtt://user@:1883", "has no host"),
        ("mqtt://h:0", "has a port that is not a number from 1 to 65535"),
        ("mqtt://h:70000", "has a port that is not a number from 1 to 65535"),
        ("mqtt://h:port", "has a port that is not a number from 1 to 65535"),
        ("mqtt://h/uagv/v2", "has a path, query or fragment after the host"),
        ("mqtt://h?clean=1", "has a path, query or fragment after the host"),
        ("mqtt://[::1", "is not a URL"),
    ],
)
def test_a_malformed_broker_url_is_a_usage_error_naming_it(text: str, problem: str) -> None:
    with pytest.raises(BrokerError) as caught:
        parse_broker_url(text)
    message = str(caught.value)
    assert message.startswith(f"broker URL {text!r} {problem}")
    assert FORM in message
    assert isinstance(caught.value, PlannerSpecError)  # the CLI's exit status 2, pytest's usage error
    assert isinstance(caught.value, ValueError)


def test_a_malformed_broker_url_is_shown_without_its_password() -> None:
    with pytest.raises(BrokerError) as caught:
        parse_broker_url("mqtt://fleet:s3cret@h:port")
    assert "'mqtt://fleet:***@h:port' has a port" in str(caught.value)
    assert "s3cret" not in str(caught.value)
    assert caught.value.address == "mqtt://fleet:***@h:port"


# -- where the brokers listen, and the embedded broker's stop ----------------------------------------------------


def _non_loopback_address() -> str | None:
    """This machine's address on its network, when it has one (not 127.x)."""
    candidates = []
    with contextlib.suppress(OSError):
        candidates.append(socket.gethostbyname(socket.gethostname()))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe, contextlib.suppress(OSError):
        probe.connect(("192.0.2.1", 9))  # a UDP "connect" sends nothing; it picks the outgoing interface
        candidates.append(probe.getsockname()[0])
    return next((ip for ip in candidates if not ip.startswith("127.") and ip != "0.0.0.0"), None)


def _listening_addresses(port: int) -> set[str]:
    """The local addresses (hex, as the kernel writes them) of sockets listening on ``port`` (Linux)."""
    addresses = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with contextlib.suppress(FileNotFoundError), open(table, encoding="ascii") as rows:
            for row in list(rows)[1:]:
                local, _remote, state = row.split()[1:4]
                address, hex_port = local.split(":")
                if state == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
                    addresses.add(address)
    return addresses


def test_the_broker_listens_on_loopback_only(broker: BrokerAddress) -> None:
    socket.create_connection(("127.0.0.1", broker.port), timeout=2.0).close()  # open on loopback
    # What the kernel says the broker is bound to: 127.0.0.1 only (IPv4 loopback, or ::1), whatever the
    # machine's network.
    assert _listening_addresses(broker.port) <= {"0100007F", "00000000000000000000000001000000"}
    assert _listening_addresses(broker.port)
    outside = _non_loopback_address()
    if outside is not None:  # and, where the machine has an address of its own, it is closed there
        with pytest.raises(OSError):
            socket.create_connection((outside, broker.port), timeout=2.0).close()


def _bind(port: int) -> socket.socket:
    """A listening socket on ``port``; SO_REUSEADDR so that closed connections in TIME_WAIT do not count."""
    sock = socket.socket()
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(("127.0.0.1", port))
        sock.listen()
    except OSError:
        sock.close()
        raise
    return sock


def test_the_embedded_broker_stops_within_5_s_and_frees_its_port() -> None:
    with EmbeddedBroker() as running:
        port = running.address.port
        client = MqttLink(running.address, "vehicle")
        client.connect()
        with pytest.raises(OSError) as taken:
            _bind(port)
        assert taken.value.errno == errno.EADDRINUSE
        start = time.monotonic()
    assert time.monotonic() - start < 5.0
    _bind(port).close()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
    client.disconnect()


def test_the_embedded_broker_retries_a_taken_port_and_then_says_why_it_did_not_start(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    with _bind(0) as holder:
        taken: int = holder.getsockname()[1]
        tried: list[int] = []

        def always_taken() -> int:
            tried.append(taken)
            return taken

        monkeypatch.setattr(broker_module, "_free_port", always_taken)
        with pytest.raises(BrokerError, match=r"^the embedded MQTT broker did not start: .*address already in use"):
            EmbeddedBroker().__enter__()
    assert len(tried) == broker_module._PORT_ATTEMPTS


def _connect_once(address: BrokerAddress) -> None:
    link = MqttLink(address, "vehicle")
    link.connect()
    link.subscribe("fleet/v1/order")
    link.disconnect()


def test_the_embedded_broker_logs_nothing_unless_verbose(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG)
    with EmbeddedBroker() as quiet:
        _connect_once(quiet.address)
    assert [record.name for record in caplog.records if record.name.startswith(("amqtt", "transitions"))] == []

    with EmbeddedBroker(verbose=True) as verbose:
        _connect_once(verbose.address)
    assert any(record.name.startswith("amqtt") for record in caplog.records)


def test_a_mosquitto_that_will_not_start_is_a_broker_error_with_its_status(tmp_path: Path) -> None:
    with pytest.raises(BrokerError, match=r"mosquitto \(/bin/false\) for mqtt://127\.0\.0\.1:\d+ exited with status 1"):
        Mosquitto("/bin/false", tmp_path).__enter__()


def test_a_started_mosquitto_accepts_connections_and_is_stopped_on_leaving(tmp_path: Path) -> None:
    with Mosquitto(mosquitto_executable(), tmp_path) as running:
        check_reachable(running.address, timeout=2.0)
        process = running.process
        assert process is not None
    assert process.poll() is not None and running.process is None
