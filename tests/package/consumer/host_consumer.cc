// SPDX-License-Identifier: MIT
// The installed host library and core: reads a patch file (argv[1], the
// teapot) and steps a curve. Prints "patches: N" and the curve's points.
#include <cstdio>
#include <exception>

#include "curve.h"
#include "fdsurf/host/patch_io.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer FILE.bpt\n");
    return 2;
  }
  try {
    const fdsurf::host::PatchSet set = fdsurf::host::ReadPatchFile(argv[1]);
    std::printf("patches: %zu\n", set.patches.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return PrintBezierCurve();
}
