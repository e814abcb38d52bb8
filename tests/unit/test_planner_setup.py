"""A suite entry's ``planner_options`` and ``files``: read and checked with the suite, given to the planner
factory, carried to a sweep's workers and to planner processes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import MappingProxyType
from typing import Any

import jsonschema
import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.errors import SuiteError
from fleetsim.exec.protocol import encode_init
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.controller import FleetController
from fleetsim.scenario import PlannerSetup
from fleetsim.sim.record import RunOrigin
from fleetsim.specs.python import PlannerFactory, PlannerSpecError
from fleetsim.sweep.payload import scenario_from_payload, scenario_payload

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "scenario_suites" / "examples"


def suite(tmp_path: Path, entry: str, defaults: str = "") -> Path:
    """A suite in ``tmp_path`` whose one scenario is the crossing (with a data file) plus ``entry``'s lines."""
    if not (tmp_path / "examples").exists():
        shutil.copytree(EXAMPLES / "crossing", tmp_path / "examples" / "crossing")
        shutil.copytree(EXAMPLES.parent / "tiled", tmp_path / "tiled")
        (tmp_path / "examples" / "crossing" / "speeds.bin").write_bytes(bytes(range(256)))
    path = tmp_path / "s.fleetsim.yaml"
    path.write_text(
        f"fleetsim: 1\nname: s\n{defaults}scenarios:\n  - name: crossing\n    dir: examples/crossing\n{entry}",
        encoding="utf-8",
    )
    return path


def load_error(path: Path) -> str:
    with pytest.raises(SuiteError) as info:
        load_suite(path)
    return str(info.value)


# -- the suite --------------------------------------------------------------------------------------


def test_options_over_the_defaults_and_files_in_the_scenario_folder_are_read(tmp_path: Path) -> None:
    path = suite(
        tmp_path,
        "    planner_options: {table: speeds.bin, weights: {a: [1, 2.5]}}\n    files: [speeds.bin]\n",
        defaults="defaults:\n  planner_options: {table: other, horizon: 3}\n",
    )
    setup = load_suite(path).scenarios[0].planner_setup
    assert dict(setup.options) == {"table": "speeds.bin", "horizon": 3, "weights": {"a": [1, 2.5]}}
    assert setup.folder == tmp_path / "examples" / "crossing" and setup.files == ("speeds.bin",)
    assert setup.where == f"{path}:8:22"  # the entry's own planner_options
    loaded = load_suite(path)
    assert load_scenario(loaded.scenarios[0], loaded).planner_setup == setup


@pytest.mark.parametrize(
    ("entry", "said"),
    [
        ("    planner_options: [table]\n", ":6:22: scenarios[0].planner_options: ['table'] is not a mapping"),
        ("    planner_options: {when: 2024-01-01}\n", ":6:29: scenarios[0].planner_options.when: datetime.date("),
        ("    planner_options: {scenario_dir: x}\n", "'scenario_dir' must not be scenario_dir (fleetsim gives it"),
        ("    files: [../x.csv]\n", ":6:13: scenarios[0].files[0]: files entry '../x.csv' must be a path inside"),
        ("    files: [nothere.csv]\n", ":6:13: scenarios[0].files[0]: files entry 'nothere.csv': no such file"),
    ],
)
def test_a_bad_planner_options_or_files_entry_is_refused_at_its_place(tmp_path: Path, entry: str, said: str) -> None:
    message = load_error(suite(tmp_path, entry))
    assert said in message and "Traceback" not in message


# -- the factory ------------------------------------------------------------------------------------


class Recording(ReservingPlanner):
    """Keeps what it was made with."""

    def __init__(self, weights: list[int] | None = None, scenario_dir: Path | None = None) -> None:
        self.weights = weights
        self.scenario_dir = scenario_dir
        super().__init__()


def test_a_factory_without_options_is_called_with_none_and_scenario_dir_only_when_it_asks() -> None:
    calls: list[dict[str, Any]] = []

    def plain(**given: Any) -> ReservingPlanner:
        calls.append(given)
        return ReservingPlanner()

    PlannerFactory("m:plain", plain)(PlannerSetup(folder=Path("/somewhere")))
    assert calls == [{}]
    made = PlannerFactory("m:Recording", Recording)(PlannerSetup(folder=Path("/somewhere")))
    assert isinstance(made, Recording) and made.scenario_dir == Path("/somewhere") and made.weights is None


def test_each_planner_gets_its_own_copy_of_the_options() -> None:
    setup = PlannerSetup(MappingProxyType({"weights": [1, 2]}))
    first = PlannerFactory("m:Recording", Recording)(setup)
    assert isinstance(first, Recording) and first.weights is not None
    first.weights.append(3)
    second = PlannerFactory("m:Recording", Recording)(setup)
    assert isinstance(second, Recording) and second.weights == [1, 2]


def test_an_option_the_factory_does_not_take_is_named_with_where_it_is_written() -> None:
    setup = PlannerSetup(MappingProxyType({"weight": [1]}), where="s.fleetsim.yaml:6:22")
    with pytest.raises(PlannerSpecError) as info:
        PlannerFactory("m:Recording", Recording)(setup)
    message = str(info.value)
    assert message.startswith(
        "s.fleetsim.yaml:6:22: planner spec 'm:Recording': Recording does not take the planner option"
    )
    assert "option weight=[1] (planner_options); its options: weights" in message
    assert "did you mean 'weights'" in message


# -- on the way to workers and planner processes ----------------------------------------------------


def test_a_sweep_payload_carries_the_options_and_the_data_files_bytes(tmp_path: Path) -> None:
    path = suite(tmp_path, "    planner_options: {table: speeds.bin}\n    files: [speeds.bin]\n")
    loaded = load_suite(path)
    payload = scenario_payload(load_scenario(loaded.scenarios[0], loaded))
    worker = tmp_path / "worker"
    worker.mkdir()
    sent = scenario_from_payload(payload, worker).planner_setup
    assert (dict(sent.options), sent.folder, sent.files) == ({"table": "speeds.bin"}, worker, ("speeds.bin",))
    assert (worker / "speeds.bin").read_bytes() == bytes(range(256))


def test_the_init_message_holds_the_options_and_the_folder_since_protocol_1_4() -> None:
    loaded = load_suite(ROOT / "scenario_suites" / "examples.fleetsim.yaml")
    scenario = load_scenario(next(s for s in loaded.scenarios if s.name == "crossing"), loaded)
    init = encode_init(scenario.layout, FleetController(scenario).snapshot(0.0), {"table": "t.csv"}, "/data/crossing")
    schema = json.loads((ROOT / "schemas" / "planner-init.schema.json").read_text(encoding="utf-8"))
    jsonschema.validate(init, schema)
    assert (init["protocol"], init["planner_options"], init["scenario_dir"]) == (
        "fleetsim-planner/1.5",
        {"table": "t.csv"},
        "/data/crossing",
    )


def test_a_record_takes_only_the_documented_producer_keys() -> None:
    with pytest.raises(ValueError, match=r"own=\['flavour'\]: a record's own keys must be among PRODUCER_KEYS"):
        RunOrigin(own={"flavour": 1})
