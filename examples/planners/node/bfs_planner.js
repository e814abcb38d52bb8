#!/usr/bin/env node
// An example fleetsim planner process in plain Node.js (no dependencies): the in-process BFSPlanner
// (fleetsim/planners/bfs.py) ported to the JSON-lines planner protocol "fleetsim-planner/1".
//
//   fleetsim run scenario_suites/examples.fleetsim.yaml --planner "exec:node examples/planners/node/bfs_planner.js"
//
// The protocol (specified in fleetsim/exec/protocol.py; JSON Schemas in schemas/planner-*.schema.json):
//   * fleetsim starts this process once per run and writes one JSON object per line to our stdin;
//     we answer every message with exactly one JSON object on one line of stdout. stdout carries
//     answers only: diagnostics go to stderr (fleetsim keeps it for its error reports).
//   * 1st message, {"type": "init", "protocol": "fleetsim-planner/1", "layout": {...}, "scenario": {...}}
//     -> answer {"type": "ready"}.
//   * then one request per planner call:
//       {"type": "plan_routes" | "fix_legs", "id": N, "vehicle": V, "task": TASK, "fleet": FLEET}
//     -> answer {"id": N, "plans": [PLAN...], "route_errors": [{"vehicle_id": V, "message": S}...]}
//        or {"id": N, "route_error": "..."} when the whole request cannot be routed.
//     "fleet" is left out when the fleet has not changed since the previous request: keep the last one.
//     The first "fleet" is complete; later ones hold only the vehicles, plans and queues that changed.
//   * protocol 1.2: answering init with {"type": "ready", "rounds": true} asks for a planning round's calls
//     in one message instead, {"type": "round", "calls": [{"type", "id", "vehicle", "task"}...], "fleet": FLEET}:
//     we make the calls in order and stop after the first answer that changes something (anything but
//     nothing or the plan in force handed back), answering {"answers": [ANSWER...], "durations": [SECONDS...]};
//     fleetsim applies them and sends the calls left, with the fleet as changed, in a new round.
//   * at the end of the run fleetsim closes stdin: we exit with status 0.
// A message we cannot understand is a protocol violation: we say why on stderr and exit with status 1.
"use strict";

const fs = require("fs");

const PROTOCOL = "fleetsim-planner/1"; // the major version; minor versions (1.1, ...) only add optional fields
const ROUNDS = process.env.BFS_PLANNER_ROUNDS !== "0"; // BFS_PLANNER_ROUNDS=0: one request per call
const FIX_HORIZON = 3; // fix_legs commits (at most) the first three legs of a plan, like BFSPlanner

// What the init message tells us, and the fleet of the last request that carried one.
let successors = null; // "segment|traverse" -> [{segment, traverse, joint}], in the order of layout.connections
const turnCapability = new Map(); // vehicle type name -> "curve" | "in_place"
let fleet = null;
let roundsAsked = false; // we answered init with "rounds": true

function fail(message) {
  process.stderr.write(`bfs_planner.js: ${message}\n`);
  process.exit(1); // stdout/stderr writes to pipes and files are synchronous on Linux: nothing is lost
}

function send(message) {
  const line = Buffer.from(JSON.stringify(message) + "\n");
  for (let done = 0; done < line.length; ) done += fs.writeSync(1, line, done);
}

const isObject = (value) => typeof value === "object" && value !== null && !Array.isArray(value);
const stateKey = (segment, traverse) => `${segment}|${traverse}`;

// ---- init: index the layout's connections by their "from" state --------------------------------------

