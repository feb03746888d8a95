// The selected robot's side panel: what it is doing now, filters by event kind, and its
// timeline (timeline.js) as rows that seek the clock when clicked; and, on the canvas, its
// current goal and the rest of its path, plus name labels on demand.
"use strict";

class TimelinePanel {
  constructor(timeline, els, onSeek) {
    this.timeline = timeline;
    this.els = els;              // {filters, list, count, doing}
    this.onSeek = onSeek;
    this.shown = new Set(Object.keys(TIMELINE_KINDS));
    this.key = null;
    this.buildFilters();
  }

  buildFilters() {
    this.els.filters.replaceChildren(...Object.entries(TIMELINE_KINDS).map(([kind, label]) => {
      const box = document.createElement("input");
      box.type = "checkbox"; box.checked = true; box.dataset.kind = kind;
      box.onchange = () => { this.setShown(kind, box.checked); };
      const l = document.createElement("label");
      l.className = `filter ${kind}`;
      l.append(box, label);
      return l;
    }));
  }

  setShown(kind, on) {
    if (on) this.shown.add(kind); else this.shown.delete(kind);
    const box = this.els.filters.querySelector(`input[data-kind="${kind}"]`);
    if (box) box.checked = on;
    this.key = null;
  }

  // Rebuild the rows when the robot, the data or the filters changed.
  show(id, version) {
    const key = `${id}/${version}/${[...this.shown].join(",")}`;
    if (key === this.key) return;
    this.key = key;
    const rows = this.timeline.rows(id, this.shown);
    const all = this.timeline.rows(id, new Set(Object.keys(TIMELINE_KINDS)));
    this.els.list.replaceChildren(...rows.map((r) => {
      const li = document.createElement("li");
      li.className = `${r.kind}${r.failed || (r.span && /failed/.test(r.span.status || "")) ? " failed" : ""}`;
      li.dataset.t = String(r.t);
      const when = r.t1 !== null && r.t1 !== undefined && r.t1 > r.t + 1e-9 ? `${r.t.toFixed(1)}–${r.t1.toFixed(1)} s` : `${r.t.toFixed(1)} s`;
      const time = document.createElement("span");
      time.className = "when";
      time.textContent = when;
      li.append(time, ` ${r.text}`);
      li.onclick = () => this.onSeek(r.t);
      return li;
    }));
    const count = (k) => all.filter((r) => r.kind === k).length;
    this.els.count.textContent = `${count("action") + count("wait")} actions, ${count("task")} tasks, ${count("collision")} contact spans; ${rows.length} of ${all.length} rows shown`;
  }

  // "now: PickAction tote_A1_0 at (2.5, 3.2) · order 0" for the frame at `step`.
  doing(id, step, state) {
    const { span } = this.timeline.activityAt(id, step);
    this.els.doing.textContent = `now ${state}${span ? `: ${span.text}` : ""}`;
    return span;
  }
}

// The goal and the rest of the path of the selected robot's current action: a dashed line
// from the robot through the waypoints not yet reached, a cross on the goal, a ring on the
// object it picks or drops.
function drawGoal(ctx, project, pose, span, objectPose) {
  if (!span || (!span.goal && !span.path)) return null;
  const points = span.path ? span.path.slice() : [span.goal];
  // Drop waypoints already behind the robot: keep from the nearest one on.
  let nearest = 0, best = Infinity;
  points.forEach((q, k) => { const d = Math.hypot(q[0] - pose.x, q[1] - pose.y); if (d < best) { best = d; nearest = k; } });
  const rest = points.slice(nearest);
  ctx.save();
  ctx.strokeStyle = "#37474f"; ctx.lineWidth = 2; ctx.setLineDash([6, 4]);
  ctx.beginPath();
  const p0 = project(pose.x, pose.y);
  ctx.moveTo(p0.x, p0.y);
  for (const q of rest) { const p = project(q[0], q[1]); ctx.lineTo(p.x, p.y); }
  ctx.stroke();
  ctx.setLineDash([]);
  const goal = span.goal || points[points.length - 1];
  const g = project(goal[0], goal[1]);
  ctx.strokeStyle = "#c62828"; ctx.lineWidth = 3;
  ctx.beginPath(); ctx.moveTo(g.x - 7, g.y - 7); ctx.lineTo(g.x + 7, g.y + 7); ctx.moveTo(g.x + 7, g.y - 7); ctx.lineTo(g.x - 7, g.y + 7); ctx.stroke();
  if (objectPose) {
    const o = project(objectPose.x, objectPose.y);
    ctx.strokeStyle = "#c62828"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.arc(o.x, o.y, 11, 0, 2 * Math.PI); ctx.stroke();
  }
  ctx.restore();
  return { goal, points: rest };
}

// Names beside the robots (and devices) in view, at most `limit` of them.
function drawLabels(ctx, items, width, height, limit) {
  ctx.save();
  ctx.font = "11px sans-serif"; ctx.lineWidth = 3; ctx.strokeStyle = "rgba(255,255,255,0.9)"; ctx.fillStyle = "#1d2327";
  let drawn = 0;
  for (const [p, text] of items) {
    if (p.x < -40 || p.y < -10 || p.x > width + 10 || p.y > height + 10) continue;
    if (drawn++ >= limit) break;
    ctx.strokeText(text, p.x + 6, p.y + 12);
    ctx.fillText(text, p.x + 6, p.y + 12);
  }
  ctx.restore();
  return drawn;
}
