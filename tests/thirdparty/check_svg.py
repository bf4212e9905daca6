#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks fdsurf's SVG reader on a real SVG file against Inkscape and librsvg.

usage: check_svg.py CURVES_TOOL FDSURF FILE.svg

CURVES_TOOL is svg_curves_json (this folder): ReadSvg's curves as JSON, each
with the element it came from. The file is first prepared (prepare()): every
element gets an id, strokes, filters, clips, masks and markers are removed
(Inkscape's --query-all gives the visual box, stroke and filter included; with
none of them the visual box is the geometric one), the elements fdsurf leaves
out are deleted (text, images, <switch>, CSS sheets) and Inkscape's private
shape and path-effect attributes are dropped so that Inkscape draws the `d`
written in the file, as every SVG renderer does.

1. Extents. The exact box of our curves per element (the cubic's extremes,
   from the roots of its derivative, computed here) equals the box
   `inkscape --query-all` prints for that element within
   r(x) + r(w) + 1e-6 mm, r the rounding of Inkscape's 6 significant
   digits (px, converted to mm) and 1e-6 mm the arc bound of the reader.
   A <use> adds its box to the element it shows; an element inside a group a
   <use> shows, or shown by a <use> inside it, is left to its ancestor (a box
   per instance is not known here), and every drawn element must be checked
   itself or through an ancestor.
