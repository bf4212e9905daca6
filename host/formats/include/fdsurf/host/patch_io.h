// SPDX-License-Identifier: MIT
// Reading drawings: BPT text, fdsurf JSON, and OBJ/PLY meshes (docs/formats.md).
#pragma once

#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/gcode_io.h"
#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quadric_hermite.h"
#include "fdsurf/host/svg_io.h"

namespace fdsurf::host {

/// The options of the readers that take any: each format's reader gets its
/// own (SVG's arc tolerance in mm on the page, G-code's in the program's
/// unit, and G-code's pen conventions); the other readers take none.
struct ReadOptions {
  SvgOptions svg;
  GcodeReadOptions gcode;
};

/// Reads a BPT or JSON patch file, or an OBJ or PLY triangle mesh drawn as
/// quadric Hermite pieces (curves; docs/formats.md). `path` "-" reads all of
/// standard input, named "<stdin>" in messages. The format is `format` when
/// given (bpt, json, obj, ply, svg, gcode), else the suffix's (.bpt, .json,
/// .obj, .ply, .svg, .gcode/.nc/.ngc, in any case), else the content's: '{'
/// JSON, '<' SVG, "ply" PLY, a digit BPT, an OBJ statement or '#' comment, a
/// G-code word or comment. Throws InputError on an unknown `format`, content
/// whose format cannot be told, a format this build cannot read, anything
/// malformed or a mesh the construction refuses; OptionError as the SVG and
/// G-code readers do for their options. `format_read`, when given, receives
/// the name of the format that was read (bpt, json, obj, ply, svg, gcode).
PatchSet ReadPatchFile(const std::string& path, const std::string& format = "",
                       const ReadOptions& options = {}, std::string* format_read = nullptr);

/// The construction a mesh file is drawn by (docs/formats.md): μ from its
/// normals, the normals turned where the triangles' conditions need it,
/// 8 sections per piece; *tolerance gets 1e-4 of the mesh's largest extent
/// (files come in metres, millimetres or inches: 0.01 mm on a 100 mm mesh).
QuadricMesh MeshFileConstruction(TriangleMesh file, double* tolerance);

/// The same from text already in memory; `name` is used in messages.
PatchSet ParseBpt(const std::string& text, const std::string& name);
PatchSet ParseJson(const std::string& text, const std::string& name);

}  // namespace fdsurf::host
