#!/usr/bin/env python3
"""Checks an X screenshot (xwd format, as `xwd -root` writes it) of the
preview window showing the Cornell box, and saves it as a PNG.

    check_screenshot.py SCREEN.xwd RENDER.png OUT.png

Passes when the screen holds a window the size of the render whose pixels
match the render written by the same run (the preview shows the image after
the latest pass; the file holds the final one, so they agree closely but not
exactly), and the red and green walls are where the render has them.
Only the standard library: the xwd and PNG formats are simple enough.
"""

import struct
import sys
import zlib


def read_xwd(path):
    data = open(path, "rb").read()
    h = struct.unpack(">25I", data[:100])
    header_size, version, fmt, depth, width, height = h[0], h[1], h[2], h[3], h[4], h[5]
    byte_order, bits_per_pixel, bytes_per_line = h[7], h[11], h[12]
    red_mask, green_mask, blue_mask, ncolors = h[14], h[15], h[16], h[19]
    if version != 7 or fmt != 2 or bits_per_pixel != 32:
        sys.exit(f"unsupported xwd: version {version}, format {fmt}, {bits_per_pixel} bpp")
    start = header_size + 12 * ncolors
    order = "<" if byte_order == 0 else ">"
    shift = lambda m: (m & -m).bit_length() - 1
    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    pixels = []
    for y in range(height):
        row = data[start + y * bytes_per_line:start + y * bytes_per_line + 4 * width]
        words = struct.unpack(f"{order}{width}I", row)
        pixels.append([((w & red_mask) >> rs, (w & green_mask) >> gs, (w & blue_mask) >> bs)
                       for w in words])
    return width, height, pixels


def read_png(path):
    """8-bit RGB, non-interlaced PNGs (what `tracer` writes)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, bit_depth, colour = struct.unpack(">IIBB", body[:10])
            assert (bit_depth, colour) == (8, 2), "expected 8-bit RGB"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = 3 * width
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b = prev[i]
            c = prev[i - 3] if i >= 3 else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        rows.append([tuple(line[3 * x:3 * x + 3]) for x in range(width)])
        prev = line
    return width, height, rows


def write_png(path, width, height, pixels):
    raw = b"".join(b"\x00" + bytes(c for p in row for c in p) for row in pixels)
    chunk = lambda kind, body: (struct.pack(">I", len(body)) + kind + body
                                + struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    open(path, "wb").write(png)


def main():
    screen_path, render_path, out_path = sys.argv[1:4]
    sw, sh, screen = read_xwd(screen_path)
    write_png(out_path, sw, sh, screen)
    rw, rh, render = read_png(render_path)

    # Find the window: the offset where the screen best matches the render,
    # searched over the screen on a coarse grid of sample points.
    samples = [(x, y) for y in range(4, rh - 4, rh // 12) for x in range(4, rw - 4, rw // 12)]

    def mismatch(ox, oy):
        total = 0
        for x, y in samples:
            s, r = screen[oy + y][ox + x], render[y][x]
            total += sum(abs(a - b) for a, b in zip(s, r))
        return total / (3 * len(samples))

    best = min(((mismatch(ox, oy), ox, oy) for oy in range(0, sh - rh + 1)
                for ox in range(0, sw - rw + 1, 1)), key=lambda t: t[0])
    error, ox, oy = best
    print(f"screen {sw}x{sh}; render {rw}x{rh} found at ({ox}, {oy}), mean difference {error:.1f}/255")
    if error > 12:
        sys.exit("FAILED: no window on the screen shows the render")

    # The whole window, pixel by pixel, against the render.
    diff = sum(abs(a - b) for y in range(rh) for x in range(rw)
               for a, b in zip(screen[oy + y][ox + x], render[y][x])) / (3 * rw * rh)
    red = sum(1 for y in range(rh) for x in range(rw // 4)
              if (lambda p: p[0] > 2 * p[1] and p[0] > 60)(screen[oy + y][ox + x]))
    green = sum(1 for y in range(rh) for x in range(3 * rw // 4, rw)
                if (lambda p: p[1] > 1.5 * p[0] and p[1] > 60)(screen[oy + y][ox + x]))
    print(f"window against the render: mean difference {diff:.1f}/255; "
          f"red-wall pixels on the left {red}, green-wall pixels on the right {green}")
    if diff > 10 or red < rw * rh // 40 or green < rw * rh // 40:
        sys.exit("FAILED: the window does not show the Cornell box as rendered")
    print(f"ok: screenshot saved to {out_path}")


if __name__ == "__main__":
    main()
