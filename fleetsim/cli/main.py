"""Argument parsing and the error boundary of the ``fleetsim`` command.

Commands live in :mod:`fleetsim.cli.commands` and :mod:`fleetsim.cli.run`; here a user's mistake becomes a
one-line located error and exit status 1 (2 for a mistake on the command line itself), never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
from collections.abc import Sequence
from importlib import import_module
from typing import Any

from fleetsim.cli.capacity import add_capacity_arguments
from fleetsim.cli.generate import add_generate_arguments
from fleetsim.cli.orders import add_orders_arguments
from fleetsim.enums import ConflictModel
from fleetsim.errors import FleetsimError
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, ScenarioSettings
from fleetsim.version import __version__

__all__ = ["build_parser", "main"]

_DEFAULTS = ScenarioSettings()


def _positive(text: str) -> float:
    value = float(text)
    if not value > 0:
        msg = f"must be > 0, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def _steps(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be a whole number of steps >= 1")
    return value


def _non_negative(text: str) -> float:
    value = float(text)
    if not value >= 0:
        msg = f"must be >= 0, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def _add_layout_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--radius",
        type=_non_negative,
        default=DEFAULT_VEHICLE_TYPE.swept_radius,
        help="vehicle circle radius in metres for conflicts (default: %(default).3f, the default "
        "vehicle type's half diagonal)",
    )
    parser.add_argument(
        "--safety-margin", type=_non_negative, default=_DEFAULTS.safety_margin, help="metres (default: %(default)s)"
    )
    parser.add_argument(
        "--conflict-model",
        choices=[m.value for m in ConflictModel],
        default=_DEFAULTS.conflict_model.value,
        help="swept circles or the thesis's bounding boxes (default: %(default)s)",
    )
    parser.add_argument(
        "--connection-tolerance",
        type=_positive,
        default=_DEFAULTS.connection_tolerance,
        help="metres (default: %(default)s)",
    )
    parser.add_argument(
        "--joint-angle-tolerance",
        type=_positive,
        default=_DEFAULTS.joint_angle_tolerance,
        help="degrees (default: %(default)s)",
    )


def _add_serving_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    parser.add_argument(
        "--port",
        type=_port,
        default=0,
        metavar="N",
        help="the loopback port to serve the page on (default: any free one)",
    )
    parser.add_argument("--no-open", action="store_true", help="serve the page without opening a browser on it")


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        msg = f"{text!r} must be a port number from 0 (any free one) to 65535"
        raise argparse.ArgumentTypeError(msg)
    return port


def _speed(text: str) -> float | None:
    from fleetsim.view.live import parse_speed

    try:
        return parse_speed(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error).removeprefix("speed=")) from None


def _add_map_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group(
        "map options", "which part of a LIF or Open-RMF map to read, a MovingAI map's cells (as map_options in a suite)"
    )
    group.add_argument("--layout", metavar="ID", help="LIF: the layoutId (required when the file has several)")
    group.add_argument(
        "--robot-type",
        metavar="TYPE",
        help="LIF: manufacturer/seriesName (or a 1.0 vehicleTypeId) whose edges form the map",
    )
    group.add_argument("--level", metavar="NAME", help="RMF: the level (default: the first)")
    group.add_argument("--graph", type=int, metavar="N", help="RMF: the lane graph_idx (default: 0)")
    group.add_argument(
        "--cell-size", type=float, metavar="M", help="MovingAI (.map): a grid cell's side in metres (default: 1)"
    )


def _command(name: str) -> Any:
    """The function a subcommand runs, from ``module:function``: a command's modules are imported only when
    it runs (or its help is shown), so that ``fleetsim --help`` answers at once."""
    module, _, function = name.partition(":")
    return getattr(import_module(module), function)


class _CommandParser(argparse.ArgumentParser):
    """A subcommand's parser; its description is the docstring of the function that runs it."""

    def __init__(self, *args: Any, command: str = "", **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.command = command
        if command:
            self.set_defaults(run=command)

    def format_help(self) -> str:
        if self.description is None and self.command:
            self.description = _command(self.command).__doc__
        return super().format_help()


class _Version(argparse.Action):
    """``--version``: the version, and whether the hot paths run compiled (fleetsim/compiled.py), found
    only when asked."""

    def __init__(self, option_strings: list[str], dest: str, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        from fleetsim.compiled import build_note

        print(f"fleetsim {__version__} ({build_note()})")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fleetsim",
        description="Check fleet route planners against scenarios drawn in Tiled.",
    )
    parser.add_argument("--version", action=_Version, help="show fleetsim's version and build, and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_CommandParser)

    validate = sub.add_parser(
        "validate", help="load suites completely and print layout lint", command="fleetsim.cli.commands:validate"
    )
    validate.add_argument(
        "suites",
        nargs="+",
        metavar="SUITE",
        help="*.fleetsim.yaml files or folders holding them, or League of Robot Runners problem files (.json)",
    )

    inspect = sub.add_parser(
        "inspect", help="segments, connections and conflicts of a map", command="fleetsim.cli.commands:inspect"
    )
    inspect.add_argument(
        "map",
        metavar="MAP",
        help="a Tiled map (.json, .tmj, .tmx), LIF file (.lif.json) or RMF building map (.building.yaml), "
        "or a scenario folder holding one",
    )
    inspect.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    _add_layout_options(inspect)
    _add_map_options(inspect)

    render = sub.add_parser(
        "render",
        help="draw a map, or one step of a recorded run, as SVG",
        command="fleetsim.cli.commands:render",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    render.add_argument(
        "map",
        nargs="?",
        metavar="MAP",
        help="a Tiled map (.json, .tmj, .tmx), LIF file or RMF building map; leave out with --trace",
    )
    render.add_argument("-o", "--output", required=True, metavar="OUT.svg", help="where to write the picture")
    render.add_argument(
        "--highlight", type=int, metavar="ID", help="draw this segment yellow, its successors green, its conflicts grey"
    )
    render.add_argument(
        "--trace", metavar="PATH", help="draw a step of a recorded run: its artifact folder or its trace.jsonl"
    )
    render.add_argument(
        "--step",
        type=int,
        metavar="N",
        help="with --trace: the step to draw (default: the first failure's, else the last)",
    )
    render.add_argument(
        "--suite",
        metavar="SUITE::SCENARIO",
        help="with --trace: the scenario the run was of (default: the suite and scenario named in result.json)",
    )
    _add_layout_options(render)
    _add_map_options(render)

    convert = sub.add_parser(
        "convert", help="write a map as Tiled JSON/TMX or LIF 1.0", command="fleetsim.cli.commands:convert"
    )
    convert.add_argument("map", metavar="IN", help="any map fleetsim loads (Tiled, LIF, RMF building map)")
    convert.add_argument(
        "output", metavar="OUT", help="OUT.lif.json for LIF 1.0; OUT.json, OUT.tmj or OUT.tmx for Tiled"
    )
    convert.add_argument(
        "--connection-tolerance",
        type=_positive,
        default=_DEFAULTS.connection_tolerance,
        help="LIF: segment ends this close (metres) share a node (default: %(default)s)",
    )
    _add_map_options(convert)

    generate_parser = sub.add_parser(
        "generate",
        help="write a ready-to-run scenario folder: a warehouse with stations, vehicles and a shift",
        command="fleetsim.cli.generate:generate",
    )
    add_generate_arguments(generate_parser)

    record_parser = sub.add_parser(
        "record",
        help="rebuild a run's MCAP recording from its trace (a run killed outright, say)",
        command="fleetsim.cli.recorded:record",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    record_parser.add_argument(
        "--trace", required=True, metavar="PATH", help="the run's artifact folder or its trace.jsonl"
    )
    record_parser.add_argument(
        "-o", "--output", metavar="OUT.mcap", help="where to write the recording (default: run.mcap beside the trace)"
    )
    record_parser.add_argument(
        "--suite",
        metavar="SUITE::SCENARIO",
        help="the scenario the run was of (default: the suite and scenario named in result.json or run.json)",
    )
    record_parser.add_argument(
        "--record-every",
        type=_steps,
        default=1,
        metavar="N",
        help="record every N-th step in full (steps with new plans, alerts or events always; default: 1)",
    )

    view_parser = sub.add_parser(
        "view",
        help="watch a recorded run in the browser (play, pause, speed, step, scrub), or write it as one HTML file",
        command="fleetsim.cli.view:view",
    )
    view_parser.add_argument("path", metavar="RUN", help="a run's artifact folder, its trace.jsonl or its result.json")
    view_parser.add_argument(
        "--html",
        metavar="OUT.html",
        help="write the viewer as one self-contained file (the run embedded; it makes no request) instead of serving it",
    )
    view_parser.add_argument(
        "--suite",
        metavar="SUITE::SCENARIO",
        help="the scenario the run was of (default: the suite and scenario named in result.json or run.json)",
    )
    _add_serving_options(view_parser)

    orders_parser = sub.add_parser(
        "orders",
        help="write a recorded run's accepted plans as VDA 5050 orders (to replay on a vehicle)",
        command="fleetsim.cli.orders:orders",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_orders_arguments(orders_parser)

    run_parser = sub.add_parser(
        "run", help="simulate scenarios with a planner and judge the runs", command="fleetsim.cli.run:run"
    )
    run_parser.add_argument(
        "suites",
        nargs="+",
        metavar="SUITE[::SCENARIO]",
        help="*.fleetsim.yaml files or folders, or League of Robot Runners problem files (.json); FILE::NAME runs one scenario",
    )
    run_parser.add_argument(
        "--planner",
        required=True,
        metavar="SPEC",
        help="module:attribute naming a planner class or zero-argument factory, "
        "e.g. fleetsim.planners:ReservingPlanner (the current directory is importable)",
    )
    run_parser.add_argument(
        "--dispatcher",
        metavar="SPEC",
        help="module:attribute naming a dispatcher class or zero-argument factory, for scenarios with transport "
        "orders, e.g. fleetsim.dispatchers:NearestVehicleDispatcher (default: the suite's dispatcher:, else the "
        "planner's own dispatch method)",
    )
    run_parser.add_argument(
        "--json", action="store_true", help="print one result object per scenario per line; the table goes to stderr"
    )
    run_parser.add_argument(
        "--planner-timeout",
        type=_non_negative,
        default=10.0,
        metavar="SECONDS",
        help="wall-clock limit per planner call; 0 switches it off (default: %(default)g)",
    )
    run_parser.add_argument(
        "--record",
        metavar="DIR",
        help="write each run's artifacts to DIR/<suite>/<scenario>/: run.mcap (RViz 2, Foxglove), "
        "fleetsim.rviz, failure.svg when it failed, trace.jsonl, result.json",
    )
    run_parser.add_argument(
        "--record-every",
        type=_steps,
        default=1,
        metavar="N",
        help="with --record: record every N-th step (steps with new plans, alerts or events always; default: 1)",
    )

    live = run_parser.add_argument_group("watching a run live (fleetsim view's page, while it runs)")
    live.add_argument(
        "--live",
        action="store_true",
        help="pace each run against the wall clock and show it in the browser while it runs "
        "(the page can pause, step and change the speed; results and hashes are those of a headless run)",
    )
    live.add_argument(
        "--speed",
        type=_speed,
        default=1.0,
        metavar="X",
        help="with --live: simulated seconds per wall second, or 'max' for as fast as it goes (default: 1)",
    )
    _add_serving_options(live)
    live.add_argument(
        "--foxglove",
        type=_port,
        nargs="?",
        const=8765,
        metavar="PORT",
        help="with --live: also serve the run's topics over the Foxglove WebSocket protocol on PORT "
        "(default 8765; 0: any free port); needs the 'live' extra (foxglove-sdk)",
    )

    # Its own parsers (a sweep, or "sweep report RESULTS") live in fleetsim.cli.sweep; imported when used.
    sweep_parser = sub.add_parser(
        "sweep",
        add_help=False,
        help="run planners x scenarios on Dask, or 'sweep report RESULTS' to compare them",
        description="fleetsim sweep SPEC.yaml [--scheduler ADDRESS] [--resume]; fleetsim sweep report RESULTS [--fail-if ...]",
        command="fleetsim.cli.sweep:sweep",
    )
    sweep_parser.add_argument("arguments", nargs=argparse.REMAINDER)

    capacity_parser = sub.add_parser(
        "capacity",
        help="the highest order arrival rate a fleet sustains, searched over seeds on Dask, with a CI gate",
        command="fleetsim.cli.capacity:capacity",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_capacity_arguments(capacity_parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["sweep"]:  # its own parsers read everything after it, options first included
        args = argparse.Namespace(command="sweep", arguments=words[1:], run="fleetsim.cli.sweep:sweep")
    else:
        args = build_parser().parse_args(words)
    from fleetsim.cli.run import UsageError
    from fleetsim.specs.python import PlannerSpecError

    try:
        return int(_command(args.run)(args))
    except (PlannerSpecError, UsageError) as error:
        print(f"fleetsim: error: {error}", file=sys.stderr)
        return 2
    except FleetsimError as error:
        print(f"fleetsim: error: {error}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        return _reader_gone()
    except OSError as error:
        where = f"{error.filename}: " if error.filename is not None else ""
        print(f"fleetsim: error: {where}{error.strerror or error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as interrupt:  # Ctrl-C outside a run, or a second stop signal (RunAborted)
        return 128 + getattr(interrupt, "signum", signal.SIGINT)


def _reader_gone() -> int:
    """The reader of our output went away (``fleetsim inspect map.json | head``): end quietly, as a
    process killed by SIGPIPE does (exit status 128 + 13), without a second error at exit's flush."""
    with contextlib.suppress(OSError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    return 128 + signal.SIGPIPE


if __name__ == "__main__":
    raise SystemExit(main())
