#!/usr/bin/env python3
"""Pixel counts in a rectangle of 8-bit RGBA PNGs, for the CLI's window tests (stdlib only).

  png_region.py not-colour FILE.png X0 Y0 X1 Y1 R,G,B
      prints how many pixels of [X0, X1) x [Y0, Y1) differ from the colour (by more than 2 per
      channel), and how many pixels the rectangle has
  png_region.py differ A.png B.png X0 Y0 X1 Y1
      prints how many pixels of the rectangle differ between the two images, and the total
"""
import struct
import sys
import zlib


def read_rgba(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG")
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour != 6 or interlace:
                sys.exit(f"{path}: not 8-bit RGBA without interlace")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * 4
    rows, prev = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 4] if i >= 4 else 0
            b = prev[i]
            c = prev[i - 4] if i >= 4 else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, rows


def pixels(rows, x0, y0, x1, y1):
    for y in range(y0, y1):
        for x in range(x0, x1):
            yield rows[y][4 * x:4 * x + 3]


def main(argv):
    if len(argv) == 8 and argv[1] == "not-colour":
        _, _, rows = read_rgba(argv[2])
        x0, y0, x1, y1 = map(int, argv[3:7])
        colour = [round(float(c) * 255) if "." in c else int(c) for c in argv[7].split(",")]
        count = sum(1 for p in pixels(rows, x0, y0, x1, y1)
                    if any(abs(p[k] - colour[k]) > 2 for k in range(3)))
    elif len(argv) == 8 and argv[1] == "differ":
        _, _, a = read_rgba(argv[2])
        _, _, b = read_rgba(argv[3])
        x0, y0, x1, y1 = map(int, argv[4:8])
        count = sum(1 for p, q in zip(pixels(a, x0, y0, x1, y1), pixels(b, x0, y0, x1, y1)) if p != q)
    else:
        sys.exit(__doc__)
    print(count, (x1 - x0) * (y1 - y0))


if __name__ == "__main__":
    main(sys.argv)
