// Drawing a frame: WebGL2 with one instanced draw call per layer (10,000 robots = one call),
// or Canvas2D batched by colour where WebGL2 is not available.
//
// Per instance the GPU reads the frame's own arrays straight from the trace (float32
// positions, int16 yaw, flag bytes) for the two frames around the clock, and interpolates.
"use strict";

// Colours come from palette.js (STATE_COLOURS, OBJECT_COLOURS, robotState, objectKind).
// Both renderers take a robot's activity (what its timeline says it is doing: ACTIVITY) in
// bits 4-6 of its flags byte, beside the trace's moving / carrying / failed bits.

const VERT = `#version 300 es
in vec2 a_corner;
in vec3 a_pos0; in vec3 a_pos1;
in float a_yaw0; in float a_yaw1;
in float a_flags;
in vec4 a_shape;   // centre x, y and half extents x, y in the body frame (m)
in vec4 a_color;
in vec4 a_kindColor; // the object kind's colour (palette.js), for colour by state
in vec3 a_info;    // kind (0 static, 1 object, 2 agent), round (1 circle), top z in body frame
uniform vec2 u_center; uniform vec2 u_scale; uniform float u_alpha; uniform float u_minHalf;
uniform vec2 u_zrange; uniform float u_colorMode; uniform float u_pxPerM;
uniform vec3 u_palette[7];  // idle, moving, carrying, charging, waiting, stopped, failed
out vec2 v_local; out vec2 v_halfPx; out vec4 v_color; out float v_round; out float v_collide;
out float v_agent;
const float PI = 3.14159265358979;
void main() {
  vec3 p = mix(a_pos0, a_pos1, u_alpha);
  float d = a_yaw1 - a_yaw0;
  d -= 2.0 * floor((d + 1.0) / 2.0);
  float yaw = (a_yaw0 + d * u_alpha) * PI;
  vec2 half_ = max(a_shape.zw, vec2(u_minHalf));
  vec2 off = a_shape.xy * step(u_minHalf, min(a_shape.z, a_shape.w));
  vec2 local = off + a_corner * half_;
  float c = cos(yaw), s = sin(yaw);
  vec2 world = p.xy + vec2(c * local.x - s * local.y, s * local.x + c * local.y);
  // Higher tops draw over lower ones (a carried box over its robot): depth from the top z.
  float depth = clamp(-(p.z + a_info.z) / 1000.0, -1.0, 1.0);
  gl_Position = vec4((world - u_center) * u_scale, depth, 1.0);
  if (p.z < u_zrange.x || p.z > u_zrange.y) gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
  v_local = a_corner;
  v_halfPx = half_ * u_pxPerM;
  v_round = a_info.y;
  v_agent = a_info.x == 2.0 ? 1.0 : 0.0;
  int f = int(a_flags + 0.5);
  v_collide = (f & 8) != 0 ? 1.0 : 0.0;
  vec4 col = a_color;
  if (u_colorMode < 0.5 && a_info.x == 2.0) {
    int act = (f >> 4) & 7;   // palette.js robotState, in the same order
    int st = 0;
    if ((f & 4) != 0) st = 6;
    else if (act == 2) st = 3;
    else if (act == 3) st = 5;
    else if ((f & 2) != 0) st = 2;
    else if ((f & 1) != 0) st = 1;
    else if (act == 1) st = 4;
    col = vec4(u_palette[st], 1.0);
  } else if (u_colorMode < 0.5 && a_kindColor.a > 0.0) {
    col = a_kindColor;
  }
  v_color = col;
}`;

const FRAG = `#version 300 es
precision mediump float;
in vec2 v_local; in vec2 v_halfPx; in vec4 v_color; in float v_round; in float v_collide;
in float v_agent;
out vec4 outColor;
void main() {
  vec2 px = v_local * v_halfPx;                 // body-frame position in screen pixels
  float edge;
  if (v_round > 0.5) {
    float r = length(v_local);
    if (r > 1.0) discard;
    edge = (1.0 - r) * min(v_halfPx.x, v_halfPx.y);
  } else {
    edge = min(v_halfPx.x - abs(px.x), v_halfPx.y - abs(px.y));
  }
  vec3 col = v_color.rgb;
  // Heading: a dark bar from the centre to the front edge.
  if (v_agent > 0.5 && v_halfPx.x >= 3.0 && px.x > 0.0 && abs(px.y) < max(1.0, v_halfPx.y * 0.18)) {
    col *= 0.35;
  }
  float border = v_collide > 0.5 ? max(2.0, min(v_halfPx.x, v_halfPx.y) * 0.35) : 1.0;
  if (edge < border && min(v_halfPx.x, v_halfPx.y) > 2.0) {
    col = v_collide > 0.5 ? vec3(0.95, 0.05, 0.55) : col * 0.55;
  } else if (v_collide > 0.5 && min(v_halfPx.x, v_halfPx.y) <= 2.0) {
    col = vec3(0.95, 0.05, 0.55);
  }
  outColor = vec4(col, max(v_color.a, 0.35));
}`;

