// A served vehicle (one that fleet software drives over VDA 5050): its part of the side panel
// (order, route still to go, task states, errors, the commands it received) and its route
// drawn on the canvas.
//
// The command list is rebuilt when the selection or the data change; the state part when the
// state at the clock's time is another event, so a render costs a binary search when nothing
// changed.
"use strict";

function idList(ids) {
  return ids.length <= 8 ? ids.join(" ") : `${ids.slice(0, 3).join(" ")} … ${ids.slice(-2).join(" ")} (${ids.length})`;
}

function describeCommand(c) {
  const cmd = c.command || {};
  const tasksOf = (list) => (list || []).map((k) => `${k.kind} ${k.task_id}`).join(", ");
  if (cmd.type === "order") {
    const nodes = cmd.nodes || [];
    const base = nodes.filter((n) => n.released).map((n) => n.node_id);
    const horizon = nodes.filter((n) => !n.released).map((n) => n.node_id);
    let text = `order ${cmd.order_id} update ${cmd.update}: nodes ${idList(base)}`;
    if (horizon.length) text += ` + horizon ${idList(horizon)}`;
    const tasks = tasksOf(nodes.flatMap((n) => n.tasks || []));
    if (tasks) text += `; tasks ${tasks}`;
    return text;
  }
  if (cmd.type === "instant") return `instant ${tasksOf(cmd.tasks)}`;
  if (cmd.type === "rejection") return `rejected ${cmd.kind}${cmd.description ? ": " + cmd.description : ""}`;
  return String(cmd.type);
}

// A served vehicle's route still to go at the clock's time: from the robot through its
// remaining nodes in order; released (base) part solid, horizon part dashed and lighter;
// nodes as circles (released filled, horizon hollow) labelled with their ids.
const ROUTE_COLOUR = "#00796b", ROUTE_HORIZON = "rgba(0, 121, 107, 0.5)";

// Returns what it drew ({vehicle, order_id, from, points}) or null; app's data-route-nodes
// says how many nodes.
function drawRoute(ctx, project, app, pose, state) {
  let drawnRoute = null;
  const all = state && state.data && Array.isArray(state.data.nodes) ? state.data.nodes : [];
  const nodes = all.filter((n) => Number.isFinite(n[3]) && Number.isFinite(n[4]));
  app.dataset.routeNodes = String(nodes.length);
  if (!nodes.length) return null;
  const start = project(pose.x, pose.y);
  const points = nodes.map(([id, sequence, released, x, y]) => {
    const p = project(x, y);
    return { node_id: id, sequence, released: !!released, x, y, px: p.x, py: p.y };
  });
  drawnRoute = { vehicle: state.data.vehicle, order_id: state.data.order_id, from: { x: pose.x, y: pose.y, px: start.x, py: start.y }, points };
  ctx.save();
  ctx.lineCap = "round"; ctx.lineJoin = "round";
  let prev = { px: start.x, py: start.y };
  for (const q of points) {   // a segment is released when the node it leads to is
    ctx.beginPath();
    ctx.moveTo(prev.px, prev.py); ctx.lineTo(q.px, q.py);
    if (q.released) { ctx.setLineDash([]); ctx.strokeStyle = ROUTE_COLOUR; ctx.lineWidth = 3; }
    else { ctx.setLineDash([7, 5]); ctx.strokeStyle = ROUTE_HORIZON; ctx.lineWidth = 2; }
    ctx.stroke();
    prev = q;
  }
  ctx.setLineDash([]);
  ctx.font = "11px sans-serif";
  for (const q of points) {
    ctx.beginPath();
    ctx.arc(q.px, q.py, 5, 0, 2 * Math.PI);
    if (q.released) { ctx.fillStyle = ROUTE_COLOUR; ctx.fill(); }
    else { ctx.fillStyle = "#fff"; ctx.fill(); ctx.strokeStyle = ROUTE_HORIZON; ctx.lineWidth = 2; ctx.stroke(); }
    ctx.lineWidth = 3; ctx.strokeStyle = "#fff"; ctx.fillStyle = q.released ? ROUTE_COLOUR : "#4a7f79";
    ctx.strokeText(String(q.node_id), q.px + 7, q.py + 14);
    ctx.fillText(String(q.node_id), q.px + 7, q.py + 14);
  }
  ctx.restore();
  return drawnRoute;
}


