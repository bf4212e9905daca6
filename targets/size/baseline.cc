// SPDX-License-Identifier: MIT
// Size baseline: the port (start-up, output, exit) with no engine. The size
// report subtracts this image from each group's image (targets/README.md).
#include "../image/image.h"

namespace fdsurf {
namespace image {

int RunImage(bool) { return 0; }

}  // namespace image
}  // namespace fdsurf
