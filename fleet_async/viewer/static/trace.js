// Decoder of the fleet_async trace format (docs/trace-format.md), fed incrementally.
//
// TraceDecoder.push(bytes) takes the file as it streams in, in chunks of any size, and adds
// complete records to a TraceData; frames reference typed-array views of their record's own
// copy of the bytes (so every view is aligned), so the per-frame GPU upload needs no JS loop.
"use strict";

const TRACE_MAGIC = "FLEETTRC";
const TRACE_VERSIONS = [1, 2];  // 2 added COMMANDS (kind 8)
const HEADER_SIZE = 16;
const RECORD_HEADER = 8;
const KIND = { META: 1, BODIES: 2, LAYOUT: 3, FRAMES: 4, EVENTS: 5, COLLISIONS: 6, END: 7, COMMANDS: 8 };
const KIND_NAME = Object.fromEntries(Object.entries(KIND).map(([k, v]) => [v, k]));
const FLAG_MOVING = 1, FLAG_CARRYING = 2, FLAG_FAILED = 4, FLAG_COLLIDING = 8;

class TraceData {
  constructor(name) {
    this.name = name;
    this.version = null;
    this.meta = null;
    this.shapes = [];
    this.bodies = new Map();      // object id -> body entry (+ .events)
    this.layouts = [];            // {ids: Int32Array, index: Map id -> i}
    this.frames = [];             // {step, t, layout, pos, yaw, flags, colliding}
    this.events = [];             // {t, step, kind, object_id, data}
    this.collisions = [];         // {step, a, b, started}
    this.commands = [];           // {step, t, vehicle, command}: what fleet masters sent
    this.vehicleCommands = new Map(); // vehicle name -> its commands, in the order applied
    this.vehicleStates = new Map();   // object id -> its vehicle_state events, in time order
    this.end = null;
    this.bounds = null;           // [xmin, ymin, xmax, ymax] over every pose of the run
    this.zBounds = null;          // [zmin, zmax]
    this.bytes = 0;
    this.version_ = 0;            // bumped on every change, for listeners
  }
  get timestep() { return this.meta ? this.meta.timestep : 0.1; }
  get duration() {
    const n = this.frames.length;
    return n ? this.frames[n - 1].t : 0;
  }
  get startTime() { return this.frames.length ? this.frames[0].t : 0; }
  // Index of the last frame at or before sim time t (binary search).
  frameAt(t) {
    const f = this.frames;
    if (!f.length) return -1;
    let lo = 0, hi = f.length - 1;
    if (t <= f[0].t) return 0;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (f[mid].t <= t + 1e-9) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  // Index of the last entry of `list` (sorted by .t) at or before sim time t, or -1.
  static lastAt(list, t) {
    let lo = 0, hi = list.length - 1, found = -1;
    while (lo <= hi) {
      const mid = (lo + hi) >> 1;
      if (list[mid].t <= t + 1e-9) { found = mid; lo = mid + 1; } else hi = mid - 1;
    }
    return found;
  }
  // A served vehicle's latest vehicle_state event at or before sim time t, or null.
  vehicleStateAt(id, t) {
    const list = this.vehicleStates.get(id);
    if (!list) return null;
    const i = TraceData.lastAt(list, t);
    return i >= 0 ? list[i] : null;
  }
  // Whether the body is a served vehicle (it received commands or reported a vehicle state).
  isServed(body) {
    if (!body) return false;
    return this.vehicleStates.has(body.id) || (body.name !== undefined && this.vehicleCommands.has(body.name));
  }
}

class TraceFormatError extends Error {}

class TraceDecoder {
  constructor(data) {
    this.data = data;
    this.pending = [];
    this.pendingBytes = 0;
    this.offset = 0;              // file offset of the first pending byte
    this.headerDone = false;
    this.records = 0;
    this.layout = null;
    this.activePairs = new Map(); // "a,b" -> true
    this.contacts = new Map();    // id -> active pair count
    this.collisionCursor = 0;
  }

  error(problem) {
    const v = this.data.version;
    const found = v !== null ? `the file's format version is ${v}; ` : "";
    return new TraceFormatError(
      `${this.data.name}: ${problem} (${found}this viewer reads trace format versions ${TRACE_VERSIONS.join(" and ")})`);
  }

  // Copy the first n pending bytes into a fresh ArrayBuffer (aligned) and drop them.
  take(n) {
    const out = new Uint8Array(n);
    let filled = 0;
    while (filled < n) {
      const head = this.pending[0];
      const need = n - filled;
      if (head.length <= need) {
        out.set(head, filled);
        filled += head.length;
        this.pending.shift();
      } else {
        out.set(head.subarray(0, need), filled);
        this.pending[0] = head.subarray(need);
        filled += need;
      }
    }
    this.pendingBytes -= n;
    this.offset += n;
    return out;
  }

