// common.js - what the page (app.js) and the test page (test.js) share: the browser's
// features, loading the module that fits them, its C functions, the scene files.
"use strict";

const TR = {};

// WebAssembly SIMD: whether the browser validates a function that uses a v128 value.
TR.SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1,
  0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);

// What the browser offers and which module runs in it: the threaded SIMD module needs
// SharedArrayBuffer, which only a cross-origin isolated page has (scripts/serve-web sends
// the headers), and SIMD; without either the single-threaded module runs.
TR.features = function () {
  let simd = false;
  try {
    simd = WebAssembly.validate(TR.SIMD_PROBE);
  } catch (e) {
    simd = false;
  }
  const sab = typeof SharedArrayBuffer !== "undefined";
  const isolated = self.crossOriginIsolated === true;
  const threads = isolated && sab;
  const f = { simd, sab, isolated, threads, cores: navigator.hardwareConcurrency || 1 };
  f.module = threads && simd ? "trac0r" : "trac0r-st";
  f.fallback = f.module !== "trac0r";
  const why = [];
  if (!isolated) why.push("the page is not cross-origin isolated (serve it with scripts/serve-web)");
  if (!sab) why.push("no SharedArrayBuffer");
  if (!simd) why.push("no WebAssembly SIMD");
  f.reason = f.fallback ? "one thread, no SIMD: " + why.join("; ") : "";
  return f;
};

TR.loadModule = function (name) {
  return new Promise((resolve, reject) => {
    const s = document.createElement("script");
    s.src = name + ".js";
    s.onload = () => createTrac0r().then(resolve, reject);
    s.onerror = () => reject(new Error("cannot load " + s.src + " (build with cmake --preset web)"));
    document.head.appendChild(s);
  });
};

// The C interface (web/web_api.h).
TR.api = function (M) {
  const n = "number", s = "string";
  return {
    M,
    error: M.cwrap("tr_web_error", s, []),
    start: M.cwrap("tr_web_start", n, [n]),
    info: M.cwrap("tr_web_info", s, []),
    loadBuiltin: M.cwrap("tr_web_load_builtin", n, [s, n, n]),
    loadFile: M.cwrap("tr_web_load_file", n, [s, n, n]),
    loadJson: M.cwrap("tr_web_load_json", n, [s, s, n, n]),
    meshesSkipped: M.cwrap("tr_web_meshes_skipped", n, []),
    viewPtr: M.cwrap("tr_web_view", n, []),
    frame: M.cwrap("tr_web_frame", n, [n, n, n, n, n, n, n]),
    pixelsPtr: M.cwrap("tr_web_pixels", n, []),
    statsPtr: M.cwrap("tr_web_stats", n, []),
    render: M.cwrap("tr_web_render", n, [n, n, n]),
    imagePtr: M.cwrap("tr_web_image", n, []),
    renderSeconds: M.cwrap("tr_web_render_seconds", n, []),
    // The module's memory as it is now (it may have grown since the last call).
    buffer() {
      return M.wasmMemory ? M.wasmMemory.buffer : M.HEAPU8.buffer;
    },
    view() {
      return new Float32Array(this.buffer(), this.viewPtr(), 10);
    },
    stats() {
      const a = new Float64Array(this.buffer(), this.statsPtr(), 12);
      return {
        width: a[0], height: a[1], spp: a[2], frameSpp: a[3], renderMs: a[4],
        temporalMs: a[5], spatialMs: a[6], tonemapMs: a[7], scale: a[8], triangles: a[9],
        threads: a[10], method: a[11],
      };
    },
    // The last frame's RGBA pixels, copied out of the module's memory (a canvas takes no
    // view of a SharedArrayBuffer).
    pixels(w, h) {
      const out = new Uint8ClampedArray(w * h * 4);
      out.set(new Uint8Array(this.buffer(), this.pixelsPtr(), w * h * 4));
      return out;
    },
    image(w, h) {
      return new Float32Array(this.buffer(), this.imagePtr(), w * h * 3).slice();
    },
  };
};

// Copies the shipped scene files (scenes/index.json lists them, textures included) into
// the module's file system under /scenes; returns the scene files' names.
TR.loadScenes = async function (M) {
  const list = await (await fetch("scenes/index.json")).json();
  M.FS.mkdir("/scenes");
  M.FS.mkdir("/scenes/textures");
  await Promise.all(list.map(async (f) => {
    const r = await fetch("scenes/" + f);
    if (!r.ok) throw new Error("scenes/" + f + ": HTTP " + r.status);
    M.FS.writeFile("/scenes/" + f, new Uint8Array(await r.arrayBuffer()));
  }));
  return list.filter((f) => f.endsWith(".json"));
};

TR.METHODS = ["off", "accumulate", "bilateral", "atrous", "svgf"];
