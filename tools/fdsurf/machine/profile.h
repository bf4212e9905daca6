// SPDX-License-Identifier: MIT
// Machine profiles (issue 15, docs/machines.md): a TOML file that gives the
// settings of `stream` and of `plot`'s G-code output for one machine, found
// by `--machine NAME` under $XDG_CONFIG_HOME/fdsurf/machines/ (~/.config
// when XDG_CONFIG_HOME is unset) or `--machine FILE`. Precedence: built-in
// default < profile < command line. The schema (MachineKeys) is the one
// home of the keys: the parser, `machine show`, the nearest-key suggestion
// and the docs check (tests) all read it.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "fdsurf/config/nodiscard.h"

namespace CLI {
class App;
}

namespace fdsurf::host {

/// What a key's TOML value must be.
enum class KeyType {
  kText,        // a string
  kInteger,     // an integer
  kNumber,      // a number, not converted between units
  kLength,      // a number in the profile's units, converted to the command's
  kLengthList,  // an array of 2 or 3 positive lengths (WxH[xD])
  kBool,        // true or false (a command-line flag)
  kTextList,    // a string, or an array of 1 to 3 strings (one per axis), "A,B,C" as an option
  kStepsPer,    // motor steps per mm or per inch (the key's own unit): a number for every axis,
                // or one per axis (equal: the host plans every axis on one step); --step 1/N
};

/// A further check beyond the type and the option's own (CLI11) check.
enum class KeyCheck {
  kNone,
  kPositive,
  kQuantum,
  kNotNegative,  // a number, 0 or more
  kMinOrMax,     // each string "min" or "max"
  kAxisLetters,  // a string of distinct letters of "xyz", at least one
};

/// The TOML table of the homing keys: their schema names are "homing.KEY",
/// written `KEY = ...` under `[homing]` in the file.
inline constexpr std::string_view kHomingTable = "homing";

/// One key of a profile.
struct MachineKey {
  const char* name;  // the TOML key
  KeyType type;
  const char* unit;    // "units", "units/s", "ms", ... ("" for none)
  const char* option;  // the command-line option it feeds ("" for `units`)
  KeyCheck check;
  const char* help;
};

/// The schema: every key a profile may hold, `units` first.
const std::vector<MachineKey>& MachineKeys();

/// The known key nearest to `key` by edit distance (Levenshtein), for
/// "did you mean ...?". With a `table` ("homing"), only that table's keys
/// are candidates, and the answer is the name inside the table ("rate").
std::string NearestMachineKey(std::string_view key, std::string_view table = {});

/// One value of a profile, where it stands in its file (1-based).
struct ProfileValue {
  const MachineKey* key = nullptr;
  std::string text;             // kText, kInteger, kBool ("true"/"false"), kTextList ("a,b")
  std::vector<double> numbers;  // kNumber, kLength (one), kLengthList
  int line = 0;
  int column = 0;
};

/// A parsed profile: its path, the units of its figures ("mm" or "in",
/// default mm) and its values in file order.
struct MachineProfile {
  std::string path;
  std::string units = "mm";
  std::vector<ProfileValue> values;

  /// The value of `key`, or nullptr when the profile leaves it out.
  FDSURF_NODISCARD const ProfileValue* Find(std::string_view key) const;
};

/// The file `--machine NAME_OR_FILE` names: FILE when it holds a '/' or ends
/// in ".toml", else NAME.toml under $XDG_CONFIG_HOME/fdsurf/machines/ (an
/// unset, empty or relative XDG_CONFIG_HOME means $HOME/.config, as the XDG
/// Base Directory spec says). Throws InputError naming where it looked.
std::string FindMachineProfile(const std::string& name_or_file);

/// Parses `text` (the TOML of `path`). Throws InputError
/// "PATH:LINE:COLUMN: ..." for a TOML syntax error, a key not in the schema
/// (with the nearest known key, or "not supported yet"), a value of the
/// wrong type or out of range. The `[homing]` table's keys are checked
/// against the "homing.*" keys, and a key unknown there is suggested the
/// nearest of them.
MachineProfile ParseMachineProfile(std::string_view text, const std::string& path);

/// Reads and parses the file at `path` (InputError when it cannot be read).
MachineProfile LoadMachineProfile(const std::string& path);

/// The value as the command-line option takes it, in `command_units` ("mm"
/// or "in"): lengths converted from the profile's units, a list as WxH[xD].
std::string OptionText(const MachineProfile& profile, const ProfileValue& value,
                       const std::string& command_units);

/// " mm/s" for a key in "units/s" and --units mm; "" for a key without a unit.
std::string UnitText(const MachineKey& key, const std::string& command_units);

/// "PATH:LINE", where a value came from, for `machine show`.
std::string SourceOf(const MachineProfile& profile, const ProfileValue& value);

/// Adds `--machine NAME|FILE` to `command`.
void AddMachineOption(CLI::App* command, std::string* machine);

/// Gives each of `command`'s options that the command line left out the
/// profile's value, through the option's own conversion and checks, in the
/// units of the command's --units. Keys whose option `command` lacks are
/// skipped. Throws InputError "PATH:LINE:COLUMN: key 'K': ..." when the
/// option refuses a value; nothing is run then.
void ApplyMachineProfile(const MachineProfile& profile, CLI::App* command);

/// Loads `--machine`'s profile (when `machine` is not empty) and applies it
/// to `command`, as fdsurf.cc does for stream and plot before they run.
void ApplyMachineOption(const std::string& machine, CLI::App* command);

}  // namespace fdsurf::host
