"""fleetsim driven by an independent master control: ``node/master.js``, built on vda-5050-lib 1.4.0's
MasterController (npm, Siemens; none of fleetsim's code), started by ``fleetsim run`` with
``vda5050:...,exec=node tests/vda5050/node/master.js``.

What it shows: a third-party VDA 5050 2.0 implementation accepts fleetsim's connection, factsheet and
state messages (the library validates every inbound message against its 2.0 schemas and drops those that
fail, so an order it never sees processed would hang the run), assigns orders fleetsim executes, and
the crossing completes. And the library's known fault, instant actions under the key ``instantActions``
instead of the text's ``actions``: fleetsim names the key in the vehicle's state (a validationError the
library's own state subscription reads back) and the run records an ``order-invalid`` rejection.

Skipped when node or the package is missing (``npm ci --prefix tests/vda5050/node``); fails instead
under FLEETSIM_REQUIRE_TOOLS=1.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from official import NODE_DIR
from runs import run_example
from tooling import missing

ROOT = Path(__file__).resolve().parents[2]
MASTER = NODE_DIR / "master.js"
_LIB = NODE_DIR / "node_modules" / "vda-5050-lib" / "controller" / "master-controller.js"
_MQTT = NODE_DIR / "node_modules" / "mqtt"


@pytest.fixture(scope="module")
def node() -> str:
    """The ``node`` executable, with vda-5050-lib and mqtt installed next to master.js."""
    executable = shutil.which("node")
    if executable is None:
        missing("Node.js 'node' is not on PATH (Debian/Ubuntu: apt install nodejs)")
    if not _LIB.is_file() or not _MQTT.is_dir():
        missing(f"vda-5050-lib is not installed in {NODE_DIR} (npm ci --prefix tests/vda5050/node)")
    assert executable is not None
    return executable


def _run(node: str, **environment: str) -> tuple[dict[str, Any], list[str]]:
    """``fleetsim run`` of the crossing with master.js as its master control: the JSON result and the
    stderr lines (fleetsim's and master.js's, which it inherits)."""
    spec = f"vda5050:speed=20,exec={node} {MASTER.relative_to(ROOT)}"
    done = run_example("crossing", spec, **environment)
    lines = done.stdout.splitlines()
    assert len(lines) == 1, done.stdout + done.stderr
    result: dict[str, Any] = json.loads(lines[0])
    assert done.returncode == (0 if result["status"] == "passed" else 1), done.stderr
    return result, done.stderr.splitlines()


def test_vda_5050_libs_master_controller_drives_the_crossing_one_vehicle_at_a_time(node: str) -> None:
    result, stderr = _run(node)
    assert result["status"] == "passed", "\n".join(stderr)
    assert result["tasks"] == {"total": 2, "completed": 2}
    assert result["collisions"] == [] and result["rejections"] == [] and result["failures"] == []
    assert result["paced"] == 20.0
    # The library drops (and says so on stderr) any inbound message its 2.0 validators reject: none was.
    assert not [line for line in stderr if "Drop inbound message" in line]
    master = [line for line in stderr if line.startswith("master.js: ")]
    assert any("vda-5050-lib MasterController started on mqtt://127.0.0.1:" in line for line in master)
    assigned = [k for k, line in enumerate(master) if ": vda-5050-lib-" in line and " to vehicle " in line]
    assert len(assigned) == 2, "\n".join(master)  # one order per task, through assignOrder
    words = master[assigned[0]].split()  # master.js: task T: ORDER to vehicle S over EDGES...
    task, serial = words[2].rstrip(":"), words[6]
    finished = master.index(f"master.js: transport order {task} of vehicle {serial}: FINISHED")
    assert assigned[0] < finished < assigned[1]  # the second vehicle only once the first task was done
    # The library saw its first order processed: it took fleetsim's states as valid 2.0 states.
    assert any(line.endswith("processed (canceled: false, active: false)") for line in master), "\n".join(master)


def test_the_libs_instant_actions_key_is_named_in_the_state_and_rejected_as_order_invalid(node: str) -> None:
    result, stderr = _run(node, FLEETSIM_MASTER_STATE_REQUEST="1")
    assert result["status"] == "failed" and result["ended"] == "rejection"
    [rejection, *_] = result["rejections"]
    assert rejection["code"] == "order-invalid"
    assert "expected key 'actions'" in rejection["message"] and "'instantActions'" in rejection["message"]
    assert result["tasks"]["completed"] == 0
    assert not [line for line in stderr if "Drop inbound message" in line]  # a state with errors is valid too
    # The vehicle told the library why, in its state's errors, as the library's state subscription read it.
    prefix = "master.js: vehicle 1 errors: "
    [reported, *_] = [json.loads(line.removeprefix(prefix)) for line in stderr if line.startswith(prefix)]
    [error] = [e for e in reported if e["errorType"] == "validationError"]
    references = {r["referenceKey"]: r["referenceValue"] for r in error["errorReferences"]}
    assert references["key"] == "instantActions" and "'instantActions'" in error["errorDescription"]


def test_master_js_names_the_environment_variable_it_lacks(node: str) -> None:
    environment = {k: v for k, v in os.environ.items() if not k.startswith("FLEETSIM_")}
    done = subprocess.run([node, str(MASTER)], capture_output=True, text=True, timeout=30, env=environment)
    assert done.returncode == 2
    assert "the environment has no FLEETSIM_MQTT_URL" in done.stderr
    environment["FLEETSIM_MQTT_URL"] = "mqtt://127.0.0.1:1"
    done = subprocess.run([node, str(MASTER)], capture_output=True, text=True, timeout=30, env=environment)
    assert done.returncode == 2 and "the environment has no FLEETSIM_VDA5050_INTERFACE" in done.stderr
