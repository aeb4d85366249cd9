"""EXR to PFM through Blender's image loader, for tools/cycles/pfmtool.py (no numpy, no
OpenEXR module in Debian's Python): each IN.exr becomes IN.pfm beside it.

    blender -b --factory-startup -P tools/cycles/exr_to_pfm.py -- IN.exr...
"""

import os
import struct
import sys

import bpy


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not args:
        sys.stderr.write("exr_to_pfm.py: expected IN.exr...\n")
        os._exit(2)
    for path in args:
        if not path.lower().endswith(".exr") or not os.path.isfile(path):
            sys.stderr.write("exr_to_pfm.py: %s: not an .exr file\n" % path)
            os._exit(2)
        img = bpy.data.images.load(os.path.abspath(path))
        w, h = img.size
        ch = img.channels
        px = img.pixels[:]
        if w * h == 0 or ch < 3:
            sys.stderr.write("exr_to_pfm.py: %s: %dx%d, %d channels\n" % (path, w, h, ch))
            os._exit(2)
        rgb = [0.0] * (3 * w * h)
        for i in range(w * h):
            rgb[3 * i:3 * i + 3] = px[ch * i:ch * i + 3]
        out = path[:-4] + ".pfm"
        # Blender's pixels run bottom row first, as PFM's do.
        with open(out + ".tmp", "wb") as fh:
            fh.write(b"PF\n%d %d\n-1.0\n" % (w, h))
            fh.write(struct.pack("<%df" % len(rgb), *rgb))
        os.replace(out + ".tmp", out)
        bpy.data.images.remove(img)
        print("exr_to_pfm: %s -> %s" % (path, out))
    sys.stdout.flush()
    os._exit(0)


main()
