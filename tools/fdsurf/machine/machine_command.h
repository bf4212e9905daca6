// SPDX-License-Identifier: MIT
// `fdsurf machine show`: the effective machine settings (profile.h's schema)
// and where each came from.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace fdsurf::host {

/// `fdsurf machine show`'s options.
struct MachineShowOptions {
  std::string machine;
  std::string units;
  /// The schema's options as typed, one per MachineKeys() entry ("" when
  /// left out).
  std::vector<std::string> values;
};

/// Adds `machine show`'s options: --machine, --units and one per key.
void AddMachineShowOptions(CLI::App* command, MachineShowOptions* options);

/// Prints every setting of the profile's schema with its effective value and
/// where it came from ("command line", "profile PATH:LINE", "default").
/// 0, or throws InputError as ApplyMachineProfile does.
int RunMachineShow(const MachineShowOptions& options);

}  // namespace fdsurf::host
