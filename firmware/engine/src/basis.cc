// SPDX-License-Identifier: MIT
#include "fdsurf/basis.h"

namespace fdsurf {
namespace {

// Indexed by Basis. Sources: the power, Hermite, Bézier and B-spline forms of
// the bicubic patch (Foley & van Dam, ch. 11; seed 004); Catmull-Rom as in
// Catmull & Rom (1974) with tension 1/2.
const BasisMatrix kBasisMatrices[kBasisCount] = {
    {1, {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
    {1, {{2, -2, 1, 1}, {-3, 3, -2, -1}, {0, 0, 1, 0}, {1, 0, 0, 0}}},
    {1, {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}}},
    {6, {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 0, 3, 0}, {1, 4, 1, 0}}},
    {2, {{-1, 3, -3, 1}, {2, -5, 4, -1}, {-1, 0, 1, 0}, {0, 2, 0, 0}}},
};

const char* const kBasisNames[kBasisCount] = {"power", "hermite", "bezier", "bspline",
                                              "catmull-rom"};

}  // namespace

const BasisMatrix* GetBasisMatrix(Basis basis) {
  const unsigned index = static_cast<unsigned>(basis);
  return index < kBasisCount ? &kBasisMatrices[index] : nullptr;
}

const char* BasisName(Basis basis) {
  const unsigned index = static_cast<unsigned>(basis);
  return index < kBasisCount ? kBasisNames[index] : nullptr;
}

}  // namespace fdsurf
