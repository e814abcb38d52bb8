"""What VDA 5050 vehicles cost: message rates, order latency, CPU per vehicle, and where pacing breaks.

(Not named ``vda5050.py``: with ``benchmarks/`` on ``sys.path`` that would shadow the ``vda5050`` package
of vda5050-sdk, whose schemas the tests validate with.)

    python benchmarks/vda5050_vehicles.py [--vehicles 10,50,100,200] [--speeds 10,20,50] [--seconds 20]

Each fleet drives a generated warehouse lattice (``benchmarks/warehouse.py``) through fleetsim's embedded
broker, with state and visualization at their default rates (state on every change and every 5 simulated
seconds, visualization every simulated second). A small master control in this process (paho-mqtt) sends
every vehicle one order as soon as it sees the vehicle's first state: its start edge, released; the
vehicles then stand, so the figures are the protocol's own, not a planner's. Per run:

- ``msg/s``: messages the vehicles published per wall second (state, visualization, connection, factsheet);
- order latency: wall seconds from an order's arrival at its vehicle to the harness's verdict on its plan
  (median and max over the fleet's first orders);
- ``CPU/vehicle``: this process's CPU seconds (the simulation, the vehicles' MQTT clients, the embedded
  broker and the master control all run in it) per vehicle and simulated second;
- pacing: the most wall seconds a step began behind its paced time, how many steps began more than one
  step's wall time behind, and "kept" when the paced run (from the master control's first message to the
  end) took at most 5 % longer than its simulated time at that speed:
  the fleet size and speed at which it is no longer kept is where this machine cannot pace the run.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from paho.mqtt.client import Client, MQTTMessage, MQTTv311
from paho.mqtt.enums import CallbackAPIVersion

sys.path.insert(0, str(Path(__file__).resolve().parent))
from warehouse import write_fleet_scenario

from fleetsim.load.scenario import load_scenario_dir
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
from fleetsim.vda5050.broker import EmbeddedBroker
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings


class _FirstOrders:
    """Sends each vehicle one order, its start edge released, on its first state."""

    def __init__(self, host: str, port: int) -> None:
        self.site: dict[str, Any] | None = None
        self.ordered: set[str] = set()
        self.lock = threading.Lock()
        self.client = Client(
            callback_api_version=CallbackAPIVersion.VERSION2, client_id="bench-master", protocol=MQTTv311
        )
        self.client.on_message = self._on_message
        self.client.connect(host, port)
        self.client.subscribe([("uagv/fleetsim/site", 1), ("uagv/v2/fleetsim/+/state", 0)])
        self.client.loop_start()

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        document = json.loads(message.payload)
        with self.lock:
            if message.topic.endswith("/site"):
                self.site = document
                return
            serial = document["serialNumber"]
            if self.site is None or serial in self.ordered:
                return
            self.ordered.add(serial)
        vehicle = next(v for v in self.site["vehicles"] if v["serialNumber"] == serial)
        edge = next(
            e
            for e in self.site["edges"]
            if e["edgeId"] == vehicle["startEdgeId"] and e["startNodeId"] == vehicle["startNodeId"]
        )
        order = {
            "headerId": len(self.ordered), "timestamp": "2026-01-01T00:00:00.00Z", "version": "2.0.0",
            "manufacturer": "fleetsim", "serialNumber": serial, "orderId": f"o{serial}", "orderUpdateId": 0,
            "nodes": [
                {"nodeId": edge["startNodeId"], "sequenceId": 0, "released": True, "actions": []},
                {"nodeId": edge["endNodeId"], "sequenceId": 2, "released": True, "actions": []},
            ],
            "edges": [
                {"edgeId": edge["edgeId"], "sequenceId": 1, "released": True, "startNodeId": edge["startNodeId"],
                 "endNodeId": edge["endNodeId"], "actions": []},
            ],
        }  # fmt: skip
        self.client.publish(f"uagv/v2/fleetsim/{serial}/order", json.dumps(order).encode())

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def run_one(vehicles: int, speed: float, seconds: float, folder: Path) -> dict[str, Any]:
    write_fleet_scenario(folder, vehicles, seed=1)
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=seconds, stop_on=()))
    with EmbeddedBroker() as broker:
        master = _FirstOrders(broker.address.host, broker.address.port)
        fleet = Vda5050Fleet(Vda5050Settings(broker=broker.address, speed=speed, start_timeout=60.0))
        cpu_before = resource.getrusage(resource.RUSAGE_SELF)
        wall_before = time.perf_counter()
        result = run_scenario(scenario, fleet, planner_timeout=None, keep_trace=False)
        wall = time.perf_counter() - wall_before
        cpu_after = resource.getrusage(resource.RUSAGE_SELF)
        master.close()
    published = sum(sum(count + 1 for count in v.headers.values()) for v in fleet.vehicles.values())
    cpu = (cpu_after.ru_utime - cpu_before.ru_utime) + (cpu_after.ru_stime - cpu_before.ru_stime)
    latencies = fleet.latencies or [float("nan")]
    return {
        "vehicles": vehicles,
        "speed": speed,
        "sim_s": result.sim_time,
        "wall_s": wall,
        "paced_s": fleet.finished - fleet.started,  # from the master control's first message to the end
        "msg_per_s": published / (fleet.finished - fleet.started),
        "latency_median_ms": statistics.median(latencies) * 1e3,
        "latency_max_ms": max(latencies) * 1e3,
        "orders": len(fleet.latencies),
        "cpu_ms_per_vehicle_s": cpu / vehicles / result.sim_time * 1e3,
        "lag_s": fleet.lag,
        "late_steps": fleet.late_steps,
        "steps": result.steps,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vehicles", default="10,50,100,200")
    parser.add_argument("--speeds", default="10,20,50")
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per run")
    args = parser.parse_args(argv)
    print(
        f"{'vehicles':>8} {'speed':>6} {'msg/s':>8} {'latency med/max ms':>19} {'orders':>6} {'CPU ms/vehicle-s':>16} {'lag s':>7} {'late steps':>10}  pace"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for vehicles in (int(v) for v in args.vehicles.split(",")):
            for speed in (float(s) for s in args.speeds.split(",")):
                row = run_one(vehicles, speed, args.seconds, Path(tmp, f"v{vehicles}-s{speed:g}"))
                # Kept: the run took at most 5 % longer than its paced time (steps may jitter a little).
                kept = "kept" if row["paced_s"] <= row["sim_s"] / row["speed"] * 1.05 else "NOT kept"
                print(
                    f"{row['vehicles']:>8} {row['speed']:>6g} {row['msg_per_s']:>8.0f} "
                    f"{row['latency_median_ms']:>9.1f}/{row['latency_max_ms']:<9.1f} {row['orders']:>6} "
                    f"{row['cpu_ms_per_vehicle_s']:>16.2f} {row['lag_s']:>7.2f} {row['late_steps']:>5}/{row['steps']:<4}  {kept}",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