function init(message) {
  if (typeof message.protocol !== "string" || message.protocol.split(".")[0] !== PROTOCOL) fail(`unsupported protocol ${JSON.stringify(message.protocol)}, expected ${PROTOCOL}`);
  // Rounds came with 1.2; an earlier fleetsim would refuse a ready answer that asks for them.
  roundsAsked = ROUNDS && Number(message.protocol.split(".")[1] || 0) >= 2;
  const { layout, scenario } = message;
  if (!isObject(layout) || !Array.isArray(layout.connections)) fail("init: layout.connections missing");
  if (!isObject(scenario) || !Array.isArray(scenario.vehicle_types)) fail("init: scenario.vehicle_types missing");
  successors = new Map();
  // A connection {"from": [segment, traverse], "to": [segment, traverse], "joint": kind} lets a vehicle
  // leaving `from` drive on to `to`. Only traverses a segment's direction allows appear. The successors
  // of a state are its connections in the order given: keeping it makes the search below pick the same
  // route as the Python planner when several routes are equally short.
  for (const c of layout.connections) {
    if (!Array.isArray(c.from) || !Array.isArray(c.to)) fail(`init: malformed connection ${JSON.stringify(c)}`);
    const key = stateKey(c.from[0], c.from[1]);
    if (!successors.has(key)) successors.set(key, []);
    successors.get(key).push({ segment: c.to[0], traverse: c.to[1], joint: c.joint });
  }
  // "curve": follows curves only; "in_place": can also turn on the spot.
  for (const kind of scenario.vehicle_types) turnCapability.set(kind.name, kind.turn_capability);
}

// ---- the route search (fleetsim/planners/routing.py) -----------------------------------------------

// A state is [segment, traverse, progress]: progress is "forward" (nose first) or "reverse" (backing).
function* nextStates(capability, [segment, traverse, progress]) {
  for (const step of successors.get(stateKey(segment, traverse)) || []) {
    if (capability === "in_place" || step.joint === "same") {
      yield [step.segment, step.traverse, progress]; // smooth joint, or the vehicle turns on the spot
    } else if (step.joint === "opposite") {
      // a cusp: a curve-only vehicle must change between driving nose first and backing
      yield [step.segment, step.traverse, progress === "forward" ? "reverse" : "forward"];
    }
    // a "turn_in_place" corner is no way on for a vehicle that only follows curves
  }
}

// Fewest legs from `start` to any state on segment `goal` (`start` itself excluded), or null.
function breadthFirstRoute(capability, start, goal) {
  const key = (state) => state.join("|");
  const cameFrom = new Map(); // state key -> the state it was reached from
  const seen = new Set([key(start)]);
  const frontier = [start];
  for (let head = 0; head < frontier.length; head++) {
    const state = frontier[head];
    for (const following of nextStates(capability, state)) {
      const k = key(following);
      if (seen.has(k)) continue;
      seen.add(k);
      cameFrom.set(k, state);
      if (following[0] === goal) {
        const path = [following]; // walk back to the start, then drop it
        while (cameFrom.has(key(path[path.length - 1]))) path.push(cameFrom.get(key(path[path.length - 1])));
        return path.reverse().slice(1);
      }
      frontier.push(following);
    }
  }
  return null;
}

// ---- the two planner calls (fleetsim/planners/bfs.py) -------------------------------------------

// A plan is {"vehicle_id", "legs"}; a leg is {"segment", "traverse", "progress", "fixed", "goal_for_task"}.
// The fixed legs are the committed prefix: the leading legs with fixed = true.
function fixedLegs(plan) {
  let count = 0;
  while (count < plan.legs.length && plan.legs[count].fixed === true) count++;
  return plan.legs.slice(0, count);
}

function planOf(vehicleId) {
  const plan = fleet.plans.get(vehicleId);
  if (!plan || !Array.isArray(plan.legs)) fail(`the fleet has no plan for vehicle ${vehicleId}`);
  return plan;
}

