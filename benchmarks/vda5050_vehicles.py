"""What VDA 5050 vehicles cost: message rates, order latency, CPU per vehicle, and where pacing breaks,
on fleetsim's embedded broker and on mosquitto side by side.

(Not named ``vda5050.py``: with ``benchmarks/`` on ``sys.path`` that would shadow the ``vda5050`` package
of vda5050-sdk, whose schemas the tests validate with.)

    python benchmarks/vda5050_vehicles.py [--vehicles 10,50,100,200] [--speeds 10,20,50] [--seconds 20]
        [--broker embedded,mosquitto] [--repeat 1]

Each fleet drives a generated warehouse lattice (``benchmarks/warehouse.py``) through an MQTT broker, with
state and visualization at their default rates (state on every change and every 5 simulated seconds,
visualization every simulated second). A small master control in this process (paho-mqtt) sends every
vehicle one order as soon as it sees the vehicle's first state: its start edge, released; the vehicles
then stand, so the figures are the protocol's own, not a planner's.

Brokers (``--broker``; by default both when mosquitto is installed, else the embedded one): ``embedded`` is
fleetsim's own (amqtt in a thread of this process), ``mosquitto`` a mosquitto process of its own started
for each run on a free loopback port (anonymous, no persistence). Each (vehicles, speed) runs ``--repeat``
times on every broker, the brokers taking turns (the order flips every repetition) so that both see the
same moments of a noisy machine; the table shows the medians. Per broker:

- ``msg/s``: messages the vehicles published per wall second (state, visualization, connection, factsheet);
- order latency: wall seconds from an order's arrival at its vehicle to the harness's verdict on its plan
  (median and max over the fleet's first orders);
- CPU per vehicle and simulated second, of this process (the simulation, the vehicles' MQTT clients, the
  master control and, for ``embedded``, the broker) and of the mosquitto process (from its
  ``/proc/PID/stat``), and their sum, which compares the brokers; ``core %`` is each process's CPU
  seconds per wall second of the paced part of the run (100 % = one core busy: this process runs its
  Python under one interpreter lock, so about 100 % is all it can have);
- pacing: the most wall seconds a step began behind its paced time, how many steps began more than one
  step's wall time behind, and "kept" when the paced run (from the master control's first message to the
  end) took at most 5 % longer than its simulated time at that speed:
  the fleet size and speed at which it is no longer kept is where this machine cannot pace the run.
"""

from __future__ import annotations

import argparse
import bisect
import contextlib
import json
import os
import resource
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from paho.mqtt.client import Client, MQTTMessage, MQTTv311
from paho.mqtt.enums import CallbackAPIVersion

sys.path.insert(0, str(Path(__file__).resolve().parent))
from warehouse import write_fleet_scenario

from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
from fleetsim.vda5050.broker import BrokerAddress, BrokerError, EmbeddedBroker, Mosquitto, find_mosquitto
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


BROKERS = ("embedded", "mosquitto")
_KEPT = 1.05  # kept: the paced run took at most 5 % longer than its paced time (steps may jitter a little)


class _Broker(NamedTuple):
    """A running broker: where it listens, and how many CPU seconds its own process has used so far (None:
    it runs in this process, and the harness's CPU holds it)."""

    address: BrokerAddress
    cpu: Callable[[], float | None]


@contextlib.contextmanager
def running_broker(kind: str, folder: Path) -> Iterator[_Broker]:
    """A fresh broker of ``kind`` (one of `BROKERS`) on a free loopback port, stopped afterwards."""
    if kind == "embedded":
        with EmbeddedBroker() as embedded:
            yield _Broker(embedded.address, lambda: None)
        return
    executable = find_mosquitto()
    if executable is None:
        msg = "broker 'mosquitto' is not installed (Debian/Ubuntu: apt install mosquitto)"
        raise BrokerError(msg, "mosquitto")
    with Mosquitto(executable, folder) as mosquitto:
        assert mosquitto.process is not None
        pid = mosquitto.process.pid
        yield _Broker(mosquitto.address, lambda: _process_cpu(pid))


