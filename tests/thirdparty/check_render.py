#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Renders fdsurf's SVG and HPGL with third-party programs and compares what they draw.

usage: check_render.py STROKES.json --svg FILE.svg --hpgl FILE.hpgl

- The SVG goes through rsvg-convert (librsvg) to a PNG at 100 dpi. The bounding
  box of its non-white pixels, in mm, must match the strokes' bounding box from
  STROKES.json. The SVG is y-down and fdsurf's coordinates are y-up, so y is
  flipped with the page height. The PNG shows the SVG's viewBox, which must
  hold the page and may reach past it (a drawing kept at coordinates outside
  its page); pixels are placed from the viewBox's origin.
- The HPGL goes through Debian's hp2xx. The "Coordinate range" that hp2xx
  reports in plotter units (1/40 mm) must equal the strokes' bounding box.
  hp2xx also renders it true-size (-t) to a PBM bitmap at 100 dpi, and the
  drawn width and height must match.

Both renderers must succeed. The pixel comparisons allow one pixel (0.254 mm)
plus half the pen width on each side. STROKES.json must come from
`fdsurf plot --format json` with the same options (for HPGL, --quantum 0.025).
"""
import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import zlib

DPI = 100
PIXEL_MM = 25.4 / DPI


def fail(message):
    print(f"check_render: {message}", file=sys.stderr)
    sys.exit(1)


def run(command):
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        fail(f"{command[0]} failed ({result.returncode}): {result.stderr.strip()}")
    return result


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def read_png(path):
    """Returns (width, height, rows) with rows of per-pixel tuples; 8-bit grey/RGB(A) only."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(f"{path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        fail(f"{path}: unsupported PNG (depth {depth}, colour type {colour}, interlace {interlace})")
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            line[i] = (line[i] + (0, a, b, (a + b) // 2, paeth(a, b, c))[kind]) & 0xFF
        rows.append([tuple(line[x * channels:(x + 1) * channels]) for x in range(width)])
        previous = line
    return width, height, rows


def drawn_box_png(rows):
    def ink(px):
        if len(px) in (2, 4) and px[-1] < 32:
            return False  # transparent
        return min(px[:3] if len(px) >= 3 else px[:1]) < 200
    xs, ys = [], []
    for y, row in enumerate(rows):
        for x, px in enumerate(row):
            if ink(px):
                xs.append(x)
                ys.append(y)
    if not xs:
        fail("the rendering is blank")
    return min(xs), min(ys), max(xs), max(ys)


def drawn_box_pbm(path):
    with open(path, "rb") as f:
        data = f.read()
    tokens = re.match(rb"P4\s+(?:#[^\n]*\n\s*)*(\d+)\s+(\d+)\s", data)
    if not tokens:
        fail(f"{path}: not a binary PBM")
    width, height = int(tokens.group(1)), int(tokens.group(2))
    bits = data[tokens.end():]
    stride = (width + 7) // 8
    xs, ys = [], []
    for y in range(height):
        row = bits[y * stride:(y + 1) * stride]
        for x in range(width):
            if row[x // 8] & (0x80 >> (x % 8)):
                xs.append(x)
                ys.append(y)
    if not xs:
        fail(f"{path}: hp2xx drew nothing")
    return min(xs), min(ys), max(xs), max(ys)


def near(what, got, want, slack):
    if abs(got - want) > slack:
        fail(f"{what}: renderer {got:.3f} mm, fdsurf {want:.3f} mm (allowed ±{slack:.3f})")


def svg_view(svg):
    """The root's viewBox: min-x, min-y, width, height (the output's units, y down)."""
    with open(svg, encoding="utf-8") as f:
        match = re.search(r'<svg[^>]*\sviewBox="([^"]*)"', f.read())
    if not match:
        fail(f"{svg}: no viewBox on the root")
    return [float(v) for v in match.group(1).replace(",", " ").split()]


def check_svg(svg, strokes, tmp):
    page = strokes["height"]
    vx, vy, vw, vh = svg_view(svg)
    eps = 1e-9
    if vx > eps or vy > eps or vx + vw < strokes["width"] - eps or vy + vh < page - eps:
        fail(f"{svg}: the viewBox {vx} {vy} {vw} {vh} does not hold the page "
             f"{strokes['width']} x {page}")
    left, top = vx, page - vy  # the drawing's coordinates of pixel (0, 0)'s corner
    x0, y0, x1, y1 = strokes["bbox"][0], strokes["bbox"][1], strokes["bbox"][-3 if strokes["dims"] == 3 else 2], \
        strokes["bbox"][-2 if strokes["dims"] == 3 else 3]
    png = os.path.join(tmp, "svg.png")
    run(["rsvg-convert", "--dpi-x", str(DPI), "--dpi-y", str(DPI), "-b", "white", "-o", png, svg])
    width, height, rows = read_png(png)
    px0, py0, px1, py1 = drawn_box_png(rows)
    slack = PIXEL_MM + 0.125 + PIXEL_MM  # a pixel each way plus half the 0.25 mm pen
    near(f"{svg}: view width", width * PIXEL_MM, vw, PIXEL_MM)
    near(f"{svg}: left edge", left + px0 * PIXEL_MM, x0, slack)
    near(f"{svg}: right edge", left + (px1 + 1) * PIXEL_MM, x1, slack)
    near(f"{svg}: bottom edge", top - (py1 + 1) * PIXEL_MM, y0, slack)
    near(f"{svg}: top edge", top - py0 * PIXEL_MM, y1, slack)
    print(f"check_render: {svg}: rsvg-convert drew [{left + px0 * PIXEL_MM:.2f}, {top - (py1 + 1) * PIXEL_MM:.2f}]"
          f"..[{left + (px1 + 1) * PIXEL_MM:.2f}, {top - py0 * PIXEL_MM:.2f}] mm, fdsurf [{x0}, {y0}]..[{x1}, {y1}] mm"
          f" (viewBox {vx:g} {vy:g} {vw:g} {vh:g})")


def check_hpgl(hpgl, strokes, tmp):
    if strokes["quantum"] != 0.025 or strokes["units"] != "mm":
        fail("HPGL is compared with strokes written at --quantum 0.025 in mm")
    x0, y0, x1, y1 = (round(v / 0.025) for v in strokes["bbox"][:4])
    pbm = os.path.join(tmp, "hpgl.pbm")
    result = run(["hp2xx", "-m", "pbm", "-t", "-d", str(DPI), "-p", "1", "-f", pbm, hpgl])
    report = result.stdout + result.stderr
    match = re.search(r"Coordinate range: \((-?\d+), (-?\d+)\) \.\.\. \((-?\d+), (-?\d+)\)", report)
    if not match:
        fail(f"{hpgl}: hp2xx did not report a coordinate range:\n{report}")
    got = tuple(int(v) for v in match.groups())
    if got != (x0, y0, x1, y1):
        fail(f"{hpgl}: hp2xx reads the range {got} plotter units, fdsurf drew {(x0, y0, x1, y1)}")
    px0, py0, px1, py1 = drawn_box_pbm(pbm)
    slack = 2 * PIXEL_MM + 0.1  # a pixel each way plus the 0.1 mm pen
    near(f"{hpgl}: drawn width", (px1 - px0 + 1) * PIXEL_MM, (x1 - x0) * 0.025, slack)
    near(f"{hpgl}: drawn height", (py1 - py0 + 1) * PIXEL_MM, (y1 - y0) * 0.025, slack)
    print(f"check_render: {hpgl}: hp2xx reads ({x0}, {y0})..({x1}, {y1}) plotter units as drawn, "
          f"renders {(px1 - px0 + 1) * PIXEL_MM:.2f} x {(py1 - py0 + 1) * PIXEL_MM:.2f} mm")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("strokes")
    parser.add_argument("--svg")
    parser.add_argument("--hpgl")
    args = parser.parse_args()
    with open(args.strokes, encoding="utf-8") as f:
        strokes = json.load(f)
    with tempfile.TemporaryDirectory() as tmp:
        if args.svg:
            check_svg(args.svg, strokes, tmp)
        if args.hpgl:
            check_hpgl(args.hpgl, strokes, tmp)


if __name__ == "__main__":
    main()
