"""The planner-facing reference is complete, as the site renders it.

The reference pages (docs/reference/*.md) are generated into Markdown from the docstrings as griffe
parses them (Google style; scripts/docs_reference.py), so these tests read the docstrings through griffe too: an attribute counts as
documented when it has a docstring of its own or an entry in its class's ``Attributes:`` section, which is
exactly what the pages show (members without either are hidden). Every public member of every type a
planner touches must be documented, and so must every attribute the shipped planners read.
"""

from __future__ import annotations

import ast
import re
import textwrap
from collections.abc import Iterable, Iterator
from pathlib import Path

import griffe
import pytest

from tests.docs.examples import REPO

# Every type a planner receives, returns or reads from, by the path its reference entry names.
PLANNER_FACING = (
    "fleetsim.planning.protocol.Planner",
    "fleetsim.planning.plans.FleetPlan",
    "fleetsim.planning.plans.FleetLeg",
    "fleetsim.planning.plans.RouteError",
    "fleetsim.scenario.Task",
    "fleetsim.planning.snapshot.FleetSnapshot",
    "fleetsim.planning.snapshot.VehicleState",
    "fleetsim.scenario.Vehicle",
    "fleetsim.scenario.VehicleType",
    "fleetsim.layout.layout.Layout",
    "fleetsim.layout.segment.Segment",
    "fleetsim.layout.connections.Connection",
    "fleetsim.layout.continuations.Continuation",
    "fleetsim.enums.JointKind",
    "fleetsim.enums.Traverse",
    "fleetsim.enums.Progress",
    "fleetsim.enums.Direction",
    "fleetsim.enums.Shape",
    "fleetsim.enums.TurnCapability",
    "fleetsim.enums.Disturbed",
    "fleetsim.planning.checks.Rejection",
    "fleetsim.planning.checks.RejectionCode",
    "fleetsim.planning.reservations.CollisionAlert",
)
# The shipped planners, and the route search and progress rules they share with scenario loading and the checks.
PLANNER_SOURCES = (
    *sorted((REPO / "fleetsim" / "planners").glob("*.py")),
    REPO / "fleetsim/layout/reachability.py",
    REPO / "fleetsim/layout/continuations.py",
)
REFERENCE_PAGES = sorted((REPO / "docs" / "reference").glob("*.md"))
# A number's docs must say what it is measured in.
UNITS = re.compile(r"\b(metres?|seconds?|degrees?|radians?|m/s)\b", re.IGNORECASE)
SPHINX_ROLE = re.compile(r":(?:class|meth|func|mod|attr|data|exc|obj|ref):`")


@pytest.fixture(scope="module")
def package() -> griffe.Module:
    return griffe.load("fleetsim", search_paths=[str(REPO)], docstring_parser="google")


def find(package: griffe.Module, path: str) -> griffe.Object:
    found = package[path.removeprefix("fleetsim.")]
    return found.final_target if isinstance(found, griffe.Alias) else found


def public_members(cls: griffe.Object) -> dict[str, griffe.Object]:
    """The class's own public members (inherited ones, of ``str``, ``Enum`` or ``tuple``, aside)."""
    return {
        name: member
        for name, member in cls.members.items()
        if not name.startswith("_") and not isinstance(member, griffe.Alias)
    }


def sections(obj: griffe.Object) -> list[griffe.DocstringSection]:
    return obj.docstring.parse("google") if obj.docstring is not None else []


def attribute_entries(cls: griffe.Object) -> dict[str, griffe.DocstringAttribute]:
    """The entries of the class docstring's ``Attributes:`` section, by name."""
    return {
        entry.name: entry
        for section in sections(cls)
        if section.kind is griffe.DocstringSectionKind.attributes
        for entry in section.value
    }


def docs_of(cls: griffe.Object, name: str) -> str:
    """What the reference says about member ``name`` of ``cls``: its entry in the class's ``Attributes:``
    section, else its own docstring; empty when it says nothing (and so the page does not show it)."""
    entry = attribute_entries(cls).get(name)
    if entry is not None:
        return entry.description.strip()
    member = cls.members.get(name)
    return member.docstring.value.strip() if member is not None and member.docstring is not None else ""


def undocumented(cls: griffe.Object, names: Iterable[str]) -> list[str]:
    """The names among ``names`` that the reference entry of ``cls`` leaves undocumented."""
    return sorted(name for name in names if not docs_of(cls, name))


def is_number(member: griffe.Object) -> bool:
    annotation = member.annotation if member.is_attribute else getattr(member, "returns", None)
    return str(annotation) in {"float", "float | None"}


def attributes_read(sources: Iterable[Path]) -> set[str]:
    """Every attribute name the sources read (``obj.name``), whatever ``obj`` is."""
    names: set[str] = set()
    for path in sources:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        names.update(node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute))
    return names


def rendered_paths() -> Iterator[str]:
    """The path of every object a reference page renders (an entry ``<!-- reference: path -->``)."""
    for page in REFERENCE_PAGES:
        for line in page.read_text(encoding="utf-8").splitlines():
            if line.startswith("<!-- reference: "):
                yield line.split()[2]


def rendered_objects(package: griffe.Module) -> Iterator[griffe.Object]:
    """Every object a reference page renders, and the public members of its classes."""
    for path in rendered_paths():
        obj = find(package, path)
        yield obj
        if obj.is_class:
            yield from public_members(obj).values()


