"""``fleetsim view RUN``: watch a recorded run in the browser, or write it as one self-contained page.

The page (:mod:`fleetsim.view`) replays the run from its trace; a trace that ends early (a killed or
interrupted run) is replayed up to its last complete line and the page says so.
"""

from __future__ import annotations

import argparse
import sys
import webbrowser
from pathlib import Path

from fleetsim.cli.recorded import RecordedRun, read_recorded_run
from fleetsim.cli.run import UsageError
from fleetsim.load.common.text import write_text_atomically
from fleetsim.recording.replay import TraceError

__all__ = ["view", "view_page"]


def view_page(run: RecordedRun) -> str:
    """The self-contained viewer page of a recorded run."""
    from fleetsim.view import recorded_view

    document = dict(run.document)
    if run.unfinished:
        document["ended"] = "killed"
    try:
        return recorded_view(run.scenario, run.lines, document, run.failures, run.notes)
    except TraceError as error:
        raise UsageError(f"{run.trace_path}: {error}; name the run's scenario with --suite SUITE::SCENARIO") from None


def view(args: argparse.Namespace) -> int:
    """Serve the viewer of a recorded run on a loopback port (and open it), or write it with --html."""
    run = read_recorded_run(Path(args.path), args.suite)
    page = view_page(run)
    for note in run.notes:
        print(f"note: {note}")
    end = (run.last_step + 1) * run.scenario.settings.time_step
    what = f"{run.scenario.name}, steps 0-{run.last_step} up to t = {end:.2f} s"
    if args.html is not None:
        output = Path(args.html)
        write_text_atomically(output, page)
        print(f"wrote {output} ({what}, {output.stat().st_size / 1e6:.1f} MB; it makes no request)")
        return 0
    from fleetsim.view import PageServer

    with PageServer(page, port=args.port) as server:
        print(f"viewing {what} at {server.url} (Ctrl-C to stop)", flush=True)
        if not args.no_open:
            webbrowser.open(server.url)
        try:
            server.wait()
        except KeyboardInterrupt:
            print("", file=sys.stderr)
    return 0