class GLRenderer {
  static create(canvas) {
    const gl = canvas.getContext("webgl2", { antialias: false, alpha: true, depth: true, premultipliedAlpha: false, preserveDrawingBuffer: true });
    return gl ? new GLRenderer(canvas, gl) : null;
  }

  constructor(canvas, gl) {
    this.kind = "webgl2";
    this.canvas = canvas;
    this.gl = gl;
    this.prog = this.program(VERT, FRAG);
    this.loc = {};
    for (const a of ["a_corner", "a_pos0", "a_pos1", "a_yaw0", "a_yaw1", "a_flags", "a_shape", "a_color", "a_kindColor", "a_info"]) this.loc[a] = gl.getAttribLocation(this.prog, a);
    this.uni = {};
    for (const u of ["u_center", "u_scale", "u_alpha", "u_minHalf", "u_zrange", "u_colorMode", "u_pxPerM", "u_palette"]) this.uni[u] = gl.getUniformLocation(this.prog, u);
    this.corner = this.buffer(new Float32Array([-1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1]));
    this.layers = new Map();   // layout serial or "static" -> {vao, static buffers, dynamic slots}
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LEQUAL);
  }

  program(vs, fs) {
    const gl = this.gl;
    const compile = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src); gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    };
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }

  buffer(data, usage) {
    const gl = this.gl, b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, data, usage || gl.STATIC_DRAW);
    return b;
  }

  attrib(name, buf, size, type, norm, divisor) {
    const gl = this.gl, loc = this.loc[name];
    if (loc < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, size, type, norm, 0, 0);
    gl.vertexAttribDivisor(loc, divisor);
  }

  // A layer: the bodies of one layout (per-instance shape, colour, kind) plus two slots of
  // per-frame data (frame i and i + 1) that the shader interpolates between.
  layer(key, bodies) {
    let layer = this.layers.get(key);
    if (layer) return layer;
    const gl = this.gl, n = bodies.length;
    const shape = new Float32Array(4 * n), color = new Uint8Array(4 * n), info = new Float32Array(3 * n);
    const kindColor = new Uint8Array(4 * n);
    bodies.forEach((b, i) => {
      const s = b ? b.shapeInfo : null;
      const kind = objectKind(b);
      if (kind) kindColor.set([...OBJECT_COLOURS[kind].map((c) => Math.round(c * 255)), 255], 4 * i);
      if (s) {
        shape.set([s.center[0], s.center[1], s.radius || s.half[0], s.radius || s.half[1]], 4 * i);
        color.set(s.rgba.map((c) => Math.round(c * 255)), 4 * i);
        info.set([isRobot(b) ? 2 : b.kind === "static" ? 0 : 1, s.type === "circle" ? 1 : 0, s.z ? s.z[1] : 0], 3 * i);
      } else {
        shape.set([0, 0, 0.05, 0.05], 4 * i); color.set([128, 128, 128, 255], 4 * i);
        info.set([1, 1, 0], 3 * i);
      }
    });
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    this.attrib("a_corner", this.corner, 2, gl.FLOAT, false, 0);
    this.attrib("a_shape", this.buffer(shape), 4, gl.FLOAT, false, 1);
    this.attrib("a_color", this.buffer(color), 4, gl.UNSIGNED_BYTE, true, 1);
    this.attrib("a_kindColor", this.buffer(kindColor), 4, gl.UNSIGNED_BYTE, true, 1);
    this.attrib("a_info", this.buffer(info), 3, gl.FLOAT, false, 1);
    const slot = () => ({
      frame: null,
      pos: this.buffer(new Float32Array(3 * n), gl.DYNAMIC_DRAW),
      yaw: this.buffer(new Int16Array(n + (n % 2)), gl.DYNAMIC_DRAW),
      flags: this.buffer(new Uint8Array(n + ((4 - (n % 4)) % 4)), gl.DYNAMIC_DRAW),
    });
    layer = { vao, n, slots: [slot(), slot()], flagScratch: new Uint8Array(n) };
    gl.bindVertexArray(null);
    this.layers.set(key, layer);
    return layer;
  }

  upload(layer, slot, frame, statics, activity) {
    const gl = this.gl;
    const acts = !statics && activity ? activity(frame) : null;
    if ((slot.frame === frame && slot.acts === acts) || (window.viewer && window.viewer.debug.noUpload)) return;
    slot.frame = frame;
    slot.acts = acts;
    gl.bindBuffer(gl.ARRAY_BUFFER, slot.pos); gl.bufferSubData(gl.ARRAY_BUFFER, 0, frame.pos);
    gl.bindBuffer(gl.ARRAY_BUFFER, slot.yaw); gl.bufferSubData(gl.ARRAY_BUFFER, 0, frame.yaw);
    let flags = frame.flags;
    if ((frame.colliding && frame.colliding.length && !statics) || acts) {
      flags = layer.flagScratch;
      flags.set(frame.flags);
      const index = frame.layout.index;
      for (const id of statics ? [] : frame.colliding) {
        const i = index.get(id);
        if (i !== undefined) flags[i] |= 8;
      }
      if (acts) for (const [i, code] of acts) flags[i] |= code << 4;
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, slot.flags); gl.bufferSubData(gl.ARRAY_BUFFER, 0, flags);
  }

  bindSlots(layer, a, b, flagsFrom) {
    const gl = this.gl;
    gl.bindVertexArray(layer.vao);
    this.attrib("a_pos0", a.pos, 3, gl.FLOAT, false, 1);
    this.attrib("a_pos1", b.pos, 3, gl.FLOAT, false, 1);
    this.attrib("a_yaw0", a.yaw, 1, gl.SHORT, true, 1);
    this.attrib("a_yaw1", b.yaw, 1, gl.SHORT, true, 1);
    this.attrib("a_flags", (flagsFrom || a).flags, 1, gl.UNSIGNED_BYTE, false, 1);
  }

  resize(w, h, dpr) {
    const W = Math.round(w * dpr), H = Math.round(h * dpr);
    if (this.canvas.width !== W || this.canvas.height !== H) { this.canvas.width = W; this.canvas.height = H; }
  }

  // view: {cx, cy, scale (css px per m), width, height, dpr}; scene: {statics, frame0, frame1,
  // alpha, zrange, colorMode}
  pixelAt(x, y) {   // device pixels from the top left; [r, g, b, a] 0..255
    const gl = this.gl, out = new Uint8Array(4);
    gl.readPixels(Math.round(x), this.canvas.height - 1 - Math.round(y), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, out);
    return Array.from(out);
  }

  draw(view, scene) {
    const gl = this.gl;
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0, 0, 0, 0);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(this.prog);
    const u = this.uni;
    gl.uniform2f(u.u_center, view.cx, view.cy);
    gl.uniform2f(u.u_scale, (2 * view.scale) / view.width, (2 * view.scale) / view.height);
    gl.uniform1f(u.u_pxPerM, view.scale);
    gl.uniform1f(u.u_minHalf, 1.6 / view.scale);   // robots stay at least ~3 px wide
    gl.uniform2f(u.u_zrange, scene.zrange[0], scene.zrange[1]);
    gl.uniform1f(u.u_colorMode, scene.colorMode === "body" ? 1 : 0);
    gl.uniform3fv(u.u_palette, STATE_ORDER.flatMap((name) => STATE_COLOURS[name]));
    if (scene.statics && scene.statics.n) {
      const layer = this.layer("static", scene.statics.bodies);
      this.upload(layer, layer.slots[0], scene.statics.frame, true);
      this.bindSlots(layer, layer.slots[0], layer.slots[0]);
      gl.uniform1f(u.u_alpha, 0);
      gl.drawArraysInstanced(gl.TRIANGLES, 0, 6, layer.n);
    }
    const f0 = scene.frame0, f1 = scene.frame1;
    if (f0 && f0.layout.n) {
      const layer = this.layer(f0.layout.serial, scene.layoutBodies(f0.layout));
      let [s0, s1] = layer.slots;
      // Reuse a slot that already holds one of the two frames (playback moves one frame on).
      if (s1.frame === f0 || s0.frame === f1) { [s0, s1] = [s1, s0]; layer.slots = [s0, s1]; }
      this.upload(layer, s0, f0, false, scene.activity);
      const same = f1 && f1.layout === f0.layout;
      if (same) this.upload(layer, s1, f1, false, scene.activity);
      this.bindSlots(layer, s0, same ? s1 : s0, same && scene.alpha > 0.5 ? s1 : s0);
      gl.uniform1f(u.u_alpha, same ? scene.alpha : 0);
      const dbg = window.viewer ? window.viewer.debug : {};
      gl.drawArraysInstanced(gl.TRIANGLES, 0, 6, dbg.maxInstances ? Math.min(dbg.maxInstances, layer.n) : layer.n);
    }
    gl.bindVertexArray(null);
  }
}

