"""Watching a run: a browser page that replays a recorded run or follows a live one, with time control.

It reads the trace format (through :mod:`fleetsim.recording.replay`) and the result document, never the
simulator's internals: :mod:`~fleetsim.view.document` makes what the page draws, :mod:`~fleetsim.view.page`
the page, :mod:`~fleetsim.view.server` serves it on a loopback port and :mod:`~fleetsim.view.live` paces a
live run and streams it to the pages watching.
"""

from fleetsim.view.artifact import VIEW_FILE, recorded_view, write_view_file
from fleetsim.view.document import VIEW_FORMAT, StepRecords, outcome_part, scene_part, view_document
from fleetsim.view.live import LiveRun, Pacer
from fleetsim.view.page import live_page, recorded_page
from fleetsim.view.server import PageServer
from fleetsim.view.session import LiveSession

__all__ = [
    "VIEW_FILE",
    "VIEW_FORMAT",
    "LiveRun",
    "LiveSession",
    "Pacer",
    "PageServer",
    "StepRecords",
    "live_page",
    "outcome_part",
    "recorded_page",
    "recorded_view",
    "scene_part",
    "view_document",
    "write_view_file",
]
