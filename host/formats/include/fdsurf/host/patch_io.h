// SPDX-License-Identifier: MIT
// Reading drawings: BPT text, fdsurf JSON, and OBJ/PLY meshes (docs/formats.md).
#pragma once

#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// Reads a BPT or JSON patch file, or an OBJ or PLY triangle mesh drawn as
/// quadric Hermite pieces (curves; docs/formats.md). The format is taken from
/// the extension (.bpt, .json; .obj, .ply in any case) or, failing that, from
/// the first non-blank character. Throws InputError on anything malformed or
/// a mesh the construction refuses.
PatchSet ReadPatchFile(const std::string& path);

/// The same from text already in memory; `name` is used in messages.
PatchSet ParseBpt(const std::string& text, const std::string& name);
PatchSet ParseJson(const std::string& text, const std::string& name);

}  // namespace fdsurf::host
