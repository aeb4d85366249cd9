#!/usr/bin/env python3
"""Small PFM arithmetic for the Cycles comparison (plain Python, no numpy).

    pfmtool.py mean OUT.pfm IN.pfm...      the pixel-wise mean of images (a reference from
                                           independent renders)
    pfmtool.py relmse A.pfm B.pfm          trac0r compare's relative MSE, mean of
                                           (a - b)^2 / (b^2 + 0.01) on values clamped to [0, 1]
    pfmtool.py halves A.pfm B.pfm          two independent halves of a reference: their
                                           relative MSE / 4 estimates the error of their mean
    pfmtool.py blocks A.pfm REF.pfm [N]    N x N-pixel block means (default 8) of A against
                                           REF, RGB mean: the largest relative deviation, the
                                           mean deviation and the fraction beyond 3 %
    pfmtool.py compare A1 A2 B1 B2 [N]     two renderers, each as two independent halves:
                                           the relative MSE of A's mean against B's with
                                           both renderers' noise (from their halves) taken
                                           out, and N x N-pixel block means (default 8) of
                                           the two means in units of their own noise
    pfmtool.py side OUT.png A.pfm B.pfm [C.pfm]
                                           the images side by side as one 8-bit sRGB PNG
                                           (clamped to [0, 1], no tonemapping), then
                                           (A - B) x 4 on grey 0.5 (C instead, if given)
    pfmtool.py fit CSV TARGET [REF_ERROR]  log-log interpolation of spp/time against relMSE
                                           (less the reference's own relMSE, default 0)

PFM as trac0r writes it: "PF", width height, a negative scale (little-endian), float RGB
rows bottom to top. Errors name the file and exit with status 2.
"""

import math
import struct
import sys
import zlib


def die(msg):
    sys.stderr.write("pfmtool.py: %s\n" % msg)
    sys.exit(2)


def read_pfm(path):
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as e:
        die("%s: %s" % (path, e.strerror))
    fields = []
    pos = 0
    while len(fields) < 4:
        while pos < len(data) and data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while pos < len(data) and not data[pos:pos + 1].isspace():
            pos += 1
        if start == pos:
            die("%s: truncated PFM header" % path)
        fields.append(data[start:pos].decode("ascii", "replace"))
    pos += 1
    if fields[0] != "PF":
        die("%s: not a colour PFM (magic '%s')" % (path, fields[0]))
    try:
        w, h, scale = int(fields[1]), int(fields[2]), float(fields[3])
    except ValueError:
        die("%s: bad PFM header %s" % (path, fields[1:]))
    if w <= 0 or h <= 0 or w * h > 1 << 26:
        die("%s: bad PFM size %dx%d" % (path, w, h))
    n = w * h * 3
    if len(data) - pos < 4 * n:
        die("%s: %d bytes of pixels, expected %d" % (path, len(data) - pos, 4 * n))
    px = struct.unpack(("<" if scale < 0 else ">") + "%df" % n, data[pos:pos + 4 * n])
    return w, h, px


def write_pfm(path, w, h, px):
    with open(path, "wb") as fh:
        fh.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        fh.write(struct.pack("<%df" % len(px), *px))


def same_size(a, b, pa, pb):
    if a[0] != b[0] or a[1] != b[1]:
        die("%s is %dx%d but %s is %dx%d" % (pa, a[0], a[1], pb, b[0], b[1]))


def clamp01(v):
    return 0.0 if not v > 0.0 else (1.0 if v > 1.0 else v)


def relmse(a, b):
    s = 0.0
    for x, y in zip(a[2], b[2]):
        x, y = clamp01(x), clamp01(y)
        s += (x - y) * (x - y) / (y * y + 0.01)
    return s / len(a[2])


