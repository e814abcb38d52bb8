"""Where the MQTT broker of a VDA 5050 run is: an address parsed from the user's URL, or a broker fleetsim
starts itself (:class:`EmbeddedBroker`, amqtt in a thread of its own) when the user gives none.

A broker that is badly written or cannot be reached is a :class:`BrokerError`; it is a mistake in the
``vda5050:`` planner spec, so the command line and the pytest plugin show it as a usage error.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import os
import re
import shutil
import socket
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any
from urllib.parse import unquote, urlsplit

from fleetsim.specs.python import PlannerSpecError

__all__ = [
    "BrokerAddress",
    "BrokerError",
    "EmbeddedBroker",
    "Mosquitto",
    "check_reachable",
    "find_mosquitto",
    "parse_broker_url",
]

_FORM = "mqtt://[user[:password]@]host[:port] (port 1883 by default) or mqtts://... (TLS, port 8883)"
_DEFAULT_PORTS = {"mqtt": 1883, "mqtts": 8883}
_PORT_ATTEMPTS = 5  # free ports tried when another process takes the one found between look-up and bind
_MOSQUITTO = "/usr/sbin/mosquitto"  # Debian installs it outside a user's PATH
_MOSQUITTO_START_TIMEOUT = 5.0  # seconds until a started mosquitto must accept connections
_AMQTT_LOGGERS = ("amqtt", "transitions")  # transitions: the state machine library amqtt logs through


class BrokerError(PlannerSpecError):
    """The MQTT broker cannot be used: its URL is malformed, it cannot be reached or started, or it refused
    a client. ``address`` names the broker (a URL without its password).

    It is a `PlannerSpecError` because the broker is part of what the ``vda5050:`` planner spec names.
    """

    def __init__(self, message: str, address: str) -> None:
        self.address = address
        super().__init__(message, address)


@dataclass(frozen=True, slots=True)
class BrokerAddress:
    """An MQTT broker and how to log in to it. ``password`` is never shown (not in ``url``, not in repr).

    ``insecure`` turns off the checks of the broker's certificate and host name (a test broker with a
    self-signed certificate); ``ca_file`` is the better way to trust such a broker.
    """

    host: str
    port: int
    username: str | None = None
    password: str | None = field(default=None, repr=False)
    tls: bool = False
    ca_file: Path | None = None
    cert_file: Path | None = None
    key_file: Path | None = None
    insecure: bool = False

    @property
    def url(self) -> str:
        """``mqtt://host:port`` (``mqtts://`` with TLS): the broker as messages name it, without the login."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{'mqtts' if self.tls else 'mqtt'}://{host}:{self.port}"

    def __str__(self) -> str:
        return self.url


def parse_broker_url(
    text: str,
    *,
    ca_file: str | os.PathLike[str] | None = None,
    cert_file: str | os.PathLike[str] | None = None,
    key_file: str | os.PathLike[str] | None = None,
    insecure: bool = False,
) -> BrokerAddress:
    """The broker ``text`` names: ``mqtt://[user[:password]@]host[:port]`` or ``mqtts://`` for TLS.

    User name and password may be percent-encoded (``%40`` for ``@``). The TLS files belong to an
    ``mqtts://`` broker only. A mistake is a :class:`BrokerError` that shows ``text`` (its password hidden).
    """
    shown = _without_password(text)

    def error(problem: str) -> BrokerError:
        return BrokerError(f"broker URL {shown!r} {problem}: expected {_FORM}", shown)

    try:
        parts = urlsplit(text.strip())
    except ValueError as exc:  # an unbalanced "[" of an IPv6 host
        raise error(f"is not a URL ({exc})") from None
    if "://" not in text:  # "localhost:1883" would read as the scheme "localhost"
        raise error("has no scheme")
    if parts.scheme not in _DEFAULT_PORTS:
        raise error(f"has the scheme {parts.scheme!r}")
    if parts.path not in ("", "/") or parts.query or parts.fragment:
        raise error("has a path, query or fragment after the host")
    if not parts.hostname:
        raise error("has no host")
    try:
        port = parts.port
    except ValueError:
        raise error("has a port that is not a number from 1 to 65535") from None
    if port == 0:
        raise error("has a port that is not a number from 1 to 65535")
    tls = parts.scheme == "mqtts"
    files = {"ca_file": ca_file, "cert_file": cert_file, "key_file": key_file}
    given = [name for name, value in files.items() if value is not None]
    if given and not tls:
        raise error(f"is not mqtts:// but {', '.join(given)} (TLS) given")
    if insecure and not tls:
        raise error("is not mqtts:// but insecure=True (a TLS setting) given")
    if key_file is not None and cert_file is None:
        raise error(f"needs cert_file for key_file={str(key_file)!r}")
    return BrokerAddress(
        host=parts.hostname,
        port=port if port is not None else _DEFAULT_PORTS[parts.scheme],
        username=unquote(parts.username) if parts.username else None,
        password=unquote(parts.password) if parts.password is not None else None,
        tls=tls,
        ca_file=_path(ca_file),
        cert_file=_path(cert_file),
        key_file=_path(key_file),
        insecure=insecure,
    )


