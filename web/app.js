// app.js - trac0r's page: loads the module that fits the browser (common.js), the
// built-in scenes and the shipped scene files, and runs the real-time loop: WASD and
// mouse look move the camera (frames at the budget's resolution while moving), at rest
// the same view accumulates until MAX_SPP. window.trac0r exposes the state for
// scripts/web-screenshot.
//
// Query: scene (a built-in name or a file in scenes/), size (WxH), method, spp,
// orbit=1 (the camera sways by itself: the picture in motion).
"use strict";

const MAX_SPP = 4096;
const BUILTINS = ["cornell", "cornell-mirror", "cornell-diffuse", "cornell-ico-3"];

const ui = {
  scene: document.getElementById("scene"),
  size: document.getElementById("size"),
  spp: document.getElementById("spp"),
  method: document.getElementById("method"),
  budget: document.getElementById("budget"),
  exposure: document.getElementById("exposure"),
  shot: document.getElementById("shot"),
  canvas: document.getElementById("view"),
  stats: document.getElementById("stats"),
  notice: document.getElementById("notice"),
};
const ctx = ui.canvas.getContext("2d");
const state = (window.trac0r = { ready: false, spp: 0, frames: 0, error: "", moving: false });

function notice(text, error) {
  ui.notice.textContent = text;
  ui.notice.className = error ? "error" : "";
  ui.notice.style.display = text ? "block" : "none";
}

const v3 = {
  add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
  scale: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
  dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
  cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
  norm: (a) => v3.scale(a, 1 / Math.hypot(a[0], a[1], a[2])),
  // a turned by angle t about unit axis k (Rodrigues).
  rot: (a, k, t) => {
    const c = Math.cos(t), s = Math.sin(t), kd = v3.dot(k, a) * (1 - c);
    return v3.add(v3.add(v3.scale(a, c), v3.scale(v3.cross(k, a), s)), v3.scale(k, kd));
  },
};

let api = null;
let cam = null; // {pos, dir, up, fov, speed}
let keys = new Set();
let drag = null, look = [0, 0];
let lastT = 0, fps = 0, changed = true, idle = true; // idle: no frame scheduled
const query = new URLSearchParams(location.search);

async function main() {
  const f = TR.features();
  if (f.fallback) notice("Running on " + f.reason + ".", false);
  let M;
  try {
    M = await TR.loadModule(f.module);
  } catch (e) {
    notice("Cannot load the module: " + e.message, true);
    state.error = String(e.message);
    return;
  }
  api = TR.api(M);
  api.start(f.threads ? f.cores : 1);
  state.module = f.module;
  state.info = api.info();
  const files = await TR.loadScenes(M);
  for (const name of BUILTINS.concat(files)) {
    const o = document.createElement("option");
    o.value = name;
    o.textContent = name.endsWith(".json") ? "scenes/" + name : "built-in " + name;
    ui.scene.appendChild(o);
  }
  ui.scene.value = query.get("scene") || "cornell-classic.json";
  if (query.has("size")) ui.size.value = query.get("size");
  if (query.has("spp")) ui.spp.value = query.get("spp");
  if (query.has("method")) ui.method.value = String(Math.max(0, TR.METHODS.indexOf(query.get("method"))));
  for (const el of [ui.size, ui.scene]) el.addEventListener("change", load);
  for (const el of [ui.spp, ui.method, ui.budget, ui.exposure]) {
    el.addEventListener("change", () => { changed = true; wake(); });
  }
  ui.shot.addEventListener("click", screenshot);
  bindInput();
  load();
}

function size() {
  const [w, h] = ui.size.value.split("x").map(Number);
  return { w, h };
}

function load() {
  const { w, h } = size();
  const name = ui.scene.value;
  const rc = name.endsWith(".json") ? api.loadFile("/scenes/" + name, w, h) : api.loadBuiltin(name, w, h);
  if (rc !== 0) {
    notice(name + ": " + api.error(), true);
    state.error = api.error();
    return;
  }
  const skipped = api.meshesSkipped();
  const f = TR.features();
  const parts = [];
  if (f.fallback) parts.push("Running on " + f.reason + ".");
  if (skipped) parts.push(name + ": " + skipped + " mesh" + (skipped > 1 ? "es" : "") +
    " left out (the web build imports no meshes).");
  notice(parts.join(" "), false);
  const v = api.view();
  const pos = [v[0], v[1], v[2]];
  cam = { pos, dir: [v[3], v[4], v[5]], dir0: [v[3], v[4], v[5]], up: [v[6], v[7], v[8]], fov: v[9],
          speed: Math.max(1e-3, Math.hypot(pos[0], pos[1], pos[2])) * 0.4 };
  ui.canvas.width = w;
  ui.canvas.height = h;
  state.ready = true;
  changed = true;
  wake();
}

