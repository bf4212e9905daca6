// SPDX-License-Identifier: MIT
// Reading triangle meshes with vertex normals: Wavefront OBJ and PLY
// (docs/formats.md, "Triangle meshes (OBJ, PLY)").
//
// What is read
//   OBJ: `v x y z [w]` (w, a weight for rational free-form geometry, is
//   ignored; `v x y z r g b`, the common vertex-colour extension, is read as
//   x y z), `vn i j k`, and `f` whose corners are `v`, `v/vt`, `v//vn` or
//   `v/vt/vn`, with 1-based or negative (relative: -1 is the latest) indices.
//   `vt`, `vp`, `o`, `g`, `s`, `mg`, `usemtl`, `mtllib` and the other
//   display and grouping statements carry no geometry and are skipped, as are
//   comments (`#` to the end of the line), blank lines and CR before LF. A
//   line ending in a backslash continues on the next one (the backslash reads
//   as a space); errors name the line on which the statement starts.
//   Points and lines (`p`, `l`) are not surfaces: they are skipped with a
//   note. Free-form geometry (`cstype`, `curv`, `curv2`, `surf`, `parm`,
//   `trim`, `hole`, `scrv`, `sp`, `end`, `deg`, `bmat`, `step`, `con`, and the
//   old `bsp`, `bzp`, `cdc`, `cdp`, `res`) is refused: it would be a surface
//   that the mesh silently lacks. Any other statement is skipped with a note.
//
//   PLY: `format ascii 1.0`, `binary_little_endian 1.0` and
//   `binary_big_endian 1.0`; `comment` and `obj_info` lines; `element vertex
//   N` with scalar properties x y z (any scalar type, any order) and
//   optionally nx ny nz (all three or none); `element face N` with `property
//   list <count type> <index type> vertex_indices` (or `vertex_index`),
//   0-based. Types are char/int8, uchar/uint8, short/int16, ushort/uint16,
//   int/int32, uint/uint32, float/float32, double/float64. Other properties
//   and elements (lists too) are skipped. ASCII PLY has one element a line;
//   its values are read as written (a `float` value is not rounded to single
//   precision).
//
//   Polygons with more than 3 corners are fanned from their first corner,
//   (c0, c1, c2), (c0, c2, c3), ...: right for convex polygons (and for any
//   polygon whose first corner sees all the others); a concave polygon may
//   give overlapping triangles, so triangulate such files beforehand.
//
// How normals are chosen
//   OBJ: a vertex takes the `vn` its face corners name, normalised. If its
//   corners name different normals (hard edges, a per-face-normal export),
//   it takes the normalised mean of the distinct ones, and a note counts the
//   vertices for which that happened. A vertex that no corner gives a normal
//   (its faces name none) gets an estimated one, with a note.
//   PLY: nx ny nz, normalised.
//   Estimated normals are area-weighted: the sum of the cross products
//   (b - a) x (c - a) of the triangles around the vertex (each twice the
//   triangle's area, along its normal), normalised; so they follow the
//   faces' winding (counter-clockwise seen from the side they point to).
//
// Errors
//   InputError, with "NAME:LINE: what was wrong" for text (OBJ, the PLY
//   header, ASCII PLY bodies, which also name the element and its index:
//   "f.ply:14: vertex 3: ..."), and "NAME: ELEMENT INDEX: what was wrong" for
//   binary PLY bodies ("f.ply: face 17: vertex index 99 out of range (the
//   file has 12 vertices)"). Refused: malformed or non-finite numbers, a
//   missing coordinate, an index 0 (OBJ) or out of range, a face with fewer
//   than 3 vertices or naming one vertex twice, a zero-length normal, no
//   faces at all, a truncated file or data after the last element (PLY), and
//   a vertex whose normal must be estimated but that is in no face or whose
//   faces' cross products sum to zero (to rounding). Topology (edges in more
//   than two faces, inconsistent orientation) is the construction's to check,
//   not the reader's.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// A triangle mesh as read from a file.
struct TriangleMesh {
  /// The vertices in file order, in file units (nothing is scaled).
  std::vector<Point3> vertices;
  /// One unit normal per vertex (same order), from the file or estimated.
  std::vector<Point3> normals;
  /// Triangles as 0-based indices into `vertices`, in file order and with the
  /// file's orientation; polygons are fanned in place.
  std::vector<std::array<int, 3>> triangles;
  /// True when the file gave no normals at all and every normal was
  /// estimated; a partial estimate (OBJ) is reported in `notes` only.
  bool normals_estimated = false;
  /// What a person should know that is not an error, each starting with the
  /// file's name: "f.obj: no vertex normals; estimated (area-weighted)".
  std::vector<std::string> notes;
};

/// Reads an OBJ or PLY file, chosen by the suffix .obj or .ply (in any case).
/// Throws InputError if the file cannot be read, has another suffix, or is
/// malformed (see above).
TriangleMesh ReadMeshFile(const std::string& path);

/// The same from OBJ text in memory; `name` is used in messages and notes.
TriangleMesh ParseObj(const std::string& text, const std::string& name);

/// The same from the bytes of a PLY file (ASCII or binary).
TriangleMesh ParsePly(const std::string& bytes, const std::string& name);

}  // namespace fdsurf::host
