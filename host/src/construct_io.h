// Reading the JSON "construct" and "curves" arrays (docs/formats.md,
// docs/constructions.md). Private to the host library: patch_io.cc calls it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// Appends the patches of every construction in `construct` (a JSON array) to
/// `set`; constructions may refer to patches already in the set by number.
/// Throws InputError naming `file` and the JSON path.
void AddConstructions(const nlohmann::json& construct, const std::string& file, PatchSet* set);

/// Appends the curves of every entry in `curves` (a JSON array) to `set`.
void AddCurves(const nlohmann::json& curves, const std::string& file, PatchSet* set);

}  // namespace fdsurf::host
