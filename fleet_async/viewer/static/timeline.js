// A robot's day: its trace events turned into spans (actions with their goal, object and
// task; waits and charging; carrying; collisions collapsed into contact spans; safety stops)
// and instants (errors, removals, anything else), for the side panel and the palette.
//
// Spans are in frame steps (the frame that first shows them up to the frame that shows
// them over) and in sim seconds; an action belongs to the task (an order) that the robot
// ended next: task_completed / task_failed events carry the task's text.
"use strict";

const TIMELINE_KINDS = {
  task: "tasks", action: "actions", wait: "waits & charging", carrying: "carrying",
  collision: "collisions", safety: "safety", other: "other",
};

class Timeline {
  constructor(data) {
    this.data = data;
    this.cache = new Map();        // object id -> {version, spans, instants, activity}
  }

  // Everything about robot `id`, rebuilt when the trace has grown since.
  of(id) {
    let entry = this.cache.get(id);
    if (!entry || entry.version !== this.data.version_) {
      entry = this.build(id);
      this.cache.set(id, entry);
    }
    return entry;
  }

  name(id) { return id === null || id === undefined ? "" : displayName(this.data, id); }

  build(id) {
    const d = this.data, dt = d.timestep;
    const body = d.bodies.get(id);
    const events = body ? body.events.slice().sort((a, b) => a.step - b.step || a.t - b.t) : [];
    const spans = [], instants = [], activity = [], open = new Map();
    const end = d.frames.length ? d.frames[d.frames.length - 1].step : 0;
    let safety = null;
    for (const e of events) {
      const x = e.data || {};
      if (e.kind === "action_started") {
        const s = { kind: /^Wait/.test(x.action) || x.label === "charge" ? "wait" : "action", action: x.action, t0: e.t, s0: e.step, t1: null, s1: end, goal: x.goal, path: x.path, object: x.object, label: x.label, duration: x.duration, status: "in progress" };
        if (s.kind === "wait" && (x.label === "charge" || /charg/i.test(x.action))) s.charging = true;
        open.set(x.action, s);
        spans.push(s);
      } else if (e.kind === "action_ended") {
        const s = open.get(x.action) || [...open.values()].pop();
        if (s) {
          s.t1 = e.t; s.s1 = e.step; s.status = x.status; s.reason = x.reason;
          if (x.object !== undefined) s.object = x.object;
          open.delete(s.action);
        } else instants.push({ kind: "action", t: e.t, step: e.step, text: `${x.action} ${x.status}` });
      } else if (e.kind === "task_completed" || e.kind === "task_failed") {
        instants.push({ kind: "task", t: e.t, step: e.step, task: x.task, text: `${x.task} ${e.kind === "task_completed" ? "done" : "failed"}`, failed: e.kind === "task_failed" });
      } else if (e.kind === "safety_stop_started") {
        safety = { kind: "safety", t0: e.t, s0: e.step, t1: null, s1: end, protective: x.protective, warning: x.warning, text: `safety stop${x.reason ? ": " + x.reason : ""}` };
        spans.push(safety);
      } else if (e.kind === "safety_stop_ended") {
        if (safety) { safety.t1 = e.t; safety.s1 = e.step; safety = null; }
      } else {
        instants.push({ kind: e.kind === "deadlock_suspected" ? "safety" : "other", t: e.t, step: e.step, text: this.describeOther(e) });
      }
    }
    this.assignTasks(spans, instants);
    for (const s of spans) {
      if (s.t1 === null) s.t1 = end * dt;
      if (s.kind === "action" || s.kind === "wait") activity.push([s.s0, s.s1, s.charging ? ACTIVITY.charging : ACTIVITY.waiting, s]);
      if (s.kind === "safety") activity.push([s.s0, s.s1, ACTIVITY.stopped, s]);
      s.text = s.text || this.describeSpan(s);
    }
    activity.sort((a, b) => a[0] - b[0]);
    return { version: d.version_, spans, instants, activity, scanned: null };
  }

  // Carrying and contact spans scan every frame and collision: only for the panel.
  scanned(id) {
    const entry = this.of(id);
    if (!entry.scanned) entry.scanned = [...this.carrying(id), ...this.contacts(id)];
    return entry.scanned;
  }

  // An action belongs to the first task the robot ends at or after the action's start.
  assignTasks(spans, instants) {
    const tasks = instants.filter((i) => i.kind === "task").sort((a, b) => a.t - b.t);
    for (const s of spans) {
      // In steps: an action that starts in the frame after a task ended is the next task's.
      const task = tasks.find((k) => k.step >= s.s0);
      if (task) s.task = task.task;
    }
  }

  describeSpan(s) {
    const at = s.goal ? ` at (${s.goal[0].toFixed(1)}, ${s.goal[1].toFixed(1)})` : "";
    const object = s.object !== undefined ? ` ${this.name(s.object)}` : "";
    let text;
    const lasting = s.duration !== undefined ? ` ${s.duration} s` : "";
    if (s.kind === "wait") text = s.charging ? `charging${lasting}` : `waiting${s.label && s.label !== "idle" ? " (" + s.label + ")" : ""}${lasting}`;
    else text = `${s.action}${object}${at}`;
    if (s.status !== "completed") text += ` · ${s.status}${s.reason ? ": " + s.reason : ""}`;
    if (s.task) text += ` · ${s.task}`;
    return text;
  }

