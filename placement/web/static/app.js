// The planning page: draws the state the server sends (room, anchors, maps, jobs) and
// sends what the user does. Every number shown is computed by the server (anchorplan's
// own functions); this file only draws and forwards.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const PAD = 0.4; // metres of margin around the room in the drawings
let state = null; // the last state from the server
let layer = "coverage";
let fieldResult = null; // the field simulation's result for the shown layout
let drag = null; // {index, view, point, sent, pending}
let pollTimer = null;
let openedPlan = null; // the id of the plan whose result was opened in the page

// -- talking to the server -------------------------------------------------------------
async function api(method, path, body) {
  const opts = { method, headers: {} };
  if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  const res = await fetch(path, opts);
  const data = await res.json().catch(() => ({ error: `HTTP ${res.status}` }));
  if (!res.ok) throw new Error(data.error || `HTTP ${res.status}`);
  return data;
}

function showError(msg) {
  const box = document.getElementById("error");
  box.textContent = msg ? `error: ${msg}` : "";
  box.hidden = !msg;
}

async function act(method, path, body) {
  try {
    const data = await api(method, path, body);
    showError(null);
    render(data);
    return data;
  } catch (e) {
    showError(e.message);
    return null;
  }
}

// -- drawing helpers ---------------------------------------------------------------------
// (m) anchors this close in a view share one label (the figures' STACKED)
const STACKED = 0.05;

function el(name, attrs, parent) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function frame(svg, w, h) {
  // metres -> pixels: x to the right, the second axis up
  const width = svg.clientWidth || 800;
  const scale = Math.min(width / (w + 2 * PAD), 520 / (h + 2 * PAD));
  svg.setAttribute("viewBox", `0 0 ${(w + 2 * PAD) * scale} ${(h + 2 * PAD) * scale}`);
  svg.style.height = `${(h + 2 * PAD) * scale}px`;
  svg.innerHTML = "";
  return {
    scale,
    px: (x) => (x + PAD) * scale,
    py: (y) => (h + PAD - y) * scale,
    inv: (X, Y) => [X / scale - PAD, h + PAD - Y / scale],
  };
}

