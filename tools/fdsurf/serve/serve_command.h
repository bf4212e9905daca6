// SPDX-License-Identifier: MIT
// `fdsurf serve`'s command line (gpio_server.h is the server): --machine,
// --device, --link, --tick-hz, the servo widths, --quiet.
#pragma once

#include "gpio_server.h"

namespace CLI {
class App;
}

namespace fdsurf::host {

/// Adds serve's options to `command`.
void AddServeOptions(CLI::App* command, ServeOptions* options);

/// ServeGpio, with a line, chip or PWM channel that cannot be had reported
/// as "fdsurf: error: serve: ..." and exit 3. InputError passes through.
int RunServe(const ServeOptions& options);

}  // namespace fdsurf::host
