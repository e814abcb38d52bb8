// An independent VDA 5050 master control for fleetsim's tests, built on vda-5050-lib's MasterController
// (npm vda-5050-lib 1.4.0, Siemens) and none of fleetsim's code.
//
// Started by fleetsim as the `exec=` command of a `vda5050:` planner spec, it finds the broker and the
// topics in its environment (FLEETSIM_MQTT_URL, FLEETSIM_MQTT_USERNAME/PASSWORD when the broker has them,
// FLEETSIM_VDA5050_INTERFACE, FLEETSIM_VDA5050_MANUFACTURER). It reads fleetsim's own retained topics
// `<interface>/fleetsim/site` (the map: directed edges with what may follow each) and
// `<interface>/fleetsim/transportOrders/+` (each task, OPEN then FINISHED) with the `mqtt` package the
// library depends on, learns the vehicles from the controller's `trackAgvs` and their states from its
// `state` subscription, and assigns each OPEN task as one order through `assignOrder`: a breadth-first
// route over the edges (following each edge's `next`), all nodes and edges released. A vehicle's first
// order starts with the edge it stands on (the site's `startEdgeId`); a later one at its `lastNodeId`.
// One vehicle drives at a time: the next task is assigned only once the previous one comes back FINISHED,
// so no two vehicles ever meet. It runs until fleetsim stops it (SIGTERM).
//
// With FLEETSIM_MASTER_STATE_REQUEST=1 it also initiates a `stateRequest` instant action through the
// library's `initiateInstantActions` to every vehicle it tracks before assigning anything: a probe of
// how fleetsim answers the library's instant actions message.
//
// Everything it does is logged on stderr, prefixed "master.js:", so a failed run shows why.
"use strict";

const path = require("path");
const mqtt = require(path.join(__dirname, "node_modules", "mqtt"));
const { MasterController } = require(path.join(__dirname, "node_modules", "vda-5050-lib"));

function log(...words) {
    process.stderr.write(`master.js: ${words.join(" ")}\n`);
}

function required(name) {
    const value = process.env[name];
    if (value === undefined || value === "") {
        log(`the environment has no ${name} (fleetsim's vda5050: planner spec sets it for exec=)`);
        process.exit(2);
    }
    return value;
}

const brokerUrl = required("FLEETSIM_MQTT_URL");
const interfaceName = required("FLEETSIM_VDA5050_INTERFACE");
const manufacturer = required("FLEETSIM_VDA5050_MANUFACTURER");
const credentials = {};
if (process.env.FLEETSIM_MQTT_USERNAME) credentials.username = process.env.FLEETSIM_MQTT_USERNAME;
if (process.env.FLEETSIM_MQTT_PASSWORD) credentials.password = process.env.FLEETSIM_MQTT_PASSWORD;
const probeStateRequest = process.env.FLEETSIM_MASTER_STATE_REQUEST === "1";

let site = null; // fleetsim's site document
const tasks = new Map(); // taskId -> latest transport order document
const assigned = new Set(); // taskIds whose order was assigned
const states = new Map(); // serialNumber -> latest State
const orderCount = new Map(); // serialNumber -> orders assigned so far
const tracked = new Set(); // serialNumbers trackAgvs reported ONLINE
const probed = new Set(); // serialNumbers a stateRequest was sent to
let busy = null; // the taskId whose vehicle drives now
let stopping = false;

const controller = new MasterController(
    { interfaceName, transport: { brokerUrl, ...credentials }, vdaVersion: "2.0.0" },
    { targetAgvs: { manufacturer } },
);

// The site's directed edges keyed "edgeId|startNodeId" (an edge may be listed once per direction).
function edgeKey(edgeId, startNodeId) {
    return `${edgeId}|${startNodeId}`;
}

function siteEdges() {
    const byKey = new Map();
    for (const edge of site.edges) byKey.set(edgeKey(edge.edgeId, edge.startNodeId), edge);
    return byKey;
}