  peek(n) {
    // The first n pending bytes as a DataView (copied only if they span chunks).
    const head = this.pending[0];
    if (head.length >= n) return new DataView(head.buffer, head.byteOffset, n);
    const out = new Uint8Array(n);
    let filled = 0;
    for (const part of this.pending) {
      const m = Math.min(part.length, n - filled);
      out.set(part.subarray(0, m), filled);
      filled += m;
      if (filled === n) break;
    }
    return new DataView(out.buffer);
  }

  push(chunk) {
    this.pending.push(chunk);
    this.pendingBytes += chunk.length;
    this.data.bytes += chunk.length;
    let changed = false;
    if (!this.headerDone) {
      if (this.pendingBytes < HEADER_SIZE) return false;
      const h = this.take(HEADER_SIZE);
      const magic = String.fromCharCode(...h.subarray(0, 8));
      const dv = new DataView(h.buffer);
      if (magic !== TRACE_MAGIC) throw this.error(`not a fleet_async trace (magic bytes ${JSON.stringify(magic)})`);
      this.data.version = dv.getUint16(8, true);
      if (!TRACE_VERSIONS.includes(this.data.version)) throw this.error(`unsupported trace format version ${this.data.version}`);
      const headerSize = dv.getUint16(10, true);
      if (headerSize > HEADER_SIZE) {
        if (this.pendingBytes < headerSize - HEADER_SIZE) throw this.error("truncated header");
        this.take(headerSize - HEADER_SIZE);
      }
      this.headerDone = true;
    }
    while (this.pendingBytes >= RECORD_HEADER) {
      const dv = this.peek(RECORD_HEADER);
      const kind = dv.getUint32(0, true), length = dv.getUint32(4, true);
      const padded = length + ((4 - (length % 4)) % 4);
      if (this.pendingBytes < RECORD_HEADER + padded) break;
      const at = this.offset;
      this.take(RECORD_HEADER);
      const payload = this.take(padded);
      try {
        this.record(kind, payload, length);
      } catch (e) {
        if (e instanceof TraceFormatError) throw e;
        throw this.error(`record ${this.records} (${KIND_NAME[kind] || kind}) at byte ${at}: ${e.message}`);
      }
      this.records += 1;
      changed = true;
    }
    if (changed) this.data.version_ += 1;
    return changed;
  }

  // Called when the stream ended: anything left over, or no end record, is reported. A trace
  // that ends early (a killed run) keeps its readable prefix: data.cut says what is missing;
  // without even a META record there is nothing to show, and that is an error.
  finish() {
    if (!this.headerDone) throw this.error(`truncated: ${this.pendingBytes} bytes, shorter than the ${HEADER_SIZE}-byte header`);
    const cut = (problem) => {
      if (!this.data.meta) throw this.error(`${problem}; nothing to show before it (no META)`);
      this.data.cut = `${this.data.name}: ${problem}; showing the readable prefix (${this.data.frames.length} frames)`;
    };
    if (this.pendingBytes > 0) {
      let what = `${this.pendingBytes} bytes`;
      if (this.pendingBytes >= RECORD_HEADER) {
        const dv = this.peek(RECORD_HEADER);
        const kind = dv.getUint32(0, true), length = dv.getUint32(4, true);
        what = `record ${this.records} (${KIND_NAME[kind] || kind}) at byte ${this.offset} needs ${length} payload bytes, the file has ${this.pendingBytes - RECORD_HEADER} left`;
      } else {
        what = `record ${this.records} at byte ${this.offset} has only ${this.pendingBytes} of its ${RECORD_HEADER} header bytes`;
      }
      return cut(`truncated: ${what}`);
    }
    if (!this.data.end) cut(`truncated: no end record after ${this.records} records (the run did not finish its trace: it is still running, or it stopped without stop_trace / close)`);
  }

  json(payload, length) {
    return JSON.parse(new TextDecoder().decode(payload.subarray(0, length)));
  }

  record(kind, payload, length) {
    const d = this.data;
    switch (kind) {
      case KIND.META: d.meta = this.json(payload, length); break;
      case KIND.BODIES: this.bodies(this.json(payload, length)); break;
      case KIND.LAYOUT: {
        const n = new DataView(payload.buffer).getUint32(0, true);
        const ids = new Int32Array(payload.buffer, 4, n);
        const index = new Map();
        for (let i = 0; i < n; i++) index.set(ids[i], i);
        this.layout = { ids, index, n, serial: d.layouts.length };
        d.layouts.push(this.layout);
        break;
      }
      case KIND.FRAMES: this.frames(payload); break;
      case KIND.EVENTS: {
        for (const [t, step, k, id, data] of this.json(payload, length).events) {
          const e = { t, step, kind: k, object_id: id, data };
          d.events.push(e);
          const body = d.bodies.get(id);
          if (body) body.events.push(e);
          if (k === "vehicle_state" && id !== null) {
            let list = d.vehicleStates.get(id);
            if (!list) d.vehicleStates.set(id, (list = []));
            list.push(e);
            if (list.length > 1 && list[list.length - 2].t > e.t) list.sort((x, y) => x.t - y.t);
          }
        }
        break;
      }
      case KIND.COMMANDS: {
        const dt = d.timestep;
        for (const [step, vehicle, command] of this.json(payload, length).commands) {
          const c = { step, t: step * dt, vehicle, command };
          d.commands.push(c);
          let list = d.vehicleCommands.get(vehicle);
          if (!list) d.vehicleCommands.set(vehicle, (list = []));
          list.push(c);
        }
        break;
      }
      case KIND.COLLISIONS: {
        const n = new DataView(payload.buffer).getUint32(0, true);
        const buf = payload.buffer;
        const steps = new Int32Array(buf, 4, n), a = new Int32Array(buf, 4 + 4 * n, n);
        const b = new Int32Array(buf, 4 + 8 * n, n), started = new Uint8Array(buf, 4 + 12 * n, n);
        for (let i = 0; i < n; i++) d.collisions.push({ step: steps[i], a: a[i], b: b[i], started: started[i] });
        break;
      }
      case KIND.END: d.end = this.json(payload, length); break;
      default: break; // unknown kinds are skipped (forward compatible within a version)
    }
  }

