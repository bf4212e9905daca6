// SPDX-License-Identifier: MIT
#include "fdsurf/host/svg_io.h"

#include <gtest/gtest.h>
