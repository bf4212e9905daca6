// SPDX-License-Identifier: MIT
// The server behind `fdsurf serve --device gpio:CHIP:LINES[:ENDSTOPS]
// [--link PATH]`: this host becomes a board. The firmware's Device runs here
// in real time on the GPIO lines (as `stream --device gpio:…` runs it for
// one job) for as long as the command runs, and speaks the wire protocol on a pseudo-terminal
// published at PATH, so every host command reaches it as `--device serial:PATH`: `machine home`,
// `jog`, `where`, `stream --journal/--resume`, one process after another, with the position,
// homing, motors and pen held in between. Klipper's Linux MCU process (klipper_mcu,
// /tmp/klipper_host_mcu) is the model (docs/machines.md, "A gpio machine: fdsurf serve").
#pragma once

#include <string>

namespace fdsurf::host {

struct ServeOptions {
  std::string machine;   // --machine NAME|FILE (device, tick_hz, servo widths)
  std::string device;    // --device gpio:CHIP:LINES[:ENDSTOPS]
  std::string link;      // --link PATH; DefaultServeLink() when empty
  unsigned tick_hz = 0;  // --tick-hz; 0: 10000
  int servo_pulse_up_us = 0;
  int servo_pulse_down_us = 0;
  bool quiet = false;
};

/// Where `serve` publishes its port when --link is not given:
/// $XDG_RUNTIME_DIR/fdsurf-gpio, or /tmp/fdsurf-gpio without it.
std::string DefaultServeLink();

/// The device a command given `device` talks to: "serial:LINK" when a
/// running `serve` publishes that gpio:… spec (compared as written) at
/// DefaultServeLink(), saying so on stderr unless `quiet`; else `device`
/// as it is. `serve` writes the spec it drives beside its link, as
/// LINK.device, while it runs; `stream` and `machine` call this.
std::string DeviceThroughServer(const std::string& device, bool quiet);

/// Serves until SIGINT or SIGTERM. Then the device stops as on STOP
/// (decelerating along its path, 10 s at most; a second signal halts at
/// once), the pen is lifted and the drivers disabled on the lines, the
/// link is removed, and it returns 0. Returns 3 when an output fails (the
/// lines made safe first; the message names the line). Throws InputError
/// for a bad --device or --link (nothing opened), DeviceError when a line,
/// the chip or the PWM channel cannot be had.
int ServeGpio(const ServeOptions& options);

}  // namespace fdsurf::host
