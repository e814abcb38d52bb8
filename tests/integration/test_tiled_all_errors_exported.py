"""A mutated map saved by the real Tiled editor reports every broken object, as the hand-edited one does."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from fleetsim.errors import LoadErrors
from fleetsim.load.tiled.reader import load_map

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

pytestmark = pytest.mark.integration

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


@pytest.mark.parametrize("suffix", [".json", ".tmx"])
def test_a_mutated_map_exported_by_tiled_reports_each_broken_object(
    tiled: TiledCli, tmp_path: Path, suffix: str
) -> None:
    folder = tmp_path / "examples" / "loop"
    shutil.copytree(SUITES / "examples" / "loop", folder)
    shutil.copytree(SUITES / "tiled", tmp_path / "tiled")
    source = folder / "map.tmx"
    text = source.read_text(encoding="utf-8")
    text = text.replace('value="forward"', 'value="sideways"', 1)  # object 3
    text = text.replace('<object id="7"', '<object id="7" type="stright"')
    source.write_text(text, encoding="utf-8")
    exported = tiled.export_map(source, folder / ("by_tiled" + suffix))
    with pytest.raises(LoadErrors) as info:
        load_map(exported)
    found = [(inner.location.object_id, inner.problem) for inner in info.value.errors if inner.location]
    assert [object_id for object_id, _ in found] == [3, 7]
    assert found[0][1] == "unknown direction 'sideways' (expected both, forward or backward)"
    assert found[1][1].startswith("unknown class 'stright' on a polyline; did you mean 'straight'?")
    assert {str(inner.location.path) for inner in info.value.errors if inner.location} == {str(exported)}
