// SPDX-License-Identifier: MIT
// `fdsurf machine home | jog DX DY | goto X Y | pen up|down | motors off|on |
// where` (issue 15, "Manual control and homing"; docs/machines.md): one
// command to the device through the protocol, with the machine's settings
// from --machine's profile and the command line as `stream` takes them.
//
// Every invocation connects (a new session), sends CONFIG and the command,
// waits until the device has executed it and is at rest, and prints where
// the machine is. A device that stays powered (serial, usb, gpio) keeps its
// position and homing between invocations; the simulated plotter (sim) is a
// new machine each time, so on it `home` shows the search from a carriage
// placed away from its switches, and the other commands start at 0.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace fdsurf::host {

struct ManualOptions {
  std::string machine;  // --machine NAME|FILE
  std::string device;   // --device (else the profile's, else sim)
  std::string units;    // --units of the arguments and the output (else the profile's, mm)
  std::vector<std::string> args;
  /// stream's --step, --travel, --speed, --accel, --tick-hz as typed ("" when
  /// not given; they override the profile).
  std::string step, travel, speed, accel, tick_hz;
  /// home: --axes (letters of x, y, z), --toward (min|max, or one per
  /// axis min,max[,min]), --rate (units/s), --backoff (units); empty or
  /// nullopt when not given: the profile's [homing] table, else the
  /// defaults (all axes, min, 5 mm/s, 1 mm). --require-homing (every
  /// command): on when given or when the profile's homing.required is true.
  std::string axes;
  std::string toward;
  std::optional<double> rate;
  std::optional<double> backoff;
  bool require_homing = false;
  bool quiet = false;
};

/// Adds the subcommands home, jog, goto, pen, motors and where to `machine`
/// (all sharing `options`); *action is set to the one parsed.
void AddManualCommands(CLI::App* machine, ManualOptions* options, std::string* action);

/// Runs `action` with `options`: 0, or 3 when the device refused it or the
/// link failed (the message names the device and the reason). Throws
/// InputError for a bad argument or a target outside the travel.
int RunManual(const std::string& action, const ManualOptions& options);

}  // namespace fdsurf::host
