// SPDX-License-Identifier: MIT
// A servo pen's pulse widths and the state they serve, as every servo board
// keeps them: the image's built-in widths (build-time settings) until a
// CONFIG gives others, and both 0 in a CONFIG brings the image's back
// (hal::PenOutput::ConfigureServo). The board turns WidthUs() into its
// timer's compare value.
#pragma once

#include <stdint.h>

#include "fdsurf/config/nodiscard.h"

namespace fdsurf {
namespace board {

/// kImageUpUs, kImageDownUs: the image's widths, microseconds.
template <uint16_t kImageUpUs, uint16_t kImageDownUs>
class ServoWidths {
 public:
  /// The pen's state from now on.
  void set_down(bool down) { down_ = down; }
  FDSURF_NODISCARD bool down() const { return down_; }
  /// A CONFIG's widths, microseconds; both 0: the image's.
  void Configure(uint16_t up_us, uint16_t down_us) {
    const bool image_widths = up_us == 0 && down_us == 0;
    up_us_ = image_widths ? kImageUpUs : up_us;
    down_us_ = image_widths ? kImageDownUs : down_us;
  }
  /// The width of the pen's state, microseconds.
  FDSURF_NODISCARD uint16_t WidthUs() const { return down_ ? down_us_ : up_us_; }

 private:
  uint16_t up_us_ = kImageUpUs;
  uint16_t down_us_ = kImageDownUs;
  bool down_ = false;
};

}  // namespace board
}  // namespace fdsurf