// The edges that may follow `edge`: its `next` entries name an edgeId and that edge's end node.
function successors(edge, byKey) {
    const found = [];
    for (const next of edge.next || []) {
        for (const candidate of site.edges) {
            if (candidate.edgeId === next.edgeId && candidate.endNodeId === next.endNodeId) {
                const known = byKey.get(edgeKey(candidate.edgeId, candidate.startNodeId));
                if (known) found.push(known);
            }
        }
    }
    return found;
}

// Breadth-first over directed edges from `firstEdges` (the edges the route may begin with) to any edge
// whose id is in `goals`: the list of edges driven, or null when no goal is reachable.
function route(firstEdges, goals) {
    const byKey = siteEdges();
    const previous = new Map();
    const queue = [];
    for (const edge of firstEdges) {
        const key = edgeKey(edge.edgeId, edge.startNodeId);
        if (!previous.has(key)) {
            previous.set(key, null);
            queue.push(edge);
        }
    }
    while (queue.length > 0) {
        const edge = queue.shift();
        if (goals.has(edge.edgeId)) {
            const path = [];
            for (let key = edgeKey(edge.edgeId, edge.startNodeId); key !== null; key = previous.get(key)) {
                path.unshift(byKey.get(key));
            }
            return path;
        }
        for (const next of successors(edge, byKey)) {
            const key = edgeKey(next.edgeId, next.startNodeId);
            if (!previous.has(key)) {
                previous.set(key, edgeKey(edge.edgeId, edge.startNodeId));
                queue.push(next);
            }
        }
    }
    return null;
}

// The edges a route for `serial` may begin with: its start edge for its first order, else any edge
// leaving the node it last reached.
function firstEdgesOf(serial) {
    if ((orderCount.get(serial) || 0) === 0) {
        const vehicle = site.vehicles.find((v) => v.serialNumber === serial);
        if (!vehicle) return [];
        return site.edges.filter((e) => e.edgeId === vehicle.startEdgeId && e.startNodeId === vehicle.startNodeId);
    }
    const state = states.get(serial);
    if (!state || !state.lastNodeId) return [];
    return site.edges.filter((e) => e.startNodeId === state.lastNodeId);
}

function orderOf(serial, edges) {
    const count = (orderCount.get(serial) || 0) + 1;
    const nodeIds = [edges[0].startNodeId, ...edges.map((e) => e.endNodeId)];
    return {
        orderId: `vda-5050-lib-${serial}-${count}`,
        orderUpdateId: 0,
        nodes: nodeIds.map((nodeId, k) => ({ nodeId, sequenceId: 2 * k, released: true, actions: [] })),
        edges: edges.map((edge, k) => ({
            edgeId: edge.edgeId,
            sequenceId: 2 * k + 1,
            released: true,
            startNodeId: edge.startNodeId,
            endNodeId: edge.endNodeId,
            actions: [],
        })),
    };
}

function dispatch() {
    if (site === null || busy !== null || stopping) return;
    const open = [...tasks.values()]
        .filter((t) => t.state === "OPEN" && !assigned.has(t.taskId))
        .sort((a, b) => Number(a.taskId) - Number(b.taskId));
    for (const task of open) {
        const serial = task.serialNumber;
        if (!tracked.has(serial) || !states.has(serial)) continue;
        if (probeStateRequest && !probed.has(serial)) continue;
        const edges = route(firstEdgesOf(serial), new Set(task.goalEdgeIds));
        if (edges === null) {
            log(`task ${task.taskId}: no route for vehicle ${serial} to any of ${task.goalEdgeIds.join(", ")}`);
            assigned.add(task.taskId);
            continue;
        }
        const order = orderOf(serial, edges);
        assigned.add(task.taskId);
        orderCount.set(serial, (orderCount.get(serial) || 0) + 1);
        busy = task.taskId;
        log(`task ${task.taskId}: ${order.orderId} to vehicle ${serial} over ${edges.map((e) => e.edgeId).join(" ")}`);
        controller
            .assignOrder({ manufacturer, serialNumber: serial }, order, {
                onOrderProcessed(withError, byCancelation, active) {
                    if (withError) {
                        log(`${order.orderId} rejected: ${JSON.stringify(withError)}`);
                    } else {
                        log(`${order.orderId} processed (canceled: ${byCancelation}, active: ${active})`);
                    }
                },
            })
            .catch((error) => {
                log(`assignOrder ${order.orderId} failed: ${error && error.message ? error.message : error}`);
                busy = null;
            });
        return; // one vehicle at a time
    }
}

