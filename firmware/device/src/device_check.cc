// SPDX-License-Identifier: MIT
// Instantiates the device under the core's freestanding flags, so that the
// header-only firmware is held to the same rules as the .cc files (and the
// freestanding-symbols check sees everything it links).
#include "fdsurf/device/device.h"

namespace fdsurf {
namespace device {

template class Device<2>;
template class Device<3, 4, 256>;

}  // namespace device
}  // namespace fdsurf
