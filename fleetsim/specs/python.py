"""Planner specs (SPEC §14): ``module:attr`` names a planner class or zero-argument factory.

``import_planner_factory`` imports the module once and returns a ``PlannerFactory`` that makes a fresh
planner for every run (``exec:COMMAND`` specs, planners in other processes, are read by
``fleetsim.exec.spec``, which builds on this module). A suite entry's ``planner_options`` are given to
the factory as keyword arguments, over its parameters' defaults, and ``scenario_dir`` (the scenario's
folder) to a factory that declares a parameter of that name. The current working directory is
importable, so ``--planner my_planner:MyPlanner`` works from a user's project folder. Every mistake is one
``PlannerSpecError`` saying what is wrong and how to fix it; the user's own import-time or
construction errors are shown as their message and location, not as a harness traceback.
"""

from __future__ import annotations

import copy
import functools
import importlib
import inspect
import os
import shlex
import shutil
import sys
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import ModuleType
from typing import Any, cast

from fleetsim.errors import FleetsimError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.planning.protocol import Planner
from fleetsim.scenario import PlannerSetup

__all__ = [
    "METHODS",
    "SCENARIO_DIR",
    "PlannerFactory",
    "PlannerSpecError",
    "SpecError",
    "command_words",
    "import_planner_factory",
]

EXAMPLE = "fleetsim.planners:ReservingPlanner"
METHODS = ("plan_routes", "fix_legs")
_SHOWN_NAMES = 8  # public names listed when an attribute is missing
SCENARIO_DIR = "scenario_dir"  # the parameter a factory declares to be given the scenario's folder
_BY_NAME = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)


class SpecError(FleetsimError, ValueError):
    """A spec (``module:attr`` and the like) that cannot give what it names.

    ``spec`` is the spec as given; ``details`` holds the user's traceback where there is one.
    """

    def __init__(self, message: str, spec: str, details: str = "") -> None:
        self.spec = spec
        self.details = details
        super().__init__(message)


class PlannerSpecError(SpecError):
    """A planner spec cannot give planners: malformed, not importable, not callable, or makes no planner."""


@dataclass(frozen=True, slots=True)
class PlannerFactory:
    """Makes a fresh planner per call; ``spec`` is the identity shown in results.

    ``make`` is called with a run's planner options as keyword arguments (a fresh copy each time, so no
    run sees what another's planner did to them), plus ``scenario_dir`` when it declares a parameter of
    that name: without options, and without that parameter, it is called with no arguments.
    """

    spec: str
    make: Callable[..., object]

    def __call__(self, setup: PlannerSetup | None = None) -> Planner:
        """A fresh planner made with ``setup`` (a suite entry's ``planner_options``, and its folder as
        ``scenario_dir`` when the factory asks for it); a :class:`PlannerSpecError` when it cannot be made."""
        setup = setup if setup is not None else PlannerSetup()
        arguments = self._arguments(setup)
        try:
            planner = self.make(**arguments)
        except Exception as exc:  # the user's constructor: report it, do not crash the harness
            where, given = (f"{setup.where}: ", "**planner_options") if setup.options else ("", "")
            msg = f"{where}planner spec {self.spec!r}: {_name(self.make)}({given}) raised {_exception_line(exc)}{_where(exc)}"
            raise PlannerSpecError(msg, self.spec, _user_traceback(exc)) from None
        missing = [name for name in METHODS if not callable(getattr(planner, name, None))]
        if missing:
            msg = (
                f"planner spec {self.spec!r}: {_name(self.make)}() returned {planner!r}, which has no callable "
                f"{' or '.join(missing)}; a planner needs plan_routes(task, fleet, layout) and "
                "fix_legs(task, fleet, layout)"
            )
            raise PlannerSpecError(msg, self.spec)
        return cast(Planner, planner)

    def for_setup(self, setup: PlannerSetup) -> Callable[[], Planner]:
        """Fresh planners for a scenario whose entry gives ``setup`` (its options and folder)."""
        return functools.partial(self, setup)

    def _arguments(self, setup: PlannerSetup) -> dict[str, Any]:
        """The keyword arguments of a call: the options (copied) and ``scenario_dir`` if it is asked for;
        options the factory does not take are a :class:`PlannerSpecError` naming them and where they are."""
        options = setup.options
        arguments = copy.deepcopy(dict(options))
        try:
            signature = inspect.signature(self.make)
        except (TypeError, ValueError):  # some builtins have none; the call will tell
            return arguments
        asked = signature.parameters.get(SCENARIO_DIR)
        if asked is not None and asked.kind in _BY_NAME:
            arguments[SCENARIO_DIR] = setup.folder
        if options:
            problem = _options_problem(signature, options, arguments)
            if problem is not None:
                where = f"{setup.where}: " if setup.where else ""
                msg = f"{where}planner spec {self.spec!r}: {_name(self.make)} {problem}"
                raise PlannerSpecError(msg, self.spec)
        return arguments


