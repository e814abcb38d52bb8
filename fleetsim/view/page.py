"""The viewer page: one HTML file with its script, its style and (for a recorded run) the run itself.

The page is plain HTML, CSS and JavaScript drawing on a canvas, shipped as three files beside this module
and put together here: no build step, no library, nothing fetched. A recorded run's view document
(:mod:`fleetsim.view.document`) is embedded in the page, gzip-compressed and base64-encoded when it is
large (the page unpacks it with the browser's own ``DecompressionStream``); its Content-Security-Policy
lets it make no request at all. A live page embeds only where its WebSocket is (``/live``) and connects
back to the server that sent it.
"""

from __future__ import annotations

import base64
import gzip
import json
from functools import cache
from pathlib import Path
from typing import Any

import orjson

__all__ = ["COMPRESS_FROM", "live_page", "recorded_page"]

COMPRESS_FROM = 256 * 1024  # documents larger than this (bytes of JSON) are embedded compressed
_HERE = Path(__file__).parent


@cache
def _template() -> str:
    html = (_HERE / "page.html").read_text(encoding="utf-8")
    css = (_HERE / "page.css").read_text(encoding="utf-8")
    js = (_HERE / "page.js").read_text(encoding="utf-8")
    return html.replace("/*FLEETSIM-CSS*/", css).replace("/*FLEETSIM-JS*/", js)


def _page(data: str, encoding: str) -> str:
    head, _, tail = _template().partition("/*FLEETSIM-DATA*/")
    return head.replace("/*FLEETSIM-ENCODING*/", encoding) + data + tail


def recorded_page(document: dict[str, Any], *, compress_from: int = COMPRESS_FROM) -> str:
    """The self-contained page of a recorded run's view document."""
    encoded = orjson.dumps(document)  # as json.dumps writes it, compact, in UTF-8, several times faster
    if len(encoded) >= compress_from:
        # The fastest level: a large run's page is written in a fraction of the time level 6 takes, for
        # a few percent more bytes.
        packed = gzip.compress(encoded, compresslevel=1, mtime=0)
        return _page(base64.b64encode(packed).decode("ascii"), "gzip+base64")
    # Inside <script>, "</" could end the element: JSON allows "<\/" for it.
    return _page(encoded.decode("utf-8").replace("</", "<\\/"), "json")


def live_page(socket_path: str = "/live") -> str:
    """The page of a live run: it connects to ``socket_path`` on the server that sent it."""
    return _page(json.dumps({"format": "fleetsim-view/1", "live": True, "socket": socket_path}), "json")
