"""The loopback server of a viewer page: the page at ``/``, a live run's WebSocket at ``/live``.

Built on ``websockets`` (its threaded server): one small, well-kept library that speaks both plain HTTP
(for the page) and WebSocket (for a live run), with no event loop for the simulation to share. Each
connection is served in a thread of its own, so a slow or closed page never holds up the run.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from http import HTTPStatus
from typing import Any

__all__ = ["PageServer"]

_LOOPBACK = "127.0.0.1"


class PageServer:
    """Serves ``page`` (HTML) at ``/``; ``on_socket(connection)`` serves each WebSocket at ``/live``."""

    def __init__(
        self,
        page: str,
        *,
        port: int = 0,
        host: str = _LOOPBACK,
        on_socket: Callable[[Any], None] | None = None,
    ) -> None:
        from websockets.datastructures import Headers
        from websockets.http11 import Response
        from websockets.sync.server import serve

        body = page.encode("utf-8")
        self._on_socket = on_socket

        def respond(status: HTTPStatus, kind: str, content: bytes) -> Any:
            headers = [("Content-Type", kind), ("Content-Length", str(len(content))), ("Cache-Control", "no-store")]
            return Response(status.value, status.phrase, Headers(headers), content)

        def process_request(connection: Any, request: Any) -> Any:
            path = request.path.split("?", 1)[0]
            if path in ("/", "/index.html"):
                return respond(HTTPStatus.OK, "text/html; charset=utf-8", body)
            if path == "/live" and on_socket is not None:
                return None  # the WebSocket handshake goes on
            return respond(HTTPStatus.NOT_FOUND, "text/plain; charset=utf-8", f"{path}: the page is at /\n".encode())

        self._server = serve(
            self._handle, host, port, process_request=process_request, compression=None, max_size=2**20
        )
        self.host = host
        self.port: int = self._server.socket.getsockname()[1]
        self._thread = threading.Thread(target=self._server.serve_forever, name="fleetsim-view", daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/"

    def _handle(self, connection: Any) -> None:
        if self._on_socket is not None:
            self._on_socket(connection)

    def wait(self) -> None:
        """Until the server is closed (Ctrl-C raises KeyboardInterrupt here)."""
        while self._thread.is_alive():
            self._thread.join(timeout=0.5)

    def close(self) -> None:
        self._server.shutdown()
        self._thread.join(timeout=5)

    def __enter__(self) -> PageServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
