"""``fleetsim orders RUN``: a recorded run's accepted plans as VDA 5050 orders, to replay on a vendor's
simulator or a vehicle (:mod:`fleetsim.vda5050.export` says how plans become orders).

The run is read as ``fleetsim record --trace`` reads it (:func:`fleetsim.cli.recorded.read_recorded_run`);
this module imports nothing heavy until the command runs, so registering it costs ``fleetsim --help``
nothing.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

__all__ = ["ORDERS_FOLDER", "add_orders_arguments", "orders"]

ORDERS_FOLDER = "vda5050-orders"  # the default output folder, inside the run's folder


def add_orders_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``fleetsim orders``, on the subcommand's ``parser``."""
    # dest "path", not "run": fleetsim's main keeps the function a subcommand runs in ``args.run``
    parser.add_argument("path", metavar="RUN", help="the run's artifact folder (from --record) or its trace.jsonl")
    parser.add_argument(
        "--vda", choices=["2.0", "2.1"], default="2.0", help="the VDA 5050 version to write (default: %(default)s)"
    )
    parser.add_argument(
        "--out", metavar="DIR", help=f"where to write <serialNumber>.orders.jsonl (default: RUN/{ORDERS_FOLDER}/)"
    )
    parser.add_argument(
        "--manufacturer", default="fleetsim", metavar="M", help="the header's manufacturer (default: %(default)s)"
    )
    parser.add_argument(
        "--interface-name",
        default="uagv",
        metavar="NAME",
        help="the first level of the MQTT topic (default: %(default)s)",
    )
    parser.add_argument(
        "--suite",
        metavar="SUITE::SCENARIO",
        help="the scenario the run was of (default: the suite and scenario named in result.json or run.json)",
    )


def orders(args: argparse.Namespace) -> int:
    """Write the VDA 5050 order messages that drive a recorded run's accepted plans.

    fleetsim orders RUN [--vda 2.0|2.1] [--out DIR] [--manufacturer M] [--interface-name uagv] [--suite SUITE::SCENARIO]
      RUN is a run's artifact folder (trace.jsonl with result.json or run.json) or a trace.jsonl, of any
      planner's run. Per vehicle, DIR/<serialNumber>.orders.jsonl (serialNumber: the vehicle's id) gets
      one line per order message, in time order:
        {"topic": "uagv/v2/M/<serialNumber>/order", "at": SECONDS, "message": {...the order...}}
      "at" is the simulated time the plan was accepted at; publishing each message on its topic at its
      time replays the run's plans. The first plan is a new order, each later one an update of it.
      The same run always gives the same bytes (timestamps count from 2000-01-01T00:00:00Z).
    """
    from fleetsim.cli.recorded import read_recorded_run
    from fleetsim.cli.run import UsageError
    from fleetsim.load.common.text import write_text_atomically
    from fleetsim.recording.replay import TraceError
    from fleetsim.vda5050.export import ExportError, export_orders, order_line

    for label, level in (("--manufacturer", args.manufacturer), ("--interface-name", args.interface_name)):
        if not level or any(character in level for character in "/+#"):
            raise UsageError(f"{label}={level!r} must be a non-empty MQTT topic level without '/', '+' or '#'")
    run = read_recorded_run(Path(args.path), args.suite)
    folder = run.trace_path.parent
    if args.out is not None:
        out = Path(args.out)
    elif os.access(folder, os.W_OK):
        out = folder / ORDERS_FOLDER
    else:
        raise UsageError(f"{folder}: the run's folder is not writable; name another folder with --out DIR")
    try:
        exported = export_orders(run.scenario, run.lines, version=args.vda, manufacturer=args.manufacturer)
    except TraceError as error:  # a trace of another scenario, or not a trace at all
        raise UsageError(f"{run.trace_path}: {error}; name the run's scenario with --suite SUITE::SCENARIO") from None
    except ExportError as error:
        raise ExportError(f"{run.trace_path}: {error}") from None
    for note in run.notes:
        print(f"note: {note}")
    for vehicle in sorted(run.scenario.vehicles, key=lambda v: v.id):
        mine = [e for e in exported if e.vehicle_id == vehicle.id]
        path = out / f"{vehicle.id}.orders.jsonl"
        write_text_atomically(path, "".join(order_line(e, interface_name=args.interface_name) + "\n" for e in mine))
        updates = sum(1 for e in mine if e.order.order_update_id > 0)
        what = f"{len(mine)} order message{'s' if len(mine) != 1 else ''}"
        detail = f" (1 order, {updates} update{'s' if updates != 1 else ''})" if mine else " (no plan accepted)"
        print(f"wrote {path}: vehicle {vehicle.id}, {what}{detail}, VDA 5050 {args.vda}")
    return 0
