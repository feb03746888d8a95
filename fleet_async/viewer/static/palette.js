// Colours and names: the robot state palette, object kinds, display names and the legend.
//
// A robot's state at a frame comes from its flags (moving, carrying, failed) and from what
// its timeline says it is doing then (charging, waiting on an action, a safety stop): see
// robotState. Other bodies are coloured by kind (racks, stations, totes, chargers), guessed
// from their name, class and pickable flag, unless the page colours bodies as modelled.
"use strict";

// A robot: an agent that is not a device (doors, lifts and workcells are agents too, and are
// drawn in their own colours, without a heading mark, and not counted as robots).
function isRobot(b) {
  return b !== undefined && b !== null && b.kind === "agent" && !b.device;
}

const STATE_COLOURS = {
  idle: [0.56, 0.64, 0.68],
  moving: [0.16, 0.55, 0.95],
  carrying: [0.98, 0.6, 0.1],
  charging: [0.18, 0.72, 0.3],
  waiting: [0.96, 0.82, 0.18],
  stopped: [0.5, 0.22, 0.68],
  failed: [0.9, 0.15, 0.15],
  collision: [0.95, 0.1, 0.6],
};
const STATE_HELP = {
  idle: "no action in progress",
  moving: "driving",
  carrying: "holding a load",
  charging: "a charge action in progress",
  waiting: "an action in progress, not moving (a wait, a pick or drop underway)",
  stopped: "a safety stop",
  failed: "its last action failed",
  collision: "touching another body",
};
// Activity codes (bits 4-6 of the flags the renderers read): what the timeline says.
const ACTIVITY = { none: 0, waiting: 1, charging: 2, stopped: 3 };
const ACTIVITY_NAME = ["none", "waiting", "charging", "stopped"];
const STATE_ORDER = ["idle", "moving", "carrying", "charging", "waiting", "stopped", "failed"];

// Failed first, then what the robot is doing that its flags do not say, then its flags.
function robotState(flags, activity) {
  if (flags & 4) return "failed";
  if (activity === ACTIVITY.charging) return "charging";
  if (activity === ACTIVITY.stopped) return "stopped";
  if (flags & 2) return "carrying";
  if (flags & 1) return "moving";
  if (activity === ACTIVITY.waiting) return "waiting";
  return "idle";
}

const OBJECT_COLOURS = {
  rack: [0.55, 0.42, 0.3],
  station: [0.38, 0.44, 0.58],
  tote: [0.3, 0.72, 0.76],
  charger: [0.1, 0.42, 0.22],
  scenery: [0.74, 0.76, 0.79],
};
const OBJECT_HELP = { rack: "racks, shelves", station: "stations, tables", tote: "totes, loads (pickable)", charger: "chargers", scenery: "other scenery" };

// What kind of object a body is, for its colour: from its name and class (charger, rack or
// shelf, station or table), else a pickable body or one named like a load is a tote.
function objectKind(b) {
  if (!b || b.kind === "agent") return null;
  if (b.objectKind) return b.objectKind;
  const text = `${b.name || ""} ${b.class || ""}`;
  let kind = "scenery";
  if (/charg/i.test(text)) kind = "charger";
  else if (/shelf|rack/i.test(text)) kind = "rack";
  else if (/station|table|desk|dock|conveyor/i.test(text)) kind = "station";
  else if (b.pickable || /tote|pallet|parcel|\bbox|bin_|load/i.test(text)) kind = "tote";
  b.objectKind = kind;
  return kind;
}

// The name shown everywhere on the page: the body's name, with #id where several bodies of
// the trace share it (the seed's Python API allows that; a scenario file does not).
function displayName(data, id) {
  const b = data.bodies.get(id);
  if (!b) return `#${id}`;
  if (!b.name) return `(unnamed)#${id}`;
  if (data.nameCount === undefined || data.nameCountSize !== data.bodies.size) {
    data.nameCount = new Map();
    for (const other of data.bodies.values()) if (other.name) data.nameCount.set(other.name, (data.nameCount.get(other.name) || 0) + 1);
    data.nameCountSize = data.bodies.size;
  }
  return data.nameCount.get(b.name) > 1 ? `${b.name}#${id}` : b.name;
}

function cssColour(rgb) {
  return `rgb(${rgb.map((c) => Math.round(c * 255)).join(",")})`;
}

// The legend for what is drawn now: the state palette and the object kinds present, or,
// when bodies are coloured as modelled, a line that says so (no state colours then).
function legendItems(data, colorMode) {
  if (colorMode === "body") return [{ text: "colours as modelled in the scenario (robot states not shown)" }];
  const items = STATE_ORDER.map((s) => ({ swatch: cssColour(STATE_COLOURS[s]), text: s, title: STATE_HELP[s] }));
  const kinds = new Set();
  for (const b of data.bodies.values()) { const k = objectKind(b); if (k) kinds.add(k); }
  for (const k of Object.keys(OBJECT_COLOURS)) {
    if (kinds.has(k)) items.push({ swatch: cssColour(OBJECT_COLOURS[k]), text: k, title: OBJECT_HELP[k], object: true });
  }
  items.push({ ring: cssColour(STATE_COLOURS.collision), text: "collision", title: STATE_HELP.collision });
  return items;
}

function renderLegend(el, data, colorMode) {
  el.replaceChildren(...legendItems(data, colorMode).map((it) => {
    const span = document.createElement("span");
    span.className = it.object ? "item object" : "item";
    if (it.title) span.title = it.title;
    const i = document.createElement("i");
    if (it.swatch) i.style.background = it.swatch;
    else if (it.ring) { i.className = "ring"; i.style.borderColor = it.ring; }
    else i.hidden = true;
    span.append(i, it.text);
    return span;
  }));
}

if (typeof module !== "undefined") {
  module.exports = { isRobot, robotState, objectKind, displayName, legendItems, STATE_COLOURS, OBJECT_COLOURS, ACTIVITY };
}
