// SPDX-License-Identifier: MIT
// What fuzz_bpt and fuzz_json check on every input the reader accepts: each
// patch and curve, converted at a quantum that suits its size and stepped on
// a small grid by the fixed engine, lies within 0.51 quanta of the double
// reference at every grid point (the bound `fdsurf check` tests,
// tools/fdsurf/check_command.cc). A refusal (InputError from the reader,
// EngineError from the engine) is clean; any other exception, or a point
// outside the bound, is a finding and traps.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "fdsurf/host/constructions.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/fixed_curve.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_set.h"
#include "fdsurf/host/quantum.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::fuzz {

// The grid of the check, and how many patches and curves of one input are
// stepped (the rest are only read), so that an input costs little.
constexpr int kGridSteps = 4;
constexpr std::size_t kMaxChecked = 64;
constexpr double kBoundQuanta = 0.51;

[[noreturn]] inline void Finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "FINDING: %s: %s\n", what, detail.c_str());
  __builtin_trap();
}

// A power of ten Q with |largest| / Q about 10^5 (10^-9 ≤ Q ≤ 10^8, what
// Quantum::Parse takes): the coordinates then have some 17 bits in quanta,
// well inside the engine's range, and the reference's rounding is far below
// a quantum.
inline host::Quantum QuantumFor(double largest) {
  int exponent = 0;
  if (largest > 0 && std::isfinite(largest)) {
    exponent = static_cast<int>(std::ceil(std::log10(largest))) - 5;
  }
  exponent = std::clamp(exponent, -9, 8);
  std::string text;
  if (exponent >= 0) {
    text = "1" + std::string(static_cast<std::size_t>(exponent), '0');
  } else {
    text = "0." + std::string(static_cast<std::size_t>(-exponent - 1), '0') + "1";
  }
  return host::Quantum::Parse(text);
}

template <typename Points>
double Largest(const Points& points) {
  double largest = 0;
  for (const host::Point3& p : points) {
    for (const double v : p) largest = std::max(largest, std::fabs(v));
  }
  return largest;
}

inline void CheckPatch(const host::Patch& patch) {
  double largest = 0;
  for (const auto& row : patch.g) largest = std::max(largest, Largest(row));
  const host::Quantum quantum = QuantumFor(largest);
  PreparedPatch<3> prepared;
  try {
    prepared = host::PrepareFixedPatch(patch, quantum, kGridSteps, kGridSteps);
  } catch (const host::EngineError&) {
    return;  // the engine cannot serve it at this quantum: a clean refusal
  }
  double worst = 0;
  host::ForEachGridPoint(
      prepared, [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
        const host::Point3 exact = host::EvaluateReference(
            patch, static_cast<double>(i) / kGridSteps, static_cast<double>(j) / kGridSteps);
        for (int c = 0; c < 3; ++c) {
          worst = std::max(worst, std::fabs(k[c] - quantum.ToQuanta(exact[c])));
        }
      });
  // !(<=) so that a NaN error is a finding too.
  if (!(worst <= kBoundQuanta)) {
    Finding("patch outside the 0.51-quantum bound", patch.origin + ": " + std::to_string(worst) +
                                                        " quanta at quantum " + quantum.Format(1));
  }
}

inline void CheckCurve(const host::Curve& curve) {
  const host::Quantum quantum = QuantumFor(Largest(curve.g));
  PreparedCurve<3> prepared;
  try {
    prepared = host::PrepareFixedCurve(curve, quantum, kGridSteps);
  } catch (const host::EngineError&) {
    return;
  }
  double worst = 0;
  host::ForEachCurvePoint(prepared, [&](std::uint32_t i, const std::int32_t(&k)[3]) {
    const host::Point3 exact = host::EvaluateCurve(curve, static_cast<double>(i) / kGridSteps);
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::fabs(k[c] - quantum.ToQuanta(exact[c])));
    }
  });
  if (!(worst <= kBoundQuanta)) {
    Finding("curve outside the 0.51-quantum bound", curve.origin + ": " + std::to_string(worst) +
                                                        " quanta at quantum " + quantum.Format(1));
  }
}

// Reads `data` with `parse` and checks what it accepted.
template <typename Parse>
int CheckReader(const std::uint8_t* data, std::size_t size, Parse&& parse) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  host::PatchSet set;
  try {
    set = parse(text);
  } catch (const host::InputError&) {
    return 0;  // the documented refusal of malformed input
  } catch (const std::exception& e) {
    // The readers promise InputError (naming file and place) for anything
    // malformed; anything else reaches the tool as an internal error.
    Finding("the reader threw something other than InputError", e.what());
  }
  for (std::size_t p = 0; p < std::min(set.patches.size(), kMaxChecked); ++p) {
    CheckPatch(set.patches[p]);
  }
  for (std::size_t c = 0; c < std::min(set.curves.size(), kMaxChecked); ++c) {
    CheckCurve(set.curves[c]);
  }
  return 0;
}

}  // namespace fdsurf::fuzz
