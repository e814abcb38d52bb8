"""A suite entry's ``planner_options`` and ``files``: what it gives its planner (a :class:`PlannerSetup`).

The schema has checked the shapes (a mapping of JSON values by identifier, a list of strings); what it
cannot say is checked here: a data file must lie inside the scenario's folder (its ``dir``, else the
suite file's folder), since a sweep recreates that folder on its workers, and must exist. An entry's
``planner_options`` override the defaults' key by key; its ``files`` replace the defaults' list.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path, PurePosixPath
from types import MappingProxyType
from typing import Any

from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.yaml_source import Locate
from fleetsim.load.suites.schema import dotted_path, raise_suite_errors, suite_error
from fleetsim.scenario import PlannerSetup

__all__ = ["PLANNER_KEYS", "planner_setup"]

PLANNER_KEYS = ("planner_options", "files")


def planner_setup(
    entry: Mapping[str, Any],
    defaults: Mapping[str, Any],
    folder: Path,
    locate: Locate,
    where: tuple[Any, ...],
) -> PlannerSetup:
    """The entry's setup over the defaults' (both schema-checked), its files checked to lie in ``folder``
    and exist; every problem is raised (several as one SuiteErrors)."""
    options = {**defaults.get("planner_options", {}), **entry.get("planner_options", {})}
    own = "files" in entry
    listed = entry["files"] if own else defaults.get("files", [])
    errors = ErrorCollector()
    files = []
    for index, name in enumerate(listed):
        here = (*where, "files", index) if own else ("defaults", "files", index)
        with errors.collecting():
            files.append(_data_file(name, folder, here, locate, "" if own else f" (for {dotted_path(where)})"))
    raise_suite_errors(errors)
    written = (*where, "planner_options") if "planner_options" in entry else ("defaults", "planner_options")
    return PlannerSetup(MappingProxyType(options), folder, tuple(files), str(locate(written)) if options else "")


def _data_file(name: str, folder: Path, where: tuple[Any, ...], locate: Locate, entry: str) -> str:
    """``name`` as a ``/``-separated path inside ``folder``, or a located :class:`SuiteError` (``entry``
    names the scenario entry a defaults' file was looked for)."""
    path = PurePosixPath(name.replace("\\", "/"))
    if path.is_absolute() or Path(name).is_absolute() or ".." in path.parts or path == PurePosixPath("."):
        msg = (
            f"files entry {name!r}{entry} must be a path inside the scenario's folder ({str(folder)!r}), relative "
            "to it and without '..': a sweep recreates that folder on its workers"
        )
        raise suite_error(msg, where, locate(where))
    if not (folder / path).exists():
        msg = f"files entry {name!r}{entry}: no such file or folder in the scenario's folder ({str(folder / path)!r})"
        raise suite_error(msg, where, locate(where))
    return path.as_posix()