  bodies(value) {
    const d = this.data;
    for (const s of value.shapes) d.shapes.push(s);
    for (const b of value.bodies) {
      b.events = [];
      b.shapeInfo = d.shapes[b.shape];
      d.bodies.set(b.id, b);
      if (b.pose) this.grow(b.pose[0], b.pose[1], b.pose[2], b.shapeInfo);
    }
  }

  grow(x, y, z, shape) {
    const d = this.data;
    const r = shape ? (shape.radius || Math.hypot(shape.half[0], shape.half[1])) : 0;
    if (!d.bounds) d.bounds = [x - r, y - r, x + r, y + r];
    else {
      d.bounds[0] = Math.min(d.bounds[0], x - r); d.bounds[1] = Math.min(d.bounds[1], y - r);
      d.bounds[2] = Math.max(d.bounds[2], x + r); d.bounds[3] = Math.max(d.bounds[3], y + r);
    }
    if (!d.zBounds) d.zBounds = [z, z];
    else { d.zBounds[0] = Math.min(d.zBounds[0], z); d.zBounds[1] = Math.max(d.zBounds[1], z); }
  }

  frames(payload) {
    const d = this.data, buf = payload.buffer;
    const dv = new DataView(buf);
    const k = dv.getUint32(0, true), n = dv.getUint32(4, true);
    const layout = this.layout;
    if (!layout || layout.n !== n) throw this.error(`FRAMES record ${this.records} holds ${n} bodies per frame, but the layout before it lists ${layout ? layout.n : 0}`);
    const steps = new Int32Array(buf, 8, k);
    let at = 8 + 4 * k;
    const pos = new Float32Array(buf, at, 3 * k * n); at += 12 * k * n;
    const yaw = new Int16Array(buf, at, k * n); at += 2 * k * n; at += (4 - (at % 4)) % 4;
    const flags = new Uint8Array(buf, at, k * n);
    // Bounds of the whole run, so the camera frames every place a robot went.
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity, z0 = Infinity, z1 = -Infinity;
    for (let i = 0; i < 3 * k * n; i += 3) {
      const x = pos[i], y = pos[i + 1], z = pos[i + 2];
      if (x < x0) x0 = x; if (x > x1) x1 = x;
      if (y < y0) y0 = y; if (y > y1) y1 = y;
      if (z < z0) z0 = z; if (z > z1) z1 = z;
    }
    if (n > 0) { this.grow(x0, y0, z0, null); this.grow(x1, y1, z1, null); }
    const dt = d.timestep;
    for (let f = 0; f < k; f++) {
      const step = steps[f];
      d.frames.push({
        step, t: step * dt, layout,
        pos: pos.subarray(f * n * 3, (f + 1) * n * 3),
        yaw: yaw.subarray(f * n, (f + 1) * n),
        flags: flags.subarray(f * n, (f + 1) * n),
        colliding: this.collidingAt(step),
      });
    }
  }

  // Object ids in at least one active collision pair at `step`, from the collision records.
  collidingAt(step) {
    const list = this.data.collisions;
    while (this.collisionCursor < list.length && list[this.collisionCursor].step <= step) {
      const c = list[this.collisionCursor++];
      const key = c.a < c.b ? `${c.a},${c.b}` : `${c.b},${c.a}`;
      if (c.started) {
        if (this.activePairs.has(key)) continue;
        this.activePairs.set(key, [c.a, c.b]);
        for (const id of [c.a, c.b]) this.contacts.set(id, (this.contacts.get(id) || 0) + 1);
      } else {
        const pair = this.activePairs.get(key);
        if (!pair) continue;  // an end without its start (the trace began after it)
        this.activePairs.delete(key);
        for (const id of pair) {
          const left = (this.contacts.get(id) || 1) - 1;
          if (left > 0) this.contacts.set(id, left); else this.contacts.delete(id);
        }
      }
    }
    return Int32Array.from(this.contacts.keys());
  }
}

if (typeof module !== "undefined") {
  module.exports = { TraceData, TraceDecoder, TraceFormatError, FLAG_MOVING, FLAG_CARRYING, FLAG_FAILED, FLAG_COLLIDING };
}
