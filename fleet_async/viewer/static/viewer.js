// The replay viewer: loads the trace as it streams in, plays it on a sim-time clock, draws it
// top-down, and shows a selected robot's timeline (timeline.js, panel.js), goal and path. A selected served vehicle (one
// fleet masters send orders to) also shows its order, its task states and the commands it
// received, and its route still to go is drawn on the canvas.
//
// Test and benchmark hooks: window.viewer (seek, play, pause, setSpeed, select, project,
// bodyAt, route, overlayPixelAt, state, stats), and #app's data-state / data-sim-time /
// data-frame / data-selected / data-route-nodes.
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  const app = $("app");
  const params = new URLSearchParams(location.search);
  const traceUrl = params.get("trace") || "trace";
  const traceName = app.dataset.name || traceUrl;

  const data = new TraceData(traceName);
  const decoder = new TraceDecoder(data);
  const timeline = new Timeline(data);
  const traffic = new TrafficLayer(data);  // maps, route graph, safety fields (traffic.js)
  const stage = $("stage"), grid = $("grid"), gl = $("gl"), overlay = $("overlay");
  // WebGL2 only on request or on a hardware GPU: software WebGL is far slower than the
  // Canvas2D pixel renderer at fleet sizes (see render.js).
  let renderer = null;
  const wanted = params.get("renderer") || "auto";
  if (wanted === "webgl2" || (wanted === "auto" && hardwareWebGL())) {
    try { renderer = GLRenderer.create(gl); } catch (e) { console.warn("WebGL2 renderer failed", e); renderer = null; }
  }
  if (!renderer) renderer = new PixelRenderer(gl);
  app.dataset.renderer = renderer.kind;

  function hardwareWebGL() {
    const probe = document.createElement("canvas").getContext("webgl2");
    if (!probe) return false;
    const info = probe.getExtension("WEBGL_debug_renderer_info");
    const name = info ? String(probe.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
    const lose = probe.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return name !== "" && !/swiftshader|llvmpipe|software|softpipe/i.test(name);
  }

  const view = { cx: 0, cy: 0, scale: 20, width: 800, height: 600, dpr: 1, userMoved: false };
  const clock = { t: 0, playing: false, speed: 1, last: null, follow: false, loop: params.get("loop") === "1" };
  const ui = { selected: null, colorMode: "state", zrange: [-Infinity, Infinity], zAuto: true, error: null, done: false, labels: false };
  const vehiclePanel = new VehiclePanel(data, $, app, (t) => { setPlaying(false); seek(t); });
  const timelinePanel = new TimelinePanel(timeline, { filters: $("sel-filters"), list: $("sel-events"), count: $("sel-count"), doing: $("sel-doing") }, (t) => { setPlaying(false); seek(t); });
  const stats = { frames: 0, times: [], drawMs: [] };
  const debug = { skipGL: false, skipGrid: false, skipOverlay: false };
  let statics = null, staticsCount = -1, dirty = true, layoutBodyCache = new Map(), legendBodies = -1;
  let activityCache = { version: -1, frames: new Map() };

  // Per frame, [layout index, ACTIVITY code] of the robots doing something their flags do
  // not say (palette.js robotState); only robots with events are looked at.
  function activity(frame) {
    if (activityCache.version !== data.version_) activityCache = { version: data.version_, frames: new Map() };
    let list = activityCache.frames.get(frame);
    if (list) return list.length ? list : null;
    list = [];
    const bodies = layoutBodies(frame.layout);
    for (let i = 0; i < frame.layout.n; i++) {
      const b = bodies[i];
      if (!isRobot(b) || !b.events.length) continue;
      const code = timeline.activityAt(b.id, frame.step).code;
      if (code) list.push([i, code]);
    }
    if (activityCache.frames.size > 256) activityCache.frames.clear();
    activityCache.frames.set(frame, list);
    return list.length ? list : null;
  }

  // ----- loading ----------------------------------------------------------------------------

  async function load() {
    app.dataset.state = "loading";
    let response;
    try {
      response = await fetch(traceUrl);
    } catch (e) { return fail(`${traceName}: could not fetch the trace (${e})`); }
    if (!response.ok) return fail(`${traceName}: the server answered ${response.status} ${await response.text()}`);
    const total = Number(response.headers.get("Content-Length")) || 0;
    clock.follow = response.headers.get("X-Trace-Live") === "1";
    const reader = response.body.getReader();
    for (;;) {
      let chunk;
      try { chunk = await reader.read(); } catch (e) { return fail(`${traceName}: the stream broke (${e})`); }
      if (chunk.done) break;
      try {
        if (decoder.push(chunk.value)) onData();
      } catch (e) { return fail(e.message); }
      $("status").textContent = total ? `loading ${Math.round((100 * data.bytes) / total)}%` : `loading ${(data.bytes / 1e6).toFixed(1)} MB`;
    }
    try { decoder.finish(); } catch (e) { return fail(e.message); }
    ui.done = true;
    onData();
    app.dataset.state = "ready";
    $("status").textContent = `${data.frames.length} frames, ${countAgents()} robots, ${(data.bytes / 1e6).toFixed(1)} MB`;
  }

  function fail(message) {
    ui.error = message;
    app.dataset.state = "error";
    $("error").textContent = message;
    $("error").hidden = false;
    $("status").textContent = "error";
    dirty = true;
  }

  function countAgents() {
    let n = 0;
    for (const b of data.bodies.values()) if (isRobot(b)) n++;
    return n;
  }

  function onData() {
    if (!data.frames.length) return;
    const first = !$("scrub").dataset.ready;
    $("scrub").dataset.ready = "1";
    $("scrub").min = String(data.startTime);
    $("scrub").max = String(data.duration);
    $("scrub").step = String(data.timestep * (data.meta ? data.meta.every_n_steps : 1));
    if (first) clock.t = data.startTime;
    if (clock.follow && !clock.playing && ui.done === false) clock.t = data.duration;
    if (ui.zAuto && data.zBounds) {
      $("zmin").placeholder = data.zBounds[0].toFixed(2);
      $("zmax").placeholder = data.zBounds[1].toFixed(2);
    }
    if (!view.userMoved) fit();
    if (data.bodies.size !== legendBodies) { legendBodies = data.bodies.size; renderLegend($("legend"), data, ui.colorMode); }
    app.dataset.frames = String(data.frames.length);
    app.dataset.duration = String(data.duration);
    if (app.dataset.state === "loading" && data.frames.length) app.dataset.state = ui.done ? "ready" : "streaming";
    updateSelection();
    dirty = true;
  }

  function layoutBodies(layout) {
    let list = layoutBodyCache.get(layout);
    if (!list || list.length !== layout.n || list.some((b) => b === undefined)) {
      list = Array.from(layout.ids, (id) => data.bodies.get(id));
      layoutBodyCache.set(layout, list);
    }
    return list;
  }

  function staticScene() {
    const list = [];
    for (const b of data.bodies.values()) if (b.kind === "static" && b.pose && !traffic.isMapBody(b.id)) list.push(b);
    if (list.length + 1e6 * traffic.mapBodies.size === staticsCount) return statics;
    staticsCount = list.length + 1e6 * traffic.mapBodies.size;
    const n = list.length;
    const pos = new Float32Array(3 * n), yaw = new Int16Array(n), flags = new Uint8Array(n);
    list.forEach((b, i) => {
      pos.set(b.pose.slice(0, 3), 3 * i);
      yaw[i] = Math.round((b.pose[3] / Math.PI) * 32767);
    });
    statics = { n, bodies: list, frame: { pos, yaw, flags, layout: null, colliding: null } };
    if (renderer.layers) renderer.layers.delete("static");
    return statics;
  }

  // ----- camera -----------------------------------------------------------------------------

  // The largest footprint radius of the moving bodies: the bounds hold their centres only, so
  // fit() pads by it to show the robots at the edge of the run whole.
  let padCache = { bodies: -1, pad: 0 };
  function movingPad() {
    if (padCache.bodies === data.bodies.size) return padCache.pad;
    let pad = 0;
    for (const body of data.bodies.values()) {
      const s = body.shapeInfo;
      if (body.kind !== "static" && s) pad = Math.max(pad, s.radius || Math.hypot(s.half[0], s.half[1]));
    }
    padCache = { bodies: data.bodies.size, pad };
    return pad;
  }

  function fit() {
    const bounds = data.bounds;
    if (!bounds) return;
    const m = movingPad();
    const b = [bounds[0] - m, bounds[1] - m, bounds[2] + m, bounds[3] + m];
    const w = Math.max(b[2] - b[0], 1), h = Math.max(b[3] - b[1], 1);
    view.cx = (b[0] + b[2]) / 2;
    view.cy = (b[1] + b[3]) / 2;
    view.scale = Math.min(view.width / (w * 1.08), view.height / (h * 1.08));
    dirty = true;
  }

  function project(x, y) {
    return { x: view.width / 2 + (x - view.cx) * view.scale, y: view.height / 2 - (y - view.cy) * view.scale };
  }

  function unproject(px, py) {
    return { x: view.cx + (px - view.width / 2) / view.scale, y: view.cy - (py - view.height / 2) / view.scale };
  }

  function resize() {
    const r = stage.getBoundingClientRect();
    view.width = Math.max(1, r.width);
    view.height = Math.max(1, r.height);
    view.dpr = window.devicePixelRatio || 1;
    renderer.resize(view.width, view.height, view.dpr);
    for (const c of [grid, overlay]) {
      c.width = Math.round(view.width * view.dpr);
      c.height = Math.round(view.height * view.dpr);
    }
    if (!view.userMoved) fit();
    dirty = true;
  }

  // ----- the clock --------------------------------------------------------------------------

  function frameIndex() { return data.frameAt(clock.t); }

  function seek(t) {
    if (!data.frames.length) return;
    clock.t = Math.min(Math.max(t, data.startTime), data.duration);
    dirty = true;
    render();
    return clock.t;
  }

  function setPlaying(on) {
    clock.playing = on && data.frames.length > 0;
    if (clock.playing && clock.t >= data.duration - 1e-9 && !clock.follow) clock.t = data.startTime;
    clock.last = null;
    $("play").textContent = clock.playing ? "❚❚" : "▶";
    $("play").title = clock.playing ? "pause (space)" : "play (space)";
    app.dataset.playing = clock.playing ? "1" : "0";
  }

  function tick(now) {
    if (clock.playing) {
      if (clock.last !== null) {
        clock.t += ((now - clock.last) / 1000) * clock.speed;
        if (clock.t >= data.duration) {
          clock.t = clock.loop && ui.done ? data.startTime : data.duration;
          if (ui.done && !clock.follow && !clock.loop) setPlaying(false);
        }
      }
      clock.last = now;
      dirty = true;
    }
    if (dirty) render();
    stats.times.push(now);
    if (stats.times.length > 600) stats.times.shift();
    requestAnimationFrame(tick);
  }

  // ----- drawing ----------------------------------------------------------------------------

  function render() {
    dirty = false;
    const t0 = performance.now();
    const i = frameIndex();
    const f0 = i >= 0 ? data.frames[i] : null;
    const f1 = i >= 0 && i + 1 < data.frames.length ? data.frames[i + 1] : null;
    const alpha = f0 && f1 ? Math.min(Math.max((clock.t - f0.t) / (f1.t - f0.t || 1), 0), 1) : 0;
    if (!debug.skipGrid) { drawGrid(); traffic.drawScenery(grid.getContext("2d"), project, view, f0 ? f0.step : null); }
    if (!debug.skipGL) renderer.draw(view, {
      statics: staticScene(), frame0: f0, frame1: f1, alpha, zrange: zrange(), colorMode: ui.colorMode, layoutBodies, activity,
    });
    if (!debug.skipOverlay) drawOverlay(f0, f1, alpha);
    const simTime = f0 ? clock.t : 0;
    app.dataset.simTime = simTime.toFixed(6);
    app.dataset.frame = String(i);
    app.dataset.step = f0 ? String(f0.step) : "";
    $("time").textContent = `${simTime.toFixed(2)} s / ${data.duration.toFixed(2)} s` + (f0 ? `  (step ${f0.step})` : "");
    if (document.activeElement !== $("scrub")) $("scrub").value = String(simTime);
    stats.frames++;
    stats.drawMs.push(performance.now() - t0);
    if (stats.drawMs.length > 600) stats.drawMs.shift();
    if (ui.selected !== null) { updatePose(f0); vehiclePanel.update(data.bodies.get(ui.selected), clock.t, false); }
  }

  function zrange() {
    const lo = parseFloat($("zmin").value), hi = parseFloat($("zmax").value);
    return [Number.isFinite(lo) ? lo : -1e9, Number.isFinite(hi) ? hi : 1e9];
  }

  function drawGrid() {
    const ctx = grid.getContext("2d"), dpr = view.dpr;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, view.width, view.height);
    // Grid spacing: a power of ten metres that puts lines 40+ px apart.
    let step = Math.pow(10, Math.ceil(Math.log10(40 / view.scale)));
    if (step * view.scale > 200) step /= 5;
    const a = unproject(0, view.height), b = unproject(view.width, 0);
    ctx.lineWidth = 1;
    for (const [s, colour] of [[step, "#e4e7ea"], [step * 10, "#c9ced3"]]) {
      ctx.strokeStyle = colour;
      ctx.beginPath();
      for (let x = Math.floor(a.x / s) * s; x <= b.x; x += s) { const p = project(x, 0).x; ctx.moveTo(p, 0); ctx.lineTo(p, view.height); }
      for (let y = Math.floor(a.y / s) * s; y <= b.y; y += s) { const p = project(0, y).y; ctx.moveTo(0, p); ctx.lineTo(view.width, p); }
      ctx.stroke();
    }
    const o = project(0, 0);
    ctx.strokeStyle = "#e53935"; ctx.beginPath(); ctx.moveTo(o.x, o.y); ctx.lineTo(o.x + 30, o.y); ctx.stroke();
    ctx.strokeStyle = "#43a047"; ctx.beginPath(); ctx.moveTo(o.x, o.y); ctx.lineTo(o.x, o.y - 30); ctx.stroke();
    $("scale").textContent = `grid ${step >= 1 ? step : step.toFixed(2)} m`;
  }

  function bodyPose(f0, f1, alpha, id) {
    if (!f0) return null;
    const i = f0.layout.index.get(id);
    if (i === undefined) {
      const b = data.bodies.get(id);
      return b && b.pose ? { x: b.pose[0], y: b.pose[1], z: b.pose[2], yaw: b.pose[3] } : null;
    }
    let x = f0.pos[3 * i], y = f0.pos[3 * i + 1], z = f0.pos[3 * i + 2];
    let yaw = (f0.yaw[i] * Math.PI) / 32767;
    if (f1 && f1.layout === f0.layout && alpha > 0) {
      x += (f1.pos[3 * i] - x) * alpha; y += (f1.pos[3 * i + 1] - y) * alpha; z += (f1.pos[3 * i + 2] - z) * alpha;
    }
    return { x, y, z, yaw, flags: f0.flags[i] };
  }

  // Robots on (nearly) the same spot hide each other from above: groups of them, per frame,
  // as [x, y, count]. A robot joins a group whose first robot is nearer than half the smaller
  // footprint half-size of the two (found through a grid of that size); the z filter applies.
  let stacks = { frame: null, z: "", groups: [] };

  function stackRadius(b) {
    const s = b.shapeInfo;
    return 0.5 * (s ? (s.radius || Math.min(s.half[0], s.half[1])) : 0.05);
  }

  function stackedRobots(f0) {
    const [z0, z1] = zrange();
    const zkey = `${z0},${z1}`;
    if (stacks.frame === f0 && stacks.z === zkey) return stacks.groups;
    const bodies = layoutBodies(f0.layout), n = f0.layout.n;
    let cell = 0;
    for (let i = 0; i < n; i++) if (isRobot(bodies[i])) cell = Math.max(cell, stackRadius(bodies[i]));
    const cells = new Map(), all = [];
    for (let i = 0; cell > 0 && i < n; i++) {
      const b = bodies[i];
      if (!isRobot(b)) continue;
      const x = f0.pos[3 * i], y = f0.pos[3 * i + 1], z = f0.pos[3 * i + 2];
      if (z < z0 || z > z1) continue;
      const r = stackRadius(b), kx = Math.floor(x / cell), ky = Math.floor(y / cell);
      let group = null;
      for (let dx = -1; dx <= 1 && !group; dx++) {
        for (let dy = -1; dy <= 1 && !group; dy++) {
          for (const g of cells.get((kx + dx) * 4194304 + (ky + dy)) || []) {
            if (Math.hypot(g[0] - x, g[1] - y) < Math.min(g[3], r)) { group = g; break; }
          }
        }
      }
      if (group) { group[2]++; continue; }
      const g = [x, y, 1, r], key = kx * 4194304 + ky;
      if (cells.has(key)) cells.get(key).push(g); else cells.set(key, [g]);
      all.push(g);
    }
    const groups = all.filter((g) => g[2] > 1);
    stacks = { frame: f0, z: zkey, groups };
    return groups;
  }

  function drawOverlay(f0, f1, alpha) {
    const ctx = overlay.getContext("2d"), dpr = view.dpr;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, view.width, view.height);
    traffic.drawn.fields = null;
    const groups = f0 ? stackedRobots(f0) : [];
    app.dataset.stacked = String(groups.length);
    if (groups.length) {
      ctx.font = "bold 12px sans-serif"; ctx.lineWidth = 3; ctx.strokeStyle = "#fff"; ctx.fillStyle = "#111";
      for (const [x, y, count] of groups) {
        const p = project(x, y);
        if (p.x < -20 || p.y < -20 || p.x > view.width + 20 || p.y > view.height + 20) continue;
        ctx.strokeText(`\u00d7${count}`, p.x + 6, p.y - 6);
        ctx.fillText(`\u00d7${count}`, p.x + 6, p.y - 6);
      }
    }
    if (ui.labels && f0) drawNames(ctx, f0, f1, alpha);
    drawnRoute = null;
    drawnGoal = null;
    if (ui.selected === null) { app.dataset.routeNodes = ""; return; }
    const pose = bodyPose(f0, f1, alpha, ui.selected);
    if (!pose) { app.dataset.routeNodes = ""; return; }
    drawnRoute = drawRoute(ctx, project, app, pose, data.vehicleStateAt(ui.selected, clock.t));
    if (f0) {
      const span = timeline.activityAt(ui.selected, f0.step).span;
      const target = span && span.object !== undefined ? bodyPose(f0, f1, alpha, span.object) : null;
      drawnGoal = drawGoal(ctx, project, pose, span, target);
      traffic.drawFields(ctx, project, traffic.stopAt(timeline, ui.selected, f0.step));
    }
    const b = data.bodies.get(ui.selected);
    const s = b && b.shapeInfo;
    const r = Math.max(8, (s ? (s.radius || Math.hypot(s.half[0], s.half[1])) : 0.1) * view.scale + 4);
    const p = project(pose.x, pose.y);
    ctx.strokeStyle = "#111"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.arc(p.x, p.y, r, 0, 2 * Math.PI); ctx.stroke();
    ctx.font = "12px sans-serif"; ctx.fillStyle = "#111";
    ctx.fillText(displayName(data, ui.selected), p.x + r + 3, p.y - r);
  }

  let drawnGoal = null;   // the goal and path drawn last, for tests (viewer.goal())
  let drawnRoute = null;  // a served vehicle's route drawn last (viewer.route())

  function drawNames(ctx, f0, f1, alpha) {
    const bodies = layoutBodies(f0.layout), items = [];
    const [z0, z1] = zrange();
    for (let i = 0; i < f0.layout.n; i++) {
      const b = bodies[i];
      if (!b || b.kind !== "agent" || b.id === ui.selected) continue;  // the selection has its own
      const q = bodyPose(f0, f1, alpha, b.id);
      if (q && q.z >= z0 && q.z <= z1) items.push([project(q.x, q.y), displayName(data, b.id)]);
    }
    app.dataset.labels = String(drawLabels(ctx, items, view.width, view.height, 400));
  }

  // ----- picking and the side panel -----------------------------------------------------------

  // The body under CSS pixel (px, py): the nearest robot there, else the nearest other body.
  function bodyAt(px, py) {
    const i = frameIndex();
    const f0 = i >= 0 ? data.frames[i] : null;
    const w = unproject(px, py);
    const [z0, z1] = zrange();
    const best = { agent: null, agentD: Infinity, other: null, otherD: Infinity };
    const consider = (id, x, y, z, body) => {
      if (z < z0 || z > z1) return;
      const shape = body ? body.shapeInfo : null;
      const reach = Math.max(shape ? (shape.radius || Math.hypot(shape.half[0], shape.half[1])) : 0.1, 6 / view.scale);
      const d = Math.hypot(x - w.x, y - w.y);
      if (d > reach) return;
      if (isRobot(body)) { if (d < best.agentD) { best.agent = id; best.agentD = d; } }
      else if (d < best.otherD) { best.other = id; best.otherD = d; }
    };
    if (f0) {
      const bodies = layoutBodies(f0.layout);
      for (let k = 0; k < f0.layout.n; k++) consider(f0.layout.ids[k], f0.pos[3 * k], f0.pos[3 * k + 1], f0.pos[3 * k + 2], bodies[k]);
    }
    if (statics) for (const b of statics.bodies) consider(b.id, b.pose[0], b.pose[1], b.pose[2], b);
    return best.agent !== null ? best.agent : best.other;
  }

  function select(id) {
    ui.selected = id === null || id === undefined ? null : Number(id);
    app.dataset.selected = ui.selected === null ? "" : String(ui.selected);
    updateSelection();
    dirty = true;
    render();
    return ui.selected;
  }

  function updateSelection() {
    const panel = $("details");
    const wasHidden = panel.hidden;
    panel.hidden = ui.selected === null;
    // The panel takes width from the stage: size the canvases to it again (else they are
    // drawn squeezed, and circles become ellipses).
    if (panel.hidden !== wasHidden) resize();
    if (ui.selected === null) { vehiclePanel.update(null, clock.t, true); return; }
    const b = data.bodies.get(ui.selected);
    $("sel-name").textContent = `${displayName(data, ui.selected)}  #${ui.selected}`;
    $("sel-kind").textContent = b ? `${b.kind}${objectKind(b) ? " · " + objectKind(b) : ""} · ${b.class}` : "";
    timelinePanel.show(ui.selected, data.version_);
    vehiclePanel.update(b || null, clock.t, true);
  }

  function updatePose(f0) {
    const i = frameIndex();
    const p = bodyPose(f0, null, 0, ui.selected);
    if (!p) { $("sel-pose").textContent = "not in the scene at this time"; return; }
    const fl = p.flags || 0;
    const colliding = f0 && f0.colliding.includes(ui.selected);
    const b = data.bodies.get(ui.selected);
    const state = isRobot(b) ? robotState(fl, timeline.activityAt(ui.selected, f0.step).code) : objectKind(b) || b.kind;
    if (isRobot(b)) timelinePanel.doing(ui.selected, f0.step, state); else $("sel-doing").textContent = "";
    $("sel-pose").textContent = `x ${p.x.toFixed(2)}  y ${p.y.toFixed(2)}  z ${p.z.toFixed(2)} m  yaw ${((p.yaw * 180) / Math.PI).toFixed(1)}°  ${state}${colliding ? ", colliding" : ""}`;
    app.dataset.selectedState = state;
    void i;
  }

  // ----- input ----------------------------------------------------------------------------

  let drag = null;
  overlay.addEventListener("pointerdown", (e) => { drag = { x: e.offsetX, y: e.offsetY, cx: view.cx, cy: view.cy, moved: false }; overlay.setPointerCapture(e.pointerId); });
  overlay.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
    if (drag.moved) { view.cx = drag.cx - dx / view.scale; view.cy = drag.cy + dy / view.scale; view.userMoved = true; dirty = true; }
  });
  overlay.addEventListener("pointerup", (e) => {
    if (drag && !drag.moved) select(bodyAt(e.offsetX, e.offsetY));
    drag = null;
  });
  overlay.addEventListener("wheel", (e) => {
    e.preventDefault();
    const before = unproject(e.offsetX, e.offsetY);
    view.scale *= Math.exp(-e.deltaY * 0.0015);
    const after = unproject(e.offsetX, e.offsetY);
    view.cx += before.x - after.x; view.cy += before.y - after.y;
    view.userMoved = true; dirty = true;
  }, { passive: false });

  $("play").onclick = () => setPlaying(!clock.playing);
  $("speed").onchange = () => { clock.speed = parseFloat($("speed").value); };
  $("scrub").oninput = () => { seek(parseFloat($("scrub").value)); };
  $("fit").onclick = () => { view.userMoved = false; fit(); };
  $("colour").onchange = () => { setColorMode($("colour").value); };
  $("labels").onchange = () => { ui.labels = $("labels").checked; dirty = true; };
  function setColorMode(m) { ui.colorMode = m; $("colour").value = m; renderLegend($("legend"), data, m); dirty = true; render(); }
  for (const id of ["zmin", "zmax"]) $(id).oninput = () => { dirty = true; };
  $("close-details").onclick = () => select(null);
  document.addEventListener("keydown", (e) => {
    if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
    if (e.code === "Space") { e.preventDefault(); setPlaying(!clock.playing); }
    const frameDt = data.timestep * (data.meta ? data.meta.every_n_steps : 1);
    if (e.code === "ArrowRight") seek(clock.t + frameDt);
    if (e.code === "ArrowLeft") seek(clock.t - frameDt);
    if (e.code === "KeyF") { view.userMoved = false; fit(); }
  });
  window.addEventListener("resize", resize);

  // ----- the page API (tests, benchmarks, scripting from the console) ---------------------

  window.viewer = {
    data,
    debug,
    seek,
    play: () => setPlaying(true),
    pause: () => setPlaying(false),
    setLoop: (on) => { clock.loop = !!on; return clock.loop; },
    setSpeed: (s) => { clock.speed = s; $("speed").value = String(s); return s; },
    select,
    bodyAt,
    fit: () => { view.userMoved = false; fit(); render(); },
    project: (x, y) => { const p = project(x, y); const r = stage.getBoundingClientRect(); return { x: p.x, y: p.y, pageX: r.left + p.x, pageY: r.top + p.y }; },
    // Colour of the bodies layer at CSS pixel (x, y) of the stage: [r, g, b, a], 0..255.
    pixelAt: (x, y) => renderer.pixelAt(x * view.dpr, y * view.dpr),
    stateColours: () => ({ ...STATE_COLOURS }),
    objectColours: () => ({ ...OBJECT_COLOURS }),
    // The route drawn for the selected served vehicle (null if none): vehicle, order_id, from
    // (the robot) and points (its nodes still to go), each with world x, y and CSS px, py.
    route: () => (drawnRoute ? JSON.parse(JSON.stringify(drawnRoute)) : null),
    vehicleStateAt: (id, t) => data.vehicleStateAt(id, t === undefined ? clock.t : t),
    // Colour of the overlay (selection, route, labels) at CSS pixel (x, y): [r, g, b, a].
    overlayPixelAt: (x, y) => Array.from(overlay.getContext("2d").getImageData(Math.round(x * view.dpr), Math.round(y * view.dpr), 1, 1).data),
    poseOf: (id) => { const i = frameIndex(); return bodyPose(i >= 0 ? data.frames[i] : null, null, 0, id); },
    setZRange: (lo, hi) => { $("zmin").value = lo === null ? "" : String(lo); $("zmax").value = hi === null ? "" : String(hi); dirty = true; render(); },
    setColorMode,
    setLabels: (on) => { ui.labels = !!on; $("labels").checked = ui.labels; dirty = true; render(); return ui.labels; },
    setFilter: (kind, on) => { timelinePanel.setShown(kind, !!on); updateSelection(); return [...timelinePanel.shown]; },
    timeline: (id) => timeline.rows(id === undefined ? ui.selected : id, new Set(Object.keys(TIMELINE_KINDS))).map((r) => ({ kind: r.kind, t: r.t, t1: r.t1, text: r.text })),
    displayName: (id) => displayName(data, id),
    legend: () => legendItems(data, ui.colorMode).map((it) => it.text),
    goal: () => (drawnGoal ? JSON.parse(JSON.stringify(drawnGoal)) : null),
    // What traffic.js drew last: map rectangles, graph nodes and edges, the selection's fields.
    traffic: () => JSON.parse(JSON.stringify(traffic.drawn)),
    state: () => ({ simTime: clock.t, frame: frameIndex(), frames: data.frames.length, playing: clock.playing, selected: ui.selected, error: ui.error, done: ui.done, bodies: data.bodies.size, renderer: renderer.kind, view: { ...view } }),
    stats: () => ({ frames: stats.frames, times: stats.times.slice(), drawMs: stats.drawMs.slice() }),
    resetStats: () => { stats.frames = 0; stats.times.length = 0; stats.drawMs.length = 0; },
  };

  resize();
  requestAnimationFrame(tick);
  load();
})();
