#!/usr/bin/env python3
"""Writes the test images in this directory (run from here): checker.png (the 4x2 RGBA
texture test_surface.c checks texel for texel), truncated.png (its first half), zero.png
(a 0x0 PNG), huge.png (a header declaring 100000 x 100000 texels), not_image.png (text)
sky.hdr (a 32x16 Radiance sky with a small bright sun, flat texels), sky_rle.hdr (the
same sky in run-length scanlines), and checker's colours as a 24-bit BMP (checker.bmp,
rows bottom up) and a run-length TGA (checker_rle.tga). rle_past_end.tga and
dht_overflow.jpg are fuzz_texture's finds, kept as they were found."""
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

def rle_channel(vals):
    """Radiance's new-style run-length coding of one channel of a scanline."""
    out, i = bytearray(), 0
    while i < len(vals):
        run = 1
        while i + run < len(vals) and run < 127 and vals[i + run] == vals[i]:
            run += 1
        if run >= 3:
            out += bytes([128 + run, vals[i]])
            i += run
        else:
            lit = 1
            while i + lit < len(vals) and lit < 128 and not (
                    i + lit + 2 < len(vals) and vals[i + lit] == vals[i + lit + 1] == vals[i + lit + 2]):
                lit += 1
            out += bytes([lit]) + bytes(vals[i:i + lit])
            i += lit
    return out

rle = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
flat = out[len(rle):]
for j in range(H):
    line = flat[4 * W * j:4 * W * (j + 1)]
    rle += bytes([2, 2, W >> 8, W & 255])
    for c in range(4):
        rle += rle_channel(list(line[c::4]))
open('sky_rle.hdr', 'wb').write(rle)

# checker.png's colours (alpha dropped) as a 24-bit BMP: BGR, rows bottom up, padded to 4 bytes.
bmp_rows = b''
for y in (1, 0):
    r = b''.join(bytes([(p >> 16) & 255, (p >> 8) & 255, p & 255]) for p in tex[4 * y:4 * y + 4])
    bmp_rows += r + b'\x00' * (-len(r) % 4)
info = struct.pack('<IiiHHIIiiII', 40, 4, 2, 1, 24, 0, len(bmp_rows), 2835, 2835, 0, 0)
open('checker.bmp', 'wb').write(b'BM' + struct.pack('<IHHI', 14 + 40 + len(bmp_rows), 0, 0, 54)
                                + info + bmp_rows)

# ... and as a run-length TGA (type 10, 32 bits BGRA, top row first): each row one raw packet
# of 2 texels and one run packet of 2 copies of its third texel (texel 4 differs: the TGA
# is compared with its own list below, not with checker.png).
tga = bytearray(struct.pack('<BBBHHBHHHHBB', 0, 0, 10, 0, 0, 0, 0, 0, 4, 2, 32, 0x28))
for y in range(2):
    px = [bytes([(p >> 16) & 255, (p >> 8) & 255, p & 255, p >> 24]) for p in tex[4 * y:4 * y + 4]]
    tga += bytes([1]) + px[0] + px[1] + bytes([128 + 1]) + px[2]
open('checker_rle.tga', 'wb').write(tga)
