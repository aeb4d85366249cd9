// test.js - the web check (tests/web_check.sh opens test.html in headless Chromium):
// renders a still of a scene as `trac0r render` does, compares it with the native
// render's PFM when given one, then times real-time frames; writes key=value lines into
// #result and sets window.testDone.
//
// Query: scene (file in scenes/, default cornell-classic.json), w, h, spp, seed, threads
// (0: every core), ref (a PFM beside the page), frames, fw, fh (the real-time frames'
// size), method (off, accumulate, bilateral, atrous, svgf), stills (renders of the still
// timed, the fastest kept), allscenes=1 (every scene file rendered once first), budget (the frames' budget in ms: 0, the default, keeps the
// full resolution).
"use strict";

(async function () {
  const q = new URLSearchParams(location.search);
  const num = (k, d) => (q.has(k) ? Number(q.get(k)) : d);
  const lines = [];
  const out = (k, v) => {
    lines.push(k + "=" + v);
    document.getElementById("result").textContent = lines.join("\n");
  };
  try {
    const f = TR.features();
    out("isolated", f.isolated ? 1 : 0);
    out("shared_array_buffer", f.sab ? 1 : 0);
    out("simd", f.simd ? 1 : 0);
    out("module", f.module);
    out("fallback", f.fallback ? 1 : 0);
    if (f.fallback) out("fallback_reason", f.reason);
    const M = await TR.loadModule(f.module);
    const api = TR.api(M);
    const scenes = await TR.loadScenes(M);
    out("scenes", scenes.length);
    const threads = num("threads", 0);
    out("threads", api.start(threads > 0 ? threads : f.cores));
    out("info", api.info());

    // Every shipped scene file loads and renders (allscenes=1): a sample per pixel at 32x24.
    if (q.has("allscenes")) {
      let rendered = 0;
      for (const name of scenes) {
        if (api.loadFile("/scenes/" + name, 32, 24) !== 0 || api.render(1, 0, 0) !== 0) {
          out("scene_error", name + ": " + api.error());
          continue;
        }
        ++rendered;
      }
      out("scenes_rendered", rendered);
    }

    // The still.
    const scene = q.get("scene") || "cornell-classic.json";
    const w = num("w", 160), h = num("h", 120), spp = num("spp", 8), seed = num("seed", 0);
    if (api.loadFile("/scenes/" + scene, w, h) !== 0) throw new Error(api.error());
    let best = Infinity;
    for (let i = 0; i < num("stills", 1); ++i) {
      if (api.render(spp, seed, threads) !== 0) throw new Error(api.error());
      best = Math.min(best, api.renderSeconds());
    }
    const img = api.image(w, h);
    out("still_seconds", best.toFixed(4));
    out("samples_per_second", Math.round((w * h * spp) / best));
    let hash = 0x811c9dc5;
    const bytes = new Uint8Array(img.buffer);
    for (let i = 0; i < bytes.length; ++i) hash = Math.imul(hash ^ bytes[i], 16777619) >>> 0;
    out("image_fnv1a", hash.toString(16).padStart(8, "0"));
    // The same still from the file's text (tr_scene_file_parse) must give the same bits.
    const text = await (await fetch("scenes/" + scene)).text();
    if (api.loadJson("/scenes/" + scene, text, w, h) !== 0) throw new Error(api.error());
    if (api.render(spp, seed, threads) !== 0) throw new Error(api.error());
    const again = new Uint8Array(api.image(w, h).buffer);
    out("json_text_same", again.every((b, i) => b === bytes[i]) ? 1 : 0);
    if (q.has("ref")) compare(img, w, h, await (await fetch(q.get("ref"))).arrayBuffer(), out);

    // Real-time frames: the camera turning a little every frame (each frame a new view).
    const frames = num("frames", 0);
    if (frames > 0) {
      const fw = num("fw", 320), fh = num("fh", 240);
      const method = Math.max(0, TR.METHODS.indexOf(q.get("method") || "svgf"));
      if (api.loadFile("/scenes/" + scene, fw, fh) !== 0) throw new Error(api.error());
      const v = api.view();
      const d0 = [v[3], v[4], v[5]];
      const sum = { render: 0, temporal: 0, spatial: 0, tonemap: 0, scale: 0 };
      let t0 = 0;
      for (let i = 0; i <= frames; ++i) {
        if (i === 1) t0 = performance.now(); // the first frame builds the loop's buffers
        const a = 0.002 * i, view = api.view();
        view[3] = d0[0] * Math.cos(a) - d0[2] * Math.sin(a);
        view[5] = d0[0] * Math.sin(a) + d0[2] * Math.cos(a);
        if (api.frame(fw, fh, method, 1, 1, num("budget", 0), 0) !== 0) throw new Error(api.error());
        if (i > 0) {
          const s = api.stats();
          sum.render += s.renderMs;
          sum.temporal += s.temporalMs;
          sum.spatial += s.spatialMs;
          sum.tonemap += s.tonemapMs;
          sum.scale += s.scale;
        }
      }
      const ms = performance.now() - t0;
      out("frames", frames);
      out("frame_method", TR.METHODS[method]);
      out("fps", ((frames * 1000) / ms).toFixed(2));
      for (const k of ["render", "temporal", "spatial", "tonemap"]) {
        out(k + "_ms", (sum[k] / frames).toFixed(3));
      }
      out("mean_scale", (sum.scale / frames).toFixed(2));
    }
    out("ok", 1);
  } catch (e) {
    out("error", String(e && e.message ? e.message : e).replace(/\n/g, " "));
    out("ok", 0);
  }
  window.testDone = true;
})();

// The still against a PFM (little-endian, bottom row first): equal floats, the largest
// difference, and the PSNR of displayable values ([0,1], NaN as black, as `trac0r compare`
// measures).
function compare(img, w, h, pfm, out) {
  const bytes = new Uint8Array(pfm);
  let pos = 0, fields = [];
  while (fields.length < 4) {
    let s = "";
    while (bytes[pos] <= 32) ++pos;
    while (bytes[pos] > 32) s += String.fromCharCode(bytes[pos++]);
    fields.push(s);
  }
  ++pos;
  const pw = Number(fields[1]), ph = Number(fields[2]);
  if (fields[0] !== "PF" || pw !== w || ph !== h) {
    out("compare_error", "reference is " + fields.slice(0, 3).join(" ") + ", not PF " + w + " " + h);
    return;
  }
  const ref = new Float32Array(bytes.slice(pos, pos + w * h * 12).buffer);
  let equal = 0, maxDiff = 0, se = 0;
  const disp = (x) => (x > 0 ? (x < 1 ? x : 1) : 0);
  for (let y = 0; y < h; ++y) {
    for (let i = 0; i < w * 3; ++i) {
      const a = img[y * w * 3 + i], b = ref[(h - 1 - y) * w * 3 + i];
      if (Object.is(a, b)) ++equal;
      const d = Math.abs(a - b);
      if (d > maxDiff) maxDiff = d;
      const e = disp(a) - disp(b);
      se += e * e;
    }
  }
  const n = w * h * 3, mse = se / n;
  out("compare_values", n);
  out("compare_equal", equal);
  out("identical", equal === n ? 1 : 0);
  out("max_abs_diff", maxDiff.toExponential(3));
  out("psnr", mse > 0 ? (10 * Math.log10(1 / mse)).toFixed(2) : "inf");
}
