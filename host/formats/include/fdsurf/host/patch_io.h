// SPDX-License-Identifier: MIT
// Reading drawings: BPT text, fdsurf JSON, and OBJ/PLY meshes (docs/formats.md).
#pragma once

#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/mesh_io.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quadric_hermite.h"

namespace fdsurf::host {

/// Reads a BPT or JSON patch file, an SVG drawing (ReadSvg, default
/// SvgOptions), or an OBJ or PLY triangle mesh drawn as quadric Hermite
/// pieces (curves; docs/formats.md). The format is taken from the extension
/// (.bpt, .json; .svg, .obj, .ply in any case) or, failing that, from the
/// content (LooksLikeSvg, else the first non-blank character). Throws InputError on anything malformed or
/// a mesh the construction refuses.
PatchSet ReadPatchFile(const std::string& path);

/// The construction a mesh file is drawn by (docs/formats.md): μ from its
/// normals, the normals turned where the triangles' conditions need it,
/// 8 sections per piece; *tolerance gets 1e-4 of the mesh's largest extent
/// (files come in metres, millimetres or inches: 0.01 mm on a 100 mm mesh).
QuadricMesh MeshFileConstruction(TriangleMesh file, double* tolerance);

/// The same from text already in memory; `name` is used in messages.
PatchSet ParseBpt(const std::string& text, const std::string& name);
PatchSet ParseJson(const std::string& text, const std::string& name);

}  // namespace fdsurf::host
