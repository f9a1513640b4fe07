// robonix-nav dashboard: plain browser APIs (WebSocket, canvas, fetch), no library.
"use strict";

const canvas = document.getElementById("map");
const ctx = canvas.getContext("2d");
const $ = (id) => document.getElementById(id);

let snap = null;            // the latest state snapshot from /ws
let mapImg = null;          // ImageBitmap of the current map
let mapMeta = null;         // {version, width, height, resolution, origin_x, origin_y}
let loadingVersion = 0;
let view = null;            // {s, ox, oy}: canvas px = ox + (x - x0) * s ...
let drag = null;            // {x, y, cx, cy, yaw}
let frames = 0, frameT0 = performance.now();
let drawPending = false;

// Read by the browser test and the latency benchmark.
const dash = window.__dash = {
  mapVersion: 0, mapMeta: null, goal: null, messages: 0, drawnPose: null, drawLog: [],
  worldToCanvas: (x, y) => view ? [view.ox + (x - view.x0) * view.s, view.oy + (view.y1 - y) * view.s] : null,
  canvasToWorld: (cx, cy) => view ? [view.x0 + (cx - view.ox) / view.s, view.y1 - (cy - view.oy) / view.s] : null,
  // centre of grid cell (col, row) as in OccupancyGrid.data (row 0 = lowest y)
  cellToCanvas: (col, row) => mapMeta ? dash.worldToCanvas(
    mapMeta.origin_x + (col + 0.5) * mapMeta.resolution, mapMeta.origin_y + (row + 0.5) * mapMeta.resolution) : null,
};

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.onopen = () => { $("conn").textContent = "live"; $("conn").className = "badge ok"; };
  ws.onclose = () => {
    $("conn").textContent = "disconnected"; $("conn").className = "badge bad";
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    snap = JSON.parse(ev.data);
    dash.messages += 1; frames += 1;
    if (snap.map && snap.map.version !== (mapMeta && mapMeta.version) && snap.map.version !== loadingVersion) {
      loadMap(snap.map);
    }
    dash.goal = snap.goal;
    updatePanel();
    schedule();
  };
}

async function loadMap(meta) {
  loadingVersion = meta.version;
  const resp = await fetch(`/api/map.png?v=${meta.version}`, {cache: "no-store"});
  if (!resp.ok) { loadingVersion = 0; return; }
  const img = await createImageBitmap(await resp.blob());
  if (mapMeta && mapMeta.version > meta.version) return;
  mapImg = img; mapMeta = meta; dash.mapMeta = meta; dash.mapVersion = meta.version;
  schedule();
}

function schedule() {
  if (!drawPending) { drawPending = true; requestAnimationFrame(draw); }
}

function fitView() {
  if (!mapMeta) return null;
  const r = mapMeta.resolution, w = mapMeta.width * r, h = mapMeta.height * r;
  const s = Math.min(canvas.width / w, canvas.height / h);
  return {s, x0: mapMeta.origin_x, y1: mapMeta.origin_y + h,
          ox: (canvas.width - w * s) / 2, oy: (canvas.height - h * s) / 2};
}

function polyline(pts, color, width) {
  if (!pts || pts.length < 2) return;
  ctx.strokeStyle = color; ctx.lineWidth = width; ctx.beginPath();
  pts.forEach(([x, y], i) => { const [cx, cy] = dash.worldToCanvas(x, y); i ? ctx.lineTo(cx, cy) : ctx.moveTo(cx, cy); });
  ctx.stroke();
}

function arrow(x, y, yaw, len, color) {
  const [cx, cy] = dash.worldToCanvas(x, y);
  const ex = cx + Math.cos(yaw) * len, ey = cy - Math.sin(yaw) * len;
  ctx.strokeStyle = color; ctx.fillStyle = color; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.arc(cx, cy, 5, 0, 2 * Math.PI); ctx.fill();
  ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(ex, ey); ctx.stroke();
}

function drawRobot(p) {
  const fp = (snap.footprint && snap.footprint.length >= 3) ? snap.footprint
    : [[0.3, 0.25], [-0.3, 0.25], [-0.3, -0.25], [0.3, -0.25]];
  const c = Math.cos(p.yaw), s = Math.sin(p.yaw);
  ctx.strokeStyle = "#d22"; ctx.fillStyle = "rgba(221,34,34,0.25)"; ctx.lineWidth = 2; ctx.beginPath();
  fp.forEach(([bx, by], i) => {
    const [cx, cy] = dash.worldToCanvas(p.x + c * bx - s * by, p.y + s * bx + c * by);
    i ? ctx.lineTo(cx, cy) : ctx.moveTo(cx, cy);
  });
  ctx.closePath(); ctx.fill(); ctx.stroke();
  arrow(p.x, p.y, p.yaw, Math.max(12, 0.4 * view.s), "#d22");
}

