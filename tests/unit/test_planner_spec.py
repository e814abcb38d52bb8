"""Planner specs (``module:attr``): what they may name, and the error for every way they can be wrong."""

from __future__ import annotations

import os
import sys
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from fleetsim.errors import FleetsimError
from fleetsim.exec import SubprocessPlanner
from fleetsim.exec.spec import load_planner_factory
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.specs.python import PlannerFactory, PlannerSpecError

WriteModule = Callable[[str, str], Path]

PLANNER_MODULE = """\
from fleetsim.planners import ReservingPlanner


class MyPlanner(ReservingPlanner):
    name = "a user's planner: the reference one under another name"


def make_planner():
    return MyPlanner()


class Outer:
    @staticmethod
    def make():
        return MyPlanner()


ready_made = MyPlanner()
LIMIT = 3
"""


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[WriteModule]:
    """A user's project folder as the current directory, in which planner modules can be written.

    sys.path is stripped of the current directory (as for the ``fleetsim`` console script), so only
    the loader can make it importable; sys.path and sys.modules are restored afterwards.
    """
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", os.getcwd())])
    before = set(sys.modules)

    def write(name: str, source: str) -> Path:
        path = tmp_path / f"{name}.py"
        path.write_text(textwrap.dedent(source), encoding="utf-8")
        return path

    yield write
    for name in set(sys.modules) - before:
        del sys.modules[name]


def spec_error(spec: str) -> str:
    with pytest.raises(PlannerSpecError) as info:
        load_planner_factory(spec)()
    assert info.value.spec == spec
    return str(info.value)


# -- what a spec may name -------------------------------------------------------------------------


def test_a_class_gives_a_factory_that_carries_the_spec_as_its_identity() -> None:
    factory = load_planner_factory("fleetsim.planners:ReservingPlanner")
    assert isinstance(factory, PlannerFactory)
    assert factory.spec == "fleetsim.planners:ReservingPlanner"
    assert isinstance(factory(), ReservingPlanner)


def test_every_call_makes_a_fresh_planner() -> None:
    factory = load_planner_factory("fleetsim.planners:BFSPlanner")
    first, second = factory(), factory()
    assert isinstance(first, BFSPlanner) and isinstance(second, BFSPlanner)
    assert first is not second


def test_a_zero_argument_factory_function_is_called_for_every_planner(project: WriteModule) -> None:
    project("user_factory", PLANNER_MODULE)
    factory = load_planner_factory("user_factory:make_planner")
    first, second = factory(), factory()
    assert type(first).__name__ == "MyPlanner"
    assert first is not second


def test_a_dotted_attribute_reaches_a_factory_inside_a_class(project: WriteModule) -> None:
    project("user_outer", PLANNER_MODULE)
    factory = load_planner_factory("user_outer:Outer.make")
    assert factory.spec == "user_outer:Outer.make"
    assert type(factory()).__name__ == "MyPlanner"


def test_a_dotted_module_path_is_imported() -> None:
    assert isinstance(load_planner_factory("fleetsim.planners.bfs:BFSPlanner")(), BFSPlanner)


def test_a_module_in_the_current_directory_is_importable(project: WriteModule) -> None:
    project("planner_in_cwd", PLANNER_MODULE)
    assert "planner_in_cwd" not in sys.modules
    planner = load_planner_factory("planner_in_cwd:MyPlanner")()
    assert type(planner).__module__ == "planner_in_cwd"


# -- malformed specs ------------------------------------------------------------------------------


def test_a_spec_without_a_colon_is_rejected_with_an_example() -> None:
    assert spec_error("foo") == (
        "planner spec 'foo' must look like module:attribute, e.g. fleetsim.planners:ReservingPlanner"
    )


def test_an_exec_spec_makes_a_fresh_planner_process_per_run_with_the_call_timeout() -> None:
    factory = load_planner_factory(
        f"exec:{sys.executable} -m fleetsim.exec fleetsim.planners:BFSPlanner", call_timeout=2.5
    )
    first, second = factory(), factory()
    assert isinstance(first, SubprocessPlanner) and first is not second
    assert first.command == [sys.executable, "-m", "fleetsim.exec", "fleetsim.planners:BFSPlanner"]
    assert first.timeout == 2.5


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("exec:", "names no command; write exec:COMMAND"),
        ("exec:   ", "names no command"),
        ("exec:no-such-program-xyz --stdio", "the program 'no-such-program-xyz' is not on PATH"),
        ("exec:./missing/planner.sh", "the program './missing/planner.sh' is not a file"),
        ("exec:node 'unclosed", "cannot be split into words"),
    ],
)
def test_a_bad_exec_spec_says_what_is_wrong(spec: str, expected: str) -> None:
    assert expected in spec_error(spec)


def test_a_file_path_instead_of_a_module_name_is_rejected_with_the_module_name_to_use() -> None:
    message = spec_error("planners/my_planner.py:MyPlanner")
    assert "my_planner:MyPlanner" in message


