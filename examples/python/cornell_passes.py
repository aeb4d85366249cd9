"""Renders the Cornell box with its passes and shows them side by side (matplotlib), or
writes them as PNG files where matplotlib is not installed.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/cornell_passes.py [OUT_DIR]
"""
import os
import sys

import numpy as np

import trac0r

out_dir = sys.argv[1] if len(sys.argv) > 1 else "."
scene = trac0r.load("builtin:cornell", width=320, height=240)
result = trac0r.render(scene, spp=64, seed=1, passes=["albedo", "normal", "depth", "variance"])
print(f"{result.spp} spp in {result.seconds:.2f} s, {result.rays / result.seconds / 1e6:.1f} Mrays/s")

# Each pass as linear values to look at: normals from [-1, 1], depth and noise scaled.
panels = {
    "image": result.image,
    "albedo": result.passes["albedo"],
    "normal": result.passes["normal"] * 0.5 + 0.5,
    "depth": result.passes["depth"] / result.passes["depth"].max(),
    "variance": np.sqrt(result.passes["variance"]) * 4,
}
try:
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
if plt is None:
    for name, linear in panels.items():
        path = os.path.join(out_dir, f"cornell-{name}.png")
        trac0r.write(path, linear, tonemap="filmic" if name == "image" else "clamp")
        print("wrote", path)
else:
    fig, axes = plt.subplots(1, len(panels), figsize=(3 * len(panels), 2.6))
    for ax, (name, linear) in zip(axes, panels.items()):
        ax.imshow(trac0r.tonemap(linear, tonemap="filmic" if name == "image" else "clamp"))
        ax.set_title(name)
        ax.axis("off")
    fig.tight_layout()
    path = os.path.join(out_dir, "cornell-passes.png")
    fig.savefig(path)
    print("wrote", path)
