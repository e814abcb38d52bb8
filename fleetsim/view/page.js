"use strict";
// The fleetsim viewer: one run (recorded, embedded in this page; or live, over a WebSocket) drawn on a
// canvas, with time control. It reads the view document (fleetsim/view/document.py) and nothing else.
(function () {
  const el = (id) => document.getElementById(id);
  const WAYS = [["forward", "nose first"], ["forward", "backing"], ["backward", "nose first"], ["backward", "backing"]];
  const KEY = 32; // steps between the full copies of the fleet kept for scrubbing
  const FASTEST = 100; // "fastest" plays a recording at 100x, or one step per drawn frame if that is more
  const DEG = Math.PI / 18000;
  const EVENT_ROWS = 5000; // the events list shows this many; the timeline shows them all
  // an order's routine (a shift has thousands): listed, not stopped at by "next event"
  const ROUTINE = new Set(["release", "assign", "served", "order-done"]);

  // -- the run: steps as they arrive, the fleet at any step --------------------------------------------
  class Run {
    constructor(scene) {
      this.scene = scene;
      this.dt = scene.time_step;
      this.ids = scene.vehicles.map((v) => v[0]);
      this.n = this.ids.length;
      this.index = new Map(this.ids.map((id, i) => [id, i]));
      this.vehicles = scene.vehicles.map((v) => ({ id: v[0], type: v[1], length: v[2], width: v[3], colour: v[4] }));
      this.segments = new Map();
      for (const [id, shape, direction, name, points] of scene.segments) {
        this.segments.set(id, { id, shape, direction, name, points });
      }
      this.tasks = new Map(scene.tasks.map((t) => [t[0], { id: t[0], vehicle: t[1], goal: t[2] }]));
      this.tasksOf = new Map(this.ids.map((id) => [id, []]));
      for (const task of this.tasks.values()) (this.tasksOf.get(task.vehicle) || []).push(task);
      this.completedAt = new Map(); // task -> step
      this.steps = [];
      this.keyframes = [];
      this.tail = this.blank(); // the fleet after the last step received
      this.state = this.blank(); // the fleet at step this.at
      this.at = -1;
      this.plans = this.ids.map(() => []); // per vehicle: [step, legs] as they changed
      this.alerts = []; // [step, alerts]
      this.disturbed = []; // [step, {vehicle: kind}]
      // transport orders (a run with them): per vehicle [step, carry], per station [step, waiting orders],
      // [step, [open, done]], and the backlog [seconds, open orders] once a minute
      this.hasOrders = false;
      this.carry = this.ids.map(() => []);
      this.waiting = new Map();
      this.counts = [];
      this.backlog = [];
      this.events = []; // {step, event}
      this.eventSteps = []; // the steps that hold events, ascending, once each
      this.outcome = scene.outcome || null;
      this.bounds = this.mapBounds();
    }
    blank() {
      return { pose: new Float64Array(this.n * 4), segment: new Int32Array(this.n), way: new Int8Array(this.n) };
    }
    get last() {
      return this.steps.length - 1;
    }
    time(step) {
      return (step + 1) * this.dt;
    }
    mapBounds() {
      let minX = Infinity, minY = Infinity, maxX = -Infinity, maxY = -Infinity;
      for (const s of this.segments.values()) {
        const p = s.points;
        for (let i = 0; i < p.length; i += 2) {
          if (p[i] < minX) minX = p[i];
          if (p[i] > maxX) maxX = p[i];
          if (p[i + 1] < minY) minY = p[i + 1];
          if (p[i + 1] > maxY) maxY = p[i + 1];
        }
      }
      if (!isFinite(minX)) return { minX: -10, minY: -10, maxX: 10, maxY: 10 };
      return { minX, minY, maxX, maxY };
    }
    apply(into, record) {
      // the trace's records: [vehicle, segment, traverse f|b, progress f|r, x mm, y mm, heading cdeg, speed mm/s]
      const pose = into.pose, index = this.index;
      for (const r of record[1]) {
        const i = index.get(r[0]);
        if (i === undefined) continue;
        pose[4 * i] = r[4] / 1000;
        pose[4 * i + 1] = r[5] / 1000;
        pose[4 * i + 2] = r[6] * DEG;
        pose[4 * i + 3] = r[7] / 1000;
        into.segment[i] = r[1];
        into.way[i] = 2 * (r[2] === "b") + (r[3] === "r");
      }
    }
    add(record) {
      const step = record[0];
      if (step !== this.steps.length) return false; // out of order: not this run's next step
      this.steps.push(record);
      this.apply(this.tail, record);
      if (step % KEY === 0) {
        this.keyframes.push({ pose: this.tail.pose.slice(), segment: this.tail.segment.slice(), way: this.tail.way.slice() });
      }
      for (const [vid, legs] of record[2]) {
        const i = this.index.get(vid);
        if (i !== undefined) this.plans[i].push([step, legs]);
      }
      if (record[3] !== null) this.alerts.push([step, record[3]]);
      if (record[5] !== null) this.disturbed.push([step, record[5]]);
      if (record[4].some((e) => !ROUTINE.has(e[0]))) this.eventSteps.push(step);
      if (record[6]) this.addOrders(step, record[6]);
      for (const event of record[4]) {
        this.events.push({ step, event });
        if (event[0] === "complete") this.completedAt.set(event[1], step);
      }
      return true;
    }
    addOrders(step, orders) {
      this.hasOrders = true;
      for (const [vid, carry] of Object.entries(orders.carry || {})) {
        const i = this.index.get(Number(vid));
        if (i !== undefined) this.carry[i].push([step, carry]);
      }
      for (const [segment, waiting] of Object.entries(orders.waiting || {})) {
        const sid = Number(segment);
        if (!this.waiting.has(sid)) this.waiting.set(sid, []);
        this.waiting.get(sid).push([step, waiting]);
      }
      if (orders.open !== undefined) this.counts.push([step, [orders.open, orders.done]]);
      if (orders.backlog !== undefined) this.backlog.push([step * this.dt, orders.backlog]);
    }
    carryOf(i, step) {
      // [orders, loaded, stop, stops, dwell since, dwell seconds, stalled], or null
      return this.changedAt(this.carry[i], step);
    }
    seek(step) {
      step = Math.max(0, Math.min(step, this.last));
      if (step === this.at) return;
      if (!(this.at >= 0 && step > this.at && step - this.at <= KEY)) {
        const k = Math.floor(step / KEY);
        const frame = this.keyframes[k];
        this.state.pose.set(frame.pose);
        this.state.segment.set(frame.segment);
        this.state.way.set(frame.way);
        this.at = k * KEY;
      }
      for (let s = this.at + 1; s <= step; s++) this.apply(this.state, this.steps[s]);
      this.at = step;
    }
    changedAt(list, step) {
      // the last entry of [step, value] pairs at or before step
      let lo = 0, hi = list.length - 1, found = null;
      while (lo <= hi) {
        const mid = (lo + hi) >> 1;
        if (list[mid][0] <= step) {
          found = list[mid][1];
          lo = mid + 1;
        } else hi = mid - 1;
      }
      return found;
    }
    planOf(i, step) {
      return this.changedAt(this.plans[i], step) || [];
    }
    headTask(vid, step) {
      const tasks = this.tasksOf.get(vid) || [];
      let done = 0, head = null;
      for (const task of tasks) {
        const at = this.completedAt.get(task.id);
        if (at !== undefined && at <= step) done++;
        else if (head === null) head = task;
      }
      return { head, done, total: tasks.length };
    }
  }

  // -- the page -------------------------------------------------------------------------------------
  const canvas = el("canvas"), ctx = canvas.getContext("2d");
  const timeline = el("timeline"), tctx = timeline.getContext("2d");
  const mapLayer = document.createElement("canvas"), mctx = mapLayer.getContext("2d");
  const hook = { ready: false, frames: 0, frameTimes: [], drawn: null, connected: false, loadMs: null };
  window.fleetsimView = hook;
  let run = null;
  let live = null; // {socket, paused, speed, ended, following}
  const view = { scale: 1, cx: 0, cy: 0, width: 0, height: 0, dpr: 1, mapDirty: true };
  const player = { playing: false, speed: 1, fastest: false, position: 0, wall: null };
  let dirty = true, hover = null, eventsShown = 0, eventsPast = 0;

  function shown() {
    return run === null ? -1 : run.at;
  }

  function fit() {
    const b = run.bounds, margin = 2;
    const w = Math.max(b.maxX - b.minX + 2 * margin, 1), h = Math.max(b.maxY - b.minY + 2 * margin, 1);
    view.scale = Math.min(view.width / w, view.height / h);
    view.cx = (b.minX + b.maxX) / 2;
    view.cy = (b.minY + b.maxY) / 2;
    view.mapDirty = true;
    dirty = true;
  }

  function resize() {
    const dpr = window.devicePixelRatio || 1, rect = canvas.getBoundingClientRect();
    view.dpr = dpr;
    view.width = rect.width;
    view.height = rect.height;
    for (const c of [canvas, mapLayer]) {
      c.width = Math.round(rect.width * dpr);
      c.height = Math.round(rect.height * dpr);
    }
    for (const c of [timeline, el("backlog")]) {
      const t = c.getBoundingClientRect();
      c.width = Math.round(t.width * dpr);
      c.height = Math.round(t.height * dpr);
    }
    view.mapDirty = true;
    dirty = true;
  }

  const sx = (x) => (x - view.cx) * view.scale + view.width / 2;
  const sy = (y) => view.height / 2 - (y - view.cy) * view.scale;

  // A polyline onto path c, in driving order (backward: last point first), leaving out points within a
  // pixel of the last one drawn (a curve's many waypoints, zoomed out), never the last.
  function tracePoints(c, points, backward, join) {
    const n = points.length / 2;
    let lastX = NaN, lastY = NaN;
    for (let k = 0; k < n; k++) {
      const j = backward ? n - 1 - k : k;
      const x = sx(points[2 * j]), y = sy(points[2 * j + 1]);
      if (k === 0 && !join) c.moveTo(x, y);
      else if (k === 0 || k === n - 1 || Math.abs(x - lastX) + Math.abs(y - lastY) >= 1.5) c.lineTo(x, y);
      else continue;
      lastX = x;
      lastY = y;
    }
  }

  function drawMap() {
    const c = mctx;
    c.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    c.clearRect(0, 0, view.width, view.height);
    c.lineCap = "round";
    c.lineJoin = "round";
    c.strokeStyle = "#a8a8a8";
    c.lineWidth = Math.max(1, Math.min(3, 0.08 * view.scale));
    c.beginPath();
    for (const s of run.segments.values()) tracePoints(c, s.points, false, false);
    c.stroke();
    // one-way arrows at the middle of segments long enough on screen to carry one
    c.fillStyle = "#7d7d7d";
    const labels = el("show-labels").checked;
    c.font = "11px system-ui, sans-serif";
    c.textAlign = "center";
    for (const s of run.segments.values()) {
      const p = s.points, n = p.length / 2;
      const mid = Math.max(0, Math.floor((n - 1) / 2));
      const a = [p[2 * mid], p[2 * mid + 1]], b = [p[2 * Math.min(mid + 1, n - 1)], p[2 * Math.min(mid + 1, n - 1) + 1]];
      const length = Math.hypot(sx(p[2 * (n - 1)]) - sx(p[0]), sy(p[2 * (n - 1) + 1]) - sy(p[1]));
      if (s.direction !== 0 && length > 24) {
        let dx = sx(b[0]) - sx(a[0]), dy = sy(b[1]) - sy(a[1]);
        const d = Math.hypot(dx, dy) || 1;
        dx /= d;
        dy /= d;
        if (s.direction === 2) {
          dx = -dx;
          dy = -dy;
        }
        const mx = (sx(a[0]) + sx(b[0])) / 2, my = (sy(a[1]) + sy(b[1])) / 2, r = 5;
        c.beginPath();
        c.moveTo(mx + dx * r, my + dy * r);
        c.lineTo(mx - dx * r - dy * r * 0.7, my - dy * r + dx * r * 0.7);
        c.lineTo(mx - dx * r + dy * r * 0.7, my - dy * r - dx * r * 0.7);
        c.closePath();
        c.fill();
      }
      if (labels && s.name && length > 60) {
        c.fillStyle = "#8a8f96";
        c.fillText(s.name, (sx(a[0]) + sx(b[0])) / 2, (sy(a[1]) + sy(b[1])) / 2 - 6);
        c.fillStyle = "#7d7d7d";
      }
    }
    view.mapDirty = false;
    viewVersion++;
  }

  function segmentPath(c, ids) {
    for (const sid of ids) {
      const s = run.segments.get(sid);
      if (s) tracePoints(c, s.points, false, false);
    }
  }

  // Each vehicle's plan as paths on screen, made again only when its legs or the view change.
  let planPaths = [];
  let viewVersion = 0;

  function planPath(i, legs) {
    const cached = planPaths[i];
    if (cached && cached.legs === legs && cached.version === viewVersion) return cached;
    let fixed = 0;
    while (fixed < legs.length && legs[fixed][2]) fixed++;
    const made = { legs, version: viewVersion, fixed: null, planned: null };
    if (fixed) {
      made.fixed = new Path2D();
      for (let k = 0; k < fixed; k++) tracePoints(made.fixed, run.segments.get(legs[k][0])?.points || [], legs[k][1] >= 2, k > 0);
    }
    if (fixed < legs.length) {
      made.planned = new Path2D();
      for (let k = fixed; k < legs.length; k++) {
        tracePoints(made.planned, run.segments.get(legs[k][0])?.points || [], legs[k][1] >= 2, k > fixed);
      }
    }
    planPaths[i] = made;
    return made;
  }

  function drawPlans(step) {
    const c = ctx;
    let planned = null;
    c.lineCap = "butt";
    c.lineJoin = "bevel";
    for (let i = 0; i < run.n; i++) {
      const legs = run.planOf(i, step);
      if (!legs.length) continue;
      const colour = run.vehicles[i].colour, paths = planPath(i, legs);
      // Zoomed out (the vehicle a few pixels wide), the reservation band would be a blur of colour that
      // costs most of the frame: the fixed legs are drawn thick, the planned thin, and no band.
      const wide = run.vehicles[i].width * view.scale;
      c.strokeStyle = colour;
      if (paths.fixed) {
        if (wide >= 4) {
          // the reservation: the fixed legs' segments, as wide as the vehicle
          c.globalAlpha = 0.16;
          c.lineWidth = wide;
          c.stroke(paths.fixed);
        }
        c.globalAlpha = 1;
        c.lineWidth = wide >= 4 ? 3 : 2;
        c.stroke(paths.fixed);
      }
      if (paths.planned) {
        if (wide >= 4) {
          c.globalAlpha = 0.75;
          c.lineWidth = 1;
          c.stroke(paths.planned);
        } else {
          (planned || (planned = new Path2D())).addPath(paths.planned);
        }
      }
    }
    if (planned) {
      // Zoomed out, the planned legs of the whole fleet in one thin stroke: a thousand strokes of a
      // pixel's width, each in its own colour, cost a third of a frame and are a blur at that size.
      c.globalAlpha = 0.55;
      c.strokeStyle = "#55606e";
      c.lineWidth = 1;
      c.stroke(planned);
    }
    c.globalAlpha = 1;
    c.lineCap = "round";
    c.lineJoin = "round";
  }

  function corners(i, grow) {
    const p = run.state.pose, v = run.vehicles[i];
    const x = p[4 * i], y = p[4 * i + 1], h = p[4 * i + 2];
    const l = v.length / 2 + grow, w = v.width / 2 + grow, c = Math.cos(h), s = Math.sin(h);
    return [
      [x + c * l - s * w, y + s * l + c * w],
      [x - c * l - s * w, y - s * l + c * w],
      [x - c * l + s * w, y - s * l - c * w],
      [x + c * l + s * w, y + s * l - c * w],
    ];
  }

  function drawVehicles() {
    const c = ctx, p = run.state.pose;
    c.lineWidth = 1;
    c.strokeStyle = "#1d232b";
    for (let i = 0; i < run.n; i++) {
      c.fillStyle = run.vehicles[i].colour;
      if (view.scale * run.vehicles[i].length < 3) {
        // smaller than a few pixels: a 3-pixel square, so that every vehicle shows
        c.fillRect(sx(p[4 * i]) - 1.5, sy(p[4 * i + 1]) - 1.5, 3, 3);
        continue;
      }
      const k = corners(i, 0);
      c.beginPath();
      c.moveTo(sx(k[0][0]), sy(k[0][1]));
      for (let j = 1; j < 4; j++) c.lineTo(sx(k[j][0]), sy(k[j][1]));
      c.closePath();
      c.fill();
      if (view.scale * run.vehicles[i].width > 4) {
        c.stroke();
        // the nose: a line from the middle to the front edge
        c.beginPath();
        c.moveTo(sx(p[4 * i]), sy(p[4 * i + 1]));
        c.lineTo(sx((k[0][0] + k[3][0]) / 2), sy((k[0][1] + k[3][1]) / 2));
        c.stroke();
      }
    }
    if (el("show-labels").checked && (run.n <= 300 || view.scale > 12)) {
      c.fillStyle = "#1d232b";
      c.font = "bold 11px system-ui, sans-serif";
      c.textAlign = "center";
      for (let i = 0; i < run.n; i++) {
        const size = (run.vehicles[i].width / 2) * view.scale;
        c.fillText(String(run.ids[i]), sx(p[4 * i]), sy(p[4 * i + 1]) - size - 4);
      }
    }
  }

  function drawOutline(i, grow, colour, width, text) {
    const k = corners(i, grow), c = ctx;
    c.strokeStyle = colour;
    c.lineWidth = width;
    c.beginPath();
    c.moveTo(sx(k[0][0]), sy(k[0][1]));
    for (let j = 1; j < 4; j++) c.lineTo(sx(k[j][0]), sy(k[j][1]));
    c.closePath();
    c.stroke();
    if (text) {
      c.fillStyle = colour;
      c.font = "bold 11px system-ui, sans-serif";
      c.textAlign = "center";
      const p = run.state.pose;
      c.fillText(text, sx(p[4 * i]), sy(p[4 * i + 1]) + (run.vehicles[i].width / 2) * view.scale + 14);
    }
  }

  function arrow(x1, y1, x2, y2, colour, width) {
    const c = ctx, a = Math.atan2(y2 - y1, x2 - x1), r = 4 + 2 * width;
    c.strokeStyle = c.fillStyle = colour;
    c.lineWidth = width;
    c.beginPath();
    c.moveTo(x1, y1);
    c.lineTo(x2, y2);
    c.stroke();
    c.beginPath();
    c.moveTo(x2, y2);
    c.lineTo(x2 - r * Math.cos(a - 0.4), y2 - r * Math.sin(a - 0.4));
    c.lineTo(x2 - r * Math.cos(a + 0.4), y2 - r * Math.sin(a + 0.4));
    c.closePath();
    c.fill();
  }

  function drawAlerts(step) {
    // the collision alerts in force: their segments in orange (under the vehicles), with who holds them
    const c = ctx;
    const alerts = run.changedAt(run.alerts, step) || [];
    if (!alerts.length) return;
    c.strokeStyle = "#ff8c00";
    c.lineWidth = Math.max(view.scale > 10 ? 4 : 2, 0.35 * view.scale);
    c.globalAlpha = 0.85;
    c.beginPath();
    segmentPath(c, alerts.map((a) => a[0]));
    c.stroke();
    c.globalAlpha = 1;
    if (alerts.length > 30 && view.scale < 15) return; // labels only where they can be read
    c.fillStyle = "#b35f00";
    c.font = "bold 12px system-ui, sans-serif";
    c.textAlign = "left";
    for (const [segment, primary, secondary] of alerts) {
      const s = run.segments.get(segment);
      if (!s) continue;
      const m = Math.floor(s.points.length / 4) * 2;
      const x = sx(s.points[m]), y = sy(s.points[m + 1]);
      if (x < -50 || y < -20 || x > view.width || y > view.height + 20) continue;
      c.fillText(`\u26a0 ${segment}: ${primary.join(",")} \u27c2 ${secondary.join(",")}`, x + 6, y - 6);
    }
  }

  function drawMarks(step) {
    const c = ctx, p = run.state.pose, time = run.time(step), outcome = run.outcome;
    // disturbed vehicles: a magenta outline, STOP or SLOW
    const disturbed = run.changedAt(run.disturbed, step) || {};
    for (const [vid, kind] of Object.entries(disturbed)) {
      const i = run.index.get(Number(vid));
      if (i !== undefined) drawOutline(i, 0.25, "#e6007e", 2, kind.toUpperCase());
    }
    // rejections of the last two seconds: a red outline over the vehicle
    for (let e = lowerEvent(step - Math.round(2 / run.dt)); e < run.events.length && run.events[e].step <= step; e++) {
      const event = run.events[e].event;
      if (event[0] === "reject" || event[0] === "route-error" || event[0] === "planner-error") {
        const vid = event[0] === "reject" ? event[2] : event[1];
        const i = run.index.get(vid);
        if (i !== undefined) drawOutline(i, 0.45, "#d0021b", 2.5, event[0] === "reject" ? `rejected: ${event[1]}` : event[0]);
      }
    }
    if (outcome) {
      for (const contact of outcome.contacts || []) {
        if (contact.time > time + 1e-9) continue;
        c.strokeStyle = "#d0021b";
        c.lineWidth = 3;
        c.beginPath();
        c.arc(sx(contact.x), sy(contact.y), Math.max(8, 0.8 * view.scale), 0, 2 * Math.PI);
        c.stroke();
        c.fillStyle = "#d0021b";
        c.font = "bold 12px system-ui, sans-serif";
        c.fillText(`contact ${contact.vehicles.join(" \u27c2 ")}`, sx(contact.x) + 10, sy(contact.y) - 10);
      }
      const stuck = outcome.stuck;
      if (stuck && step === run.last) {
        c.strokeStyle = "#8e44ad";
        c.globalAlpha = 0.5;
        c.lineWidth = Math.max(4, 0.4 * view.scale);
        c.beginPath();
        segmentPath(c, stuck.contested);
        c.stroke();
        c.globalAlpha = 1;
        for (const vid of stuck.roots) {
          const i = run.index.get(vid);
          if (i === undefined) continue;
          c.fillStyle = "rgba(208, 2, 27, 0.3)";
          c.beginPath();
          c.arc(sx(p[4 * i]), sy(p[4 * i + 1]), Math.max(10, run.vehicles[i].length * view.scale), 0, 2 * Math.PI);
          c.fill();
        }
        for (const [from, to, kind, cycle] of stuck.relations) {
          const a = run.index.get(from), b = run.index.get(to);
          if (a === undefined || b === undefined) continue;
          arrow(sx(p[4 * a]), sy(p[4 * a + 1]), sx(p[4 * b]), sy(p[4 * b + 1]), cycle ? "#d0021b" : "#2c3e50", kind === "wait-for" ? 2.5 : 1);
        }
      }
    }
  }

  // -- transport orders: who waits where, who carries what, dwells, stalls -----------------------------
  function segmentMiddle(sid) {
    const s = run.segments.get(sid);
    if (!s) return null;
    const p = s.points, m = Math.floor((p.length / 2 - 1) / 2);
    const n = Math.min(m + 1, p.length / 2 - 1);
    return [(p[2 * m] + p[2 * n]) / 2, (p[2 * m + 1] + p[2 * n + 1]) / 2];
  }

  function inkOn(colour) {
    // black or white, whichever reads on the colour (#rrggbb)
    const n = parseInt(colour.slice(1, 7), 16);
    const luma = 0.299 * ((n >> 16) & 255) + 0.587 * ((n >> 8) & 255) + 0.114 * (n & 255);
    return luma > 150 ? "#1d232b" : "#ffffff";
  }

  function drawOrders(step) {
    const c = ctx, p = run.state.pose, time = run.time(step);
    const shownOrders = { step, waiting: {}, badges: {}, loaded: [], dwelling: [], stalled: [] };
    // waiting orders: a marker at their first stop's station with how many wait there
    c.font = "bold 11px system-ui, sans-serif";
    c.textAlign = "center";
    c.textBaseline = "middle";
    for (const [sid, changes] of run.waiting) {
      const waiting = run.changedAt(changes, step);
      if (!waiting || !waiting.length) continue;
      const at = segmentMiddle(sid);
      if (!at) continue;
      const x = sx(at[0]), y = sy(at[1]), text = String(waiting.length), r = 8 + 3 * (text.length - 1);
      c.fillStyle = "#ffb300";
      c.strokeStyle = "#7a4f00";
      c.lineWidth = 1.5;
      c.beginPath();
      c.moveTo(x, y - r - 2);
      c.lineTo(x + r + 2, y);
      c.lineTo(x, y + r + 2);
      c.lineTo(x - r - 2, y);
      c.closePath();
      c.fill();
      c.stroke();
      c.fillStyle = "#1d232b";
      c.fillText(text, x, y + 0.5);
      shownOrders.waiting[sid] = waiting.length;
    }
    // each vehicle's order: a badge in its colour; loaded, a dark load on its body; a ring that fills
    // as it dwells; stalled, a red dashed outline
    const texts = el("show-labels").checked && (run.n <= 300 || view.scale > 12);
    for (let i = 0; i < run.n; i++) {
      const carry = run.carryOf(i, step);
      if (!carry) continue;
      const [orders, loaded, , , since, seconds, stalled] = carry, v = run.vehicles[i], vid = run.ids[i];
      const x = sx(p[4 * i]), y = sy(p[4 * i + 1]), size = Math.max(1.5, (v.width / 2) * view.scale);
      if (loaded && view.scale * v.length >= 3) {
        shownOrders.loaded.push(vid);
        const k = corners(i, -Math.min(v.width, v.length) * 0.22);
        c.fillStyle = "#1d232b";
        c.beginPath();
        c.moveTo(sx(k[0][0]), sy(k[0][1]));
        for (let j = 1; j < 4; j++) c.lineTo(sx(k[j][0]), sy(k[j][1]));
        c.closePath();
        c.fill();
      }
      if (since !== null && seconds) {
        const done = Math.max(0, Math.min(1, (time - since) / seconds));
        const r = Math.max(7, (Math.hypot(v.length, v.width) / 2) * view.scale + 4);
        c.lineWidth = 3;
        c.strokeStyle = "rgba(29, 35, 43, 0.2)";
        c.beginPath();
        c.arc(x, y, r, 0, 2 * Math.PI);
        c.stroke();
        c.strokeStyle = v.colour;
        c.beginPath();
        c.arc(x, y, r, -Math.PI / 2, -Math.PI / 2 + 2 * Math.PI * done);
        c.stroke();
        shownOrders.dwelling.push(vid);
      }
      if (stalled) {
        c.setLineDash([4, 3]);
        drawOutline(i, 0.5, "#d0021b", 2.5, "STALLED");
        c.setLineDash([]);
        shownOrders.stalled.push(vid);
      }
      if (orders.length && texts) {
        const text = orders[0] + (orders.length > 1 ? ` +${orders.length - 1}` : "");
        c.font = "bold 10px system-ui, sans-serif";
        const w = c.measureText(text).width + 8, bx = x + size + 4, by = y - size - 16;
        c.fillStyle = v.colour;
        c.strokeStyle = "#1d232b";
        c.lineWidth = 1;
        c.beginPath();
        c.rect(bx, by, w, 14);
        c.fill();
        c.stroke();
        c.fillStyle = inkOn(v.colour);
        c.textAlign = "left";
        c.fillText(text, bx + 4, by + 7.5);
        shownOrders.badges[vid] = text;
      }
    }
    c.textBaseline = "alphabetic";
    hook.drawnOrders = shownOrders;
  }

  function orderCounts(step) {
    return run.changedAt(run.counts, step) || [0, 0];
  }

  function lowerEvent(step) {
    let lo = 0, hi = run.events.length;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (run.events[mid].step < step) lo = mid + 1;
      else hi = mid;
    }
    return lo;
  }

  function draw(now) {
    const step = shown();
    if (view.mapDirty) drawMap();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(mapLayer, 0, 0);
    ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    ctx.lineCap = "round";
    ctx.lineJoin = "round";
    if (step >= 0) {
      if (el("show-plans").checked) drawPlans(step);
      drawAlerts(step);
      drawVehicles();
      drawMarks(step);
      if (run.hasOrders) drawOrders(step);
      if (hover !== null) drawOutline(hover, 0.35, "#1d232b", 1.5, "");
    }
    hook.frames++;
    hook.frameTimes.push(now);
    if (hook.frameTimes.length > 600) hook.frameTimes.splice(0, 300);
    hook.drawn = { step, time: step >= 0 ? run.time(step) : 0, poses: run ? run.state.pose.slice() : null };
    drawTimeline(step);
    if (run.hasOrders) drawBacklog(step);
    showTime(step);
    updateEvents(step);
    updateTooltip(step);
  }

  // -- time control ---------------------------------------------------------------------------------
  // DOM is touched only where something changed: a frame's style and layout work stays small
  function put(node, key, value) {
    if (node[key] !== value) node[key] = value;
  }

  function showTime(step) {
    if (run === null || step < 0) {
      put(el("time"), "textContent", "t = 0.00 s");
      return;
    }
    let text = `t = ${run.time(step).toFixed(2)} s \u00b7 step ${step} of ${run.last}`;
    if (live) {
      const pace = live.speed === null ? "fastest" : `${live.speed}\u00d7`;
      text += live.ended ? " \u00b7 run ended" : live.paused ? " \u00b7 live, paused" : ` \u00b7 live at ${pace}`;
    }
    put(el("time"), "textContent", text);
    if (run.hasOrders) {
      const [open, done] = orderCounts(step);
      put(el("orders"), "textContent", `orders: ${done} completed \u00b7 ${open} open`);
    }
    const scrub = el("scrub");
    put(scrub, "max", String(Math.max(0, run.last)));
    put(scrub, "value", String(step));
    put(el("play"), "textContent", (live ? !live.paused && !live.ended : player.playing) ? "pause" : "play");
    put(el("to-live"), "hidden", !live || live.following || live.ended);
  }

  function seek(step, keepPlaying) {
    if (run === null || run.last < 0) return;
    step = Math.max(0, Math.min(Math.round(step), run.last));
    if (live) live.following = step === run.last;
    if (!keepPlaying) player.playing = false;
    run.seek(step);
    player.position = run.time(step);
    dirty = true;
  }

  function send(message) {
    if (live && live.socket && live.socket.readyState === 1) live.socket.send(JSON.stringify(message));
  }

  function togglePlay() {
    if (live) {
      if (!live.ended) send({ type: live.paused ? "resume" : "pause" });
      return;
    }
    if (run === null) return;
    if (!player.playing && shown() >= run.last) seek(0);
    player.playing = !player.playing;
    player.wall = null;
    dirty = true;
  }

  function stepBy(delta) {
    if (run === null) return;
    if (live && delta > 0 && shown() >= run.last && !live.ended) {
      if (!live.paused) send({ type: "pause" });
      send({ type: "step" });
      live.following = true;
      return;
    }
    seek(shown() + delta);
  }

  function setSpeed(value) {
    player.fastest = value === "max";
    player.speed = player.fastest ? FASTEST : Number(value);
    player.wall = null;
    if (live) send({ type: "speed", value: player.fastest ? null : player.speed });
    dirty = true;
  }

  function nextEvent() {
    if (run === null) return;
    const step = shown();
    const later = run.eventSteps.find((s) => s > step);
    if (later !== undefined) seek(later);
  }

  function toFailure() {
    const failure = run && run.outcome && run.outcome.failure;
    if (failure) seek(failure.step);
  }

  function advance(now) {
    if (run === null || run.last < 0) return;
    if (live) {
      if (live.following && run.at !== run.last) {
        run.seek(run.last);
        dirty = true;
      }
      return;
    }
    if (!player.playing) return;
    if (player.wall === null) {
      player.wall = now;
      return;
    }
    const elapsed = (now - player.wall) / 1000;
    player.wall = now;
    player.position += elapsed * player.speed;
    let step = Math.floor(player.position / run.dt + 1e-9) - 1;
    if (player.fastest) step = Math.max(step, run.at + 1);
    if (step >= run.last) {
      step = run.last;
      player.playing = false;
    }
    if (step !== run.at) {
      run.seek(step);
      if (player.fastest) player.position = Math.max(player.position, run.time(step));
    }
    dirty = true;
  }

  function frame(now) {
    requestAnimationFrame(frame);
    if (run === null) return;
    advance(now);
    if (dirty || player.playing || (live && !live.paused)) {
      dirty = false;
      draw(now);
    }
  }

  // -- the timeline, the events list, the tooltip ---------------------------------------------------
  const EVENT_COLOURS = { stall: "#d0021b", release: "#b36b00", "order-done": "#2e9e4f", failure: "#d0021b", complete: "#2e9e4f", reject: "#d0021b", "route-error": "#d0021b", "planner-error": "#d0021b", alert: "#ff8c00", disturb: "#e6007e", resume: "#e6007e", interrupted: "#6b7480" };

  // the timeline's ticks are drawn once into a layer of their own, again only when events arrive
  const ticksLayer = document.createElement("canvas"), kctx = ticksLayer.getContext("2d");
  let ticksDrawn = null; // [events, total, width] the layer was drawn for

  function timelineTotal() {
    return Math.max(run.last + 1, live && !live.ended ? Math.round(run.scene.time_limit / run.dt) : 1);
  }

  function drawTicks(total) {
    const c = kctx, w = timeline.width / view.dpr, h = timeline.height / view.dpr;
    ticksLayer.width = timeline.width;
    ticksLayer.height = timeline.height;
    c.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    c.fillStyle = "#eef1f5";
    c.fillRect(0, 4, w, h - 8);
    const x = (s) => ((s + 0.5) / total) * w;
    let previous = -1, previousKind = "";
    for (const { step: s, event } of run.events) {
      const px = Math.round(x(s));
      if (px === previous && event[0] === previousKind) continue; // one tick per pixel and kind
      previous = px;
      previousKind = event[0];
      c.fillStyle = EVENT_COLOURS[event[0]] || "#6b7480";
      c.fillRect(px, 5, 1.5, h - 10);
    }
    const failure = run.outcome && run.outcome.failure;
    if (failure) {
      c.fillStyle = "#d0021b";
      c.beginPath();
      c.moveTo(x(failure.step) - 5, 0);
      c.lineTo(x(failure.step) + 5, 0);
      c.lineTo(x(failure.step), 8);
      c.fill();
    }
    ticksDrawn = [run.events.length, total, timeline.width, run.outcome];
  }

  function drawTimeline(step) {
    const c = tctx, w = timeline.width / view.dpr, h = timeline.height / view.dpr;
    c.setTransform(1, 0, 0, 1, 0, 0);
    c.clearRect(0, 0, timeline.width, timeline.height);
    if (run === null) return;
    const total = timelineTotal();
    const d = ticksDrawn;
    if (!d || d[0] !== run.events.length || d[1] !== total || d[2] !== timeline.width || d[3] !== run.outcome) drawTicks(total);
    c.drawImage(ticksLayer, 0, 0);
    c.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    const x = (s) => ((s + 0.5) / total) * w;
    c.fillStyle = "rgba(29, 35, 43, 0.15)";
    c.fillRect(x(run.last), 4, w - x(run.last), h - 8);
    c.fillStyle = "#1d232b";
    c.fillRect(x(step) - 1, 0, 2, h);
  }

  // the backlog: open orders at each full minute, as a step line under the timeline, the shown time marked
  const backlogLayer = document.createElement("canvas"), bctx = backlogLayer.getContext("2d");
  let backlogDrawn = null; // [samples, total, width] the layer was drawn for

  function drawBacklogLayer(total) {
    const c = bctx, chart = el("backlog"), w = chart.width / view.dpr, h = chart.height / view.dpr;
    backlogLayer.width = chart.width;
    backlogLayer.height = chart.height;
    c.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    c.fillStyle = "#f6f7f9";
    c.fillRect(0, 0, w, h);
    const most = Math.max(1, ...run.backlog.map((b) => b[1]));
    const x = (t) => ((t / run.dt + 0.5) / total) * w, y = (n) => h - 3 - (n / most) * (h - 14);
    c.strokeStyle = "#b36b00";
    c.fillStyle = "rgba(255, 179, 0, 0.25)";
    c.lineWidth = 1.5;
    c.beginPath();
    run.backlog.forEach(([t, n], k) => {
      if (k === 0) c.moveTo(x(t), y(n));
      else c.lineTo(x(t), y(n));
    });
    c.stroke();
    c.fillStyle = "#6b7480";
    c.font = "10px system-ui, sans-serif";
    c.textAlign = "left";
    c.fillText(`backlog (open orders each minute), most ${most}`, 4, 10);
    backlogDrawn = [run.backlog.length, total, chart.width];
  }

  function drawBacklog(step) {
    const chart = el("backlog");
    if (chart.hidden) {
      chart.hidden = false;
      resize();
    }
    const c = chart.getContext("2d"), w = chart.width / view.dpr, h = chart.height / view.dpr;
    const total = timelineTotal(), d = backlogDrawn;
    if (!d || d[0] !== run.backlog.length || d[1] !== total || d[2] !== chart.width) drawBacklogLayer(total);
    c.setTransform(1, 0, 0, 1, 0, 0);
    c.clearRect(0, 0, chart.width, chart.height);
    c.drawImage(backlogLayer, 0, 0);
    c.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    const at = ((step + 0.5) / total) * w;
    c.fillStyle = "#1d232b";
    c.fillRect(at - 1, 0, 2, h);
    // the sample in force: the last taken at or before the shown step's start
    let sample = null;
    for (let lo = 0, hi = run.backlog.length - 1; lo <= hi; ) {
      const mid = (lo + hi) >> 1;
      if (run.backlog[mid][0] <= step * run.dt + 1e-9) {
        sample = run.backlog[mid][1];
        lo = mid + 1;
      } else hi = mid - 1;
    }
    hook.drawnBacklog = { step, samples: run.backlog.length, sample };
  }

  function heldUp(vid, step) {
    // the orders a stalled vehicle holds up (the trace), and why it stands (result.json, when there)
    const i = run.index.get(vid), carry = i === undefined ? null : run.carryOf(i, step);
    const orders = carry ? carry[0] : [];
    const found = ((run.outcome && run.outcome.stalls) || []).find((s) => s.vehicle === vid && Math.abs(s.time - run.time(step)) < 1e-6);
    return (orders.length ? `; orders held up: ${orders.join(", ")}` : "; no order held up") + (found ? ` (${found.reason})` : "");
  }

  function eventText(event, step) {
    const [kind] = event;
    if (kind === "complete") {
      const task = run.tasks.get(event[1]);
      return `task ${event[1]} completed` + (task ? ` (vehicle ${task.vehicle}, segment ${task.goal})` : run.hasOrders ? " (an order's stop reached)" : "");
    }
    if (kind === "reject") return `vehicle ${event[2]}: plan rejected (${event[1]}), leg ${event[3]}`;
    if (kind === "route-error") return `vehicle ${event[1]}: route error: ${event[2]}`;
    if (kind === "alert") return `collision alert on segment ${event[1]}: ${event[2].join(", ")} \u27c2 ${event[3].join(", ")}`;
    if (kind === "planner-error") return `planner error (vehicle ${event[1]})`;
    if (kind === "disturb") return `vehicle ${event[1]} disturbed: ${event[2]}`;
    if (kind === "resume") return `vehicle ${event[1]} resumes (${event[2]})`;
    if (kind === "interrupted") return `run interrupted by ${event[1]}`;
    if (kind === "failure") return `failure: ${event[1]}: ${event[2]}`;
    if (kind === "release") return `order ${event[1]} released`;
    if (kind === "assign") return `vehicle ${event[1]} assigned ${event[2].length ? event[2].join(", ") : "no order"}`;
    if (kind === "served") return `vehicle ${event[1]} served order ${event[2]}'s stop ${event[3] + 1}`;
    if (kind === "order-done") return `order ${event[1]} completed`;
    if (kind === "stall") return `vehicle ${event[1]} stalled` + heldUp(event[1], step);
    return event.join(" ");
  }

  function addEventRow(step, kind, text) {
    const li = document.createElement("li");
    li.dataset.step = String(step);
    li.dataset.kind = kind;
    li.textContent = `${run.time(step).toFixed(2)} s  ${text}`;
    li.addEventListener("click", () => seek(step));
    el("events").appendChild(li);
    rowSteps.push(step);
  }

  let eventsSeen = [-2, -1]; // [step, events] the list was last brought up to
  let rowSteps = []; // the step of each event row, ascending
  let currentRows = []; // the rows marked as the shown step's

  function updateEvents(step) {
    if (eventsSeen[0] === step && eventsSeen[1] === run.events.length) return;
    eventsSeen = [step, run.events.length];
    const list = el("events");
    while (eventsShown < run.events.length && list.children.length < EVENT_ROWS) {
      const { step: s, event } = run.events[eventsShown++];
      addEventRow(s, event[0], eventText(event, s));
    }
    if (eventsShown < run.events.length && !list.dataset.cut) {
      list.dataset.cut = "1";
      const li = document.createElement("li");
      li.textContent = `(the first ${EVENT_ROWS} events; the timeline shows all)`;
      list.appendChild(li);
    }
    // rows up to the shown step are past; the step's own rows are current (found by bisection: a frame
    // never walks the whole list)
    const rows = list.children;
    let lo = 0, hi = rowSteps.length;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (rowSteps[mid] <= step) lo = mid + 1;
      else hi = mid;
    }
    const past = lo;
    for (let r = Math.min(past, eventsPast); r < Math.max(past, eventsPast); r++) rows[r].classList.toggle("past", r < past);
    eventsPast = past;
    for (const row of currentRows) row.classList.remove("current");
    currentRows = [];
    for (let r = past - 1; r >= 0 && rowSteps[r] === step; r--) {
      rows[r].classList.add("current");
      currentRows.push(rows[r]);
    }
  }

  function vehicleAt(px, py) {
    let best = null, distance = Infinity;
    const p = run.state.pose;
    for (let i = 0; i < run.n; i++) {
      const d = Math.hypot(sx(p[4 * i]) - px, sy(p[4 * i + 1]) - py);
      const reach = Math.max(8, (run.vehicles[i].length / 2) * view.scale);
      if (d < reach && d < distance) {
        best = i;
        distance = d;
      }
    }
    return best;
  }

  function orderText(carry, step) {
    // "order s12, stop 2 of 2 (loaded), dwelling 12 of 20 s"
    if (!carry || !carry[0].length) return "no order";
    const [orders, loaded, stop, stops, since, seconds] = carry;
    let text = `order ${orders[0]}` + (stops ? `, stop ${stop + 1} of ${stops}` : "") + (loaded ? " (loaded)" : "");
    if (since !== null && seconds) text += `, dwelling ${Math.min(seconds, Math.max(0, run.time(step) - since)).toFixed(0)} of ${seconds} s`;
    if (orders.length > 1) text += `; then ${orders.slice(1).join(", ")}`;
    return text;
  }

  function updateTooltip(step) {
    const tip = el("tooltip");
    if (hover === null || step < 0) {
      tip.hidden = true;
      return;
    }
    const i = hover, v = run.vehicles[i], p = run.state.pose;
    const [traverse, progress] = WAYS[run.state.way[i]];
    const task = run.headTask(v.id, step);
    const legs = run.planOf(i, step);
    const planText = legs
      .slice(0, 8)
      .map((leg) => `${leg[0]}${leg[1] >= 2 ? "\u2190" : "\u2192"}${leg[2] ? " fixed" : ""}`)
      .join(", ");
    const disturbed = (run.changedAt(run.disturbed, step) || {})[String(v.id)];
    const lines = [
      `vehicle ${v.id} (${v.type})`,
      `segment ${run.state.segment[i]}, ${traverse}, ${progress}, ${p[4 * i + 3].toFixed(2)} m/s`,
      `at (${p[4 * i].toFixed(2)}, ${p[4 * i + 1].toFixed(2)}), heading ${((p[4 * i + 2] * 180) / Math.PI).toFixed(1)}\u00b0`,
      task.head ? `task ${task.head.id} \u2192 segment ${task.head.goal} (${task.done} of ${task.total} done)` : `tasks: ${task.done} of ${task.total} done`,
      `plan: ${legs.length ? planText + (legs.length > 8 ? `, \u2026 (${legs.length} legs)` : "") : "none"}`,
    ];
    if (run.hasOrders && task.total === 0) lines.splice(3, 1); // its work is orders (below), not tasks
    if (disturbed) lines.push(`disturbed: ${disturbed}`);
    const carry = run.hasOrders ? run.carryOf(i, step) : null;
    if (run.hasOrders) lines.push(orderText(carry, step));
    if (carry && carry[6]) {
      let stall = null;
      for (let e = lowerEvent(step + 1) - 1; e >= 0 && stall === null; e--) {
        const event = run.events[e].event;
        if (event[0] === "stall" && event[1] === v.id) stall = run.events[e];
      }
      lines.push(`stalled${stall ? ` at ${run.time(stall.step).toFixed(1)} s` : ""}${heldUp(v.id, stall ? stall.step : step)}`);
    }
    tip.textContent = lines.join("\n");
    tip.hidden = false;
    const x = sx(p[4 * i]) + 14, y = sy(p[4 * i + 1]) + 14;
    tip.style.left = `${Math.min(x, view.width - tip.offsetWidth - 4)}px`;
    tip.style.top = `${Math.min(y, view.height - tip.offsetHeight - 4)}px`;
  }

  // -- input ----------------------------------------------------------------------------------------
  function wire() {
    el("play").addEventListener("click", togglePlay);
    el("back").addEventListener("click", () => stepBy(-1));
    el("forward").addEventListener("click", () => stepBy(1));
    el("speed").addEventListener("change", (e) => setSpeed(e.target.value));
    el("next-event").addEventListener("click", nextEvent);
    el("to-failure").addEventListener("click", toFailure);
    el("to-live").addEventListener("click", () => seek(run.last));
    el("scrub").addEventListener("input", (e) => seek(Number(e.target.value)));
    el("show-plans").addEventListener("change", () => (dirty = true));
    el("show-labels").addEventListener("change", () => ((view.mapDirty = true), (dirty = true)));
    timeline.addEventListener("click", (e) => {
      if (run === null) return;
      const rect = timeline.getBoundingClientRect();
      const total = Math.max(run.last + 1, 1);
      seek(Math.floor(((e.clientX - rect.left) / rect.width) * total));
    });
    window.addEventListener("keydown", (e) => {
      if (e.target instanceof HTMLSelectElement || e.target instanceof HTMLInputElement) return;
      if (e.key === " ") togglePlay();
      else if (e.key === "ArrowRight") stepBy(1);
      else if (e.key === "ArrowLeft") stepBy(-1);
      else if (e.key === "Home") seek(0);
      else if (e.key === "n") nextEvent();
      else if (e.key === "f") toFailure();
      else return;
      e.preventDefault();
    });
    let drag = null;
    canvas.addEventListener("mousedown", (e) => (drag = { x: e.clientX, y: e.clientY, cx: view.cx, cy: view.cy }));
    window.addEventListener("mouseup", () => (drag = null));
    canvas.addEventListener("mousemove", (e) => {
      const rect = canvas.getBoundingClientRect();
      if (drag) {
        view.cx = drag.cx - (e.clientX - drag.x) / view.scale;
        view.cy = drag.cy + (e.clientY - drag.y) / view.scale;
        view.mapDirty = true;
      } else if (run !== null && run.at >= 0) {
        hover = vehicleAt(e.clientX - rect.left, e.clientY - rect.top);
      }
      dirty = true;
    });
    canvas.addEventListener("mouseleave", () => ((hover = null), (dirty = true)));
    canvas.addEventListener("dblclick", () => run && fit());
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      const rect = canvas.getBoundingClientRect();
      const px = e.clientX - rect.left, py = e.clientY - rect.top;
      const wx = (px - view.width / 2) / view.scale + view.cx, wy = view.cy - (py - view.height / 2) / view.scale;
      view.scale *= Math.exp(-e.deltaY * 0.0015);
      view.cx = wx - (px - view.width / 2) / view.scale;
      view.cy = wy + (py - view.height / 2) / view.scale;
      view.mapDirty = true;
      dirty = true;
    }, { passive: false });
    window.addEventListener("resize", () => run && (resize(), fit()));
  }

  // -- starting: a recorded run, or a live one --------------------------------------------------------
  function begin(scene) {
    run = new Run(scene);
    planPaths = [];
    eventsShown = eventsPast = 0;
    eventsSeen = [-2, -1];
    rowSteps = [];
    currentRows = [];
    el("events").replaceChildren();
    el("backlog").hidden = true;
    el("orders").textContent = "";
    backlogDrawn = null;
    hook.drawnOrders = null;
    hook.drawnBacklog = null;
    delete el("events").dataset.cut;
    el("title").textContent = `fleetsim \u00b7 ${scene.scenario}` + (scene.planner ? ` \u00b7 ${scene.planner}` : "");
    document.title = `${scene.scenario} \u00b7 fleetsim view`;
    resize();
    fit();
  }

  function showOutcome() {
    const outcome = run.outcome, status = el("status");
    const word = outcome && outcome.status ? outcome.status : live && !live.ended ? "running" : "";
    status.textContent = word + (outcome && outcome.failure ? ` \u2014 ${outcome.failure.kind}: ${outcome.failure.message.split("\n")[0]}` : "");
    status.className = word;
    el("to-failure").disabled = !(outcome && outcome.failure);
    const banner = el("banner");
    banner.hidden = !(outcome && outcome.stuck);
    if (outcome && outcome.stuck) banner.textContent = `${outcome.stuck.headline.split("\n")[0]} (at the end: who waits for whom)`;
    if (outcome && outcome.failure && outcome.failure.step <= run.last) {
      // the failure takes its place among the events, at its step (after the step's own events)
      const at = lowerEvent(outcome.failure.step + 1);
      run.events.splice(Math.max(at, eventsShown), 0, { step: outcome.failure.step, event: ["failure", outcome.failure.kind, outcome.failure.message.split("\n")[0]] });
      if (!run.eventSteps.includes(outcome.failure.step)) run.eventSteps = [...run.eventSteps, outcome.failure.step].sort((a, b) => a - b);
    }
  }

  function connect(path) {
    const socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}${path}`);
    live = { socket, paused: false, speed: 1, ended: false, following: true };
    socket.addEventListener("open", () => (hook.connected = true));
    socket.addEventListener("message", (e) => {
      const message = JSON.parse(e.data);
      if (message.type === "scene") {
        begin(message.scene);
        live.ended = false;
        live.following = true;
        showOutcome();
        hook.ready = true;
      } else if (message.type === "steps" && run !== null) {
        for (const record of message.steps) run.add(record);
        dirty = true;
      } else if (message.type === "status") {
        live.paused = message.paused;
        live.speed = message.speed;
        const option = message.speed === null ? "max" : String(message.speed);
        if (![...el("speed").options].some((o) => o.value === option)) el("speed").add(new Option(`${option}\u00d7`, option));
        el("speed").value = option;
        if (run !== null && !run.outcome) {
          el("status").textContent = live.paused ? "paused" : "running";
          el("status").className = "running";
        }
        dirty = true;
      } else if (message.type === "end" && run !== null) {
        run.outcome = message.outcome;
        live.ended = true;
        showOutcome();
        dirty = true;
      }
    });
    socket.addEventListener("close", () => {
      hook.connected = false;
      if (live && !live.ended) {
        live.ended = true;
        el("notes").textContent = "the connection to the run is closed; the page keeps what it received";
      }
      dirty = true;
    });
  }

  function base64Bytes(text) {
    if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text);
    const binary = atob(text), bytes = new Uint8Array(binary.length);
    for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
    return bytes;
  }

  async function readDocument() {
    const node = el("fleetsim-data");
    if (node.dataset.encoding === "gzip+base64") {
      const stream = new Blob([base64Bytes(node.textContent.trim())]).stream().pipeThrough(new DecompressionStream("gzip"));
      return JSON.parse(await new Response(stream).text());
    }
    return JSON.parse(node.textContent);
  }

  async function start() {
    const started = performance.now();
    wire();
    const doc = await readDocument();
    if (doc.live) {
      connect(doc.socket);
    } else {
      begin(doc);
      for (const record of doc.steps) run.add(record);
      showOutcome();
      // A failed run opens at its failure, as `f` goes there (what a reviewer asks first; Home is the
      // start); any other at its start. A live page follows its run instead.
      if (run.outcome && run.outcome.failure) toFailure();
      else seek(0);
      el("notes").textContent = (doc.notes || []).join("; ");
      hook.ready = true;
    }
    hook.loadMs = performance.now() - started;
    hook.state = () => ({
      step: shown(),
      time: run && shown() >= 0 ? run.time(shown()) : 0,
      last: run ? run.last : -1,
      playing: live ? !live.paused && !live.ended : player.playing,
      speed: player.fastest ? "max" : player.speed,
      live: live ? { paused: live.paused, speed: live.speed, ended: live.ended, following: live.following } : null,
      shown: el("time").textContent,
    });
    // what the last drawn frame showed: each vehicle's (x, y, heading) in metres and radians
    hook.drawnPoses = () => {
      const drawn = hook.drawn, out = {};
      if (!drawn || !drawn.poses) return { step: -1, poses: out };
      run.ids.forEach((id, i) => (out[id] = [drawn.poses[4 * i], drawn.poses[4 * i + 1], drawn.poses[4 * i + 2]]));
      return { step: drawn.step, poses: out };
    };
    hook.seek = (step) => seek(step);
    // the backlog chart's points: [seconds, open orders] at each full minute so far
    hook.backlog = () => run.backlog.map((b) => b.slice());
    // where a vehicle is drawn, in CSS pixels from the canvas's top left corner
    hook.screenOf = (id) => {
      const i = run.index.get(id), p = run.state.pose;
      return i === undefined ? null : [sx(p[4 * i]), sy(p[4 * i + 1])];
    };
    requestAnimationFrame(frame);
  }

  start().catch((error) => {
    el("status").textContent = `the view could not load: ${error}`;
    el("status").className = "failed";
    hook.error = String(error);
  });
})();