def cmd_mean(args):
    if len(args) < 2:
        die("mean: expected OUT.pfm IN.pfm...")
    imgs = [read_pfm(p) for p in args[1:]]
    for p, im in zip(args[2:], imgs[1:]):
        same_size(imgs[0], im, args[1], p)
    n = len(imgs)
    acc = [0.0] * len(imgs[0][2])
    for im in imgs:
        for i, v in enumerate(im[2]):
            acc[i] += v
    write_pfm(args[0], imgs[0][0], imgs[0][1], [v / n for v in acc])
    print("mean of %d images -> %s" % (n, args[0]))


def cmd_relmse(args):
    if len(args) != 2:
        die("relmse: expected A.pfm B.pfm")
    a, b = read_pfm(args[0]), read_pfm(args[1])
    same_size(a, b, args[0], args[1])
    print("relmse %.6g" % relmse(a, b))


def cmd_halves(args):
    if len(args) != 2:
        die("halves: expected A.pfm B.pfm")
    a, b = read_pfm(args[0]), read_pfm(args[1])
    same_size(a, b, args[0], args[1])
    # Var(a - b) = 2 Var(half); the mean of the halves has Var(half) / 2 = Var(a - b) / 4.
    # The denominator uses b, not the mean: a small second-order difference.
    r = relmse(a, b)
    print("halves_relmse %.6g reference_relmse_estimate %.6g" % (r, r / 4.0))