2. Pixels. rsvg-convert renders the prepared file with an outline style sheet
   (no fill, black round strokes, each shape's stroke 1 device pixel thick at
   its thinnest: stroke-width = 1 px / the smallest singular value of its
   transform, which this script composes from the file's transforms). Our
   drawing is `fdsurf plot --format json --fit none` of the original file,
   the strokes as 1 px polylines in an SVG written here, rendered by
   rsvg-convert at the same size. Each inked pixel of one lies within D px of
   an inked pixel of the other, both ways (see max_distance()).
"""
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_render import read_png  # noqa: E402  (one home for the PNG decoder)

SVG_NS = "http://www.w3.org/2000/svg"
XLINK_HREF = "{http://www.w3.org/1999/xlink}href"
MM_PER_PX = 25.4 / 96
ARC_BOUND_MM = 1e-6  # SvgOptions::arc_tolerance's default
CANVAS_PX = 600  # the longer side of the rendering
INK_BELOW = 250  # a channel below this is ink (coverage above ~2 %)
SHAPES = {"path", "line", "polyline", "polygon", "rect", "circle", "ellipse"}
LEFT_OUT = {"text", "flowRoot", "image", "switch", "foreignObject", "style"}
DROPPED_ATTRIBUTES = {"stroke", "stroke-width", "filter", "clip-path", "mask", "marker",
                      "marker-start", "marker-mid", "marker-end"}
DROPPED_STYLE = re.compile(r"^\s*(stroke(-width)?|filter|clip-path|mask|marker(-\w+)?)\s*:")
UNIT_MM = {"": MM_PER_PX, "px": MM_PER_PX, "mm": 1.0, "cm": 10.0, "in": 25.4,
           "pt": 25.4 / 72, "pc": 25.4 / 6}


def fail(message):
    print(f"check_svg: {message}", file=sys.stderr)
    sys.exit(1)


def run(command):
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        fail(f"{command[0]} failed ({result.returncode}): {result.stderr.strip()}")
    return result.stdout


def local(tag):
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


# --- affine maps (a b c d e f), SVG's matrix order ---------------------------------------

def compose(outer, inner):
    a, b, c, d, e, f = outer
    a2, b2, c2, d2, e2, f2 = inner
    return (a * a2 + c * b2, b * a2 + d * b2, a * c2 + c * d2, b * c2 + d * d2,
            a * e2 + c * f2 + e, b * e2 + d * f2 + f)


def parse_transform(text):
    """A transform list as one affine map (SVG 1.1 §7.6), written from the spec."""
    total = (1, 0, 0, 1, 0, 0)
    for name, args in re.findall(r"(\w+)\s*\(([^)]*)\)", text or ""):
        v = [float(x) for x in re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", args)]
        if name == "matrix":
            m = tuple(v)
        elif name == "translate":
            m = (1, 0, 0, 1, v[0], v[1] if len(v) > 1 else 0)
        elif name == "scale":
            m = (v[0], 0, 0, v[1] if len(v) > 1 else v[0], 0, 0)
        elif name == "rotate":
            r = math.radians(v[0])
            m = (math.cos(r), math.sin(r), -math.sin(r), math.cos(r), 0, 0)
            if len(v) == 3:
                m = compose((1, 0, 0, 1, v[1], v[2]), compose(m, (1, 0, 0, 1, -v[1], -v[2])))
        elif name in ("skewX", "skewY"):
            t = math.tan(math.radians(v[0]))
            m = (1, 0, t, 1, 0, 0) if name == "skewX" else (1, t, 0, 1, 0, 0)
        else:
            fail(f"unknown transform {name}")
        total = compose(total, m)
    return total


def singular_values(m):
    """(smallest, largest) stretch of m's linear part: its singular values."""
    a, b, c, d = m[:4]
    s = a * a + b * b + c * c + d * d
    det = a * d - b * c
    root = math.sqrt(max(0.0, s * s - 4 * det * det))
    return math.sqrt(max(0.0, (s - root) / 2)), math.sqrt((s + root) / 2)


# --- the prepared copy ---------------------------------------------------------------------

def root_mapping(root):
    """(mm per user unit, page width mm, page height mm, viewBox) of the root; uniform only."""
    def length_mm(text):
        match = re.fullmatch(r"\s*([-+.\deE]+)\s*([a-z]*)\s*", text or "")
        if not match or match.group(2) not in UNIT_MM:
            fail(f"root width/height '{text}' is not supported by this check")
        return float(match.group(1)) * UNIT_MM[match.group(2)]
    width, height = length_mm(root.get("width")), length_mm(root.get("height"))
    box = [float(v) for v in re.split(r"[\s,]+", root.get("viewBox", "").strip()) if v]
    if not box:
        box = [0, 0, width / MM_PER_PX, height / MM_PER_PX]
    scale = width / box[2]
    if abs(height / box[3] - scale) > 1e-9 * scale:
        fail("the root's viewBox has another aspect than its page (not supported by this check)")
    return scale, width, height, box


def strip_style(element):
    for name in DROPPED_ATTRIBUTES:
        element.attrib.pop(name, None)
    for name in list(element.attrib):
        if local(name) in ("type", "path-effect", "original-d") and name.startswith("{"):
            del element.attrib[name]  # sodipodi:type, inkscape:path-effect / original-d
    kept = [p for p in element.get("style", "").split(";") if p.strip() and
            not DROPPED_STYLE.match(p)]
    element.set("style", ";".join(kept + ["stroke:none"]))


def prepare(path, out_path):
    """Writes the prepared copy; returns (root, parent map, mm per user unit, page, viewBox)."""
    for _, (prefix, uri) in ET.iterparse(path, events=["start-ns"]):
        ET.register_namespace(prefix, uri)
    tree = ET.parse(path)
    root = tree.getroot()
    parents = {child: parent for parent in root.iter() for child in parent}
    for element in list(root.iter()):
        if local(element.tag) in LEFT_OUT and element in parents:
            parents[element].remove(element)
    parents = {child: parent for parent in root.iter() for child in parent}
    for number, element in enumerate(root.iter()):
        if not isinstance(element.tag, str) or not element.tag.startswith("{" + SVG_NS):
            continue
        element.attrib.setdefault("id", f"fdsurf-check-{number}")
        strip_style(element)
    scale, width, height, box = root_mapping(root)
    tree.write(out_path, xml_declaration=True, encoding="utf-8")
    return tree, parents, scale, (width, height), box


def href_target(element, by_id):
    ref = element.get(XLINK_HREF) or element.get("href") or ""
    return by_id.get(ref[1:]) if ref.startswith("#") else None


FLOAT32 = 2.0 ** -24  # Inkscape keeps shape lengths (SVGLength) as float: relative rounding
LENGTHS = ("x", "y", "width", "height", "cx", "cy", "r", "rx", "ry", "x1", "y1", "x2", "y2")


def length_sum(element):
    total = 0.0
    for name in LENGTHS:
        match = re.match(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)", element.get(name, ""))
        total += abs(float(match.group(1))) if match else 0.0
    return total


def shape_instances(root, by_id, base):
    """Per shape id: (map from its user space by `base`, float32 slack in base units) per
    instance, walking <use>s. The slack is Inkscape's float rounding of the shape's and the
    <use>s' lengths, stretched by the maps."""
    instances = {}

    def walk(element, ctm, slack, depth):
        if depth > 64:
            fail("<use> nesting deeper than 64")
        tag = local(element.tag)
        if tag in ("defs", "clipPath", "mask", "marker", "pattern", "symbol") or \
                "display:none" in element.get("style", "").replace(" ", "") or \
                element.get("display") == "none":
            return
        m = compose(ctm, parse_transform(element.get("transform")))
        if tag == "use":
            slack += FLOAT32 * length_sum(element) * singular_values(m)[1]
            m = compose(m, (1, 0, 0, 1, float(element.get("x", 0)), float(element.get("y", 0))))
            target = href_target(element, by_id)
            if target is not None:
                walk(target, m, slack, depth + 1)
            return
        if tag in SHAPES:
            own = FLOAT32 * length_sum(element) * singular_values(m)[1]
            instances.setdefault(element.get("id"), []).append((m, slack + own))
        for child in element:
            walk(child, m, slack, depth)

    walk(root, base, 0.0, 0)
    return instances


def set_stroke_widths(root, by_id, scale_mm, px_per_mm):
    """Gives each shape a stroke 1 px thick at its thinnest; returns the thickest, px."""
    s = scale_mm * px_per_mm
    thickest = 1.0
    for shape_id, instances in shape_instances(root, by_id, (s, 0, 0, s, 0, 0)).items():
        values = [singular_values(m) for m, _ in instances]
        low = min(v[0] for v in values)
        if low <= 0:
            fail(f"<{local(by_id[shape_id].tag)} id=\"{shape_id}\">: a singular transform")
        thickest = max(thickest, max(v[1] for v in values) / low)
        element = by_id[shape_id]
        element.set("style", element.get("style") + f";stroke-width:{1.0 / low!r}")
    return thickest


# --- extents -------------------------------------------------------------------------------

def cubic_box(points):
    """The exact box of a cubic Bézier: its ends and the roots of its derivative in (0, 1)."""
    box = []
    for axis in (0, 1):
        p0, p1, p2, p3 = (p[axis] for p in points)
        # B'(t)/3 = a t² + b t + c
        a, b, c = p3 - 3 * p2 + 3 * p1 - p0, 2 * (p2 - 2 * p1 + p0), p1 - p0
        ts = []
        if abs(a) > 1e-15 * (abs(b) + abs(c) + 1e-300):
            disc = b * b - 4 * a * c
            if disc >= 0:
                ts = [(-b + sign * math.sqrt(disc)) / (2 * a) for sign in (1, -1)]
        elif b != 0:
            ts = [-c / b]
        values = [p0, p3]
        for t in ts:
            if 0 < t < 1:
                u = 1 - t
                values.append(u ** 3 * p0 + 3 * u * u * t * p1 + 3 * u * t * t * p2 + t ** 3 * p3)
        box.append((min(values), max(values)))
    return box[0][0], box[1][0], box[0][1], box[1][1]


def union(boxes):
    boxes = list(boxes)
    return (min(b[0] for b in boxes), min(b[1] for b in boxes),
            max(b[2] for b in boxes), max(b[3] for b in boxes))


ORIGIN = re.compile(r': <(\w+) id="([^"]*)"> \(line \d+\)$')


def our_boxes(curves):
    """Per element id: the box of its curves (mm, y up)."""
    boxes = {}
    for curve in curves:
        match = ORIGIN.search(curve["origin"])
        if not match:
            fail(f"curve origin without an id: {curve['origin']}")
        box = cubic_box(curve["points"])
        old = boxes.get(match.group(2))
        boxes[match.group(2)] = box if old is None else union([old, box])
    return boxes


def inkscape_boxes(path, page_height):
    """Per id: Inkscape's box converted to mm, y up, with the rounding slack of each side."""
    boxes = {}
    for line in run(["inkscape", "--query-all", path]).splitlines():
        fields = line.split(",")
        if len(fields) != 5:
            continue
        x, y, w, h = (float(v) for v in fields[1:])
        rx, ry, rw, rh = (rounding_px(v) for v in fields[1:])
        # x0 = x; y0 (the bottom, y up) comes from y + h; x1 from x + w; y1 from y.
        rounding = (rx, ry + rh, rx + rw, ry)
        boxes[fields[0]] = ((x * MM_PER_PX, page_height - (y + h) * MM_PER_PX,
                             (x + w) * MM_PER_PX, page_height - y * MM_PER_PX),
                            [r * MM_PER_PX for r in rounding])
    return boxes


def rounding_px(text):
    """Half a unit of the last of the 6 significant digits Inkscape prints (0 for "0")."""
    value = abs(float(text))
    if value == 0:
        return 0.0
    return 0.5 * 10 ** (math.floor(math.log10(value)) - 5)


def subtree_ids(element):
    return {e.get("id") for e in element.iter() if isinstance(e.tag, str)}


def comparable(root, parents, by_id):
    """Each element whose box Inkscape gives for all of its instances: id -> the ids Inkscape
    lists for those instances (itself when drawn in the tree, the <use>s that show it)."""
    in_defs = set()  # what is drawn only where something refers to it
    for element in root.iter():
        if local(element.tag) in ("defs", "symbol", "clipPath", "mask", "marker", "pattern"):
            in_defs |= subtree_ids(element)
    shown_by = {}  # element id -> the <use> ids showing it, through chains of <use>
    for use in (e for e in root.iter() if local(e.tag) == "use" and e.get("id") not in in_defs):
        target, seen = href_target(use, by_id), 0
        while target is not None and local(target.tag) == "use" and seen < 64:
            target, seen = href_target(target, by_id), seen + 1
        if target is not None:
            shown_by.setdefault(target.get("id"), []).append(use.get("id"))
    result = {}
    for element in root.iter():
        if not isinstance(element.tag, str) or element.get("id") is None:
            continue
        ancestors, node = [], parents.get(element)
        while node is not None:
            ancestors.append(node.get("id"))
            node = parents.get(node)
        inner = subtree_ids(element) - {element.get("id")}
        if any(a in shown_by for a in ancestors) or any(i in shown_by for i in inner) or \
                any(local(e.tag) == "use" for e in element.iter()):
            continue  # a box per instance would be needed, or a <use>'s target is elsewhere
        listed = [] if element.get("id") in in_defs else [element.get("id")]
        result[element.get("id")] = (listed + shown_by.get(element.get("id"), []), inner)
    return result


def check_extents(prepared, root, parents, by_id, curves, page_height, scale_mm):
    ours = our_boxes(curves)
    base = (scale_mm, 0, 0, scale_mm, 0, 0)
    float_slack = {i: max(v for _, v in inst)
                   for i, inst in shape_instances(root, by_id, base).items()}
    theirs = inkscape_boxes(prepared, page_height)
    checked, covered, worst = 0, set(), 0.0
    for element_id, (listed, inner) in comparable(root, parents, by_id).items():
        drawn = [ours[i] for i in inner | {element_id} if i in ours]
        if not drawn:
            continue
        missing = [i for i in listed if i not in theirs]
        if not listed or missing:
            fail(f"{element_id}: we draw it, Inkscape lists no box for {missing or 'it'}")
        got = union(drawn)
        want = union(theirs[i][0] for i in listed)
        lengths = max(float_slack.get(i, 0.0) for i in inner | {element_id})
        slack = [max(theirs[i][1][k] for i in listed) + lengths + ARC_BOUND_MM +
                 1e-9 * (1 + abs(want[k])) for k in range(4)]
        for k, side in enumerate(("left", "bottom", "right", "top")):
            off = abs(got[k] - want[k])
            worst = max(worst, off / slack[k])
            if off > slack[k]:
                fail(f"<{local(by_id[element_id].tag)} id=\"{element_id}\">: {side} edge: "
                     f"fdsurf {got[k]:.6f} mm, Inkscape {want[k]:.6f} mm "
                     f"(allowed ±{slack[k]:.2g})")
        checked += 1
        covered |= (inner | {element_id}) & set(ours)
    unchecked = set(ours) - covered
    if unchecked:
        fail(f"elements drawn but not checked: {sorted(unchecked)[:10]}")
    not_drawn = len([i for i in theirs if i not in ours and by_id.get(i) is not None
                     and local(by_id[i].tag) in SHAPES])
    print(f"check_svg: extents of {checked} elements ({len(ours)} drawn) equal Inkscape's, "
          f"worst {worst:.2f} of the allowed; {not_drawn} shapes Inkscape lists are not drawn "
          f"(hidden)")


# --- pixels --------------------------------------------------------------------------------

OUTLINE_CSS = """* { fill: none !important; stroke: black !important; stroke-opacity: 1 !important;
  opacity: 1 !important; stroke-linecap: round !important; stroke-linejoin: round !important;
  stroke-dasharray: none !important; filter: none !important; clip-path: none !important;
  mask: none !important; }
"""


def plot_strokes(fdsurf, svg, tolerance_mm, quantum_mm, tmp):
    out = os.path.join(tmp, "strokes.json")
    run([fdsurf, "plot", svg, "-q", "--format", "json", "--fit", "none", "--tolerance",
         f"{tolerance_mm:.9f}", "--quantum", f"{quantum_mm:.9f}", "-o", out])
    with open(out, encoding="utf-8") as f:
        return json.load(f)


def canvas_mm(page, strokes):
    """(x0, y0, w, h) in mm, y down from the page's top: the page and every stroke point."""
    width, height = page
    xs = [p[0] for s in strokes["strokes"] for p in s] + [0, width]
    ys = [height - p[1] for s in strokes["strokes"] for p in s] + [0, height]
    return min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)


