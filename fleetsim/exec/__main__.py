"""``python -m fleetsim.exec [--no-rounds] module:attr``: serve an in-process planner over the JSON-lines
protocol (``--no-rounds``: one request per call, never a planning round in one message); a planner with a
``dispatch`` method is served as the run's dispatcher too (protocol 1.5)."""

from __future__ import annotations

import sys

from fleetsim.exec.client import serve
from fleetsim.specs.python import PlannerSpecError, import_planner_factory


def main(argv: list[str]) -> int:
    rounds = "--no-rounds" not in argv  # answer one request per call, as a protocol 1.1 client
    argv = [arg for arg in argv if arg != "--no-rounds"]
    if len(argv) != 1 or argv[0].startswith("exec:"):
        print(
            "usage: python -m fleetsim.exec [--no-rounds] module:attr   (a planner class or zero-argument factory)",
            file=sys.stderr,
        )
        return 2
    try:
        factory = import_planner_factory(argv[0])  # the planner is made with the init message's options
    except PlannerSpecError as error:
        print(f"fleetsim.exec: {error}", file=sys.stderr)
        if error.details:
            print(error.details, file=sys.stderr)
        return 2
    return serve(factory, rounds=rounds)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
