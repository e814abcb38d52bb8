"""One MQTT client connection of a VDA 5050 vehicle (or of a test's master control): a thin, thread-safe
wrapper of paho-mqtt that speaks MQTT 3.1.1 as VDA 5050 asks.

paho runs the network in a thread of its own; what arrives there waits in a bounded buffer until the
simulation's loop takes it with :meth:`MqttLink.drain`. The buffer drops its oldest messages when full, so
a master control that floods a vehicle costs a count (``dropped``), never unbounded memory. A lost
connection is recorded in ``lost`` for the loop to report; nothing is raised in paho's thread, and the
link does not reconnect by itself (the subscriptions of a clean MQTT session would be gone).
"""

from __future__ import annotations

import contextlib
import socket
import ssl
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

from paho.mqtt.client import (
    Client,
    ConnectFlags,
    DisconnectFlags,
    MQTTMessage,
    MQTTv311,
    error_string,
    topic_matches_sub,
)
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode
from paho.mqtt.properties import Properties
from paho.mqtt.reasoncodes import ReasonCode

from fleetsim.vda5050.broker import BrokerAddress, BrokerError

__all__ = ["Inbound", "MqttLink", "Will"]

_KEEPALIVE = 60  # seconds; VDA 5050 leaves it to the implementation
_CLOSE_TIMEOUT = 5.0  # seconds a clean disconnect may take before the socket is shut regardless


@dataclass(frozen=True, slots=True)
class Will:
    """The last will the broker publishes when the link ends without DISCONNECT (VDA 5050: the vehicle's
    ``connection`` topic with ``connectionState`` CONNECTIONBROKEN, QoS 1, retained)."""

    topic: str
    payload: bytes
    qos: int = 1
    retain: bool = True


@dataclass(frozen=True, slots=True)
class Inbound:
    """A message as it arrived: ``received`` is ``time.monotonic()`` when paho handed it over; ``retained``:
    the broker kept it from before the subscription (history, not news)."""

    topic: str
    payload: bytes
    received: float
    retained: bool = False


