#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the generated example meshes (Python 3 standard library only):

  examples/octahedron.obj    the regular octahedron, vertices (±50,0,0), (0,±50,0), (0,0,±50) mm
  examples/sphere-icosa.obj  an icosahedron subdivided once (80 faces, 42 vertices) on the
                             sphere of radius 50 mm
  examples/terrain.ply       a 5x5 grid over [0,80]x[0,80] mm, z = 6 sin(x/25) cos(y/30)

with exact unit normals (radial, or the terrain's analytic (-dz/dx, -dz/dy, 1) normalised) and
every triangle wound counter-clockwise seen from outside (from +z for the terrain). Each mesh is
checked before it is written: every edge in at most two triangles, once each way.

Run from anywhere: python3 examples/tools/make_meshes.py
"""
import math
import os

RADIUS = 50.0
EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def unit(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def num(x):
    """The shortest text that reads back as the same double; integers without '.0'."""
    return str(int(x)) if x == int(x) else repr(x)


def outward(vertices, triangle):
    """The triangle wound counter-clockwise seen from outside a mesh around the origin."""
    a, b, c = (vertices[i] for i in triangle)
    n = cross(sub(b, a), sub(c, a))
    centre = tuple((a[k] + b[k] + c[k]) / 3 for k in range(3))
    return triangle if dot(n, centre) > 0 else (triangle[0], triangle[2], triangle[1])


def check_edges(triangles, closed):
    directed = {}
    for t in triangles:
        for k in range(3):
            edge = (t[k], t[(k + 1) % 3])
            assert edge not in directed, f"edge {edge} twice in the same direction"
            directed[edge] = True
    for a, b in directed:
        assert not closed or (b, a) in directed, f"edge {(a, b)} in one triangle only"


def octahedron():
    r = RADIUS
    vertices = [(r, 0, 0), (-r, 0, 0), (0, r, 0), (0, -r, 0), (0, 0, r), (0, 0, -r)]
    triangles = [outward(vertices, (x, y, z)) for z in (4, 5) for y in (2, 3) for x in (0, 1)]
    return vertices, triangles


def icosphere():
    phi = (1 + math.sqrt(5)) / 2
    corners = []
    for s in (-1, 1):
        for t in (-1, 1):
            corners += [(0, s, t * phi), (s, t * phi, 0), (t * phi, 0, s)]
    vertices = [tuple(RADIUS * c for c in unit(p)) for p in corners]
    # The icosahedron's 20 faces: the triples of mutually nearest corners.
    edge = min(dot(sub(a, b), sub(a, b)) for a in corners for b in corners if a != b)
    near = lambda i, j: abs(dot(sub(corners[i], corners[j]), sub(corners[i], corners[j])) - edge) < 1e-9
    faces = [(i, j, k) for i in range(12) for j in range(i + 1, 12) for k in range(j + 1, 12)
             if near(i, j) and near(j, k) and near(i, k)]
    assert len(faces) == 20
    faces = [outward(vertices, f) for f in faces]
    # Split each face into four at its edges' midpoints, pushed onto the sphere.
    midpoints = {}

    def midpoint(i, j):
        key = (min(i, j), max(i, j))
        if key not in midpoints:
            m = tuple((vertices[i][k] + vertices[j][k]) / 2 for k in range(3))
            vertices.append(tuple(RADIUS * c for c in unit(m)))
            midpoints[key] = len(vertices) - 1
        return midpoints[key]

    triangles = []
    for a, b, c in faces:
        ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
        triangles += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    triangles = [outward(vertices, t) for t in triangles]
    assert len(vertices) == 42 and len(triangles) == 80
    return vertices, triangles


def write_obj(path, title, vertices, triangles):
    lines = [f"# {title}", "# Written by examples/tools/make_meshes.py; units: mm.",
             "# Normals are the radial unit vectors; faces are counter-clockwise from outside.",
             "o " + os.path.splitext(os.path.basename(path))[0]]
    lines += ["v " + " ".join(num(c) for c in v) for v in vertices]
    lines += ["vn " + " ".join(num(c) for c in unit(v)) for v in vertices]
    lines += ["f " + " ".join(f"{i + 1}//{i + 1}" for i in t) for t in triangles]
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def terrain():
    """Vertex (i, j) is number 5j + i at (20i, 20j); each cell is cut along its diagonal
    (i, j)-(i+1, j+1) into two triangles counter-clockwise seen from +z."""
    vertices, normals = [], []
    for j in range(5):
        for i in range(5):
            x, y = 20.0 * i, 20.0 * j
            z = 6 * math.sin(x / 25) * math.cos(y / 30)
            dzdx = 6 / 25 * math.cos(x / 25) * math.cos(y / 30)
            dzdy = -6 / 30 * math.sin(x / 25) * math.sin(y / 30)
            vertices.append((x, y, z))
            normals.append(unit((-dzdx, -dzdy, 1.0)))
    triangles = []
    for j in range(4):
        for i in range(4):
            a, b, c, d = 5 * j + i, 5 * j + i + 1, 5 * (j + 1) + i + 1, 5 * (j + 1) + i
            triangles += [(a, b, c), (a, c, d)]
    for t in triangles:
        p, q, r = (vertices[k] for k in t)
        assert cross(sub(q, p), sub(r, p))[2] > 0
    return vertices, normals, triangles


def write_terrain(path):
    vertices, normals, triangles = terrain()
    check_edges(triangles, closed=False)
    lines = ["ply", "format ascii 1.0",
             "comment Written by examples/tools/make_meshes.py; units: mm.",
             "comment z = 6 sin(x/25) cos(y/30) over [0,80]x[0,80]; normals (-dz/dx, -dz/dy, 1) "
             "normalised; triangles counter-clockwise from +z.",
             f"element vertex {len(vertices)}",
             "property double x", "property double y", "property double z",
             "property double nx", "property double ny", "property double nz",
             f"element face {len(triangles)}", "property list uchar int vertex_indices",
             "end_header"]
    lines += [" ".join(num(c) for c in v + n) for v, n in zip(vertices, normals)]
    lines += ["3 " + " ".join(str(i) for i in t) for t in triangles]
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def main():
    vertices, triangles = octahedron()
    check_edges(triangles, closed=True)
    write_obj(os.path.join(EXAMPLES, "octahedron.obj"),
              "The regular octahedron of radius 50.", vertices, triangles)
    vertices, triangles = icosphere()
    check_edges(triangles, closed=True)
    write_obj(os.path.join(EXAMPLES, "sphere-icosa.obj"),
              "An icosahedron subdivided once, on the sphere of radius 50.", vertices, triangles)
    write_terrain(os.path.join(EXAMPLES, "terrain.ply"))


if __name__ == "__main__":
    main()