function draw() {
  drawPending = false;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = "#cdcdcd"; ctx.fillRect(0, 0, canvas.width, canvas.height);
  view = fitView();
  if (!view || !snap) return;
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(mapImg, view.ox, view.oy, mapMeta.width * mapMeta.resolution * view.s,
                mapMeta.height * mapMeta.resolution * view.s);
  polyline(snap.plan, "#1a9c3a", 3);
  ctx.fillStyle = "#e08a00";
  for (const [x, y] of snap.scan || []) {
    const [cx, cy] = dash.worldToCanvas(x, y); ctx.fillRect(cx - 1.5, cy - 1.5, 3, 3);
  }
  if (snap.goal) arrow(snap.goal.x, snap.goal.y, snap.goal.yaw, 24, "#7b2cbf");
  if (drag) arrow(drag.x, drag.y, drag.yaw, 24, "rgba(123,44,191,0.6)");
  if (snap.pose) {
    drawRobot(snap.pose);
    dash.drawnPose = snap.pose;
    dash.drawLog.push({x: snap.pose.x, y: snap.pose.y, yaw: snap.pose.yaw, t: performance.timeOrigin + performance.now()});
    if (dash.drawLog.length > 5000) dash.drawLog.splice(0, 1000);
  }
}

function updatePanel() {
  const nav = snap.nav;
  $("navstatus").textContent = nav ? `${nav.state}${nav.detail ? ": " + nav.detail : ""}` : "no goal";
  const p = snap.pose;
  $("pose").textContent = p ? `pose: x ${p.x.toFixed(2)} m, y ${p.y.toFixed(2)} m, yaw ${p.yaw.toFixed(2)} rad` : "pose: unknown";
  const body = document.querySelector("#providers tbody");
  const rows = (snap.providers || []).map((pr) => {
    const buttons = pr.lifecycle ? ["activate", "deactivate"].map((cmd) =>
      `<button type="button" id="btn-${cmd}-${pr.id}" data-provider="${pr.id}" data-command="${cmd}">${cmd}</button>`).join("") : "";
    return `<tr><td>${pr.id}</td><td id="state-${pr.id}" class="state-${pr.state}">${pr.state}</td><td>${buttons}</td></tr>`;
  }).join("");
  if (body.dataset.html !== rows) { body.innerHTML = rows; body.dataset.html = rows; }
  const now = performance.now();
  if (now - frameT0 > 1000) { $("rate").textContent = `${(frames * 1000 / (now - frameT0)).toFixed(1)} updates/s`; frames = 0; frameT0 = now; }
}

async function post(path, body) {
  $("error").textContent = "";
  try {
    const resp = await fetch(path, {method: "POST", headers: {"Content-Type": "application/json"}, body: JSON.stringify(body)});
    const data = await resp.json();
    if (!resp.ok) { $("error").textContent = data.error || `HTTP ${resp.status}`; return null; }
    return data;
  } catch (e) {
    $("error").textContent = String(e); return null;
  }
}

function eventPoint(ev) {
  const r = canvas.getBoundingClientRect();
  return [(ev.clientX - r.left) * canvas.width / r.width, (ev.clientY - r.top) * canvas.height / r.height];
}

canvas.addEventListener("mousedown", (ev) => {
  if (!view) return;
  const [cx, cy] = eventPoint(ev);
  const [x, y] = dash.canvasToWorld(cx, cy);
  drag = {x, y, cx, cy, yaw: 0};
});
canvas.addEventListener("mousemove", (ev) => {
  if (!drag) return;
  const [cx, cy] = eventPoint(ev);
  if (Math.hypot(cx - drag.cx, cy - drag.cy) > 6) drag.yaw = Math.atan2(-(cy - drag.cy), cx - drag.cx);
  schedule();
});
window.addEventListener("mouseup", async () => {
  if (!drag) return;
  const g = drag; drag = null;
  const r = await post("/api/goal", {x: g.x, y: g.y, yaw: g.yaw});
  if (r && !r.accepted) $("error").textContent = `goal rejected: ${r.detail}`;
});
$("cancel").addEventListener("click", () => post("/api/cancel", {}));
document.querySelector("#providers").addEventListener("click", async (ev) => {
  const b = ev.target.closest("button[data-command]");
  if (!b) return;
  const r = await post("/api/lifecycle", {provider: b.dataset.provider, command: b.dataset.command});
  if (r && !r.ok) $("error").textContent = `${b.dataset.provider} ${b.dataset.command}: ${r.error}`;
});

connect();