def test_every_planner_facing_type_is_on_a_reference_page() -> None:
    missing = set(PLANNER_FACING) - set(rendered_paths())
    assert not missing, sorted(missing)


@pytest.mark.parametrize("path", PLANNER_FACING)
def test_every_public_member_is_documented(package: griffe.Module, path: str) -> None:
    cls = find(package, path)
    assert cls.docstring is not None, path
    assert undocumented(cls, public_members(cls)) == [], f"{path}: document these in its Attributes: section"


@pytest.mark.parametrize("path", PLANNER_FACING)
def test_every_documented_field_has_a_type_and_every_number_a_unit(package: griffe.Module, path: str) -> None:
    cls = find(package, path)
    enum = any(str(base) == "Enum" for base in cls.bases)
    for name, member in public_members(cls).items():
        if member.is_attribute and not enum:
            assert member.annotation is not None, f"{path}.{name}: annotate it, so the reference shows its type"
        if is_number(member):
            assert UNITS.search(docs_of(cls, name)), f"{path}.{name}: say its unit ({docs_of(cls, name)!r})"


def test_every_attribute_the_shipped_planners_read_is_documented(package: griffe.Module) -> None:
    read = attributes_read(PLANNER_SOURCES)
    checked: dict[str, list[str]] = {}
    for path in PLANNER_FACING:
        cls = find(package, path)
        names = read & set(public_members(cls))
        checked[path] = sorted(names)
        assert undocumented(cls, names) == [], f"{path}: the shipped planners read these"
    # The intersection is what the planners actually use; spot-check it so a broken parse cannot pass.
    assert {"fixed_legs", "legs", "vehicle_id"} <= set(checked["fleetsim.planning.plans.FleetPlan"])
    assert {"successors", "conflicts", "segments"} <= set(checked["fleetsim.layout.layout.Layout"])
    assert {"goal_segment", "goal_progress", "id"} <= set(checked["fleetsim.scenario.Task"])
    assert {"plans", "vehicles", "tasks", "time"} <= set(checked["fleetsim.planning.snapshot.FleetSnapshot"])
    assert {"turn_capability", "max_speed", "acceleration"} <= set(checked["fleetsim.scenario.VehicleType"])
    assert {"length", "first", "last", "exit"} <= set(checked["fleetsim.layout.segment.Segment"])
    assert {"FORWARD", "REVERSE"} <= set(checked["fleetsim.enums.Progress"])


def test_removing_an_attributes_entry_makes_it_undocumented(package: griffe.Module) -> None:
    leg = find(package, "fleetsim.planning.plans.FleetLeg")
    assert leg.docstring is not None
    original = leg.docstring
    assert undocumented(leg, ["fixed", "goal_for_task"]) == []
    # The same docstring without the entry for `fixed` (its first line and the lines continuing it).
    lines = original.value.splitlines()
    start = next(i for i, line in enumerate(lines) if line.lstrip().startswith("fixed:"))
    end = next(i for i in range(start + 1, len(lines)) if not lines[i].startswith(" " * 8))
    leg.docstring = griffe.Docstring("\n".join(lines[:start] + lines[end:]), parent=leg, parser="google")
    try:
        assert undocumented(leg, ["fixed", "goal_for_task"]) == ["fixed"]
    finally:
        leg.docstring = original


def test_a_member_documented_nowhere_is_reported(tmp_path: Path) -> None:
    source = '''
        """A module."""
        from dataclasses import dataclass


        @dataclass
        class Leg:
            """A leg.

            Attributes:
                segment: The segment's id.
            """

            segment: int
            fixed: bool

            @property
            def length(self) -> float:
                """Metres."""
                return 1.0

            @property
            def speed(self) -> float:
                return 1.0
    '''
    (tmp_path / "legs.py").write_text(textwrap.dedent(source), encoding="utf-8")
    module = griffe.load("legs", search_paths=[str(tmp_path)], docstring_parser="google")
    leg = module["Leg"]
    assert undocumented(leg, public_members(leg)) == ["fixed", "speed"]


def test_rendered_docstrings_use_markdown_not_sphinx_roles(package: griffe.Module) -> None:
    # The reference shows ":class:`X`" as it is; a cross-reference is [`X`][path.to.X].
    offenders = [
        obj.path
        for obj in rendered_objects(package)
        if obj.docstring is not None and SPHINX_ROLE.search(obj.docstring.value)
    ]
    assert offenders == []


def test_rendered_returns_sections_are_one_item(package: griffe.Module) -> None:
    # A Returns: section's lines after the first must be indented further, or each becomes a row of its own.
    split = [
        obj.path
        for obj in rendered_objects(package)
        for section in sections(obj)
        if section.kind is griffe.DocstringSectionKind.returns and len(section.value) > 1
    ]
    assert split == []


@pytest.mark.parametrize("name", ["crossing", "loop", "mixed"])
def test_the_example_map_pictures_are_up_to_date(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # docs/errors.md shows these maps; redraw them with `fleetsim render MAP -o docs/images/example-NAME.svg`.
    from fleetsim.cli.main import main

    monkeypatch.chdir(REPO)
    (map_file,) = Path("scenario_suites/examples", name).glob("map.*")
    assert main(["render", str(map_file), "-o", str(tmp_path / "map.svg")]) == 0
    picture = REPO / "docs" / "images" / f"example-{name}.svg"
    assert (tmp_path / "map.svg").read_text(encoding="utf-8") == picture.read_text(encoding="utf-8")
