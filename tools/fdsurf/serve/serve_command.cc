// SPDX-License-Identifier: MIT
#include "serve_command.h"

#include <CLI/CLI.hpp>
#include <cstdio>

#include "../machine/profile.h"
#include "../runners/runner.h"

namespace fdsurf::host {

void AddServeOptions(CLI::App* command, ServeOptions* o) {
  AddMachineOption(command, &o->machine);
  command->add_option("--device", o->device,
                      "the lines to drive: gpio:CHIP:STEPX,DIRX,STEPY,DIRY[,STEPZ,DIRZ],EN,PEN"
                      "[:xmin=!N,...] (as stream's)");
  command->add_option("--link", o->link,
                      "where to publish the port (default $XDG_RUNTIME_DIR/fdsurf-gpio, else "
                      "/tmp/fdsurf-gpio); clients use --device serial:PATH");
  command->add_option("--tick-hz", o->tick_hz, "step timer rate (default 10000)")
      ->check(CLI::Range(1, 1'000'000));
  command->add_option("--servo-pulse-up", o->servo_pulse_up_us,
                      "servo pen (PEN pwmN.M): pulse width with the pen up, µs, until a CONFIG");
  command->add_option("--servo-pulse-down", o->servo_pulse_down_us,
                      "servo pen: pulse width with the pen down, µs");
  command->add_flag("--quiet,-q", o->quiet, "errors and the final summary only");
}

int RunServe(const ServeOptions& options) {
  try {
    return ServeGpio(options);
  } catch (const DeviceError& e) {
    std::fprintf(stderr, "fdsurf: error: serve: %s\n", e.what());
    return 3;
  }
}

}  // namespace fdsurf::host