@pytest.mark.parametrize("spec", [":MyPlanner", "my_planner:", "my-planner:MyPlanner", "my_planner:My Planner"])
def test_a_part_that_is_not_a_python_name_is_rejected(spec: str) -> None:
    assert "must be a dotted Python name" in spec_error(spec)


# -- modules --------------------------------------------------------------------------------------


def test_a_module_that_does_not_exist_is_named_with_how_to_fix_it(project: WriteModule) -> None:
    message = spec_error("no_such_planner_module:Planner")
    assert "no module named 'no_such_planner_module'" in message
    assert "current directory" in message and "Traceback" not in message


def test_a_missing_submodule_names_the_package() -> None:
    message = spec_error("fleetsim.planners.nope:Planner")
    assert "package 'fleetsim.planners' has no module 'nope'" in message


def test_an_error_raised_while_importing_shows_its_message_and_line_not_a_traceback(project: WriteModule) -> None:
    path = project("explodes_on_import", "import os\nraise RuntimeError('no licence key')\n")
    message = spec_error("explodes_on_import:Planner")
    assert "importing 'explodes_on_import' raised RuntimeError: no licence key" in message
    assert f"{path}:2" in message
    assert "Traceback" not in message


def test_a_missing_dependency_is_not_reported_as_the_module_missing(project: WriteModule) -> None:
    project("needs_dependency", "import not_installed_dependency_xyz\n")
    message = spec_error("needs_dependency:Planner")
    assert "importing 'needs_dependency' failed: ModuleNotFoundError" in message
    assert "not_installed_dependency_xyz" in message
    assert "no module named 'needs_dependency'" not in message


def test_a_syntax_error_names_the_file_and_line(project: WriteModule) -> None:
    path = project("broken_syntax", "class Planner:\n    def plan_routes(self\n")
    message = spec_error("broken_syntax:Planner")
    assert "SyntaxError" in message and str(path) in message


def test_a_module_that_exits_while_importing_is_reported(project: WriteModule) -> None:
    project("exits_on_import", "import sys\nsys.exit(3)\n")
    assert "raised SystemExit" in spec_error("exits_on_import:Planner")


# -- attributes -----------------------------------------------------------------------------------


def test_a_missing_attribute_lists_public_names_of_the_module() -> None:
    message = spec_error("fleetsim.planners:ReservingPlaner")
    assert "'fleetsim.planners' has no attribute 'ReservingPlaner'" in message
    assert "did you mean 'ReservingPlanner'?" in message
    assert "it has BFSPlanner, GreedyPlanner, ReservingPlanner" in message


def test_a_missing_attribute_inside_a_class_names_the_class(project: WriteModule) -> None:
    project("user_outer_missing", PLANNER_MODULE)
    message = spec_error("user_outer_missing:Outer.build")
    assert "'user_outer_missing.Outer' has no attribute 'build'" in message and "make" in message


def test_an_attribute_that_is_not_callable_is_rejected(project: WriteModule) -> None:
    project("user_constant", PLANNER_MODULE)
    message = spec_error("user_constant:LIMIT")
    assert "names 3 of type int, which is not callable" in message
    assert "class or a zero-argument function" in message


def test_a_planner_instance_is_rejected_with_a_hint_to_name_a_factory(project: WriteModule) -> None:
    project("user_instance", PLANNER_MODULE)
    message = spec_error("user_instance:ready_made")
    assert "not callable" in message and "looks like a planner instance" in message


def test_a_class_without_the_planner_methods_is_rejected_before_it_is_made() -> None:
    message = spec_error("fleetsim.sim.guard:PlannerGuard")
    assert "class PlannerGuard has no plan_routes or fix_legs method" in message


def test_a_factory_that_needs_arguments_is_rejected_before_it_is_called(project: WriteModule) -> None:
    project("needs_args", "def make(horizon):\n    raise AssertionError('must not be called')\n")
    message = spec_error("needs_args:make")
    assert "make(horizon) needs arguments" in message


# -- making planners ------------------------------------------------------------------------------


def test_a_factory_that_raises_reports_its_error_and_line(project: WriteModule) -> None:
    path = project("raising_factory", "def make():\n    return int('x')\n")
    factory = load_planner_factory("raising_factory:make")
    with pytest.raises(PlannerSpecError) as info:
        factory()
    message = str(info.value)
    assert "make() raised ValueError: invalid literal" in message
    assert f"{path}:2" in message
    assert "return int('x')" in info.value.details


def test_a_factory_whose_result_lacks_the_planner_methods_is_rejected(project: WriteModule) -> None:
    project(
        "half_planner",
        "class Half:\n    def plan_routes(self, task, fleet, layout):\n        return []\n"
        "def make():\n    return Half()\n",
    )
    message = spec_error("half_planner:make")
    assert "which has no callable fix_legs" in message
    assert "fix_legs(task, fleet, layout)" in message


def test_planner_spec_error_is_a_fleetsim_error_and_a_value_error() -> None:
    assert issubclass(PlannerSpecError, FleetsimError)
    assert issubclass(PlannerSpecError, ValueError)