function probe(serial) {
    if (!probeStateRequest || probed.has(serial)) return;
    probed.add(serial);
    const action = { actionId: controller.createUuid(), actionType: "stateRequest", blockingType: "NONE" };
    log(`vehicle ${serial}: stateRequest ${action.actionId} through initiateInstantActions`);
    controller
        .initiateInstantActions(
            { manufacturer, serialNumber: serial },
            { instantActions: [action] },
            {
                onActionStateChanged(actionState) {
                    log(`stateRequest on ${serial}: ${actionState.actionStatus}`);
                },
                onActionError(error) {
                    log(`stateRequest on ${serial} refused: ${JSON.stringify(error)}`);
                },
            },
        )
        .catch((error) => log(`initiateInstantActions failed: ${error && error.message ? error.message : error}`));
}

function onSiteMessage(topic, payload) {
    let document;
    try {
        document = JSON.parse(payload.toString());
    } catch (error) {
        log(`${topic} is not JSON: ${error.message}`);
        return;
    }
    if (topic === `${interfaceName}/fleetsim/site`) {
        site = document;
        log(`site ${document.mapId}: ${document.edges.length} edges, ${document.vehicles.length} vehicles`);
    } else {
        tasks.set(document.taskId, document);
        log(`transport order ${document.taskId} of vehicle ${document.serialNumber}: ${document.state}`);
        if (document.state === "FINISHED" && busy === document.taskId) busy = null;
    }
    dispatch();
}

async function main() {
    const sideChannel = mqtt.connect(brokerUrl, { ...credentials, clientId: `fleetsim-lib-master-${process.pid}` });
    sideChannel.on("error", (error) => log(`side channel: ${error.message}`));
    sideChannel.on("message", onSiteMessage);
    sideChannel.on("connect", () => {
        sideChannel.subscribe(
            [`${interfaceName}/fleetsim/site`, `${interfaceName}/fleetsim/transportOrders/+`],
            { qos: 1 },
            (error) => error && log(`subscribing to fleetsim's topics failed: ${error.message}`),
        );
    });

    await controller.start();
    log(`vda-5050-lib MasterController started on ${brokerUrl} (interface ${interfaceName})`);
    controller.trackAgvs((agvId, connectionState) => {
        if (agvId.manufacturer !== manufacturer) return;
        if (connectionState === "ONLINE") tracked.add(agvId.serialNumber);
        else tracked.delete(agvId.serialNumber);
        log(`vehicle ${agvId.serialNumber}: ${connectionState}`);
        probe(agvId.serialNumber);
        dispatch();
    });
    await controller.subscribe("state", { manufacturer }, (state, agvId) => {
        states.set(agvId.serialNumber, state);
        if (state.errors && state.errors.length > 0 && probeStateRequest) {
            log(`vehicle ${agvId.serialNumber} errors: ${JSON.stringify(state.errors)}`);
        }
        dispatch();
    });

    const stop = async () => {
        if (stopping) return;
        stopping = true;
        log("SIGTERM: stopping");
        sideChannel.end(true);
        try {
            await controller.stop();
        } finally {
            process.exit(0);
        }
    };
    process.on("SIGTERM", stop);
    process.on("SIGINT", stop);
}

main().catch((error) => {
    log(`failed: ${error && error.stack ? error.stack : error}`);
    process.exit(1);
});
