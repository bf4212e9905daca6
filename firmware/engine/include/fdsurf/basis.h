// SPDX-License-Identifier: MIT
// The cubic bases the engine evaluates, as exact integer matrices.
//
// A patch is x(s,t) = S·M·G·Mᵀ·Tᵀ with S = [s³ s² s 1]. Every basis matrix M
// used here is an integer matrix divided by a small denominator (6 for the
// uniform B-spline, 2 for Catmull-Rom, 1 otherwise), so the set-up can form
// the power coefficients C = M·G·Mᵀ exactly in integers.
#pragma once

#include <stdint.h>

namespace fdsurf {

enum class Basis : uint8_t {
  /// G is the coefficient matrix itself: G[i][j] multiplies s^(3-i)·t^(3-j).
  kPower = 0,
  /// G = [[P00,P01,Pt00,Pt01],[P10,P11,Pt10,Pt11],[Ps00,Ps01,Pst00,Pst01],[Ps10,Ps11,Pst10,Pst11]].
  kHermite = 1,
  /// G[i][j] is the control point in row i (along s), column j (along t).
  kBezier = 2,
  /// Uniform cubic B-spline: C² surfaces from a control net (G is a 4×4 window of it).
  kBSpline = 3,
  /// Catmull-Rom: C¹ surfaces through the net's inner points (G is a 4×4 window).
  kCatmullRom = 4,
};

constexpr int kBasisCount = 5;

/// M = matrix / denominator.
struct BasisMatrix {
  int8_t denominator;
  int8_t matrix[4][4];
};

/// The integer form of a basis. Returns nullptr for a value outside the enum.
const BasisMatrix* GetBasisMatrix(Basis basis);

/// A short lower-case name ("bezier", "catmull-rom", ...) or nullptr.
const char* BasisName(Basis basis);

}  // namespace fdsurf
