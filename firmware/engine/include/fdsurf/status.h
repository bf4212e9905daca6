// SPDX-License-Identifier: MIT
// Error codes of the fdsurf core. The core has no exceptions: every fallible
// call returns a Status and leaves its outputs untouched on failure.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf {

/// [[nodiscard]] (FDSURF_NODISCARD): dropping a Status drops an error.
enum class FDSURF_NODISCARD Status : uint8_t {
  kOk = 0,
  /// A count, a basis or another argument is outside what the call accepts.
  kInvalidArgument,
  /// The grid asks for more steps than the engine supports (see kMaxPatchSteps).
  kGridOutOfRange,
  /// A geometry value is too large for the geometry format (|value| >= 2^31 quanta).
  kGeometryOutOfRange,
  /// No accumulator width allowed by the caller can hold every difference of
  /// this patch with the fractional bits the error bound needs.
  kPrecisionUnreachable,
  /// An adaptive curve's tolerance is not above what rounding to whole quanta
  /// already uses (sqrt(dims)·(0.5 + 2^-10) quanta).
  kToleranceUnreachable,
};

/// A short, stable, human-readable name for a status ("ok", "grid out of range", ...).
const char* StatusMessage(Status status);

}  // namespace fdsurf