def _process_cpu(pid: int) -> float:
    """CPU seconds (user and system) process ``pid`` has used: fields 14 and 15 of Linux's /proc/PID/stat,
    counted after the command name in parentheses (which may hold spaces)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _own_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)  # all threads of this process
    return usage.ru_utime + usage.ru_stime


class _CpuSampler:
    """This process's and the broker process's CPU seconds, sampled every 20 ms in a thread of its own: the
    paced part of a run is known only afterwards (as ``time.monotonic()`` times), and its share of a core is
    what tells whether a process was the one that could not keep up (start-up and the hold at t = 0 would
    dilute it)."""

    def __init__(self, broker_cpu: Callable[[], float | None]) -> None:
        self._broker_cpu = broker_cpu
        self.samples: list[tuple[float, float, float | None]] = []  # (monotonic, own CPU, broker CPU)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, name="bench-cpu-sampler", daemon=True)

    def __enter__(self) -> _CpuSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._stop.set()
        self._thread.join()

    def _sample(self) -> None:
        while True:
            self.samples.append((time.monotonic(), _own_cpu(), self._broker_cpu()))
            if self._stop.wait(0.02):
                return

    def cores(self, start: float, end: float) -> tuple[float, float | None]:
        """Busy cores (CPU seconds per wall second) of this process and of the broker's from ``start`` to
        ``end``, between the samples nearest them."""
        times = [sample[0] for sample in self.samples]
        first = self.samples[max(0, min(bisect.bisect_left(times, start), len(times) - 1))]
        last = self.samples[max(0, min(bisect.bisect_left(times, end), len(times) - 1))]
        wall = last[0] - first[0]
        if wall <= 0:
            return float("nan"), None
        broker = None if first[2] is None or last[2] is None else (last[2] - first[2]) / wall
        return (last[1] - first[1]) / wall, broker


def run_one(vehicles: int, speed: float, seconds: float, folder: Path, broker_kind: str) -> dict[str, Any]:
    """One fleet of ``vehicles`` paced at ``speed`` for ``seconds`` simulated seconds on a fresh broker."""
    folder.mkdir(parents=True, exist_ok=True)
    write_fleet_scenario(folder / "scenario", vehicles, seed=1)
    scenario = load_scenario_dir(folder / "scenario", settings=ScenarioSettings(time_limit=seconds, stop_on=()))
    with running_broker(broker_kind, folder) as broker:
        master = _FirstOrders(broker.address.host, broker.address.port)
        fleet = Vda5050Fleet(Vda5050Settings(broker=broker.address, speed=speed, start_timeout=60.0))
        cpu_before, broker_cpu_before = _own_cpu(), broker.cpu()
        with _CpuSampler(broker.cpu) as sampler:
            result = run_scenario(scenario, fleet, planner_timeout=None, keep_trace=False)
        cpu, broker_cpu_after = _own_cpu() - cpu_before, broker.cpu()
        master.close()
    broker_cpu = None if broker_cpu_before is None or broker_cpu_after is None else broker_cpu_after - broker_cpu_before
    published = sum(sum(count + 1 for count in v.headers.values()) for v in fleet.vehicles.values())
    latencies = fleet.latencies or [float("nan")]
    per_vehicle_s = 1e3 / vehicles / result.sim_time  # CPU seconds -> ms per vehicle and simulated second
    paced = fleet.finished - fleet.started  # from the master control's first message to the end
    harness_core, broker_core = sampler.cores(fleet.started, fleet.finished)
    return {
        "vehicles": vehicles,
        "speed": speed,
        "broker": broker_kind,
        "msg_per_s": published / paced,
        "latency_median_ms": statistics.median(latencies) * 1e3,
        "latency_max_ms": max(latencies) * 1e3,
        "orders": len(fleet.latencies),
        "harness_cpu_ms": cpu * per_vehicle_s,
        "broker_cpu_ms": None if broker_cpu is None else broker_cpu * per_vehicle_s,
        "total_cpu_ms": (cpu + (broker_cpu or 0.0)) * per_vehicle_s,
        "harness_core": harness_core,
        "broker_core": broker_core,
        "lag_s": fleet.lag,
        "late_steps": fleet.late_steps,
        "steps": result.steps,
        "paced_ratio": paced / (result.sim_time / speed),  # wall time of the paced run over its paced time
    }


def median_row(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The medians of ``rows`` (runs of one broker, fleet and speed), and how many of them kept the pace."""
    summary = dict(rows[0])
    for key, value in rows[0].items():
        if isinstance(value, float | int) and key not in ("vehicles", "speed"):
            summary[key] = statistics.median(row[key] for row in rows)
        elif value is None:
            summary[key] = None
    summary["kept_runs"] = sum(row["paced_ratio"] <= _KEPT for row in rows)
    summary["runs"] = len(rows)
    return summary


