"""A live viewing session: the page server, the live run it shows, and (if asked) a Foxglove server.

``fleetsim run --live`` and ``pytest --fleetsim-live`` open one session for the whole command; each
scenario's run is shown on it in turn (``begin`` gives the watcher to hand to ``run_scenario``).
"""

from __future__ import annotations

import webbrowser
from collections.abc import Callable, Mapping
from typing import Any

from fleetsim.scenario import Scenario
from fleetsim.sim.result import RunResult
from fleetsim.view.document import outcome_part
from fleetsim.view.live import LiveRun
from fleetsim.view.page import live_page
from fleetsim.view.server import PageServer

__all__ = ["LiveSession"]


class LiveSession:
    """Serves the live page on a loopback ``port`` (0: any free one) and, with ``foxglove_port``, the
    runs' topics over the Foxglove WebSocket protocol. ``say`` gets the addresses to tell the user."""

    def __init__(
        self,
        speed: float | None,
        *,
        port: int = 0,
        open_browser: bool = True,
        foxglove_port: int | None = None,
        say: Callable[[str], None] = print,
    ) -> None:
        self.live = LiveRun(speed)
        self.foxglove: Any = None
        if foxglove_port is not None:
            from fleetsim.view.foxglove import FoxgloveLive

            self.foxglove = FoxgloveLive(port=foxglove_port)
        try:
            self.server = PageServer(live_page(), port=port, on_socket=self.live.serve)
        except BaseException:
            self._close_foxglove()
            raise
        pace = "as fast as it goes" if speed is None else f"at {speed:g}x real time"
        say(f"live: watch the runs at {self.server.url} (paced {pace}; pause, step and speed on the page)")
        if self.foxglove is not None:
            say(f"live: Foxglove: Open connection > Foxglove WebSocket > ws://127.0.0.1:{self.foxglove.port}")
        if open_browser:
            webbrowser.open(self.server.url)

    @property
    def url(self) -> str:
        return self.server.url

    def begin(
        self, scenario: Scenario, about: Mapping[str, Any], stopped: Callable[[], bool] = lambda: False
    ) -> Callable[[str], None]:
        """A run of ``scenario`` is about to start: the trace watcher to hand to ``run_scenario``.
        ``stopped``: whether a stop was asked for (a paused run then lets its loop go on to end)."""
        self.live.begin(scenario, about, stopped)
        if self.foxglove is None:
            return self.live.watch
        watch, foxglove = self.live.watch, self.foxglove.begin(scenario)

        def both(line: str) -> None:
            watch(line)  # paced first: Foxglove sees each step when the page does
            foxglove(line)

        return both

    def end(self, scenario: Scenario, result: RunResult) -> str:
        """The run ended: the pages are told; what to tell the user of the pace it kept."""
        if self.foxglove is not None:
            self.foxglove.end(result)
        dt = scenario.settings.time_step
        self.live.end(outcome_part(result.to_dict(), result.failures, dt, result.steps - 1))
        pacer = self.live.pacer
        if pacer.started_at is None:
            return f"live: {scenario.name} ran as fast as it goes"
        kept = "kept the pace" if pacer.late_steps == 0 else f"{pacer.late_steps} step(s) came late"
        return f"live: {scenario.name} ran at {pacer.started_at:g}x real time; {kept} (lag at most {pacer.lag:.3f} s)"

    def _close_foxglove(self) -> None:
        if self.foxglove is not None:
            self.foxglove.close()

    def close(self) -> None:
        """Close every page's connection (the pages keep what they received) and the servers."""
        try:
            self.live.close()
            self.server.close()
        finally:
            self._close_foxglove()

    def __enter__(self) -> LiveSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
