// SPDX-License-Identifier: MIT
// JSON input shared by the readers, and the JSON "construct" and "curves" arrays (docs/formats.md,
// docs/constructions.md). Private to the host library: patch_io.cc calls it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "fdsurf/config/nodiscard.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// Where a JSON value sits, for messages: "file: surfaces[0].net[1][2]: ...";
/// a top-level field is named without a dot ("file: units: ...").
struct JsonPlace {
  const std::string& file;
  std::string path;
  FDSURF_NODISCARD InputError Error(const std::string& what) const {
    return InputError(file + ": " + (path.empty() ? "" : path + ": ") + what);
  }
  FDSURF_NODISCARD JsonPlace Child(const std::string& key) const {
    return {file, path.empty() ? key : path + "." + key};
  }
  FDSURF_NODISCARD JsonPlace Index(std::size_t i) const {
    return {file, path + "[" + std::to_string(i) + "]"};
  }
};

/// A basis name ("bezier", "hermite", ...); InputError at `place` otherwise.
Basis ParseBasis(const nlohmann::json& value, const JsonPlace& place);

/// Appends the patches of every construction in `construct` (a JSON array) to
/// `set`; constructions may refer to patches already in the set by number.
/// Throws InputError naming `file` and the JSON path.
void AddConstructions(const nlohmann::json& construct, const std::string& file, PatchSet* set);

/// Reads an OBJ or PLY mesh and draws it as quadric Hermite pieces (row 12
/// of docs/constructions.md) by MeshFileConstruction (patch_io.h). Throws
/// InputError naming the file.
PatchSet MeshFileAsPatchSet(const std::string& path);

/// The same for a mesh already read; `path` names it in messages and notes.
PatchSet MeshAsPatchSet(TriangleMesh file, const std::string& path);

/// Appends the curves of every entry in `curves` (a JSON array) to `set`.
void AddCurves(const nlohmann::json& curves, const std::string& file, PatchSet* set);

}  // namespace fdsurf::host
