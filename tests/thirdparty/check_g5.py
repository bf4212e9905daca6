#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks fdsurf's G5 cubics against the exact curves of the input file.

usage: check_g5.py INPUT FILE.gcode [fdsurf plot options: --view --lines --fit --margin --tolerance]

Written from the documented G5 semantics, not from fdsurf's writer:
  Marlin (marlinfw.org/docs/gcode/G005.html) and LinuxCNC (G-code reference,
  "G5 Cubic spline"): `G5 I J P Q X Y` is the cubic Bézier curve from the
  current position S through the control points S + (I, J) and E + (P, Q) to
  E = (X, Y); P and Q are required, and so are I and J on the first G5 of a
  series (a G5 without them continues with I J = -(previous P Q)).

The exact curves come from INPUT itself, read here again: a BPT file's Bézier
patches (isolines at s, t = i/(n-1): the patch's rows combined by Bernstein
weights, which makes each isoline a Bézier curve) or a JSON file's
"hermite-chain" curves (Bézier points P0, P0 + T0/3, P1 - T1/3, P1). They are
placed on the page by the map docs/toolpaths.md states (view top/front/side,
the exact bounding box, scale to --fit, centred; with --fit none scale 1 and the
margin). Every G5 must lie within --tolerance of an exact curve, point for
point at the same parameter (17 samples), and every exact curve that is not a
single point must be drawn by some G5.
"""
import argparse
import math
import json
import re
import sys

VIEWS = {"top": (0, 1), "front": (0, 2), "side": (1, 2)}


def fail(message):
    print(f"check_g5: {message}", file=sys.stderr)
    sys.exit(1)


def bernstein(u):
    v = 1 - u
    return (v * v * v, 3 * u * v * v, 3 * u * u * v, u * u * u)


def bezier_point(b, u):
    w = bernstein(u)
    return tuple(sum(w[k] * b[k][c] for k in range(4)) for c in range(len(b[0])))


def read_bpt(path, lines):
    numbers = open(path, encoding="utf-8").read().split()
    count, pos = int(numbers[0]), 1
    curves = []
    params = [i / (lines - 1) for i in range(lines)]
    for _ in range(count):
        if numbers[pos:pos + 2] != ["3", "3"]:
            fail(f"{path}: only bicubic patches are read here")
        pos += 2
        pts = [tuple(float(v) for v in numbers[pos + 3 * k:pos + 3 * k + 3]) for k in range(16)]
        pos += 48
        grid = [pts[4 * i:4 * i + 4] for i in range(4)]
        for a in params:
            w = bernstein(a)
            rows = [tuple(sum(w[i] * grid[i][j][c] for i in range(4)) for c in range(3)) for j in range(4)]
            cols = [tuple(sum(w[j] * grid[i][j][c] for j in range(4)) for c in range(3)) for i in range(4)]
            curves += [rows, cols]
    return curves


def read_hermite_chains(path):
    data = json.load(open(path, encoding="utf-8"))
    curves = []
    for entry in data.get("curves", []):
        if entry.get("type") != "hermite-chain":
            fail(f"{path}: only hermite-chain curves are read here")
        pts = [tuple(p) + (0.0,) * (3 - len(p)) for p in entry["points"]]
        vecs = []
        for v in entry["vectors"]:
            pair = (v["in"], v["out"]) if isinstance(v, dict) else (v, v)
            vecs.append(tuple(tuple(x) + (0.0,) * (3 - len(x)) for x in pair))
        for k in range(len(pts) - 1):
            p0, p1, t0, t1 = pts[k], pts[k + 1], vecs[k][1], vecs[k + 1][0]
            curves.append([p0, tuple(p0[c] + t0[c] / 3 for c in range(3)),
                           tuple(p1[c] - t1[c] / 3 for c in range(3)), p1])
    return curves


def bezier_range(values):
    """Exact min and max of a cubic Bézier coordinate over [0, 1]."""
    b0, b1, b2, b3 = values
    # derivative / 3 = a u^2 + b u + c
    a = -b0 + 3 * b1 - 3 * b2 + b3
    b = 2 * (b0 - 2 * b1 + b2)
    c = b1 - b0
    ts = [0.0, 1.0]
    if abs(a) > 1e-15:
        disc = b * b - 4 * a * c
        if disc >= 0:
            ts += [(-b + s * math.sqrt(disc)) / (2 * a) for s in (1, -1)]
    elif abs(b) > 1e-15:
        ts.append(-c / b)
    vals = [bezier_point([(v,) for v in values], t)[0] for t in ts if 0 <= t <= 1]
    return min(vals), max(vals)


def place(curves, view, fit, margin):
    ax = VIEWS[view]
    flat = [[(p[ax[0]], p[ax[1]]) for p in cubic] for cubic in curves]
    lo = [min(bezier_range([p[c] for p in cubic])[0] for cubic in flat) for c in range(2)]
    hi = [max(bezier_range([p[c] for p in cubic])[1] for cubic in flat) for c in range(2)]
    bw, bh = hi[0] - lo[0], hi[1] - lo[1]
    if fit:
        width, height = fit
        scale = min((width - 2 * margin) / bw if bw > 0 else math.inf,
                    (height - 2 * margin) / bh if bh > 0 else math.inf)
    else:
        scale = 1.0
        width, height = bw + 2 * margin, bh + 2 * margin
    off = ((width - bw * scale) / 2 - lo[0] * scale, (height - bh * scale) / 2 - lo[1] * scale)
    return [[(scale * x + off[0], scale * y + off[1]) for x, y in cubic] for cubic in flat]


def strip_comments(line):
    line = re.sub(r"\([^)]*\)", " ", line)
    return line.split(";", 1)[0]


def read_g5(path):
    """Every G5 as its four Bézier control points, from the documented semantics."""
    pieces = []
    pos = [0.0, 0.0]
    motion = None
    last_pq = None
    for number, raw in enumerate(open(path, encoding="utf-8"), 1):
        words = dict()
        gcodes = []
        for letter, value in re.findall(r"([A-Za-z])\s*([-+]?[0-9]*\.?[0-9]+)", strip_comments(raw)):
            letter = letter.upper()
            if letter == "G":
                gcodes.append(float(value))
            else:
                words[letter] = float(value)
        for g in gcodes:
            if g in (20.0, 91.0):
                fail(f"{path}:{number}: G{g:g} is not handled by this checker")
            if g in (0.0, 1.0, 5.0):
                motion = g
        if "X" not in words and "Y" not in words:
            continue
        end = [words.get("X", pos[0]), words.get("Y", pos[1])]
        if motion == 5.0:
            if "P" not in words or "Q" not in words:
                fail(f"{path}:{number}: G5 without both P and Q")
            if ("I" in words) != ("J" in words):
                fail(f"{path}:{number}: G5 with only one of I and J")
            if "I" in words:
                ij = (words["I"], words["J"])
            elif last_pq is None:
                fail(f"{path}:{number}: the first G5 of a series needs I and J")
            else:
                ij = (-last_pq[0], -last_pq[1])
            pq = (words["P"], words["Q"])
            pieces.append((number, [tuple(pos), (pos[0] + ij[0], pos[1] + ij[1]),
                                    (end[0] + pq[0], end[1] + pq[1]), tuple(end)]))
            last_pq = pq
        else:
            last_pq = None
        pos = end
    return pieces


def main():
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument("input")
    parser.add_argument("gcode")
    parser.add_argument("--view", default="iso")
    parser.add_argument("--lines", default="8")
    parser.add_argument("--fit")
    parser.add_argument("--margin", type=float, default=5.0)
    parser.add_argument("--tolerance", type=float, default=0.05)
    args, _ = parser.parse_known_args()
    if args.view not in VIEWS:
        fail(f"view {args.view}: only top, front and side are placed by this checker")
    if args.input.endswith(".bpt"):
        if "x" in args.lines:
            fail("--lines UxV: only U (both families) is read by this checker")
        curves = read_bpt(args.input, int(args.lines))
    else:
        curves = read_hermite_chains(args.input)
    fit = tuple(float(v) for v in args.fit.split("x")) if args.fit and args.fit != "none" else None
    exact = place(curves, args.view, fit, args.margin)
    tol = args.tolerance

    # Exact curves by their end points, in cells of 4 tolerances.
    cell = 4 * tol
    index = {}
    key = lambda p: (math.floor(p[0] / cell), math.floor(p[1] / cell))
    for i, cubic in enumerate(exact):
        for end in (cubic[0], cubic[3]):
            index.setdefault(key(end), set()).add(i)

    samples = [k / 16 for k in range(17)]
    drawn = set()
    worst = 0.0
    pieces = read_g5(args.gcode)
    if not pieces:
        fail(f"{args.gcode}: no G5 found")
    for number, g5 in pieces:
        kx, ky = key(g5[0])
        candidates = set()
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                candidates |= index.get((kx + dx, ky + dy), set())
        best = math.inf
        for i in candidates:
            for reverse in (False, True):
                ref = exact[i][::-1] if reverse else exact[i]
                d = max(math.dist(bezier_point(g5, u), bezier_point(ref, u)) for u in samples)
                if d <= tol:
                    drawn.add(i)
                best = min(best, d)
        if best > tol:
            fail(f"{args.gcode}:{number}: this G5 is {best:.6g} from the nearest exact curve, "
                 f"more than the tolerance {tol:g}")
        worst = max(worst, best)
    missing = [i for i, c in enumerate(exact)
               if i not in drawn and max(math.dist(c[0], p) for p in c) > tol / 10]
    if missing:
        fail(f"{args.gcode}: {len(missing)} exact curves are drawn by no G5 (the first: curve {missing[0]})")
    print(f"check_g5: {args.gcode}: {len(pieces)} G5 cubics match {len(exact)} exact curves "
          f"(largest distance {worst:.3g}, tolerance {tol:g})")


if __name__ == "__main__":
    main()
