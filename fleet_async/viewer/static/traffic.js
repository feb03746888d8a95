// Traffic on the canvas (docs/traffic.md, "In the viewer"): the grid maps loaded (their
// obstacle rectangles, drawn in place of their tile bodies' bounding boxes), the route graph in
// use (nodes and directed edges, thin, under the robots) and a selected robot's protective and
// warning fields while it is in a safety stop.
//
// Read from the trace's JSON events (docs/trace-format.md): map_loaded (rects, bodies),
// route_graph (nodes [id, x, y], edges [id, start, end]; the last one at or before the clock's
// step is in use) and safety_stop_started (protective, warning: field corners [x, y]).
"use strict";

const MAP_FILL = "rgb(89, 89, 102)";
const GRAPH_EDGE = "rgba(30, 90, 160, 0.55)", GRAPH_NODE = "rgba(30, 90, 160, 0.8)";
const FIELD_WARNING = ["rgba(245, 166, 35, 0.18)", "rgba(230, 140, 0, 0.9)"];
const FIELD_PROTECTIVE = ["rgba(229, 57, 53, 0.25)", "rgba(200, 30, 30, 0.95)"];

class TrafficLayer {
  constructor(data) {
    this.data = data;
    this.scanned = 0;          // data.events read so far (the list only grows)
    this.maps = [];            // map_loaded events
    this.graphs = [];          // route_graph events, in step order
    this.mapBodies = new Set();  // tile bodies drawn as their maps' rectangles instead
    this.drawn = { rects: 0, nodes: 0, edges: 0, fields: null };
  }

  scan() {
    const events = this.data.events;
    for (; this.scanned < events.length; this.scanned++) {
      const e = events[this.scanned], x = e.data || {};
      if (e.kind === "map_loaded" && Array.isArray(x.rects)) {
        this.maps.push(e);
        for (const id of x.bodies || []) this.mapBodies.add(id);
      } else if (e.kind === "route_graph" && Array.isArray(x.nodes)) {
        this.graphs.push(e);
        if (this.graphs.length > 1 && this.graphs[this.graphs.length - 2].step > e.step) this.graphs.sort((a, b) => a.step - b.step);
      }
    }
  }

  // Whether a static body is a map tile (drawn by its rectangles, not its bounding box).
  isMapBody(id) { this.scan(); return this.mapBodies.has(id); }

  graphAt(step) {
    let graph = null;
    for (const g of this.graphs) if (g.step <= step) graph = g; else break;
    return graph && graph.data.nodes.length ? graph.data : null;
  }

  // Maps and the route graph at frame `step`, on the canvas under the bodies.
  drawScenery(ctx, project, view, step) {
    this.scan();
    const drawn = { rects: 0, nodes: 0, edges: 0, fields: this.drawn.fields };
    ctx.save();
    ctx.fillStyle = MAP_FILL;
    for (const m of this.maps) {
      if (step !== null && m.step > step) continue;
      for (const [x0, y0, x1, y1] of m.data.rects) {
        const a = project(x0, y1), b = project(x1, y0);
        if (b.x < 0 || a.x > view.width || b.y < 0 || a.y > view.height) continue;
        ctx.fillRect(a.x, a.y, Math.max(b.x - a.x, 0.5), Math.max(b.y - a.y, 0.5));
        drawn.rects++;
      }
    }
    const graph = step === null ? null : this.graphAt(step);
    if (graph) {
      const at = new Map(graph.nodes.map(([id, x, y]) => [id, project(x, y)]));
      ctx.strokeStyle = GRAPH_EDGE; ctx.fillStyle = GRAPH_EDGE; ctx.lineWidth = 1.5;
      const head = Math.min(7, Math.max(3, 0.15 * view.scale));
      for (const [, from, to] of graph.edges) {
        const a = at.get(from), b = at.get(to);
        if (!a || !b) continue;
        ctx.beginPath(); ctx.moveTo(a.x, a.y); ctx.lineTo(b.x, b.y); ctx.stroke();
        // The arrowhead at 65 % of the way: an edge and its reverse show both, side by side.
        const len = Math.hypot(b.x - a.x, b.y - a.y);
        if (len > 3 * head) {
          const ux = (b.x - a.x) / len, uy = (b.y - a.y) / len;
          const tx = a.x + 0.65 * (b.x - a.x), ty = a.y + 0.65 * (b.y - a.y);
          ctx.beginPath();
          ctx.moveTo(tx + ux * head, ty + uy * head);
          ctx.lineTo(tx - uy * head * 0.6, ty + ux * head * 0.6);
          ctx.lineTo(tx + uy * head * 0.6, ty - ux * head * 0.6);
          ctx.closePath(); ctx.fill();
        }
        drawn.edges++;
      }
      ctx.fillStyle = GRAPH_NODE;
      const r = Math.min(4, Math.max(2, 0.08 * view.scale));
      for (const p of at.values()) { ctx.beginPath(); ctx.arc(p.x, p.y, r, 0, 2 * Math.PI); ctx.fill(); drawn.nodes++; }
    }
    ctx.restore();
    this.drawn = drawn;
  }

  // The safety stop `timeline` has for robot `id` at frame `step` (a span with protective
  // and warning corners), or null.
  stopAt(timeline, id, step) {
    for (const s of timeline.of(id).spans) if (s.kind === "safety" && s.s0 <= step && step < s.s1) return s;
    return null;
  }

  // The selected robot's fields while it is stopped (on the overlay); returns what it drew.
  drawFields(ctx, project, stop) {
    this.drawn.fields = null;
    if (!stop) return null;
    const fields = {};
    ctx.save();
    ctx.lineWidth = 1.5;
    for (const [name, [fill, line]] of [["warning", FIELD_WARNING], ["protective", FIELD_PROTECTIVE]]) {
      const corners = Array.isArray(stop[name]) ? stop[name] : [];
      if (corners.length < 3) continue;
      const points = corners.map(([x, y]) => { const p = project(x, y); return { x, y, px: p.x, py: p.y }; });
      ctx.beginPath();
      points.forEach((p, k) => (k ? ctx.lineTo(p.px, p.py) : ctx.moveTo(p.px, p.py)));
      ctx.closePath();
      ctx.fillStyle = fill; ctx.fill();
      ctx.strokeStyle = line; ctx.stroke();
      fields[name] = points;
    }
    ctx.restore();
    this.drawn.fields = Object.keys(fields).length ? fields : null;
    return this.drawn.fields;
  }
}

if (typeof module !== "undefined") module.exports = { TrafficLayer };