_HEADER = (
    f"{'vehicles':>8} {'speed':>5} {'broker':>9} {'msg/s':>6} {'latency med/max ms':>18} {'orders':>6}"
    f" {'CPU ms/vehicle-s harness+broker=total':>37} {'core % h/b':>10} {'lag s':>6} {'late steps':>10}  pace"
)


def format_row(row: dict[str, Any]) -> str:
    broker_cpu = "–" if row["broker_cpu_ms"] is None else f"{row['broker_cpu_ms']:.2f}"
    broker_core = "–" if row["broker_core"] is None else f"{row['broker_core'] * 100:.0f}"
    cpu = f"{row['harness_cpu_ms']:.2f}+{broker_cpu}={row['total_cpu_ms']:.2f}"
    core = f"{row['harness_core'] * 100:.0f}/{broker_core}"
    pace = "kept" if row["paced_ratio"] <= _KEPT else "NOT kept"
    if "runs" in row:
        pace += f" ({row['kept_runs']}/{row['runs']} runs kept)"
    return (
        f"{row['vehicles']:>8} {row['speed']:>5g} {row['broker']:>9} {row['msg_per_s']:>6.0f}"
        f" {row['latency_median_ms']:>8.1f}/{row['latency_max_ms']:<9.1f} {row['orders']:>6.0f} {cpu:>37}"
        f" {core:>10} {row['lag_s']:>6.2f} {row['late_steps']:>5.0f}/{row['steps']:<4.0f}  {pace}"
    )


def _numbers(convert: Callable[[str], float], what: str) -> Callable[[str], list[float]]:
    def parse(text: str) -> list[float]:
        try:
            values = [convert(part) for part in text.split(",")]
        except ValueError:
            values = []
        if not values or any(value <= 0 for value in values):
            msg = f"{text!r} must be {what} above 0, comma-separated"
            raise argparse.ArgumentTypeError(msg)
        return values

    return parse


def _brokers(text: str) -> list[str]:
    names = [part.strip() for part in text.split(",")]
    unknown = [name for name in names if name not in BROKERS]
    if unknown or len(set(names)) != len(names):
        msg = f"{text!r} must name each of {', '.join(BROKERS)} at most once, comma-separated"
        raise argparse.ArgumentTypeError(msg)
    return names


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vehicles", type=_numbers(int, "whole numbers"), default="10,50,100,200")
    parser.add_argument("--speeds", type=_numbers(float, "numbers"), default="10,20,50")
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per run")
    parser.add_argument(
        "--broker",
        type=_brokers,
        default=None,
        help="brokers to compare: embedded, mosquitto or both (default: both when mosquitto is installed)",
    )
    parser.add_argument("--repeat", type=int, default=1, help="runs per broker, fleet and speed (medians shown)")
    args = parser.parse_args(argv)
    installed = find_mosquitto() is not None
    brokers: list[str] = args.broker or (list(BROKERS) if installed else ["embedded"])
    if "mosquitto" in brokers and not installed:
        parser.error("--broker=mosquitto: mosquitto is not installed (Debian/Ubuntu: apt install mosquitto)")
    if args.repeat < 1:
        parser.error(f"--repeat={args.repeat!r} must be at least 1")
    if args.seconds <= 0:
        parser.error(f"--seconds={args.seconds!r} must be above 0")
    print("runs, in the order measured:")
    print(_HEADER, flush=True)
    medians: list[dict[str, Any]] = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for vehicles in args.vehicles:
                for speed in args.speeds:
                    runs: dict[str, list[dict[str, Any]]] = {broker: [] for broker in brokers}
                    for repetition in range(args.repeat):
                        # The brokers take turns, the first one changing every repetition.
                        for broker in brokers if repetition % 2 == 0 else brokers[::-1]:
                            folder = Path(tmp, f"v{vehicles}-s{speed:g}-{broker}-{repetition}")
                            row = run_one(vehicles, speed, args.seconds, folder, broker)
                            runs[broker].append(row)
                            print(format_row(row), flush=True)
                    medians.extend(median_row(runs[broker]) for broker in brokers)
    except BrokerError as exc:
        print(f"vda5050_vehicles: {exc}", file=sys.stderr)
        return 1
    print(f"\nmedians of {args.repeat} run(s) per broker, {args.seconds:g} simulated seconds each:")
    print(_HEADER)
    for row in medians:
        print(format_row(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