// The head task of the vehicle is not routed yet: a plan that marks its goal leg.
function planRoutes(task) {
  const vehicleId = task.vehicle_id;
  const fixed = fixedLegs(planOf(vehicleId));
  if (fixed.length === 0) fail(`the plan of vehicle ${vehicleId} has no fixed leg to start from`);
  // If a committed leg already reaches the goal segment (and is nobody's goal yet), mark it.
  const reached = fixed.findIndex((leg) => leg.segment === task.goal_segment && leg.goal_for_task == null);
  if (reached >= 0) {
    const legs = fixed.map((leg, i) => (i === reached ? { ...leg, goal_for_task: task.id } : leg));
    return { plans: [{ vehicle_id: vehicleId, legs }], route_errors: [] };
  }
  // Else: the fewest legs from the last committed leg to the goal segment, blind to other vehicles
  // and to the task's goal progress (BFSPlanner is meant to collide: it shows a caught planner bug).
  const last = fixed[fixed.length - 1];
  const vehicle = fleet.vehicles.get(vehicleId);
  if (!vehicle) fail(`the fleet has no vehicle ${vehicleId}`);
  const capability = turnCapability.get(vehicle.type);
  if (capability === undefined) fail(`vehicle ${vehicleId} has type ${JSON.stringify(vehicle.type)}, not in the init message`);
  const path = breadthFirstRoute(capability, [last.segment, last.traverse, last.progress], task.goal_segment);
  if (path === null) {
    const message = `no route from segment ${last.segment} to segment ${task.goal_segment}`;
    return { plans: [], route_errors: [{ vehicle_id: vehicleId, message }] };
  }
  const planned = path.map(([segment, traverse, progress], i) => ({
    segment, traverse, progress, fixed: false, goal_for_task: i === path.length - 1 ? task.id : null,
  }));
  return { plans: [{ vehicle_id: vehicleId, legs: [...fixed, ...planned] }], route_errors: [] };
}

// The task is routed: commit the first FIX_HORIZON legs of the vehicle's plan.
function fixLegs(task) {
  const plan = planOf(task.vehicle_id);
  const legs = plan.legs.map((leg, i) => (i < FIX_HORIZON ? { ...leg, fixed: true } : leg));
  return { plans: [{ vehicle_id: plan.vehicle_id, legs }], route_errors: [] };
}

// ---- the message loop -------------------------------------------------------------------------------

function handle(line) {
  let message;
  try {
    message = JSON.parse(line);
  } catch (error) {
    fail(`not JSON: ${error.message}: ${line.slice(0, 200)}`);
  }
  if (!isObject(message)) fail(`not a JSON object: ${line.slice(0, 200)}`);
  if (message.type === "init") {
    if (successors !== null) fail("a second init message");
    init(message);
    send(roundsAsked ? { type: "ready", rounds: true } : { type: "ready" });
    return;
  }
  if (successors === null) fail(`a ${message.type} message before the init message`);
  if (message.type === "round") {
    if (!roundsAsked || !Array.isArray(message.calls) || message.calls.length === 0) fail(`unexpected or malformed round: ${line.slice(0, 200)}`);
    updateFleet(message, "round");
    answerRound(message.calls);
    return;
  }
  updateFleet(message, `request ${message.id}`);
  send(answer(message));
}

// The first fleet is complete; later ones carry only the vehicles, plans and queues that changed, each
// replacing the entry of the same vehicle id. A message without "fleet" reuses the last one.
function updateFleet(message, what) {
  if ("fleet" in message) {
    if (!isObject(message.fleet) || !Array.isArray(message.fleet.plans) || !Array.isArray(message.fleet.vehicles)) {
      fail(`${what}: malformed "fleet"`);
    }
    if (fleet === null) fleet = { vehicles: new Map(), plans: new Map() };
    for (const vehicle of message.fleet.vehicles) fleet.vehicles.set(vehicle.id, vehicle);
    for (const plan of message.fleet.plans) fleet.plans.set(plan.vehicle_id, plan);
  } else if (fleet === null) {
    fail(`${what} has no "fleet" and no earlier message had one`);
  }
}