function viridis(t) {
  // a short viridis ramp, t in [0, 1]
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  const s = Math.max(0, Math.min(1, t)) * (stops.length - 1);
  const i = Math.min(Math.floor(s), stops.length - 2);
  const f = s - i;
  const c = stops[i].map((a, j) => Math.round(a + f * (stops[i + 1][j] - a)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function logScale(v, lo, hi) {
  return (Math.log10(v) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo));
}

function coverageColour(n, k) {
  if (n >= k) return n >= k + 2 ? "#1a9850" : "#66bd63";
  if (n >= 4) return "#fdae61";
  return n >= 1 ? "#f46d43" : "#d73027";
}

function cellValues() {
  const m = state.maps;
  if (layer === "coverage") return m.heard.map((n) => coverageColour(n, m.k));
  const values = layer === "peb" ? m.peb : fieldResult ? fieldResult.rms : null;
  if (!values) return null;
  return values.map((v) => (v === null ? "#bbb" : viridis(1 - logScale(Math.max(v, 0.005), 0.005, 2))));
}

function drawCells(g, f) {
  const m = state.maps;
  const colours = cellValues();
  if (!colours) return;
  const s = m.cell * f.scale;
  m.cells.forEach(([x, y], i) => {
    el("rect", { x: f.px(x - m.cell / 2), y: f.py(y + m.cell / 2), width: s + 0.5, height: s + 0.5,
      fill: colours[i], "fill-opacity": 0.75 }, g);
  });
  if (layer === "coverage") drawKLine(g, f);
}

function drawKLine(g, f) {
  // the border between cells heard by k anchors or more and the others
  const m = state.maps;
  const key = (x, y) => `${Math.round(x / m.cell - 0.5)},${Math.round(y / m.cell - 0.5)}`;
  const covered = new Set();
  m.cells.forEach(([x, y], i) => { if (m.heard[i] >= m.k) covered.add(key(x, y)); });
  let d = "";
  const h = m.cell / 2;
  for (const [x, y] of m.cells) {
    if (!covered.has(key(x, y))) continue;
    const sides = [[m.cell, 0, [x + h, y - h, x + h, y + h]], [-m.cell, 0, [x - h, y - h, x - h, y + h]],
      [0, m.cell, [x - h, y + h, x + h, y + h]], [0, -m.cell, [x - h, y - h, x + h, y - h]]];
    for (const [dx, dy, [x0, y0, x1, y1]] of sides) {
      if (!covered.has(key(x + dx, y + dy))) d += `M${f.px(x0)},${f.py(y0)}L${f.px(x1)},${f.py(y1)}`;
    }
  }
  el("path", { d, stroke: "#08306b", "stroke-width": 2, fill: "none", id: "k-line" }, g);
}

function boxOutline(g, f, b, axes, attrs) {
  const [i, j] = axes;
  const x0 = f.px(b.min[i]), x1 = f.px(b.max[i]), y0 = f.py(b.max[j]), y1 = f.py(b.min[j]);
  return el("rect", { x: x0, y: y0, width: x1 - x0, height: y1 - y0, ...attrs }, g);
}

function label(g, x, y, text, attrs) {
  const t = el("text", { x, y, "font-size": 11, "text-anchor": "middle", ...attrs }, g);
  t.textContent = text;
  return t;
}

// -- the two views -------------------------------------------------------------------------
function drawPlan() {
  const svg = document.getElementById("plan");
  const r = state.room;
  const f = frame(svg, r.size[0], r.size[1]);
  const pts = r.corners.map(([x, y]) => `${f.px(x)},${f.py(y)}`).join(" ");
  el("polygon", { points: pts, fill: "#f4f4f4", stroke: "none" }, svg);
  if (state.maps) drawCells(el("g", { id: "cells" }, svg), f);
  el("polygon", { points: pts, fill: "none", stroke: "#222", "stroke-width": 3 }, svg);
  // mounting surfaces: a wall's rectangles seen from above are segments (their corners
  // project onto a line, whatever the wall's direction), drawn as lines between the two
  // farthest corners; the ceiling's are areas, left to the room's fill
  const walls = el("g", { class: "mounting" }, svg);
  for (const q of r.mounting) {
    if (Math.abs(shoelace(q)) > 1e-6) continue;
    let ends = [q[0], q[1]], far = -1;
    for (const a of q) for (const b of q) {
      const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
      if (d > far) { far = d; ends = [a, b]; }
    }
    el("line", { x1: f.px(ends[0][0]), y1: f.py(ends[0][1]), x2: f.px(ends[1][0]), y2: f.py(ends[1][1]),
      stroke: "#2b8cbe", "stroke-width": 4, "stroke-opacity": 0.6 }, walls);
  }
  // a zone box holds nodes only inside the floor plan: its outline is drawn there
  const clip = el("clipPath", { id: "plan-clip" }, el("defs", {}, svg));
  el("polygon", { points: pts }, clip);
  for (const z of r.zones) boxOutline(svg, f, z, [0, 1], { fill: "none", stroke: "#3182bd", "stroke-width": 1.5, "stroke-dasharray": "8 4", "clip-path": "url(#plan-clip)", class: "zone" });
  for (const k of r.keepouts) boxOutline(svg, f, k, [0, 1], { fill: "#e31a1c", "fill-opacity": 0.25, stroke: "#e31a1c" });
  // an obstacle the maps' slice does not cut (a duct above the tags) is its dashed outline:
  // the cells under it are the slice's
  const h = state.maps ? state.maps.height : null;
  for (const o of r.obstacles) {
    const cut = h === null || (o.min[2] <= h && h <= o.max[2]);
    boxOutline(svg, f, o, [0, 1], cut
      ? { fill: "#636363", "fill-opacity": 0.85, stroke: "#252525", class: "obstacle" }
      : { fill: "none", stroke: "#252525", "stroke-dasharray": "6 3", class: "obstacle off-slice" });
  }
  for (const o of labelled(r.obstacles)) {
    const t = label(svg, f.px((o.min[0] + o.max[0]) / 2), f.py((o.min[1] + o.max[1]) / 2) + 4,
      `${o.name || "obstacle"} ${o.min[2] > 0 ? `${heightText(o.min[2])}–` : ""}${heightText(o.max[2])} m`,
      // dark with a white halo: legible on the box and beside one thinner than the text
      { fill: "#252525", stroke: "#fff", "stroke-width": 3, "paint-order": "stroke", class: "obstacle-label" });
    // a box narrower than its label and less than two lines deep (a column in a hall)
    // would be hidden by it: the label goes above the box
    const b = t.getBBox();
    if (b.width > (o.max[0] - o.min[0]) * f.scale && 2 * b.height > (o.max[1] - o.min[1]) * f.scale) {
      t.setAttribute("y", f.py(o.max[1]) - 4);
    }
  }
  drawAnchors(svg, f, [0, 1], "plan");
}

// a height as the figures write it: to the centimetre, without trailing zeros (0.45, 3)
function heightText(v) {
  return String(Number(v.toFixed(2)));
}

// the obstacles whose names and heights the plan writes: of boxes that meet side by side
// with the same bottom and top (a pillar described as three boxes), only the largest
// footprint, so that one solid gets one label (as the report's figures)
function labelled(obstacles) {
  const group = obstacles.map((_, i) => i);
  const same = (a, b) => Math.abs(a.min[2] - b.min[2]) <= 1e-9 && Math.abs(a.max[2] - b.max[2]) <= 1e-9
    && [0, 1].every((k) => a.min[k] <= b.max[k] + 1e-9 && b.min[k] <= a.max[k] + 1e-9);
  obstacles.forEach((a, i) => {
    for (let j = 0; j < i; j++) {
      if (!same(a, obstacles[j])) continue;
      const from = group[i], to = group[j];
      for (let k = 0; k < group.length; k++) if (group[k] === from) group[k] = to;
    }
  });
  const area = (o) => (o.max[0] - o.min[0]) * (o.max[1] - o.min[1]);
  const best = new Map();
  group.forEach((g, i) => { if (!best.has(g) || area(obstacles[i]) > area(obstacles[best.get(g)])) best.set(g, i); });
  return [...best.values()].sort((a, b) => a - b).map((i) => obstacles[i]);
}

// the signed area (m²) of a polygon's projection onto the plan, [[x, y, z], ...]
function shoelace(q) {
  let a = 0;
  for (let i = 0; i < q.length; i++) {
    const [x0, y0] = q[i], [x1, y1] = q[(i + 1) % q.length];
    a += x0 * y1 - x1 * y0;
  }
  return a / 2;
}

function drawElevation() {
  const svg = document.getElementById("elevation");
  const r = state.room;
  const f = frame(svg, r.size[0], r.size[2]);
  el("rect", { x: f.px(0), y: f.py(r.size[2]), width: r.size[0] * f.scale, height: r.size[2] * f.scale,
    fill: "#f4f4f4", stroke: "#222", "stroke-width": 2 }, svg);
  if (state.maps) {
    const y = f.py(state.maps.height);
    el("line", { x1: f.px(0), x2: f.px(r.size[0]), y1: y, y2: y, stroke: "#3182bd", "stroke-dasharray": "6 4" }, svg);
  }
  for (const z of r.zones) boxOutline(svg, f, z, [0, 2], { fill: "none", stroke: "#3182bd", "stroke-dasharray": "8 4" });
  for (const o of r.obstacles) boxOutline(svg, f, o, [0, 2], { fill: "#636363", "fill-opacity": 0.6, stroke: "#252525" });
  for (const k of r.keepouts) boxOutline(svg, f, k, [0, 2], { fill: "#e31a1c", "fill-opacity": 0.25, stroke: "#e31a1c" });
  drawAnchors(svg, f, [0, 2], "elevation");
}

function drawAnchors(svg, f, axes, view) {
  const [i, j] = axes;
  // anchors on one spot of this view (three on one vertical line of a wall, from above):
  // the one drawn last, on top, carries the numbers of all ("2,3,4"), as in the figures
  const spot = (a, b) => Math.hypot(a[i] - b[i], a[j] - b[j]) <= STACKED;
  state.anchors.forEach((a, index) => {
    const g = el("g", { class: "anchor", "data-index": index, "data-view": view }, svg);
    el("circle", { cx: f.px(a[i]), cy: f.py(a[j]), r: 9, fill: "#fff", stroke: "#b30000", "stroke-width": 3 }, g);
    const above = state.anchors.some((b, k) => k > index && spot(a, b));
    const stack = state.anchors.map((b, k) => k).filter((k) => spot(a, state.anchors[k]));
    // numbered from 1, as the report's figures and the mounting sheet (A1, A2, ...) number them
    if (!above) label(g, f.px(a[i]), f.py(a[j]) + 4, stack.map((k) => k + 1).join(","),
      { "font-weight": "bold", class: "anchor-number", ...(stack.length > 1 ? { stroke: "#fff", "stroke-width": 3, "paint-order": "stroke" } : {}) });
    g.addEventListener("pointerdown", (ev) => startDrag(ev, svg, f, axes, index, view));
  });
}

// -- dragging: the circle follows the pointer; the server snaps and answers ----------------
function startDrag(ev, svg, f, axes, index, view) {
  ev.preventDefault();
  const g = ev.currentTarget;
  g.classList.add("dragging");
  svg.setPointerCapture(ev.pointerId);
  drag = { index, pending: null, busy: false };
  const toPoint = (e) => {
    const rect = svg.getBoundingClientRect();
    const vb = svg.viewBox.baseVal;
    const X = ((e.clientX - rect.left) / rect.width) * vb.width;
    const Y = ((e.clientY - rect.top) / rect.height) * vb.height;
    const [u, v] = f.inv(X, Y);
    const p = state.anchors[index].slice();
    p[axes[0]] = u;
    p[axes[1]] = v;
    g.querySelector("circle").setAttribute("cx", X);
    g.querySelector("circle").setAttribute("cy", Y);
    return p;
  };
  const move = (e) => { if (drag) sendMove(toPoint(e), false); };
  const up = (e) => {
    svg.removeEventListener("pointermove", move);
    svg.removeEventListener("pointerup", up);
    g.classList.remove("dragging");
    if (drag) sendMove(toPoint(e), true);
  };
  svg.addEventListener("pointermove", move);
  svg.addEventListener("pointerup", up);
}

async function sendMove(point, final) {
  // One request in flight; the newest point waits for it; the drop always goes. The error
  // box is updated at the drop only: shown mid-drag it would push the plan view down under
  // the pointer, and the drop would land elsewhere.
  const d = drag;
  if (!d) return;
  d.pending = point;
  d.final = d.final || final;
  if (d.busy) return;
  d.busy = true;
  while (d.pending) {
    const p = d.pending;
    d.pending = null;
    let data = null;
    let err = null;
    try {
      data = await api("POST", "/api/anchors/move", { index: d.index, point: p });
    } catch (e) {
      err = e;
    }
    if (drag !== d) continue; // a newer drag owns the page: its answers are drawn
    if (data) { state = data; fieldResult = null; }
    if (d.pending) continue;
    if (d.final) showError(err ? err.message : null);
    render(state);
  }
  d.busy = false;
  if (d.final && drag === d) drag = null;
}

// -- the side panel ----------------------------------------------------------------------------
function pct(x) { return `${(100 * x).toFixed(1)} %`; }
function metres(x) { return x === null || x === undefined ? "–" : x < 0.1 ? `${(100 * x).toFixed(1)} cm` : `${x.toFixed(3)} m`; }

function drawSummary() {
  const m = state.maps;
  const box = document.getElementById("summary");
  if (!m) { box.textContent = "No anchors."; return; }
  const s = m.summary;
  box.innerHTML = `<div class="big" id="covered-k">${pct(s.covered_k)} of the ${s.nodes} nodes hear ${m.k} or more anchors</div>
    <div class="muted">in line of sight and reach (k = ${m.k}${m.k === 5 ? ": one echo can be found" : ": a fix"}); ${pct(s.covered_fix)} hear 4 or more</div>
    <div>PEB at σ = ${m.sigma * 100} cm: median <span id="peb-median">${metres(s.peb.median)}</span>, P95 ${metres(s.peb.p95)}${s.peb.finite < 1 ? `, no fix at ${pct(1 - s.peb.finite)}` : ""}</div>`;
  document.getElementById("map-height").textContent = m.height.toFixed(2);
  const legend = document.getElementById("legend");
  const orange = m.k > 5 ? `, orange 4 to ${m.k - 1}` : m.k === 5 ? ", orange 4" : "";
  if (layer === "coverage") legend.textContent = `cells: anchors heard in line of sight and reach at the tag height (green ≥ ${m.k}${orange}, red < 4); dark blue line: the k = ${m.k} border; light blue: mountable walls`;
  else if (layer === "peb") legend.textContent = "cells: PEB, yellow 5 mm … dark 2 m (log scale); grey: no fix";
  else legend.textContent = fieldResult ? "cells: RMS error at the receiver, yellow 5 mm … dark 2 m (log scale); grey: no fix" : "simulate the error at the receiver to see this map";
}

function drawAnchorTable() {
  const body = document.querySelector("#anchors tbody");
  body.innerHTML = "";
  state.anchors.forEach((a, i) => {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td>${i + 1}</td><td>${a[0].toFixed(2)}</td><td>${a[1].toFixed(2)}</td><td>${a[2].toFixed(2)}</td><td><button type="button" data-remove="${i}" title="remove">✕</button></td>`;
    body.appendChild(tr);
  });
  document.getElementById("anchor-count").textContent = `(${state.anchors.length})`;
}

function drawField(status) {
  const bar = document.getElementById("field-progress");
  const box = document.getElementById("field-summary");
  if (!status) { bar.hidden = true; box.textContent = "Not simulated for this layout."; fieldResult = null; return; }
  bar.hidden = status.state !== "running";
  bar.max = status.total;
  bar.value = status.done;
  if (status.state === "running") box.textContent = `simulating: draw ${status.done} of ${status.total}`;
  else if (status.state === "failed") box.textContent = `failed: ${status.error}`;
  else {
    const r = status.result;
    fieldResult = r;
    const verified = state.system.verifies ? `; verified ${pct(r.verified)}` : "";
    box.innerHTML = `<span id="field-stats">median ${metres(r.median)}, mean ${metres(r.mean)}, P95 ${metres(r.p95)}</span>${verified}; a fix at ${pct(r.fixes)} <span class="muted">(${status.total} draws, anchors mounted within 3 cm, at the map's cells)</span>`;
  }
}

function drawPlanJob(p) {
  const st = document.getElementById("plan-state");
  const prog = document.getElementById("plan-progress");
  document.getElementById("plan-cancel").hidden = !(p && p.state === "running");
  document.getElementById("plan-run").disabled = Boolean(p && p.state === "running");
  if (!p) return;
  const phases = (p.progress && p.progress.order) || [];
  prog.innerHTML = phases.map((name) => {
    const [done, total] = p.progress.phases[name];
    return `<div class="phase"><span>${name}</span><progress max="${Math.max(total, 1)}" value="${done}"></progress><span>${done}/${total}</span></div>`;
  }).join("");
  if (p.state === "running") st.textContent = `running (${p.seconds.toFixed(0)} s): ${p.command}`;
  else if (p.state === "done") {
    const fld = p.result.field;
    st.innerHTML = `<span id="plan-done">done</span> in ${p.seconds.toFixed(0)} s; field median ${metres(fld.median)}, mean ${metres(fld.mean)}, P95 ${metres(fld.p95)}. <button type="button" id="plan-open">Show its layout</button>`;
  } else if (p.state === "failed") st.textContent = `failed: ${p.error}`;
  else st.textContent = "cancelled";
}

function render(data) {
  state = data;
  // a DXF plan moved to the room's origin: the page's coordinates are the drawing's minus it
  const shift = data.room_shift ? `, moved by (${data.room_shift.map((v) => v.toFixed(3)).join(", ")}) m to start at 0` : "";
  document.getElementById("room-name").textContent = `— ${data.room.name}${data.room_file ? ` (${data.room_file}${shift})` : ""}`;
  document.getElementById("system-line").textContent = data.system.describe;
  // what the DXF reader said of the drawing (arcs, round columns, entities left out)
  const notes = document.getElementById("room-notes");
  notes.textContent = (data.room_notes || []).join(" ");
  notes.hidden = !notes.textContent;
  const sel = document.getElementById("room-file");
  // each file by its name (its folder's index is the value), the room open selected
  sel.innerHTML = data.files.map((f) => `<option value="${f}">${f.slice(f.indexOf("/") + 1)}</option>`).join("");
  if (data.room_id && data.files.includes(data.room_id)) sel.value = data.room_id;
  document.getElementById("system").value = data.system.chosen || "";
  drawField(data.field);
  drawPlan();
  drawElevation();
  drawSummary();
  drawAnchorTable();
  drawPlanJob(data.plan);
  schedulePoll(data);
}

// -- polling the jobs: the plan's progress survives a reload (the server keeps it) -------------
function schedulePoll(data) {
  const running = (data.plan && data.plan.state === "running") || (data.field && data.field.state === "running");
  clearTimeout(pollTimer);
  if (running) pollTimer = setTimeout(poll, 500);
}

async function poll() {
  try {
    const jobs = await api("GET", "/api/jobs");
    const wasField = state.field && state.field.state === "running";
    state.plan = jobs.plan;
    state.field = jobs.field;
    if (jobs.plan && jobs.plan.state === "done" && openedPlan !== jobs.plan.id) {
      openedPlan = jobs.plan.id;
      const data = await act("POST", "/api/plan/open");
      if (data) return;
    }
    drawPlanJob(jobs.plan);
    drawField(jobs.field);
    if (wasField && jobs.field && jobs.field.state !== "running") { drawPlan(); drawSummary(); }
    schedulePoll(state);
  } catch (e) {
    showError(e.message);
    pollTimer = setTimeout(poll, 2000);
  }
}

// -- the controls ---------------------------------------------------------------------------------
function wire() {
  document.querySelectorAll("input[name=layer]").forEach((r) => r.addEventListener("change", () => {
    layer = r.value;
    drawPlan();
    drawSummary();
  }));
  document.getElementById("field-run").addEventListener("click", () => act("POST", "/api/field", {}));
  document.querySelector("#anchors tbody").addEventListener("click", (ev) => {
    const i = ev.target.getAttribute("data-remove");
    if (i !== null) act("POST", "/api/anchors/remove", { index: Number(i) });
  });
  document.getElementById("anchor-add").addEventListener("click", () => {
    const s = state.room.size;
    act("POST", "/api/anchors/add", { point: [s[0] / 2, s[1] / 2, s[2]] });
  });
  document.getElementById("plan-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    const form = new FormData(ev.target);
    const body = Object.fromEntries(form.entries());
    act("POST", "/api/plan", body);
  });
  document.getElementById("plan-state").addEventListener("click", (ev) => {
    if (ev.target.id === "plan-open") act("POST", "/api/plan/open");
  });
  document.getElementById("plan-cancel").addEventListener("click", () => act("POST", "/api/plan/cancel"));
  document.getElementById("room-open").addEventListener("click", () =>
    act("POST", "/api/room", { file: document.getElementById("room-file").value }));
  document.getElementById("room-upload").addEventListener("change", async (ev) => {
    const file = ev.target.files[0];
    if (!file) return;
    const content = await file.text();
    const value = (id) => document.getElementById(id).value || null;
    await act("POST", "/api/room", { upload: { name: file.name, content }, room_height: value("room-height"),
      dxf_unit: value("dxf-unit"), dxf_layer: value("dxf-layer"),
      dxf_obstacle_layer: value("dxf-obstacle-layer"), obstacle_height: value("obstacle-height") });
    ev.target.value = "";
  });
  document.getElementById("system").addEventListener("change", (ev) =>
    act("POST", "/api/system", { system: ev.target.value }));
  document.getElementById("exports").addEventListener("click", async (ev) => {
    // fetch first, so a failure shows its message in the page instead of a JSON page
    const a = ev.target.closest("a");
    if (!a || a.dataset.checked) return;
    ev.preventDefault();
    a.textContent = `${a.textContent} …`;
    const res = await fetch(a.href);
    a.textContent = a.textContent.replace(" …", "");
    if (!res.ok) { showError((await res.json().catch(() => ({}))).error || `HTTP ${res.status}`); return; }
    const blob = await res.blob();
    const name = (res.headers.get("content-disposition") || "").match(/filename="?([^";]+)"?/);
    const link = document.createElement("a");
    link.href = URL.createObjectURL(blob);
    link.download = name ? name[1] : a.textContent;
    document.body.appendChild(link);
    link.click();
    link.remove();
    showError(null);
  });
  window.addEventListener("resize", () => { if (state) { drawPlan(); drawElevation(); } });
}

wire();
act("GET", "/api/state").then((data) => {
  if (data && data.plan && data.plan.state === "done") openedPlan = data.plan.id;
});
