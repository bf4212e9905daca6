// SPDX-License-Identifier: MIT
// The test image's entry point, shared by every target and the host reference.
#pragma once

namespace fdsurf {
namespace image {

/// Runs the fixed input set and the bench, printing the report through the
/// port. small_only restricts the set to what the ATmega328P image steps
/// (host reference only; images without set-up always run the small set).
/// Returns the exit status.
int RunImage(bool small_only);

}  // namespace image
}  // namespace fdsurf