// One call (a request, or a call of a round): {"id", "plans", "route_errors"}.
function answer(call) {
  if (call.type !== "plan_routes" && call.type !== "fix_legs") fail(`unknown message type ${JSON.stringify(call.type)}`);
  if (!Number.isInteger(call.id) || call.id < 1) fail(`request without a valid "id": ${JSON.stringify(call).slice(0, 200)}`);
  const { task } = call;
  if (!isObject(task) || !Number.isInteger(task.vehicle_id) || !Number.isInteger(task.goal_segment)) {
    fail(`request ${call.id}: malformed "task"`);
  }
  return { id: call.id, ...(call.type === "plan_routes" ? planRoutes(task) : fixLegs(task)) };
}

// Two legs drive the same way with the same flags (a leg has exactly these five fields).
const sameLeg = (a, b) =>
  a === b ||
  (a.segment === b.segment && a.traverse === b.traverse && a.progress === b.progress && a.fixed === b.fixed &&
    a.goal_for_task === b.goal_for_task);

// The plan in force handed back (equal leg by leg) changes nothing, like no plan at all. Compared field by
// field: writing both plans as JSON to compare them cost more than the rest of the call.
function changesNothing(reply) {
  if (reply.route_errors.length !== 0 || reply.plans.length > 1) return false;
  if (reply.plans.length === 0) return true;
  const mine = reply.plans[0];
  const current = fleet.plans.get(mine.vehicle_id);
  if (current === undefined || current.legs.length !== mine.legs.length) return false;
  return mine.legs.every((leg, i) => sameLeg(leg, current.legs[i]));
}

// A round: its calls in order against the same fleet, up to the first answer that changes something.
function answerRound(calls) {
  const answers = [];
  const durations = [];
  for (const call of calls) {
    const started = process.hrtime.bigint();
    const reply = answer(call);
    const nothing = changesNothing(reply);
    durations.push(Number(process.hrtime.bigint() - started) / 1e9);
    answers.push(nothing ? { id: call.id, plans: [], route_errors: [] } : reply);
    if (!nothing) break; // the calls after it must see the fleet as changed: fleetsim asks them again
  }
  send({ answers, durations });
}

// fleetsim waits for each answer before it sends the next message, so there is nothing for an event loop
// to interleave: the messages are read with blocking reads of stdin and answered with blocking writes to
// stdout, which costs a few microseconds less per call than readline's events and stream writes. Lines are
// found in the bytes read and each decoded on its own (a character split between two reads stays in the
// buffer until its line is whole), which costs less than decoding every read and cutting up the text.
function serve() {
  let pending = Buffer.alloc(1 << 16); // what was read and not yet handled: pending[start, end)
  let start = 0;
  let end = 0;
  const pause = new Int32Array(new SharedArrayBuffer(4));
  for (;;) {
    if (end === pending.length) {
      // Full: what is left moves to the front, of a buffer twice the size if it fills more than half.
      const left = end - start;
      const next = left * 2 > pending.length ? Buffer.alloc(pending.length * 2) : pending;
      pending.copy(next, 0, start, end);
      [pending, start, end] = [next, 0, left];
    }
    let count;
    try {
      count = fs.readSync(0, pending, end, pending.length - end, null);
    } catch (error) {
      if (error.code === "EAGAIN") {
        Atomics.wait(pause, 0, 0, 1); // stdin is non-blocking (not fleetsim's pipe): wait a millisecond
        continue;
      }
      if (error.code === "EOF") break;
      throw error;
    }
    if (count === 0) break; // stdin closed: the run is over
    const read = pending.subarray(0, end + count);
    let newline = read.indexOf(10, end); // "\n": only the bytes just read can hold a new one
    end += count;
    while (newline >= 0) {
      const line = pending.toString("utf8", start, newline);
      if (line.trim() !== "") handle(line); // blank lines carry no message
      start = newline + 1;
      newline = read.indexOf(10, start);
    }
    if (start === end) start = end = 0;
  }
  const last = pending.toString("utf8", start, end);
  if (last.trim() !== "") handle(last); // a last line without its newline
  process.exit(0);
}

serve();