def _without_password(text: str) -> str:
    """``text`` with the password of its ``user:password@`` part replaced by ``***`` (safe to show)."""
    return re.sub(r"(//[^/@:]*:)[^/@]*@", r"\1***@", text)


def _path(value: str | os.PathLike[str] | None) -> Path | None:
    return None if value is None else Path(value)


def check_reachable(address: BrokerAddress, timeout: float = 5.0) -> None:
    """Raise :class:`BrokerError` unless a TCP connection to ``address`` opens within ``timeout`` seconds.

    Only TCP: a TLS or login problem shows when a client connects, with the broker's own reason.
    """
    try:
        socket.create_connection((address.host, address.port), timeout=timeout).close()
    except OSError as exc:
        reason = "timed out" if isinstance(exc, TimeoutError) else exc.strerror or str(exc)
        msg = f"cannot reach the MQTT broker at {address.url}: {reason}"
        raise BrokerError(msg, address.url) from None


class EmbeddedBroker:
    """An MQTT 3.1.1 broker (amqtt) in a daemon thread with its own event loop, for a run without ``--broker``.

    It listens on 127.0.0.1 only, on a free port, lets anonymous clients in and keeps nothing on disk: the
    vehicles and a master control on the same machine meet there, nobody else can. Use it as a context
    manager; ``address`` is where it listens. amqtt's logging is silenced unless ``verbose``.
    """

    def __init__(self, *, verbose: bool = False, start_timeout: float = 10.0, stop_timeout: float = 4.0) -> None:
        self._verbose = verbose
        self._start_timeout = start_timeout
        self._stop_timeout = stop_timeout
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._started = threading.Event()
        self._failure: str | None = None
        self._port: int | None = None

    @property
    def address(self) -> BrokerAddress:
        """Where the running broker listens (``mqtt://127.0.0.1:PORT``)."""
        if self._port is None:
            msg = "EmbeddedBroker.address: the broker is not running (use it as a context manager)"
            raise RuntimeError(msg)
        return BrokerAddress(host="127.0.0.1", port=self._port)

    def __enter__(self) -> EmbeddedBroker:
        if self._thread is not None:
            msg = "an EmbeddedBroker starts once; make a new one"
            raise RuntimeError(msg)
        _quiet_amqtt(self._verbose)
        self._thread = threading.Thread(target=self._serve, name="fleetsim-embedded-mqtt-broker", daemon=True)
        self._thread.start()
        if not self._started.wait(self._start_timeout):
            self._request_stop()
            msg = f"the embedded MQTT broker did not start within {self._start_timeout} s"
            raise BrokerError(msg, "embedded")
        if self._failure is not None:
            self._thread.join(self._stop_timeout)
            msg = f"the embedded MQTT broker did not start: {self._failure}"
            raise BrokerError(msg, "embedded")
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, traceback: TracebackType | None
    ) -> None:
        self.close()

    def close(self) -> None:
        """Stop the broker (its clients are disconnected) and wait for its thread, at most about 5 s."""
        thread = self._thread
        if thread is None:
            return
        self._request_stop()
        thread.join(self._stop_timeout + 1.0)
        self._port = None

    def _request_stop(self) -> None:
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None:
            with contextlib.suppress(RuntimeError):  # the loop is closed already: the broker has stopped
                loop.call_soon_threadsafe(stop.set)

    def _serve(self) -> None:
        try:
            asyncio.run(self._run())
        except Exception as exc:  # reported to the starting thread; a daemon thread must not die loudly
            if not self._started.is_set():
                self._failure = _reason(exc)
                self._started.set()

    async def _run(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        broker = await self._start()
        self._started.set()
        try:
            await self._stop.wait()
        finally:
            # amqtt waits up to 5 s for its broadcasts: bounded here so that close() keeps its promise.
            await asyncio.wait_for(broker.shutdown(), self._stop_timeout)

    async def _start(self) -> Any:
        from amqtt.broker import Broker  # type: ignore[import-untyped]  # amqtt ships no type hints

        attempt = 1
        while True:
            port = _free_port()
            broker = Broker(_amqtt_config(port))
            try:
                await broker.start()
            except Exception as exc:
                if not _port_taken(exc) or attempt == _PORT_ATTEMPTS:
                    raise
                attempt += 1
                continue
            self._port = port
            return broker


def find_mosquitto() -> str | None:
    """The mosquitto broker's executable: on PATH, or where Debian puts it; None when it is not installed."""
    return shutil.which("mosquitto") or (_MOSQUITTO if os.access(_MOSQUITTO, os.X_OK) else None)


class Mosquitto:
    """A mosquitto broker of its own (``executable``) on a free port of 127.0.0.1, with a minimal
    configuration in ``folder`` (one loopback listener, anonymous clients, nothing kept on disk), for
    tests and benchmarks that need a broker in another process. Use it as a context manager: on entering
    it accepts connections (:attr:`address`; started again on another port when another process took the
    port), on leaving it is stopped. One that will not start is a :class:`BrokerError` with its log."""

    def __init__(self, executable: str, folder: Path) -> None:
        self.executable, self.folder = executable, folder
        self.address = BrokerAddress("127.0.0.1", 0)
        self.process: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> Mosquitto:
        config, log = self.folder / "mosquitto.conf", self.folder / "mosquitto.log"
        status: int | None = None
        text = ""
        for _attempt in range(_PORT_ATTEMPTS):
            self.address = BrokerAddress("127.0.0.1", _free_port())
            config.write_text(f"listener {self.address.port} 127.0.0.1\nallow_anonymous true\npersistence false\n")
            # Its log goes to a file: a pipe nobody reads would block mosquitto once full.
            with log.open("wb") as output:
                process = subprocess.Popen(
                    [self.executable, "-c", str(config)], stdout=output, stderr=subprocess.STDOUT
                )
            deadline = time.monotonic() + _MOSQUITTO_START_TIMEOUT
            while process.poll() is None and time.monotonic() < deadline:
                try:
                    check_reachable(self.address, timeout=0.5)
                except BrokerError:
                    time.sleep(0.02)
                    continue
                self.process = process
                return self
            status = process.poll()
            _stop(process)
            text = log.read_text(errors="replace")
            if "Address already in use" not in text:
                break
        how = (
            f"exited with status {status}"
            if status is not None
            else f"did not listen within {_MOSQUITTO_START_TIMEOUT} s"
        )
        msg = f"mosquitto ({self.executable}) for {self.address.url} {how}:\n{text}"
        raise BrokerError(msg, self.address.url)

    def __exit__(
        self, kind: type[BaseException] | None, value: BaseException | None, traceback: TracebackType | None
    ) -> None:
        if self.process is not None:
            _stop(self.process)
            self.process = None


def _stop(process: subprocess.Popen[bytes]) -> None:
    process.terminate()
    try:
        process.wait(5)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(5)


def _amqtt_config(port: int) -> dict[str, Any]:
    """amqtt's broker configuration: one TCP listener on loopback, anonymous clients, no $SYS topics,
    no persistence and no packet logging (only the plugins named here are loaded)."""
    return {
        "listeners": {"default": {"type": "tcp", "bind": f"127.0.0.1:{port}"}},
        "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
    }


def _free_port() -> int:
    """A loopback port nothing listens on now (another process may take it before the broker binds it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def _port_taken(exc: BaseException) -> bool:
    cause: BaseException | None = exc
    while cause is not None:  # amqtt wraps the OSError of the bind in its own BrokerError
        if isinstance(cause, OSError) and cause.errno == errno.EADDRINUSE:
            return True
        cause = cause.__cause__
    return False


def _reason(exc: BaseException) -> str:
    """The innermost cause of ``exc`` as one line (amqtt wraps the OSError that says what went wrong)."""
    while exc.__cause__ is not None:
        exc = exc.__cause__
    return f"{type(exc).__name__}: {exc}"


_silenced: set[str] = set()


def _quiet_amqtt(verbose: bool) -> None:
    """amqtt logs every connection and packet: keep it quiet unless fleetsim runs verbose. A level the user
    configured on amqtt's loggers is left as it is."""
    for name in _AMQTT_LOGGERS:
        logger = logging.getLogger(name)
        if verbose and name in _silenced:
            logger.setLevel(logging.NOTSET)
            _silenced.discard(name)
        elif not verbose and logger.level == logging.NOTSET:
            logger.setLevel(logging.CRITICAL)
            _silenced.add(name)
