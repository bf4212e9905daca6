// SPDX-License-Identifier: MIT
// Reading patch files: BPT text and fdsurf JSON (docs/formats.md).
#pragma once

#include <string>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/patch_set.h"

namespace fdsurf::host {

/// Reads a BPT or JSON patch file; the format is taken from the extension
/// (.bpt, .json) or, failing that, from the first non-blank character.
/// Throws InputError on anything malformed.
PatchSet ReadPatchFile(const std::string& path);

/// The same from text already in memory; `name` is used in messages.
PatchSet ParseBpt(const std::string& text, const std::string& name);
PatchSet ParseJson(const std::string& text, const std::string& name);

}  // namespace fdsurf::host