function bindInput() {
  const c = ui.canvas;
  c.addEventListener("keydown", (e) => { keys.add(e.key.toLowerCase()); if (e.key.length === 1) e.preventDefault(); wake(); });
  c.addEventListener("keyup", (e) => keys.delete(e.key.toLowerCase()));
  c.addEventListener("blur", () => keys.clear());
  c.addEventListener("mousedown", (e) => { c.focus(); drag = [e.clientX, e.clientY]; e.preventDefault(); });
  window.addEventListener("mouseup", () => (drag = null));
  window.addEventListener("mousemove", (e) => {
    if (!drag) return;
    look[0] += e.clientX - drag[0];
    look[1] += e.clientY - drag[1];
    drag = [e.clientX, e.clientY];
    wake();
  });
}

// Applies keys, drag and the orbit to the camera; true when it moved.
function moveCamera(dt) {
  let moved = false;
  const right = v3.norm(v3.cross(cam.dir, cam.up));
  if (look[0] || look[1]) {
    const k = 0.0035;
    cam.dir = v3.norm(v3.rot(cam.dir, v3.norm(cam.up), -look[0] * k));
    const pitched = v3.norm(v3.rot(cam.dir, right, -look[1] * k));
    if (Math.abs(v3.dot(pitched, v3.norm(cam.up))) < 0.98) cam.dir = pitched;
    look = [0, 0];
    moved = true;
  }
  if (query.get("orbit") === "1") {
    // A slow sway about the view the scene gave.
    cam.t = (cam.t || 0) + dt;
    cam.dir = v3.norm(v3.rot(cam.dir0, v3.norm(cam.up), 0.15 * Math.sin(0.8 * cam.t)));
    moved = true;
  }
  const step = cam.speed * dt * (keys.has("shift") ? 4 : 1);
  const dirs = { w: cam.dir, s: v3.scale(cam.dir, -1), d: right, a: v3.scale(right, -1),
                 e: v3.norm(cam.up), q: v3.scale(v3.norm(cam.up), -1) };
  for (const [k, d] of Object.entries(dirs)) {
    if (keys.has(k)) {
      cam.pos = v3.add(cam.pos, v3.scale(d, step));
      moved = true;
    }
  }
  return moved;
}

function wake() {
  if (idle) {
    idle = false;
    requestAnimationFrame(tick);
  }
}

function tick(t) {
  const dt = lastT ? Math.min(0.1, (t - lastT) / 1000) : 0;
  lastT = t;
  if (!cam) return;
  const moving = moveCamera(dt) || changed;
  changed = false;
  const v = api.view();
  v.set([...cam.pos, ...cam.dir, ...cam.up, cam.fov]);
  const { w, h } = size();
  const budget = moving ? Number(ui.budget.value) : 0;
  const t0 = performance.now();
  const rc = api.frame(w, h, Number(ui.method.value), Number(ui.spp.value), moving ? 1 : 0, budget,
                       Number(ui.exposure.value) || 0);
  if (rc !== 0) {
    notice("Frame failed: " + api.error(), true);
    state.error = api.error();
    return;
  }
  const s = api.stats();
  draw(s);
  const frameMs = performance.now() - t0;
  fps = fps ? 0.9 * fps + 0.1 * (1000 / Math.max(1, t - (tick.prev || t - frameMs))) : 1000 / frameMs;
  tick.prev = t;
  state.spp = s.spp;
  state.frames += 1;
  state.moving = moving;
  ui.stats.textContent =
    `${fps.toFixed(1)} FPS   ${s.width}x${s.height} (1/${s.scale.toFixed(2)})   ${s.spp} spp\n` +
    `render   ${s.renderMs.toFixed(1)} ms\n` +
    `temporal ${s.temporalMs.toFixed(1)} ms\n` +
    `spatial  ${s.spatialMs.toFixed(1)} ms\n` +
    `tonemap  ${s.tonemapMs.toFixed(1)} ms\n` +
    `${state.info}, ${s.triangles} triangles` +
    (moving ? "" : s.spp >= MAX_SPP ? "\nat rest: converged" : "\nat rest: refining");
  if (!moving && s.spp >= MAX_SPP && !keys.size && !query.has("orbit")) {
    idle = true; // wake() starts the loop again
    return;
  }
  requestAnimationFrame(tick);
}

// The frame, scaled to the canvas when the budget lowered its resolution.
let scratch = null;
function draw(s) {
  const w = s.width, h = s.height;
  const img = new ImageData(api.pixels(w, h), w, h);
  if (w === ui.canvas.width && h === ui.canvas.height) {
    ctx.putImageData(img, 0, 0);
    return;
  }
  if (!scratch) scratch = document.createElement("canvas");
  scratch.width = w;
  scratch.height = h;
  scratch.getContext("2d").putImageData(img, 0, 0);
  ctx.imageSmoothingEnabled = true;
  ctx.drawImage(scratch, 0, 0, ui.canvas.width, ui.canvas.height);
}

function screenshot() {
  ui.canvas.toBlob((blob) => {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = `trac0r-${ui.scene.value.replace(/\.json$/, "")}-${state.spp}spp.png`;
    a.click();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  }, "image/png");
}

main().catch((e) => {
  notice(String(e && e.message ? e.message : e), true);
  state.error = String(e);
});
