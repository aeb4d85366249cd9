"""The module's overhead: trac0r.render of a small image against the same job through
the C API (libtrac0r.so from the same build, called through ctypes: device, session, run,
film), each timed N times in this process, medians printed in milliseconds.

    PYTHONPATH=build/release/python /usr/bin/python3 python/tests/bench_overhead.py \\
        build/release/libtrac0r.so [WIDTH HEIGHT SPP N]

With `realtime` instead of the library's path: real-time frames at 320x240 (svgf), the wall
time of each Realtime.frame call against the stage times the library measured inside it
(render + temporal + spatial, what `bench realtime` reports as a frame's time).

    PYTHONPATH=build/release/python /usr/bin/python3 python/tests/bench_overhead.py realtime"""
import ctypes
import statistics
import sys
import time

import trac0r


def realtime(frames=40):
    scene = trac0r.load("builtin:cornell", width=320, height=240)
    with trac0r.Realtime(scene, recon="svgf", seed=1) as rt:
        x, y, z = rt.camera["position"]
        walls, stages = [], []
        for f in range(frames + 3):
            cam = {"position": (x + 0.002 * f, y, z)}
            t0 = time.perf_counter()
            fr = rt.frame(camera=cam)
            wall = (time.perf_counter() - t0) * 1e3
            if f >= 3:  # after the warm-up
                walls.append(wall)
                stages.append(fr.render_ms + fr.temporal_ms + fr.spatial_ms)
    w, s = statistics.median(walls), statistics.median(stages)
    ratio = statistics.median([a / b for a, b in zip(walls, stages)])
    print(f"320x240 svgf, {frames} frames: Realtime.frame {w:.3f} ms, the library's stages "
          f"{s:.3f} ms (medians), per-frame ratio {ratio:.4f}")


def main():
    if sys.argv[1] == "realtime":
        realtime()
        return
    lib = ctypes.CDLL(sys.argv[1])
    w, h, spp, n = (int(x) for x in (sys.argv[2:6] if len(sys.argv) >= 6 else (64, 64, 1, 200)))
    P = ctypes.c_void_p
    lib.tr_scene_create.restype = P
    lib.tr_device_create.restype = P
    lib.tr_session_create.restype = P
    lib.tr_session_film.restype = P
    lib.tr_session_create.argtypes = [P, P, P, P, P]
    for f in ("tr_session_run", "tr_session_film"):
        getattr(lib, f).argtypes = [P, P]
    lib.tr_session_destroy.argtypes = [P]
    lib.tr_device_destroy.argtypes = [P]
    err = ctypes.create_string_buffer(1024)
    scene = lib.tr_scene_create(err)
    assert lib.tr_scene_builtin(P(scene), b"cornell", w, h, err) == 0
    assert lib.tr_scene_commit(P(scene), 1, err) == 0  # TR_ACCEL_TYPE_BVH
    desc = ctypes.create_string_buffer(256)  # tr_session_desc: zero but spp
    ctypes.c_uint32.from_buffer(desc).value = spp

    def c_api():
        dev = lib.tr_device_create(b"cpu", err)
        s = lib.tr_session_create(dev, scene, None, desc, err)
        assert s and lib.tr_session_run(s, err) == 0 and lib.tr_session_film(s, err)
        lib.tr_session_destroy(s)
        lib.tr_device_destroy(dev)

    py_scene = trac0r.load("builtin:cornell", width=w, height=h)

    def module():
        return trac0r.render(py_scene, spp=spp).image

    for run in (c_api, module):  # warm up
        run()
    times = {"C API": [], "trac0r.render": []}
    for _ in range(n):  # interleaved, so that load changes hit both alike
        for name, run in (("C API", c_api), ("trac0r.render", module)):
            t0 = time.perf_counter()
            run()
            times[name].append((time.perf_counter() - t0) * 1e3)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"{w}x{h}, {spp} spp, {n} runs each: C API {med['C API']:.3f} ms, trac0r.render "
          f"{med['trac0r.render']:.3f} ms (median), overhead "
          f"{med['trac0r.render'] - med['C API']:+.3f} ms")


if __name__ == "__main__":
    main()
