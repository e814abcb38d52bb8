"""``fleetsim generate KIND OUT_DIR``: write a generated scenario folder (today one kind: ``warehouse``)."""

from __future__ import annotations

import argparse

from fleetsim.generate.options import MAP_FORMATS, WarehouseOptions

__all__ = ["add_generate_arguments", "generate"]

_DEFAULTS = WarehouseOptions()


def add_generate_arguments(parser: argparse.ArgumentParser) -> None:
    """The kinds of site and their options, on ``fleetsim generate``'s parser."""
    kinds = parser.add_subparsers(dest="kind", required=True, metavar="KIND")
    warehouse = kinds.add_parser(
        "warehouse",
        help="parallel aisles between two cross aisles, pick lay-bys, a dock of drop stations, parking rows",
        description="Write OUT_DIR/map.json (Tiled; or map.lif.json), vehicles.csv (each vehicle on a parking "
        "place), an empty tasks.csv and warehouse.fleetsim.yaml (a one-hour shift of a Poisson order stream, "
        "pick then drop). The same options give the same files.",
    )
    warehouse.add_argument("out_dir", metavar="OUT_DIR", help="the folder to write (made if missing; must be empty)")
    site = warehouse.add_argument_group("the site (lengths in metres)")
    site.add_argument("--aisles", type=int, default=_DEFAULTS.aisles, metavar="N", help="default: %(default)s")
    site.add_argument(
        "--aisle-length", type=float, default=_DEFAULTS.aisle_length, metavar="M", help="default: %(default)g"
    )
    site.add_argument(
        "--aisle-spacing",
        type=float,
        default=_DEFAULTS.aisle_spacing,
        metavar="M",
        help="between aisle centre lines (default: %(default)g)",
    )
    site.add_argument(
        "--pick-stations",
        type=int,
        default=_DEFAULTS.pick_stations,
        metavar="N",
        help="lay-bys beside the aisles, spread over them (default: %(default)s)",
    )
    site.add_argument(
        "--drop-stations",
        type=int,
        default=_DEFAULTS.drop_stations,
        metavar="N",
        help="at the dock, beyond the top cross aisle (default: %(default)s)",
    )
    site.add_argument(
        "--parking",
        type=int,
        metavar="N",
        help="parking places beyond the bottom cross aisle (default: one per vehicle)",
    )
    ways = site.add_mutually_exclusive_group()
    ways.add_argument(
        "--one-way",
        dest="one_way",
        action="store_true",
        default=_DEFAULTS.one_way,
        help="aisles of alternating directions, cross aisles one way round (the default)",
    )
    ways.add_argument("--two-way", dest="one_way", action="store_false", help="every aisle and cross aisle two-way")
    fleet = warehouse.add_argument_group("the fleet")
    fleet.add_argument("--vehicles", type=int, default=_DEFAULTS.vehicles, metavar="N", help="default: %(default)s")
    fleet.add_argument(
        "--vehicle-length",
        type=float,
        default=_DEFAULTS.vehicle_length,
        metavar="M",
        help="the vehicle type's length; the spacing of the site follows it (default: %(default)g)",
    )
    fleet.add_argument(
        "--vehicle-width", type=float, default=_DEFAULTS.vehicle_width, metavar="M", help="default: %(default)g"
    )
    files = warehouse.add_argument_group("the files")
    files.add_argument(
        "--format", dest="map_format", choices=MAP_FORMATS, default=_DEFAULTS.map_format, help="default: %(default)s"
    )
    files.add_argument(
        "--seed", type=int, default=_DEFAULTS.seed, metavar="S", help="the order stream's seed (default: %(default)s)"
    )
    dispatchers = files.add_mutually_exclusive_group()
    dispatchers.add_argument(
        "--dispatcher",
        default=_DEFAULTS.dispatcher,
        metavar="SPEC",
        help="the dispatcher the suite names, module:attribute (default: %(default)s)",
    )
    dispatchers.add_argument(
        "--no-dispatcher",
        dest="dispatcher",
        action="store_const",
        const=None,
        help="name none in the suite (fleetsim run --dispatcher then names one)",
    )
    files.add_argument(
        "--force", action="store_true", help="write into OUT_DIR even if it holds files (replacing the generated ones)"
    )


def generate(args: argparse.Namespace) -> int:
    """Write a ready-to-run scenario folder: a map with its stations, vehicles and a suite that runs a shift.

    `fleetsim generate warehouse OUT_DIR` writes a warehouse of parallel aisles; `fleetsim generate
    warehouse --help` lists its options.
    """
    from fleetsim.cli.run import UsageError
    from fleetsim.generate import GenerateError, generate_warehouse

    try:
        options = WarehouseOptions(
            aisles=args.aisles,
            aisle_length=args.aisle_length,
            aisle_spacing=args.aisle_spacing,
            vehicles=args.vehicles,
            pick_stations=args.pick_stations,
            drop_stations=args.drop_stations,
            parking=args.parking,
            one_way=args.one_way,
            vehicle_length=args.vehicle_length,
            vehicle_width=args.vehicle_width,
            map_format=args.map_format,
            seed=args.seed,
            dispatcher=args.dispatcher,
        )
        written = generate_warehouse(args.out_dir, options, force=args.force)
    except GenerateError as error:
        raise UsageError(error.command_line()) from None
    layout = written.layout
    counts = {name: len(stations) for name, stations in layout.stations.items()}
    print(
        f"wrote {written.folder}: {written.map.name} ({len(layout.segments)} segments; {counts['pick']} pick and "
        f"{counts['drop']} drop stations, {counts['park']} parking places), {written.vehicles.name} "
        f"({options.vehicles} vehicles), {written.tasks.name}, {written.suite.name}"
    )
    dispatcher = "" if options.dispatcher is not None else " --dispatcher MODULE:CLASS"
    print(f"run it: fleetsim run {written.suite} --planner fleetsim.planners:ReservingPlanner{dispatcher}")
    return 0