def ink(png):
    width, height, rows = read_png(png)
    return width, height, {(x, y) for y, row in enumerate(rows) for x, px in enumerate(row)
                           if min(px[:3]) < INK_BELOW}


def render(svg, dpi, out, stylesheet=None):
    command = ["rsvg-convert", "--dpi-x", repr(dpi), "--dpi-y", repr(dpi), "-b", "white"]
    if stylesheet:
        command += ["--stylesheet", stylesheet]
    run(command + ["-o", out, svg])
    return ink(out)


def write_our_svg(strokes, page_height, canvas, px_per_mm, out):
    x0, y0, w, h = canvas
    paths = []
    for stroke in strokes["strokes"]:
        points = " L ".join(f"{p[0]!r} {page_height - p[1]!r}" for p in stroke)
        paths.append(f'<path d="M {points}"/>')
    with open(out, "w", encoding="utf-8") as f:
        f.write(f'<svg xmlns="{SVG_NS}" width="{w!r}mm" height="{h!r}mm" '
                f'viewBox="{x0!r} {y0!r} {w!r} {h!r}">\n<g fill="none" stroke="black" '
                f'stroke-width="{1 / px_per_mm!r}" stroke-linecap="round" '
                f'stroke-linejoin="round">\n' + "\n".join(paths) + "\n</g>\n</svg>\n")