class MqttLink:
    """A client of the broker at ``address`` with MQTT client id ``client_id``.

    Call :meth:`connect` first; :meth:`disconnect` (clean, no last will) or :meth:`abort` (as if the
    client crashed: the broker publishes ``will``) end it. At most ``inbound_limit`` messages wait for
    :meth:`drain`. Every method may be called from any thread except paho's own (the callbacks).
    """

    def __init__(
        self, address: BrokerAddress, client_id: str, *, will: Will | None = None, inbound_limit: int = 10_000
    ) -> None:
        if inbound_limit < 1:
            msg = f"inbound_limit={inbound_limit!r} must be >= 1"
            raise ValueError(msg)
        self.address = address
        self.client_id = client_id
        self._inbound: deque[Inbound] = deque(maxlen=inbound_limit)
        self._dropped = 0
        self._arrived = threading.Condition()
        self._connack = threading.Event()
        self._refused: str | None = None
        self._was_connected = False
        self._closing = False  # our own disconnect() or abort(): not a loss
        self._closed = threading.Event()  # paho has closed the connection (on_disconnect ran)
        self._lost: str | None = None
        self._acks: dict[int, list[ReasonCode]] = {}
        self._acked = threading.Condition()
        self._requested: dict[int, tuple[str, ...]] = {}  # the filters of each SUBSCRIBE, by packet id
        self._filters: tuple[str, ...] = ()  # the acknowledged ones; only paho's thread replaces it
        self._unsolicited = 0
        self._started = False

        client = Client(
            callback_api_version=CallbackAPIVersion.VERSION2,
            client_id=client_id,
            protocol=MQTTv311,
            reconnect_on_failure=False,
        )
        if address.username is not None:
            client.username_pw_set(address.username, address.password)
        if address.tls:
            client.tls_set_context(_tls_context(address))
        if will is not None:
            try:
                client.will_set(will.topic, will.payload, qos=will.qos, retain=will.retain)
            except ValueError as exc:  # paho's "Invalid topic." names nothing
                msg = f"MqttLink {client_id!r}: will {will.topic!r} (qos={will.qos!r}) is not a valid last will: {exc}"
                raise ValueError(msg) from None
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_subscribe = self._on_subscribe
        client.on_message = self._on_message
        self._client = client

    # -- state -------------------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """Whether the connection to the broker is up (CONNACK received, not closed since)."""
        return self._client.is_connected()

    @property
    def lost(self) -> str | None:
        """Why the connection closed without :meth:`disconnect` or :meth:`abort`; None while it has not."""
        return self._lost

    @property
    def dropped(self) -> int:
        """How many messages were dropped, oldest first, because ``inbound_limit`` were waiting already."""
        with self._arrived:
            return self._dropped

    @property
    def unsolicited(self) -> int:
        """How many messages were ignored because no acknowledged subscription of this link matches them.

        amqtt 0.12 sends a client, as it connects, the retained messages of every topic any client has
        subscribed to; a vehicle must not take another vehicle's retained ``connection`` for its own.
        """
        with self._arrived:
            return self._unsolicited

    @property
    def pending(self) -> int:
        """How many messages wait for :meth:`drain`."""
        with self._arrived:
            return len(self._inbound)

    # -- connecting --------------------------------------------------------------------------------------

    def connect(self, timeout: float = 5.0) -> None:
        """Open the connection and wait for the broker's CONNACK, at most ``timeout`` seconds in all.

        :class:`BrokerError` names the broker and the reason when it cannot be reached or refuses.
        """
        if self._started:
            msg = f"MqttLink {self.client_id!r}: connect() was called already; make a new link"
            raise RuntimeError(msg)
        self._started = True
        url = self.address.url
        deadline = time.monotonic() + timeout
        self._client.connect_timeout = timeout
        try:
            self._client.connect(self.address.host, self.address.port, keepalive=_KEEPALIVE)
        except (OSError, ValueError) as exc:  # refused, no route, name unknown, TLS handshake failed
            reason = "timed out" if isinstance(exc, TimeoutError) else _os_reason(exc)
            msg = f"cannot reach the MQTT broker at {url}: {reason}"
            raise BrokerError(msg, url) from None
        self._client.loop_start()
        answered = self._connack.wait(max(0.0, deadline - time.monotonic()))
        if answered and self._refused is None:
            return
        self._shut()
        if not answered:
            msg = f"the MQTT broker at {url} did not accept client {self.client_id!r} within {timeout} s"
        else:
            msg = f"the MQTT broker at {url} refused client {self.client_id!r}: {self._refused}"
        raise BrokerError(msg, url)

    def disconnect(self) -> None:
        """Close the connection cleanly (DISCONNECT: the broker does not publish the last will)."""
        self._closing = True
        if self._started and self._client.disconnect() == MQTTErrorCode.MQTT_ERR_SUCCESS:
            self._closed.wait(_CLOSE_TIMEOUT)
        self._shut()

    def abort(self) -> None:
        """Drop the connection without DISCONNECT, as a crashed client would: the broker publishes the will.

        paho has no public call for this. Shutting down the socket paho's public ``socket()`` returns makes
        its network thread read end-of-file and close the connection itself, as when the network fails;
        closing the socket under that thread instead would race with it.
        """
        self._closing = True
        self._shut()

    def _shut(self) -> None:
        """End the network thread, shutting the socket first if paho still holds it (bounded in time)."""
        sock = self._client.socket()
        if isinstance(sock, socket.socket):  # an ssl.SSLSocket too; None once paho has closed it
            with contextlib.suppress(OSError):  # closed by paho in the meantime
                # The plain socket's shutdown, also under TLS: SSLSocket.shutdown would unwrap the TLS
                # object under paho's thread, which may be reading through it.
                socket.socket.shutdown(sock, socket.SHUT_RDWR)
            self._closed.wait(_CLOSE_TIMEOUT)
        self._client.loop_stop()

    # -- messages ----------------------------------------------------------------------------------------

    def subscribe(self, *topics: str, qos: int = 0, timeout: float = 5.0) -> None:
        """Subscribe to ``topics`` (filters; ``+`` and ``#`` allowed) and wait for the broker's SUBACK.

        Messages count from the SUBACK on (brokers send a subscription's retained messages after it): what
        arrives on these topics before it is ignored as unsolicited.
        """
        if not topics:
            msg = "subscribe() needs at least one topic"
            raise ValueError(msg)
        url = self.address.url
        with self._acked:  # held until the packet id is known: the SUBACK's callback takes this lock too
            try:
                result, mid = self._client.subscribe([(topic, qos) for topic in topics])
            except ValueError as exc:  # an empty topic, a QoS outside 0..2: paho names neither
                msg = f"cannot subscribe to topics={list(topics)!r} with qos={qos!r}: {exc}"
                raise ValueError(msg) from None
            if mid is not None:
                self._requested[mid] = topics
        if result != MQTTErrorCode.MQTT_ERR_SUCCESS or mid is None:
            msg = f"cannot subscribe to {list(topics)!r} on the MQTT broker at {url}: {error_string(result)}"
            raise BrokerError(msg, url)
        with self._acked:
            if not self._acked.wait_for(lambda: mid in self._acks, timeout):
                msg = f"the MQTT broker at {url} did not acknowledge the subscription to {list(topics)!r} within {timeout} s"
                raise BrokerError(msg, url)
            codes = self._acks.pop(mid)
        refused = [topic for topic, code in zip(topics, codes, strict=False) if code.is_failure]
        if refused:
            msg = f"the MQTT broker at {url} refused the subscription to {refused!r}"
            raise BrokerError(msg, url)

    def publish(self, topic: str, payload: bytes, qos: int = 0, retain: bool = False, timeout: float = 5.0) -> None:
        """Send ``payload`` to ``topic``. QoS 0 returns at once; QoS 1 and 2 wait until the broker has it."""
        url = self.address.url
        try:
            info = self._client.publish(topic, payload, qos=qos, retain=retain)
        except ValueError as exc:  # a wildcard or an empty topic, a QoS outside 0..2: paho names neither
            msg = f"cannot publish to topic={topic!r} with qos={qos!r}: {exc}"
            raise ValueError(msg) from None
        if info.rc != MQTTErrorCode.MQTT_ERR_SUCCESS:
            msg = f"cannot publish to {topic!r} on the MQTT broker at {url}: {error_string(info.rc)}"
            raise BrokerError(msg, url)
        if qos > 0:
            try:
                info.wait_for_publish(timeout)
            except RuntimeError as exc:  # the connection closed before the broker acknowledged
                msg = f"the MQTT broker at {url} did not acknowledge the message to {topic!r}: {exc}"
                raise BrokerError(msg, url) from None
            if not info.is_published():
                msg = f"the MQTT broker at {url} did not acknowledge the message to {topic!r} within {timeout} s"
                raise BrokerError(msg, url)

    def drain(self) -> list[Inbound]:
        """The messages that arrived since the last drain, oldest first; the buffer is empty afterwards."""
        with self._arrived:
            items = list(self._inbound)
            self._inbound.clear()
            return items

    def wait(self, timeout: float) -> bool:
        """Block until a message waits for :meth:`drain` or ``timeout`` seconds pass; whether one waits."""
        with self._arrived:
            return self._arrived.wait_for(lambda: bool(self._inbound), timeout)

    # -- paho's callbacks (its network thread) ----------------------------------------------------------

    def _on_connect(
        self, client: Client, userdata: Any, flags: ConnectFlags, reason: ReasonCode, properties: Properties | None
    ) -> None:
        if reason.is_failure:
            self._refused = str(reason)
        else:
            self._was_connected = True
        self._connack.set()

    def _on_disconnect(
        self,
        client: Client,
        userdata: Any,
        flags: DisconnectFlags,
        reason: ReasonCode,
        properties: Properties | None,
    ) -> None:
        if self._was_connected and not self._closing and self._lost is None:
            self._lost = f"lost the connection to the MQTT broker at {self.address.url} (paho: {reason})"
        self._closed.set()

    def _on_subscribe(
        self, client: Client, userdata: Any, mid: int, codes: list[ReasonCode], properties: Properties | None
    ) -> None:
        with self._acked:
            granted = [
                topic for topic, code in zip(self._requested.pop(mid, ()), codes, strict=False) if not code.is_failure
            ]
            self._filters = (*self._filters, *granted)
            self._acks[mid] = codes
            self._acked.notify_all()

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        item = Inbound(message.topic, bytes(message.payload), time.monotonic(), bool(message.retain))
        with self._arrived:
            if not any(topic_matches_sub(sub, item.topic) for sub in self._filters):
                self._unsolicited += 1
                return
            if len(self._inbound) == self._inbound.maxlen:
                self._dropped += 1  # the deque drops its oldest item on append
            self._inbound.append(item)
            self._arrived.notify_all()


def _tls_context(address: BrokerAddress) -> ssl.SSLContext:
    """The TLS settings of ``address``; :class:`BrokerError` when its files cannot be read."""
    try:
        context = ssl.create_default_context(cafile=address.ca_file)
        if address.cert_file is not None:
            context.load_cert_chain(address.cert_file, address.key_file)
    except (OSError, ssl.SSLError) as exc:
        files = {"ca_file": address.ca_file, "cert_file": address.cert_file, "key_file": address.key_file}
        named = ", ".join(f"{name}={str(path)!r}" for name, path in files.items() if path is not None)
        msg = f"cannot use the TLS files for the MQTT broker at {address.url} ({named}): {_os_reason(exc)}"
        raise BrokerError(msg, address.url) from None
    if address.insecure:
        context.check_hostname = False
        context.verify_mode = ssl.CERT_NONE
    return context


def _os_reason(exc: BaseException) -> str:
    return (exc.strerror if isinstance(exc, OSError) else None) or str(exc)