def _options_problem(signature: inspect.Signature, options: Mapping[str, Any], arguments: dict[str, Any]) -> str | None:
    """What is wrong with calling a factory of ``signature`` with planner ``options``, or ``None``."""
    parameters = signature.parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        return None
    takes = [name for name, p in parameters.items() if p.kind in _BY_NAME and name != SCENARIO_DIR]
    unknown = [name for name in options if name not in takes]
    if unknown:
        name = unknown[0]
        offered = f"its options: {', '.join(takes)}" if takes else "it takes no options"
        return (
            f"does not take the planner option {name}={options[name]!r} (planner_options); {offered}"
            f"{did_you_mean(name, takes)}"
        )
    try:
        signature.bind(**arguments)
    except TypeError as error:
        return f"cannot be called with the planner_options {dict(options)!r}: {error}"
    return None


def import_planner_factory(spec: str) -> PlannerFactory:
    """The factory that a ``module:attr`` spec names: a planner class or zero-argument factory (attr
    possibly dotted), from a module imported once; the current working directory is importable.

    Every mistake in ``spec`` is a [`PlannerSpecError`][fleetsim.specs.python.PlannerSpecError].
    """
    module_name, attr_path = _split(spec)
    module = _import(spec, module_name)
    target = _resolve(spec, module, attr_path)
    _check_target(spec, target)
    return PlannerFactory(spec, cast(Callable[[], object], target))


# -- parsing --------------------------------------------------------------------------------------


def _split(spec: str) -> tuple[str, str]:
    if not isinstance(spec, str):
        msg = f"planner spec {spec!r} must be a string like {EXAMPLE}"
        raise PlannerSpecError(msg, repr(spec))
    module_name, colon, attr_path = spec.partition(":")
    if not colon:
        msg = f"planner spec {spec!r} must look like module:attribute, e.g. {EXAMPLE}"
        raise PlannerSpecError(msg, spec)
    if module_name.endswith(".py") or "/" in module_name or "\\" in module_name:
        stem = os.path.splitext(os.path.basename(module_name))[0]
        msg = (
            f"planner spec {spec!r} names a file; name the module instead, e.g. {stem}:{attr_path or 'MyPlanner'} "
            "(run fleetsim from the folder that holds the file)"
        )
        raise PlannerSpecError(msg, spec)
    if not _dotted_name(module_name):
        msg = f"planner spec {spec!r}: the module part {module_name!r} must be a dotted Python name, e.g. {EXAMPLE}"
        raise PlannerSpecError(msg, spec)
    if not _dotted_name(attr_path):
        msg = f"planner spec {spec!r}: the attribute part {attr_path!r} must be a dotted Python name, e.g. {EXAMPLE}"
        raise PlannerSpecError(msg, spec)
    return module_name, attr_path


def _dotted_name(text: str) -> bool:
    return bool(text) and all(part.isidentifier() for part in text.split("."))


# -- importing ------------------------------------------------------------------------------------


def _import(spec: str, module_name: str) -> ModuleType:
    cwd = os.getcwd()
    # A console script's sys.path holds its bin folder, not the folder the user works in.
    if cwd not in sys.path and "" not in sys.path:
        sys.path.insert(0, cwd)
    importlib.invalidate_caches()  # the module may have been written after the finders looked
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name is not None and (module_name == exc.name or module_name.startswith(exc.name + ".")):
            raise PlannerSpecError(_no_module(spec, exc.name, cwd), spec) from None
        msg = f"planner spec {spec!r}: importing {module_name!r} failed: {_exception_line(exc)}{_where(exc)}"
        raise PlannerSpecError(msg, spec, _user_traceback(exc)) from None
    except (Exception, SystemExit) as exc:  # the user's module raised while it was imported
        msg = f"planner spec {spec!r}: importing {module_name!r} raised {_exception_line(exc)}{_where(exc)}"
        raise PlannerSpecError(msg, spec, _user_traceback(exc)) from None


def _no_module(spec: str, missing: str, cwd: str) -> str:
    parent, _, child = missing.rpartition(".")
    if parent:
        return f"planner spec {spec!r}: no module named {missing!r} (package {parent!r} has no module {child!r}); check the spelling"
    return (
        f"planner spec {spec!r}: no module named {missing!r}; check the spelling, run fleetsim from the folder that "
        f"holds {missing}.py (or the {missing}/ package), or install it (current directory: {cwd})"
    )


def _resolve(spec: str, module: ModuleType, attr_path: str) -> object:
    target: object = module
    where = module.__name__
    for part in attr_path.split("."):
        try:
            target = getattr(target, part)
        except AttributeError:
            names = _public_names(target)
            listing = f"; it has {_listing(names)}" if names else ""
            msg = f"planner spec {spec!r}: {where!r} has no attribute {part!r}{did_you_mean(part, names)}{listing}"
            raise PlannerSpecError(msg, spec) from None
        where = f"{where}.{part}"
    return target