// Canvas2D renderer: every body rasterised in JS into one ImageData, drawn with a single
// putImageData per frame (no per-robot canvas call). Software WebGL (SwiftShader, llvmpipe:
// what a headless or GPU-less machine has) pays a fixed cost per primitive that makes 10,000
// robots run at a few frames per second; this renderer keeps them above 30.
function packRGB(rgb, a) {
  const r = Math.round(rgb[0] * 255), g = Math.round(rgb[1] * 255), b = Math.round(rgb[2] * 255);
  return ((Math.round((a === undefined ? 1 : a) * 255) << 24) | (b << 16) | (g << 8) | r) >>> 0;
}
const ALL_COLOURS = { ...STATE_COLOURS, ...OBJECT_COLOURS };
const PACKED = Object.fromEntries(Object.entries(ALL_COLOURS).map(([k, v]) => [k, packRGB(v)]));
const PACKED_DARK = Object.fromEntries(Object.entries(ALL_COLOURS).map(([k, v]) => [k, packRGB(v.map((c) => c * 0.55))]));
const PACKED_NOSE = Object.fromEntries(Object.entries(ALL_COLOURS).map(([k, v]) => [k, packRGB(v.map((c) => c * 0.35))]));

class PixelRenderer {
  constructor(canvas) {
    this.kind = "canvas2d";
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.img = null;
    this.buf = null;
    this.bodyColours = new Map();   // shape -> [fill, border, nose] packed
  }

