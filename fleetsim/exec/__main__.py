"""``python -m fleetsim.exec module:attr``: serve an in-process planner over the JSON-lines protocol."""

from __future__ import annotations

import sys

from fleetsim.exec.client import serve
from fleetsim.sim.planner_spec import PlannerSpecError, import_planner_factory


def main(argv: list[str]) -> int:
    if len(argv) != 1 or argv[0].startswith("exec:"):
        print(
            "usage: python -m fleetsim.exec module:attr   (a planner class or zero-argument factory)", file=sys.stderr
        )
        return 2
    try:
        planner = import_planner_factory(argv[0])()
    except PlannerSpecError as error:
        print(f"fleetsim.exec: {error}", file=sys.stderr)
        if error.details:
            print(error.details, file=sys.stderr)
        return 2
    return serve(planner)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