// The served-vehicle part of the panel. The command list is rebuilt when the selection or
// the data change; the state part when the state at the clock's time is another event, so a
// render costs a binary search when nothing changed.
class VehiclePanel {
  constructor(data, $, app, onSeek) {
  this.data = data; this.$ = $; this.app = app; this.onSeek = onSeek;
  this.view = { id: null, state: undefined, current: undefined, commands: [] };
}

// The selected body `b` (or null) at sim time `t`; `rebuild` after the selection or the
// data changed.
update(b, t, rebuild) {
  const { data, $, app } = this, vehicleView = this.view;
  const section = $("sel-vehicle");
  if (!b || !data.isServed(b)) {
    section.hidden = true;
    vehicleView.id = null;
    app.dataset.orderId = "";
    return;
  }
  section.hidden = false;
  if (rebuild || vehicleView.id !== b.id) {
    vehicleView.id = b.id;
    vehicleView.state = undefined;
    vehicleView.current = undefined;
    vehicleView.commands = data.vehicleCommands.get(b.name) || [];
    $("sel-command-count").textContent = `(${vehicleView.commands.length})`;
    $("sel-commands").replaceChildren(...vehicleView.commands.map((c) => {
      const li = document.createElement("li");
      li.className = `command ${c.command && c.command.type}`;
      li.dataset.t = String(c.t);
      li.textContent = `${c.t.toFixed(2)} s  ${describeCommand(c)}`;
      li.title = JSON.stringify(c.command);
      li.onclick = () => this.onSeek(c.t);
      return li;
    }));
  }
  const state = data.vehicleStateAt(b.id, t);
  if (state !== vehicleView.state) {
    vehicleView.state = state;
    this.showState(state ? state.data || {} : null);
  }
  // Commands at or before the clock are done; the latest of them is the current one.
  const current = TraceData.lastAt(vehicleView.commands, t);
  if (current !== vehicleView.current) {
    vehicleView.current = current;
    $("sel-commands").querySelectorAll("li").forEach((li, i) => {
      li.classList.toggle("future", i > current);
      li.classList.toggle("current", i === current);
    });
  }
}

showState(d) {
  const { $, app } = this;
  app.dataset.orderId = d && d.order_id ? String(d.order_id) : "";
  if (!d) {
    $("sel-order").textContent = "no order yet";
    $("sel-route").textContent = "";
    $("sel-tasks").hidden = true;
    $("sel-errors").hidden = true;
    return;
  }
  const order = d.order_id ? `order ${d.order_id} · update ${d.order_update}` : "no order";
  $("sel-order").textContent = `${order} · last node ${d.last_node || "–"}${d.paused ? " · paused" : ""}`;
  const nodes = d.nodes || [], edges = d.edges || [];
  const split = (list, at) => [list.filter((x) => x[at]).map((x) => x[0]), list.filter((x) => !x[at]).map((x) => x[0])];
  const [nb, nh] = split(nodes, 2), [eb, eh] = split(edges, 2);
  const line = (what, base, horizon) => `${what} ${base.length ? idList(base) : "–"}${horizon.length ? " | horizon " + idList(horizon) : ""}`;
  $("sel-route").textContent = nodes.length || edges.length
    ? `${line("nodes to go:", nb, nh)}\n${line("edges to go:", eb, eh)}`
    : d.order_id ? "order done: no nodes to go" : "";
  const tasks = d.tasks || [];
  $("sel-tasks").hidden = tasks.length === 0;
  $("sel-tasks").tBodies[0].replaceChildren(...tasks.map(([id, kind, status]) => {
    const tr = document.createElement("tr");
    tr.className = `task ${status}`;
    for (const v of [id, kind, status]) { const td = document.createElement("td"); td.textContent = String(v); tr.append(td); }
    return tr;
  }));
  const errors = d.errors || [];
  $("sel-errors").hidden = errors.length === 0;
  $("sel-errors").replaceChildren(...errors.map(([kind, description]) => {
    const li = document.createElement("li");
    li.textContent = `${kind}: ${description}`;
    return li;
  }));
}
}