  resize(w, h, dpr) {
    const W = Math.round(w * dpr), H = Math.round(h * dpr);
    if (this.canvas.width !== W || this.canvas.height !== H || !this.img) {
      this.canvas.width = W; this.canvas.height = H;
      this.img = this.ctx.createImageData(W, H);
      this.buf = new Uint32Array(this.img.data.buffer);
    }
    this.dpr = dpr;
  }

  pixelAt(x, y) {   // device pixels from the top left; [r, g, b, a] 0..255
    const v = this.buf[Math.round(y) * this.canvas.width + Math.round(x)];
    return [v & 255, (v >>> 8) & 255, (v >>> 16) & 255, v >>> 24];
  }

  colours(shape) {
    let c = this.bodyColours.get(shape);
    if (!c) {
      const rgb = shape ? shape.rgba.slice(0, 3) : [0.5, 0.5, 0.5];
      c = [packRGB(rgb), packRGB(rgb.map((v) => v * 0.55)), packRGB(rgb.map((v) => v * 0.35))];
      this.bodyColours.set(shape, c);
    }
    return c;
  }

  // One body: a rotated box or a circle, centre (sx, sy) in device pixels, half sizes in px.
  fill(sx, sy, yaw, hx, hy, round, fill, border, nose, borderPx, heading) {
    const W = this.canvas.width, H = this.canvas.height, buf = this.buf;
    const R = round ? Math.max(hx, hy) : Math.hypot(hx, hy);
    const x0 = Math.max(0, Math.floor(sx - R)), x1 = Math.min(W - 1, Math.ceil(sx + R));
    const y0 = Math.max(0, Math.floor(sy - R)), y1 = Math.min(H - 1, Math.ceil(sy + R));
    if (x0 > x1 || y0 > y1) return;
    if (R <= 2.5) {   // a few pixels: a solid square, in the border colour if it is flagged
      const col = borderPx > 1 ? border : fill;
      for (let y = y0; y <= y1; y++) buf.fill(col, y * W + x0, y * W + x1 + 1);
      return;
    }
    const c = Math.cos(yaw), s = Math.sin(yaw), r2 = hx * hx, noseW = Math.max(1, hy * 0.18);
    for (let y = y0; y <= y1; y++) {
      const dy = sy - (y + 0.5);
      let row = y * W;
      for (let x = x0; x <= x1; x++) {
        const dx = x + 0.5 - sx;
        const lx = c * dx + s * dy, ly = -s * dx + c * dy;
        let edge;
        if (round) {
          const d2 = lx * lx + ly * ly;
          if (d2 > r2) continue;
          edge = hx - Math.sqrt(d2);
        } else {
          const ax = hx - Math.abs(lx), ay = hy - Math.abs(ly);
          if (ax < 0 || ay < 0) continue;
          edge = ax < ay ? ax : ay;
        }
        buf[row + x] = edge < borderPx ? border : heading && lx > 0 && Math.abs(ly) < noseW ? nose : fill;
      }
    }
  }

