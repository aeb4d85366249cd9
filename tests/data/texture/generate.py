#!/usr/bin/env python3
"""Writes the test images in this directory (run from here): checker.png (the 4x2 RGBA
texture test_surface.c checks texel for texel), truncated.png (its first half), zero.png
(a 0x0 PNG), huge.png (a header declaring 100000 x 100000 texels), not_image.png (text)
and sky.hdr (a 32x16 Radiance sky with a small bright sun)."""
import math, struct, zlib

def chunk(t, d):
    c = struct.pack('>I', len(d)) + t + d
    return c + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)

def png(w, h, rows):
    raw = b''.join(b'\x00' + r for r in rows)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 6, 0, 0, 0))
            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))

tex = [0xff0000ff, 0xff00ff00, 0xffff0000, 0x80808080, 0xff204060, 0xffffffff, 0xff000000, 0xff10c0a0]
rows = [b''.join(bytes([p & 255, (p >> 8) & 255, (p >> 16) & 255, p >> 24]) for p in tex[4 * y:4 * y + 4])
        for y in range(2)]
good = png(4, 2, rows)
open('checker.png', 'wb').write(good)
open('truncated.png', 'wb').write(good[:len(good) // 2])
open('zero.png', 'wb').write(png(0, 0, []))
hdr = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 100000, 100000, 8, 6, 0, 0, 0))
open('huge.png', 'wb').write(hdr + chunk(b'IDAT', zlib.compress(b'\x00' * 64)) + chunk(b'IEND', b''))
open('not_image.png', 'wb').write(b'this is not an image\n')

def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return bytes([0, 0, 0, 0])
    e = math.frexp(m)[1]
    s = 256.0 / (2.0 ** e)
    return bytes([int(r * s), int(g * s), int(b * s), e + 128])

W, H = 32, 16
out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
for j in range(H):
    t = (j + 0.5) / H
    for i in range(W):
        if t < 0.5:
            k = t / 0.5
            r, g, b = 0.3 + 0.6 * k, 0.5 + 0.4 * k, 1.0
        else:
            r, g, b = 0.25, 0.22, 0.2
        if j == 4 and i == 20:
            r, g, b = 400.0, 380.0, 300.0
        out += rgbe(r, g, b)
open('sky.hdr', 'wb').write(out)