def _check_target(spec: str, target: object) -> None:
    if not callable(target):
        hint = ""
        if all(callable(getattr(target, name, None)) for name in METHODS):
            hint = "; it looks like a planner instance: name its class, or a function returning a fresh one"
        msg = (
            f"planner spec {spec!r} names {_describe(target)}, which is not callable; it must be a planner "
            f"class or a zero-argument function returning a planner{hint}"
        )
        raise PlannerSpecError(msg, spec)
    if inspect.isclass(target):
        missing = [name for name in METHODS if not callable(getattr(target, name, None))]
        if missing:
            msg = (
                f"planner spec {spec!r}: class {target.__qualname__} has no {' or '.join(missing)} method; a planner "
                "needs plan_routes(task, fleet, layout) and fix_legs(task, fleet, layout)"
            )
            raise PlannerSpecError(msg, spec)
    try:
        signature = inspect.signature(target)
    except (TypeError, ValueError):  # some builtins have none; the call will tell
        return
    try:
        signature.bind()
    except TypeError:
        msg = (
            f"planner spec {spec!r}: {_name(target)}{signature} needs arguments, but a planner is made with none "
            "(a suite entry's planner_options only override defaults); give its parameters defaults, or name "
            "a zero-argument function that supplies them"
        )
        raise PlannerSpecError(msg, spec) from None


# -- describing things ----------------------------------------------------------------------------


def _public_names(obj: object) -> list[str]:
    """Public classes and functions of ``obj`` (a module's ``__all__`` first), for "it has ..." hints."""
    exported = getattr(obj, "__all__", None) if isinstance(obj, ModuleType) else None
    names = list(exported) if isinstance(exported, (list, tuple)) else sorted(dir(obj))
    return [
        name
        for name in names
        if isinstance(name, str)
        and not name.startswith("_")
        and callable(getattr(obj, name, None))
        and not isinstance(getattr(obj, name, None), ModuleType)
    ]


def _listing(names: list[str]) -> str:
    shown = ", ".join(names[:_SHOWN_NAMES])
    return shown + (f" and {len(names) - _SHOWN_NAMES} more" if len(names) > _SHOWN_NAMES else "")


def _name(obj: object) -> str:
    return getattr(obj, "__qualname__", None) or getattr(obj, "__name__", None) or repr(obj)


def _describe(obj: object) -> str:
    if isinstance(obj, ModuleType):
        return f"module {obj.__name__!r}"
    return f"{obj!r} of type {type(obj).__name__}"


def _exception_line(exc: BaseException) -> str:
    if isinstance(exc, SyntaxError):  # its location is the point, and format_exception_only shows it
        return f"SyntaxError: {exc.msg}"
    return f"{type(exc).__name__}: {exc}"


def _user_frames(exc: BaseException) -> list[traceback.FrameSummary]:
    """The traceback without this module's and the import machinery's frames."""
    frames = traceback.extract_tb(exc.__traceback__)
    return [
        frame for frame in frames if frame.filename != __file__ and not frame.filename.startswith("<frozen importlib")
    ]


def _where(exc: BaseException) -> str:
    """`` (file:line)`` of the line that raised, in the user's code."""
    if isinstance(exc, SyntaxError) and exc.filename:
        return f" ({exc.filename}:{exc.lineno})"
    frames = _user_frames(exc)
    return f" ({frames[-1].filename}:{frames[-1].lineno})" if frames else ""


def _user_traceback(exc: BaseException) -> str:
    lines = ["Traceback (most recent call last):\n", *traceback.format_list(_user_frames(exc))]
    lines += traceback.format_exception_only(type(exc), exc)
    return "".join(lines)


def command_words(spec: str, text: str, *, whose: str, empty: str) -> tuple[str, ...]:
    """The words of the command ``text`` that planner spec ``spec`` names (``exec:COMMAND``, a
    ``vda5050:`` spec's ``exec=``), its program found on PATH or as a file; else a
    :class:`PlannerSpecError` naming the spec. ``whose`` says whose command the messages speak of ("the",
    "the master control's"); ``empty`` is the whole message for a spec that names no command."""
    try:
        words = tuple(shlex.split(text))
    except ValueError as error:
        msg = f"planner spec {spec!r}: {whose} command cannot be split into words ({error})"
        raise PlannerSpecError(msg, spec) from None
    if not words:
        raise PlannerSpecError(empty, spec)
    if shutil.which(words[0]) is None:
        where = "is not a file" if os.sep in words[0] else "is not on PATH"
        msg = f"planner spec {spec!r}: {whose} program {words[0]!r} {where}"
        raise PlannerSpecError(msg, spec)
    return words
