// SPDX-License-Identifier: MIT
// Compiles every interface header with the fdsurf_hal flags (C++14,
// -ffreestanding -nostdinc++), so an accidental C++ library include fails the
// build here rather than in a firmware port.
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/hal/clock.h"
#include "fdsurf/hal/io_status.h"
#include "fdsurf/hal/outputs.h"
#include "fdsurf/hal/pwm.h"
#include "fdsurf/hal/transport.h"