  draw(view, scene) {
    const dpr = this.dpr || 1, S = view.scale * dpr, W = this.canvas.width, H = this.canvas.height;
    const ox = W / 2 - view.cx * S, oy = H / 2 + view.cy * S;
    const minHalf = 1.6 * dpr;
    const [z0, z1] = scene.zrange;
    const byState = scene.colorMode !== "body";
    this.buf.fill(0);
    const body = (b, x, y, z, yaw, flags, colliding) => {
      if (z < z0 || z > z1) return;
      const shape = b ? b.shapeInfo : null;
      let hx = shape ? (shape.radius || shape.half[0]) * S : 0.05 * S;
      let hy = shape ? (shape.radius || shape.half[1]) * S : 0.05 * S;
      let px = ox + x * S, py = oy - y * S;
      if (shape && hx >= minHalf && hy >= minHalf && (shape.center[0] || shape.center[1])) {
        const c = Math.cos(yaw), s = Math.sin(yaw);
        px += (c * shape.center[0] - s * shape.center[1]) * S;
        py -= (s * shape.center[0] + c * shape.center[1]) * S;
      }
      hx = Math.max(hx, minHalf); hy = Math.max(hy, minHalf);
      let fill, border, nose;
      const agent = isRobot(b);
      const kind = byState ? objectKind(b) : null;
      if (agent && byState) {
        const st = robotState(flags, flags >> 4);
        fill = PACKED[st]; border = PACKED_DARK[st]; nose = PACKED_NOSE[st];
      } else if (kind) {
        fill = PACKED[kind]; border = PACKED_DARK[kind]; nose = PACKED_NOSE[kind];
      } else {
        [fill, border, nose] = this.colours(shape);
      }
      let borderPx = 1;
      if (colliding) { border = PACKED.collision; borderPx = Math.max(2, Math.min(hx, hy) * 0.35); }
      this.fill(px, py, yaw, hx, hy, shape && shape.type === "circle", fill, border, nose, borderPx, agent && hx >= 3);
    };
    if (scene.statics) for (const b of scene.statics.bodies) body(b, b.pose[0], b.pose[1], b.pose[2], b.pose[3], 0, false);
    const f0 = scene.frame0, f1 = scene.frame1;
    if (f0 && f0.layout.n) {
      const bodies = scene.layoutBodies(f0.layout), n = f0.layout.n, ids = f0.layout.ids;
      const lerp = f1 && f1.layout === f0.layout && scene.alpha > 0 ? scene.alpha : 0;
      const p0 = f0.pos, y0 = f0.yaw, p1 = lerp ? f1.pos : p0, y1 = lerp ? f1.yaw : y0;
      const colliding = f0.colliding.length ? new Set(f0.colliding) : null;
      const acts = byState && scene.activity ? new Map(scene.activity(f0) || []) : null;
      const k = Math.PI / 32767;
      // Objects first, then agents on top: a robot stays visible (orange: carrying) under
      // the box it carries, and over the totes it drives past.
      for (const pass of [false, true]) {
        for (let i = 0; i < n; i++) {
          const b = bodies[i];
          if (isRobot(b) !== pass) continue;
          const j = 3 * i;
          let yaw = y0[i] * k;
          if (lerp) {
            let d = (y1[i] - y0[i]) * k;
            if (d > Math.PI) d -= 2 * Math.PI; else if (d < -Math.PI) d += 2 * Math.PI;
            yaw += d * lerp;
          }
          body(b, p0[j] + (p1[j] - p0[j]) * lerp, p0[j + 1] + (p1[j + 1] - p0[j + 1]) * lerp, p0[j + 2] + (p1[j + 2] - p0[j + 2]) * lerp,
            yaw, (lerp > 0.5 ? f1 : f0).flags[i] | (acts && acts.has(i) ? acts.get(i) << 4 : 0), colliding !== null && colliding.has(ids[i]));
        }
      }
    }
    this.ctx.putImageData(this.img, 0, 0);
  }
}
