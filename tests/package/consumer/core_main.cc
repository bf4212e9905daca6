// SPDX-License-Identifier: MIT
// The installed core from a C++14 program (CMake or pkg-config fdsurf).
#include "curve.h"

int main() { return PrintBezierCurve(); }