def max_distance(thickest_px, tolerance_px, quantum_px):
    """D: an inked pixel's centre is within half the line width + half a pixel diagonal of its
    line's centre; that centre is within the flattening tolerance (ours: --tolerance plus half
    a quantum diagonal; cairo's: 0.1 px) of the exact curve, and the pixel of the other
    rendering that holds the nearest point of its own centre line is inked (a 1 px line covers
    at least ~1/4 of every pixel it runs through, far above the 2 % ink threshold), its
    centre within half a diagonal of that point."""
    return thickest_px / 2 + math.sqrt(2) + tolerance_px + quantum_px * math.sqrt(2) / 2 + 0.1


def unmatched(a, b, distance):
    reach = int(math.ceil(distance))
    offsets = [(dx, dy) for dx in range(-reach, reach + 1) for dy in range(-reach, reach + 1)
               if dx * dx + dy * dy <= distance * distance]
    return [p for p in a if not any((p[0] + dx, p[1] + dy) in b for dx, dy in offsets)]


def check_pixels(fdsurf, original, tree, by_id, mapping, tmp):
    scale, page, box = mapping
    px_per_mm = CANVAS_PX / max(page)
    tolerance_mm = 0.25 / px_per_mm
    quantum_mm = 10 ** math.floor(math.log10(0.05 / px_per_mm))
    strokes = plot_strokes(fdsurf, original, tolerance_mm, quantum_mm, tmp)
    x0, y0, w, h = canvas_mm(page, strokes)
    # Whole pixels, two of them around everything.
    x0, y0 = x0 - 2 / px_per_mm, y0 - 2 / px_per_mm
    w = math.ceil(w * px_per_mm + 4) / px_per_mm
    h = math.ceil(h * px_per_mm + 4) / px_per_mm
    root = tree.getroot()
    thickest = set_stroke_widths(root, by_id, scale, px_per_mm)
    root.set("viewBox", " ".join(repr(v) for v in (box[0] + x0 / scale, box[1] + y0 / scale,
                                                   w / scale, h / scale)))
    root.set("width", f"{w!r}mm")
    root.set("height", f"{h!r}mm")
    theirs_svg, ours_svg = os.path.join(tmp, "theirs.svg"), os.path.join(tmp, "ours.svg")
    tree.write(theirs_svg, xml_declaration=True, encoding="utf-8")
    css = os.path.join(tmp, "outline.css")
    with open(css, "w", encoding="utf-8") as f:
        f.write(OUTLINE_CSS)
    write_our_svg(strokes, page[1], (x0, y0, w, h), px_per_mm, ours_svg)
    dpi = px_per_mm * 25.4
    tw, th, theirs = render(theirs_svg, dpi, os.path.join(tmp, "theirs.png"), css)
    ow, oh, ours = render(ours_svg, dpi, os.path.join(tmp, "ours.png"))
    if (tw, th) != (ow, oh):
        fail(f"the renderings differ in size: {tw}x{th} and {ow}x{oh} px")
    if not theirs or not ours:
        fail("a rendering is blank")
    distance = max_distance(thickest, tolerance_mm * px_per_mm, quantum_mm * px_per_mm)
    for name, a, b in (("fdsurf's", ours, theirs), ("rsvg-convert's", theirs, ours)):
        lost = unmatched(a, b, distance)
        if lost:
            x, y = lost[0]
            fail(f"{len(lost)} of {len(a)} inked pixels of {name} rendering are farther than "
                 f"{distance:.2f} px from the other's, e.g. pixel ({x}, {y}) = "
                 f"({x0 + (x + 0.5) / px_per_mm:.3f}, {y0 + (y + 0.5) / px_per_mm:.3f}) mm "
                 f"from the page's top left")
    print(f"check_svg: {tw}x{th} px at {dpi:.0f} dpi: {len(ours)} inked pixels of ours and "
          f"{len(theirs)} of rsvg-convert's each lie within D = {distance:.2f} px of the other's "
          f"(lines 1 to {thickest:.2f} px thick)")


def main():
    if len(sys.argv) != 4:
        fail("usage: check_svg.py CURVES_TOOL FDSURF FILE.svg")
    tool, fdsurf, original = sys.argv[1:]
    with tempfile.TemporaryDirectory() as tmp:
        prepared = os.path.join(tmp, "prepared.svg")
        tree, parents, scale, page, box = prepare(original, prepared)
        root = tree.getroot()
        by_id = {e.get("id"): e for e in root.iter() if isinstance(e.tag, str) and e.get("id")}
        read = json.loads(run([tool, prepared]))
        if read["page"] is None or max(abs(a - b) for a, b in zip(read["page"], page)) > 1e-9:
            fail(f"ReadSvg's page {read['page']} is not the root's {page} mm")
        as_written = json.loads(run([tool, original]))
        if len(as_written["curves"]) != len(read["curves"]):
            fail(f"the prepared copy reads as {len(read['curves'])} curves, the file as "
                 f"{len(as_written['curves'])}")
        check_extents(prepared, root, parents, by_id, read["curves"], page[1], scale)
        check_pixels(fdsurf, original, tree, by_id, (scale, page, box), tmp)


if __name__ == "__main__":
    main()