def cmd_blocks(args):
    if len(args) not in (2, 3):
        die("blocks: expected A.pfm REF.pfm [N]")
    a, r = read_pfm(args[0]), read_pfm(args[1])
    same_size(a, r, args[0], args[1])
    n = int(args[2]) if len(args) == 3 else 8
    w, h = a[0], a[1]
    if n <= 0 or w % n or h % n:
        die("blocks: %d does not divide %dx%d" % (n, w, h))
    devs = []
    for by in range(h // n):
        for bx in range(w // n):
            sa = sr = 0.0
            for y in range(by * n, by * n + n):
                row = (y * w + bx * n) * 3
                sa += sum(a[2][row:row + 3 * n])
                sr += sum(r[2][row:row + 3 * n])
            if sr > 0.0:
                devs.append((sa / sr - 1.0, bx, by))
    if not devs:
        die("blocks: the reference is black")
    worst = max(devs, key=lambda d: abs(d[0]))
    mean_abs = sum(abs(d[0]) for d in devs) / len(devs)
    over = sum(1 for d in devs if abs(d[0]) > 0.03) / len(devs)
    signed = sum(d[0] for d in devs) / len(devs)
    print("blocks %dx%d: %d, max |dev| %.4f at block (%d, %d), mean |dev| %.4f, "
          "mean dev %+.4f, beyond 3%% %.4f" % (n, n, len(devs), abs(worst[0]), worst[1],
                                               worst[2], mean_abs, signed, over))


def cmd_compare(args):
    """A (two halves A1, A2) against B (B1, B2). The halves of one renderer differ by its
    noise only, so relmse(A1, A2) / 4 is the noise of A's mean, and likewise for B; the
    noises are independent, so relmse(mean A, mean B) less both is what A and B differ by
    beyond their noise. Block means: d = (A - B) / B over N x N pixels and the three
    channels; the variance of a block's mean is the sum over its values of each value's
    variance, which the halves estimate as (x1 - x2)^2 / 4, so z = (A - B) / sigma is a
    standard normal where the renderers agree."""
    if len(args) not in (4, 5):
        die("compare: expected A1.pfm A2.pfm B1.pfm B2.pfm [N]")
    ims = [read_pfm(p) for p in args[:4]]
    for p, im in zip(args[1:4], ims[1:]):
        same_size(ims[0], im, args[0], p)
    n = int(args[4]) if len(args) == 5 else 8
    w, h = ims[0][0], ims[0][1]
    if n <= 0 or w % n or h % n:
        die("compare: %d does not divide %dx%d" % (n, w, h))
    a1, a2, b1, b2 = (im[2] for im in ims)
    am = [(x + y) / 2.0 for x, y in zip(a1, a2)]
    bm = [(x + y) / 2.0 for x, y in zip(b1, b2)]
    noise_a = relmse((w, h, a1), (w, h, a2)) / 4.0
    noise_b = relmse((w, h, b1), (w, h, b2)) / 4.0
    measured = relmse((w, h, am), (w, h, bm))
    print("relmse %.4g noise_a %.4g noise_b %.4g beyond_noise %.4g"
          % (measured, noise_a, noise_b, measured - noise_a - noise_b))
    zs = []
    # Pooled over the blocks, with each block's variance from its halves' block means
    # ((a1 - a2)^2 / 4), which holds even where neighbouring pixels' noise is correlated.
    num = den = pix_a = pix_b = blk_a = blk_b = 0.0
    for by in range(h // n):
        for bx in range(w // n):
            sa = sb = var = da = db = va = vb = 0.0
            for y in range(by * n, by * n + n):
                for i in range((y * w + bx * n) * 3, (y * w + bx * n + n) * 3):
                    sa += am[i]
                    sb += bm[i]
                    da += a1[i] - a2[i]
                    db += b1[i] - b2[i]
                    va += (a1[i] - a2[i]) ** 2 / 4.0
                    vb += (b1[i] - b2[i]) ** 2 / 4.0
            var = va + vb
            num += (sa - sb) ** 2
            den += (da * da + db * db) / 4.0
            pix_a += va
            pix_b += vb
            blk_a += da * da / 4.0
            blk_b += db * db / 4.0
            if sb > 0.0 and var > 0.0:
                zs.append(((sa - sb) / math.sqrt(var), sa / sb - 1.0, bx, by))
    if not zs:
        die("compare: no block with light and noise")
    # Pixel noise correlated between neighbours makes a block's variance differ from the
    # sum of its pixels': the factor, pooled over the blocks, for each renderer, and z
    # rescaled by the pooled factor of both.
    corr = den / (pix_a + pix_b) if pix_a + pix_b > 0 else 1.0
    print("block variance / summed pixel variance: A %.3f B %.3f (1 for independent pixels)"
          % (blk_a / pix_a if pix_a > 0 else float("nan"),
             blk_b / pix_b if pix_b > 0 else float("nan")))
    zs = [(z[0] / math.sqrt(corr),) + z[1:] for z in zs]
    worst = max(zs, key=lambda z: abs(z[0]))
    chi2 = sum(z[0] * z[0] for z in zs) / len(zs)
    beyond = sum(1 for z in zs if abs(z[0]) > 3.0)
    signed = sum(z[1] for z in zs) / len(zs)
    print("blocks %dx%d: %d, mean z^2 %.3f, beyond 3 sigma %d (%.2f%%; 0.27%% by chance), "
          "max |z| %.2f at block (%d, %d) (dev %+.4f), mean dev %+.4f, max |dev| %.4f; "
          "pooled (A - B)^2 / noise %.3f"
          % (n, n, len(zs), chi2, beyond, 100.0 * beyond / len(zs), abs(worst[0]), worst[2],
             worst[3], worst[1], signed, max(abs(z[1]) for z in zs),
             num / den if den > 0 else float("nan")))


def srgb8(v):
    v = clamp01(v)
    v = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1.0 / 2.4) - 0.055
    return int(v * 255.0 + 0.5)


def write_png(path, w, h, rows):
    """rows: h rows top first, each bytes of w RGB triples."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    raw = b"".join(b"\0" + r for r in rows)
    with open(path, "wb") as fh:
        fh.write(b"\x89PNG\r\n\x1a\n")
        fh.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        fh.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        fh.write(chunk(b"IEND", b""))


def cmd_side(args):
    if len(args) not in (3, 4):
        die("side: expected OUT.png A.pfm B.pfm [C.pfm]")
    a, b = read_pfm(args[1]), read_pfm(args[2])
    same_size(a, b, args[1], args[2])
    w, h = a[0], a[1]
    if len(args) == 4:
        c = read_pfm(args[3])
        same_size(a, c, args[1], args[3])
        panels = [a[2], b[2], c[2]]
        lin = [True, True, True]
    else:
        diff = [0.5 + 4.0 * (x - y) for x, y in zip(a[2], b[2])]
        panels = [a[2], b[2], diff]
        lin = [True, True, False]
    rows = []
    for y in range(h - 1, -1, -1):  # PFM rows run bottom-up
        row = bytearray()
        for px, is_lin in zip(panels, lin):
            vals = px[y * w * 3:(y + 1) * w * 3]
            row.extend(srgb8(v) if is_lin else int(clamp01(v) * 255.0 + 0.5) for v in vals)
        rows.append(bytes(row))
    write_png(args[0], w * len(panels), h, rows)
    print("%s: %dx%d" % (args[0], w * len(panels), h))


def loglog_crossing(points, target):
    """points: (x, relmse) with x growing. The x where relmse crosses target, by linear
    interpolation of log relmse against log x (error ~ x^-slope between points); beyond
    the ends, the nearest two points' slope extrapolates (marked)."""
    pts = sorted(p for p in points if p[0] > 0 and p[1] > 0)
    if len(pts) < 2:
        return None, "too few points"
    for (x0, e0), (x1, e1) in zip(pts, pts[1:]):
        if (e0 - target) * (e1 - target) <= 0 and e0 != e1:
            t = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0))), "interpolated"
    (x0, e0), (x1, e1) = (pts[-2], pts[-1]) if pts[-1][1] > target else (pts[0], pts[1])
    if e0 == e1:
        return None, "flat"
    t = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
    return math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0))), "extrapolated"