  describeOther(e) {
    const d = e.data || {};
    if (e.kind === "vehicle_state") return describeVehicleState(d);
    if (e.kind === "mission_error") return `mission ${d.mission} failed: ${d.error}: ${d.message}`;
    if (e.kind === "removed") return "left the simulation";
    const rest = Object.entries(d).map(([k, v]) => `${k}=${typeof v === "object" ? JSON.stringify(v) : v}`).join(" ");
    return `${e.kind}${rest ? " " + rest : ""}`;
  }

  // Frames where the robot's carrying flag is set, as spans naming what it picked.
  carrying(id) {
    const d = this.data, out = [];
    let span = null;
    for (const f of d.frames) {
      const i = f.layout.index.get(id);
      const on = i !== undefined && (f.flags[i] & 2) !== 0;
      if (on && !span) span = { kind: "carrying", t0: f.t, s0: f.step, t1: null, s1: f.step };
      if (span && on) { span.t1 = f.t; span.s1 = f.step; }
      if (span && !on) { out.push(span); span = null; }
    }
    if (span) out.push(span);
    for (const s of out) s.text = `carrying${this.pickedBefore(id, s.t0)}`;
    return out;
  }

  // What the pick that ends first at or after `t` (the load is attached before the pick
  // action ends) picked, as " name", or "".
  pickedBefore(id, t) {
    const body = this.data.bodies.get(id);
    for (const e of body ? body.events : []) {
      if (e.kind === "action_ended" && e.data && e.data.object !== undefined && /Pick/.test(e.data.action) && e.t >= t - 1e-9) return ` ${this.name(e.data.object)}`;
    }
    return "";
  }

  // Contact spans: from the first contact that began while touching nothing to the moment
  // the robot touches nothing again, with the bodies touched and the contacts that began.
  contacts(id) {
    const d = this.data, dt = d.timestep, out = [];
    const active = new Set();
    let span = null;
    for (const c of d.collisions) {
      if (c.a !== id && c.b !== id) continue;
      const other = c.a === id ? c.b : c.a;
      if (c.started) {
        if (active.has(other)) continue;
        active.add(other);
        if (!span) span = { kind: "collision", t0: c.step * dt, s0: c.step, t1: null, s1: null, with: new Set(), count: 0 };
        span.with.add(other); span.count++;
      } else if (active.delete(other) && active.size === 0 && span) {
        span.t1 = c.step * dt; span.s1 = c.step;
        out.push(span); span = null;
      }
    }
    if (span) out.push(span);
    for (const s of out) {
      const names = [...s.with].map((o) => this.name(o));
      s.text = `in contact with ${names.slice(0, 4).join(", ")}${names.length > 4 ? ` and ${names.length - 4} more` : ""} (${s.count} contact${s.count > 1 ? "s" : ""} began)`;
    }
    return out;
  }

  // What the robot does at frame `step` that its flags do not say: an ACTIVITY code, and the
  // action span (for its goal and path), or null.
  activityAt(id, step) {
    const list = this.of(id).activity;
    let code = ACTIVITY.none, span = null;
    // The last span starting at or before `step` (binary search), and a few before it: an
    // action and a safety stop may overlap, actions of one robot follow each other.
    let lo = 0, hi = list.length - 1, last = -1;
    while (lo <= hi) {
      const mid = (lo + hi) >> 1;
      if (list[mid][0] <= step) { last = mid; lo = mid + 1; } else hi = mid - 1;
    }
    for (let k = last; k >= 0 && k > last - 4; k--) {
      const [s0, s1, c, s] = list[k];
      if (step < s1 || (s1 === s0 && step === s0)) {
        if (c > code) code = c;
        if (!span && s.kind !== "safety") span = s;
      }
    }
    return { code, span };
  }

  // The panel's rows: spans and instants of the kinds in `shown`, in time order.
  rows(id, shown) {
    const { spans, instants } = this.of(id);
    const rows = [];
    for (const s of [...spans, ...this.scanned(id)]) if (shown.has(s.kind)) rows.push({ kind: s.kind, t: s.t0, t1: s.t1, text: s.text, span: s });
    for (const i of instants) if (shown.has(i.kind)) rows.push({ kind: i.kind, t: i.t, t1: null, text: i.text, failed: i.failed });
    rows.sort((a, b) => a.t - b.t || (b.kind === "task") - (a.kind === "task"));
    return rows;
  }
}

function describeVehicleState(d) {
  const parts = [d.order_id ? `order ${d.order_id}/${d.order_update}` : "no order"];
  if (d.last_node) parts.push(`last node ${d.last_node}`);
  const nodes = d.nodes || [];
  parts.push(nodes.length ? `${nodes.length} node${nodes.length > 1 ? "s" : ""} to go` : "nothing to go");
  const tasks = (d.tasks || []).map(([id, , status]) => `${id} ${status}`);
  if (tasks.length) parts.push(`tasks ${tasks.join(", ")}`);
  if (d.paused) parts.push("paused");
  if (d.errors && d.errors.length) parts.push(`${d.errors.length} error${d.errors.length > 1 ? "s" : ""}`);
  return `vehicle state: ${parts.join(", ")}`;
}

if (typeof module !== "undefined") module.exports = { Timeline, TIMELINE_KINDS };
