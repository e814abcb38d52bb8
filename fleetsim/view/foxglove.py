"""A live run over the Foxglove WebSocket protocol: the recording's topics, as the run goes.

The same channels as the MCAP recording (:data:`fleetsim.recording.recorder.TOPICS`: ``/tf``, ``/clock``,
the markers, ``/rosout``, ...), ROS 2 CDR messages with ``ros2msg`` schemas, written by the recording's
own frame writer, so Foxglove opens a running simulation with the layout it uses for recordings. The
server is ``foxglove-sdk``'s (the ``live`` extra), on the loopback interface; it speaks only the
subprotocol ``foxglove.sdk.v1`` (a client that offers ``foxglove.websocket.v1`` alone is refused).

Latched topics (the map, the labels, the URDF, ``/tf_static``) are sent again whenever a client
subscribes to one, so Foxglove connected in the middle of a run still draws the map.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterator
from typing import Any

from fleetsim.errors import FleetsimError
from fleetsim.recording import messages as m
from fleetsim.recording.orders import OrderTracker
from fleetsim.recording.recorder import TOPICS, write_frame
from fleetsim.recording.replay import replay
from fleetsim.recording.scene import Scene
from fleetsim.scenario import Scenario
from fleetsim.sim.result import RunResult

__all__ = ["SUBPROTOCOL", "FoxgloveLive", "FoxgloveMissing"]

SUBPROTOCOL = "foxglove.sdk.v1"
_END = object()


class FoxgloveMissing(FleetsimError, ImportError):
    """``--foxglove`` without the ``foxglove-sdk`` package."""


def _sdk() -> Any:
    try:
        import foxglove
    except ImportError:
        msg = "--foxglove needs the foxglove-sdk package: pip install 'fleetsim[live]'"
        raise FoxgloveMissing(msg) from None
    return foxglove


class _Channels:
    """The recording's channels on a Foxglove server: ``write``/``write_bytes`` as the MCAP writer has them."""

    def __init__(self, foxglove: Any, context: Any) -> None:
        self.channels: dict[str, Any] = {}
        self.latched: dict[str, tuple[bytes, int]] = {}  # topic -> its last message and log time
        self._lock = threading.Lock()
        for topic, (typename, _) in TOPICS.items():
            schema = foxglove.Schema(name=typename, encoding="ros2msg", data=m.schema_text(typename))
            self.channels[topic] = foxglove.Channel(topic, schema=schema, message_encoding="cdr", context=context)

    def write(self, topic: str, time_ns: int, message: Any) -> None:
        self.write_bytes(topic, time_ns, m.serialise(message))

    def write_bytes(self, topic: str, time_ns: int, data: bytes) -> None:
        if TOPICS[topic][1]:
            with self._lock:
                self.latched[topic] = (data, time_ns)
        self.channels[topic].log(data, log_time=time_ns)

    def again(self, topic: str) -> None:
        """A latched topic's last message once more (a client subscribed to it)."""
        with self._lock:
            last = self.latched.get(topic)
        if last is not None:
            self.channels[topic].log(last[0], log_time=last[1])


class FoxgloveLive:
    """A Foxglove WebSocket server for the live runs of one command, on ``127.0.0.1:port`` (0: any free)."""

    def __init__(self, port: int = 8765) -> None:
        foxglove = _sdk()
        self._context = foxglove.Context()
        self._channels = _Channels(foxglove, self._context)
        channels = self._channels

        from foxglove.websocket import ServerListener

        class _Listener(ServerListener):
            def on_subscribe(self, client: Any, channel: Any) -> None:
                if TOPICS.get(channel.topic, ("", False))[1]:
                    threading.Thread(target=channels.again, args=(channel.topic,), daemon=True).start()

        self._server = foxglove.start_server(
            name="fleetsim", host="127.0.0.1", port=port, context=self._context, server_listener=_Listener()
        )
        self.port: int = self._server.port
        self._lines: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._writer: threading.Thread | None = None
        self._scene: Scene | None = None
        self._last: Any = None

    def begin(self, scenario: Scenario) -> Callable[[str], None]:
        """A run of ``scenario`` begins: the watcher its trace lines go to."""
        self._finish()
        self._lines = queue.SimpleQueue()
        self._scene = Scene(scenario)
        self._writer = threading.Thread(
            target=self._write, args=(scenario, self._scene, self._lines), name="fleetsim-foxglove", daemon=True
        )
        self._writer.start()
        return self._lines.put

    def _write(self, scenario: Scenario, scene: Scene, lines: queue.SimpleQueue[Any]) -> None:
        orders = OrderTracker({})

        def taken() -> Iterator[str]:
            nonlocal orders
            while (line := lines.get()) is not _END:
                if line.startswith("{"):
                    orders = OrderTracker.of_trace([line])  # the run's orders, if it has any
                yield line

        shown: Any = None
        for frame in replay(scenario, taken()):
            first = shown is None
            changes = orders.follow(frame)
            write_frame(
                self._channels,
                scene,
                frame,
                first=first,
                tick=True,
                alerts_changed=frame.alerts != shown,
                orders=orders,
                changes=changes,
            )
            shown = frame.alerts
            self._last = frame

    def _finish(self) -> None:
        if self._writer is not None:
            self._lines.put(_END)
            self._writer.join()
            self._writer = None

    def end(self, result: RunResult) -> None:
        """The run ended: its contacts and who waits for whom (a stuck run's), at its last step."""
        self._finish()
        frame, scene = self._last, self._scene
        if frame is None or scene is None:
            return
        time_ns = round(frame.time * 1e9)
        time = m.stamp(time_ns)
        contacts = [c.to_dict() for c in result.contact.contacts] if result.contact is not None else []
        if contacts:
            self._channels.write("/fleetsim/contacts", time_ns, scene.contacts(time, contacts))
        from fleetsim.recording.artifacts import stuck_overlay

        stuck = stuck_overlay(result.failures)
        if stuck:
            self._channels.write("/fleetsim/stuck", time_ns, scene.stuck(time, frame.poses, stuck))

    def close(self) -> None:
        self._finish()
        self._server.stop()