def cmd_fit(args):
    """CSV rows renderer,spp,seconds,relmse (a header line first): per renderer the spp and
    the seconds at which relmse reaches TARGET, and their ratio."""
    if len(args) not in (2, 3):
        die("fit: expected CSV TARGET [REF_ERROR]")
    try:
        target = float(args[1])
        ref_err = float(args[2]) if len(args) == 3 else 0.0
    except ValueError:
        die("fit: TARGET and REF_ERROR must be numbers, got %s" % args[1:])
    if not (target > 0 and ref_err >= 0):
        die("fit: expected TARGET > 0 and REF_ERROR >= 0")
    rows = {}
    try:
        with open(args[0], "r", encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except OSError as e:
        die("%s: %s" % (args[0], e.strerror))
    hdr = lines[0].split(",")
    need = ("renderer", "spp", "seconds", "relmse")
    for k in need:
        if k not in hdr:
            die("%s: no column '%s'" % (args[0], k))
    idx = [hdr.index(k) for k in need]
    for ln, line in enumerate(lines[1:], 2):
        f = line.split(",")
        try:
            name, spp, sec, err = f[idx[0]], float(f[idx[1]]), float(f[idx[2]]), float(f[idx[3]])
        except (ValueError, IndexError):
            die("%s:%d: bad row '%s'" % (args[0], ln, line))
        # The reference's noise is independent of the image's: measured = true + ref_err.
        rows.setdefault(name, []).append((spp, sec, err - ref_err))
    times = {}
    for name, rs in rows.items():
        s, how_s = loglog_crossing([(r[0], r[2]) for r in rs], target)
        t, how_t = loglog_crossing([(r[1], r[2]) for r in rs], target)
        times[name] = t
        print("%s: relmse %.3g reached at %s spp (%s), %s s (%s)"
              % (name, target, "%.0f" % s if s else "?", how_s,
                 "%.2f" % t if t else "?", how_t))
    if times.get("trac0r") and times.get("cycles"):
        print("time ratio trac0r / cycles to relmse %.3g: %.3f (target <= 0.5)"
              % (target, times["trac0r"] / times["cycles"]))


def main():
    cmds = {"mean": cmd_mean, "relmse": cmd_relmse, "halves": cmd_halves,
            "blocks": cmd_blocks, "compare": cmd_compare, "side": cmd_side, "fit": cmd_fit}
    if len(sys.argv) < 2 or sys.argv[1] not in cmds:
        die("usage: pfmtool.py mean|relmse|halves|blocks|compare|side|fit ... (see the file's docstring)")
    cmds[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
