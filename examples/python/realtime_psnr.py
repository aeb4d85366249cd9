"""PSNR per frame of the real-time pipeline along a camera path, against offline
references of the same views (what `trac0r bench realtime` measures), in twenty lines.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/realtime_psnr.py
"""
import math

import trac0r

scene = trac0r.load("builtin:cornell", width=160, height=120)
start = scene.camera
curves = {}
for recon in ("off", "atrous", "svgf"):
    with trac0r.Realtime(scene, width=160, height=120, recon=recon, seed=1) as rt:
        curves[recon] = []
        for f in range(12):  # a slow sideways pan
            x = start["position"][0] + 0.1 * math.sin(f / 12 * math.pi)
            cam = dict(position=(x, *start["position"][1:]), direction=start["direction"])
            frame = rt.frame(camera=cam, moving=f > 0)
            scene.camera = cam
            ref = trac0r.render(scene, spp=32, seed=1000 + f).image
            curves[recon].append(trac0r.compare(frame.image, ref).psnr)
        scene.camera = start
for recon, psnr in curves.items():
    print(f"{recon:8s}", " ".join(f"{p:5.1f}" for p in psnr), "dB")
