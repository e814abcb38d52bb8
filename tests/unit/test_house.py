"""The code's structure (STYLE.md): imports point one way down the pipeline, with no circles between
rooms, and each map format and file kind has a room of its own that does not reach into another's."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "fleetsim"
# The rooms of load/, one per format or file kind, and what each may import of load/ besides itself.
LOAD_ROOMS = {
    "common": set(),
    "tiled": {"common"},
    "lif": {"common"},
    "rmf": {"common"},
    "tables": {"common"},
    "movingai": {"common"},
    "lorr": {"common", "movingai"},  # a League problem's map is a MovingAI map, its robots placed as .scen agents
    "maps": {"common", "tiled", "lif", "rmf", "movingai"},
    "suites": {"common", "tables", "maps", "movingai", "lorr"},
}


def _room(module: str) -> str:
    """``fleetsim.load.tiled.reader`` -> ``load/tiled``; ``fleetsim.sim.loop`` -> ``sim``; ``fleetsim.orders``
    -> ``orders``."""
    parts = module.split(".")[1:]
    if parts[:1] == ["load"] and len(parts) > 2:
        return f"load/{parts[1]}"
    return parts[0] if parts else "fleetsim"


def _modules() -> Iterator[tuple[str, Path]]:
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(ROOT).with_suffix("")
        parts = list(relative.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield ".".join(parts), path


def _imports(path: Path) -> Iterator[str]:
    """Every fleetsim module ``path`` imports, at the top or inside a function."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 and node.module.startswith("fleetsim"):
            yield node.module
        elif isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names if alias.name.startswith("fleetsim"))


def _room_graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for module, path in _modules():
        if module.count(".") == 0 or (module.count(".") == 1 and path.name == "__init__.py"):
            continue  # the package's and a room's face: they only hand names on
        here = _room(module)
        graph.add_node(here)
        for imported in _imports(path):
            there = _room(imported)
            if there != here and there != "fleetsim":
                graph.add_edge(here, there, example=f"{module} -> {imported}")
    return graph


def test_no_two_rooms_import_each_other_even_through_others() -> None:
    graph = _room_graph()
    cycles = list(nx.simple_cycles(graph))
    shown = [" -> ".join([*cycle, cycle[0]]) for cycle in cycles[:5]]
    assert cycles == [], shown


def test_each_map_format_and_file_kind_has_a_room_that_reaches_into_no_other() -> None:
    rooms = {path.name for path in (PACKAGE / "load").iterdir() if path.is_dir() and path.name != "__pycache__"}
    assert rooms == set(LOAD_ROOMS)
    assert sorted(path.name for path in (PACKAGE / "load").glob("*.py")) == ["__init__.py"]
    for here, there, data in _room_graph().edges(data=True):
        if here.startswith("load/") and there.startswith("load/"):
            assert there.removeprefix("load/") in LOAD_ROOMS[here.removeprefix("load/")], data["example"]


def test_planner_specs_live_with_the_interfaces_not_in_the_simulator() -> None:
    assert not (PACKAGE / "sim" / "planner_spec.py").exists()
    assert (PACKAGE / "specs" / "python.py").is_file() and (PACKAGE / "specs" / "dispatcher.py").is_file()
