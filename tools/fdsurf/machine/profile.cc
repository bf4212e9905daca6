// SPDX-License-Identifier: MIT
#include "profile.h"

#include <toml++/toml.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/quantum.h"
#include "fdsurf/host/text.h"

namespace fdsurf::host {
namespace {

// Keys of features that do not exist yet: refused like unknown keys, but
// saying so (docs/machines.md, "Not supported yet").
struct PlannedKey {
  const char* name;
  const char* why;
};
constexpr PlannedKey kPlannedKeys[] = {
    {"home", "the key is 'homing', a table: [homing] axes, toward, rate, backoff, required"},
};

std::string Where(const std::string& path, const toml::source_region& at) {
  return path + ":" + std::to_string(at.begin.line) + ":" + std::to_string(at.begin.column);
}

InputError KeyError(const std::string& path, const toml::source_region& at, const std::string& key,
                    const std::string& what) {
  return InputError(Where(path, at) + ": key '" + key + "': " + what);
}

std::string TypeName(KeyType type) {
  switch (type) {
    case KeyType::kText:
      return "a string";
    case KeyType::kInteger:
      return "an integer";
    case KeyType::kLengthList:
      return "an array of 2 or 3 numbers [W, H] or [W, H, D]";
    case KeyType::kBool:
      return "true or false";
    case KeyType::kTextList:
      return "a string or an array of 1 to 3 strings";
    case KeyType::kStepsPer:
      return "a number, or an array of 2 or 3 numbers (one per axis)";
    default:
      return "a number";
  }
}

std::string TomlTypeName(const toml::node& node) {
  std::ostringstream s;
  s << node.type();
  return s.str();
}

// Reads one number of the profile: an integer or a float.
bool NumberOf(const toml::node& node, double* out) {
  if (const auto v = node.value<double>(); v && (node.is_integer() || node.is_floating_point())) {
    *out = *v;
    return true;
  }
  return false;
}

// A string, or an array of 1 to 3 strings, as "a,b,c"; "" when `node` is
// neither.
std::string TextListOf(const toml::node& node) {
  if (const auto text = node.value<std::string>(); text && node.is_string()) return *text;
  const toml::array* list = node.as_array();
  if (list == nullptr || list->empty() || list->size() > 3) return "";
  std::string joined;
  for (const toml::node& item : *list) {
    if (!item.is_string()) return "";
    joined += (joined.empty() ? "" : ",") + *item.value<std::string>();
  }
  return joined;
}

// Why `text` fails `check` (KeyCheck::kMinOrMax, kAxisLetters), "" when it
// passes or the check is not about text.
std::string RefusedText(KeyCheck check, const std::string& text) {
  if (check == KeyCheck::kMinOrMax) {
    std::stringstream items(text);
    for (std::string item; std::getline(items, item, ',');) {
      if (item != "min" && item != "max") return R"(must be "min" or "max", not ")" + item + "\"";
    }
  }
  if (check == KeyCheck::kAxisLetters) {
    const bool letters = !text.empty() && text.find_first_not_of("xyz") == std::string::npos;
    bool distinct = true;
    for (std::size_t i = 0; i < text.size(); ++i) {
      distinct = distinct && text.find(text[i], i + 1) == std::string::npos;
    }
    if (!letters || !distinct) {
      return R"(must name the axes as distinct letters of "xyz" (like "xy"), not ")" + text + "\"";
    }
  }
  return "";
}

// The value of `key` as the schema says it must be; throws KeyError.
ProfileValue ReadValue(const MachineKey& key, const toml::node& node, const std::string& path) {
  ProfileValue value;
  value.key = &key;
  value.line = static_cast<int>(node.source().begin.line);
  value.column = static_cast<int>(node.source().begin.column);
  const auto wrong_type = [&] {
    return KeyError(path, node.source(), key.name,
                    "must be " + TypeName(key.type) + ", not " + TomlTypeName(node));
  };
  double number = 0;
  switch (key.type) {
    case KeyType::kText:
      if (!node.is_string()) throw wrong_type();
      value.text = *node.value<std::string>();
      break;
    case KeyType::kInteger:
      if (!node.is_integer()) throw wrong_type();
      value.text = std::to_string(*node.value<std::int64_t>());
      break;
    case KeyType::kBool:
      if (!node.is_boolean()) throw wrong_type();
      value.text = *node.value<bool>() ? "true" : "false";
      break;
    case KeyType::kTextList:
      value.text = TextListOf(node);
      if (value.text.empty()) throw wrong_type();
      break;
    case KeyType::kNumber:
    case KeyType::kLength:
      if (!NumberOf(node, &number)) throw wrong_type();
      value.numbers.push_back(number);
      break;
    case KeyType::kLengthList:
    case KeyType::kStepsPer: {
      if (key.type == KeyType::kStepsPer && NumberOf(node, &number)) {
        value.numbers.push_back(number);
        break;
      }
      const toml::array* list = node.as_array();
      if (list == nullptr || list->size() < 2 || list->size() > 3) throw wrong_type();
      for (const toml::node& item : *list) {
        if (!NumberOf(item, &number)) throw wrong_type();
        value.numbers.push_back(number);
      }
      break;
    }
  }
  for (const double n : value.numbers) {
    const bool positive = key.check == KeyCheck::kPositive || key.check == KeyCheck::kQuantum ||
                          key.type == KeyType::kLengthList || key.type == KeyType::kStepsPer;
    if (!std::isfinite(n) || (positive && !(n > 0))) {
      throw KeyError(path, node.source(), key.name, "must be above 0, not " + FormatNumber(n));
    }
    if (key.check == KeyCheck::kNotNegative && n < 0) {
      throw KeyError(path, node.source(), key.name, "must be 0 or more, not " + FormatNumber(n));
    }
  }
  const std::string refused = RefusedText(key.check, value.text);
  if (!refused.empty()) throw KeyError(path, node.source(), key.name, refused);
  return value;
}

// The schema's key `name` inside `table` ("" for the top level): "rate" in
// "homing" is "homing.rate"; a top-level name never matches a table's key.
const MachineKey* KeyNamed(std::string_view name, std::string_view table) {
  const std::string full =
      table.empty() ? std::string(name) : std::string(table) + "." + std::string(name);
  if (table.empty() && full.find('.') != std::string::npos) return nullptr;
  for (const MachineKey& key : MachineKeys()) {
    if (full == key.name) return &key;
  }
  return nullptr;
}

InputError UnknownKey(const std::string& path, const toml::key& key, std::string_view table) {
  if (table.empty()) {
    for (const PlannedKey& planned : kPlannedKeys) {
      if (key.str() == planned.name) {
        return KeyError(path, key.source(), std::string(key.str()), planned.why);
      }
    }
  }
  const std::string name =
      table.empty() ? std::string(key.str()) : std::string(table) + "." + std::string(key.str());
  return KeyError(path, key.source(), name,
                  "not a machine setting (did you mean '" + NearestMachineKey(key.str(), table) +
                      "'? docs/machines.md lists them)");
}

// Reads the values of `table` (`prefix` "" for the top level, else the
// table's name) into `profile`; the top level's `[homing]` table recurses.
void ReadTable(const toml::table& table, std::string_view prefix, const std::string& path,
               MachineProfile* profile) {
  for (const auto& [name, node] : table) {
    if (prefix.empty() && name.str() == kHomingTable) {
      const toml::table* homing = node.as_table();
      if (homing == nullptr) {
        throw KeyError(
            path, node.source(), std::string(name.str()),
            "must be a table, [homing] with axes, toward, rate, backoff, required; not " +
                TomlTypeName(node));
      }
      ReadTable(*homing, kHomingTable, path, profile);
      continue;
    }
    const MachineKey* key = KeyNamed(name.str(), prefix);
    if (key == nullptr) throw UnknownKey(path, name, prefix);
    ProfileValue value = ReadValue(*key, node, path);
    if (key == &MachineKeys().front()) {
      if (value.text != "mm" && value.text != "in") {
        throw KeyError(path, node.source(), key->name,
                       R"(must be "mm" or "in", not ")" + value.text + "\"");
      }
      profile->units = value.text;
      continue;
    }
    profile->values.push_back(std::move(value));
  }
}

// A number as an option takes it: up to 15 significant digits, so that
// 0.2 stays "0.2" and a conversion keeps what a double holds of it.
std::string FormatOptionNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", v);
  return text;
}

// Whether the key's figures are lengths, converted between mm and in.
bool IsLength(const MachineKey& key) {
  return key.type == KeyType::kLength || key.type == KeyType::kLengthList;
}

}  // namespace

const std::vector<MachineKey>& MachineKeys() {
  using T = KeyType;
  using C = KeyCheck;
  static const std::vector<MachineKey> keys = {
      {"units", T::kText, "", "", C::kNone,
       "units of this profile's lengths: mm or in (default mm)"},
      {"device", T::kText, "", "--device", C::kNone,
       "stream: sim, usb[:VID:PID], serial:PATH[:BAUD], serial:auto or gpio:CHIP:LINES"},
      {"dims", T::kInteger, "", "--dims", C::kNone, "2 (pen plotter) or 3 (with Z, for CNC)"},
      {"step", T::kLength, "units", "--step", C::kQuantum,
       "stream: length of one motor step, every axis (per axis: steps_per_mm)"},
      {"steps_per_mm", T::kStepsPer, "steps/mm", "--step", C::kPositive,
       "stream: motor steps per mm, every axis or [X, Y] or [X, Y, Z]; instead of step"},
      {"steps_per_in", T::kStepsPer, "steps/in", "--step", C::kPositive,
       "stream: motor steps per inch, every axis or [X, Y] or [X, Y, Z]; instead of step"},
      {"travel", T::kLengthList, "units", "--travel", C::kPositive,
       "stream: machine travel [W, H] or [W, H, D]"},
      {"speed", T::kLength, "units/s", "--speed", C::kPositive,
       "stream: path speed limit (pen down, and pen up unless travel_speed is set)"},
      {"travel_speed", T::kLength, "units/s", "--travel-speed", C::kPositive,
       "stream: path speed limit with the pen up (default: speed)"},
      {"accel", T::kLength, "units/s²", "--accel", C::kPositive,
       "stream: path acceleration limit; plot G-code: the time estimate's"},
      {"axis_accel", T::kLength, "units/s²", "--axis-accel", C::kPositive,
       "stream: each axis's acceleration limit, turning included (default: twice accel)"},
      {"accel_x", T::kLength, "units/s²", "--accel-x", C::kPositive,
       "stream: the X axis's acceleration limit (default: axis_accel)"},
      {"accel_y", T::kLength, "units/s²", "--accel-y", C::kPositive,
       "stream: the Y axis's acceleration limit (default: axis_accel)"},
      {"accel_z", T::kLength, "units/s²", "--accel-z", C::kPositive,
       "stream: the Z axis's acceleration limit (default: axis_accel)"},
      {"origin", T::kText, "", "--machine-origin", C::kNone,
       "stream: the page's corner at position 0: bottom-left, top-left, bottom-right, top-right"},
      {"pen_delay", T::kInteger, "ms", "--pen-delay", C::kNone,
       "stream: rest after each pen change"},
      {"servo_pulse_up", T::kInteger, "µs", "--servo-pulse-up", C::kNone,
       "stream: servo pen lift's pulse width with the pen up (0: the pen is a switch)"},
      {"servo_pulse_down", T::kInteger, "µs", "--servo-pulse-down", C::kNone,
       "stream: servo pen lift's pulse width with the pen down (0: the pen is a switch)"},
      {"tick_hz", T::kInteger, "Hz", "--tick-hz", C::kNone,
       "stream: the device's step timer (sim: must divide 1000000)"},
      {"flavor", T::kText, "", "--flavor", C::kNone,
       "plot G-code: generic, grbl, marlin or linuxcnc"},
      {"pen", T::kText, "", "--pen", C::kNone, "plot G-code: pen control z, m3 or servo"},
      {"pen_up_z", T::kLength, "units", "--pen-up", C::kNone,
       "plot G-code: Z with the pen up (3-D travel height)"},
      {"pen_down_z", T::kLength, "units", "--pen-down", C::kNone,
       "plot G-code: Z with the pen down"},
      {"feed", T::kLength, "units/min", "--feed", C::kPositive,
       "plot G-code: drawing (pen-down) feed"},
      {"plunge_feed", T::kLength, "units/min", "--plunge-feed", C::kPositive,
       "plot G-code: pen-down (plunge) feed"},
      {"travel_rate", T::kLength, "units/min", "--travel-rate", C::kPositive,
       "plot G-code: G0 (pen-up) rate for the time estimate"},
      {"junction_deviation", T::kLength, "units", "--junction-deviation", C::kNone,
       "plot G-code: Grbl's junction deviation for the time estimate"},
      {"dwell", T::kNumber, "s", "--dwell", C::kNone, "plot G-code: dwell after M3/M5 or M280"},
      {"servo_up", T::kNumber, "degrees", "--servo-up", C::kNone,
       "plot G-code, pen servo: angle with the pen up"},
      {"servo_down", T::kNumber, "degrees", "--servo-down", C::kNone,
       "plot G-code, pen servo: angle with the pen down"},
      {"servo_index", T::kInteger, "", "--servo-index", C::kNone,
       "plot G-code, pen servo: M280's servo index P"},
      {"homing.axes", T::kText, "", "--axes", C::kAxisLetters,
       "machine home: the axes homed, letters of xyz (default all)"},
      {"homing.toward", T::kTextList, "", "--toward", C::kMinOrMax,
       R"(machine home: "min" or "max", or one per axis ["min", "max"] (default min))"},
      {"homing.rate", T::kLength, "units/s", "--rate", C::kPositive,
       "machine home: the switch search speed (default 5 mm/s)"},
      {"homing.backoff", T::kLength, "units", "--backoff", C::kNotNegative,
       "machine home: back-off from the switch (default 1 mm)"},
      {"homing.required", T::kBool, "", "--require-homing", C::kNone,
       "stream, machine: the device refuses motion until homed (CONFIG flag)"},
  };
  return keys;
}

std::string NearestMachineKey(std::string_view key, std::string_view table) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  const std::string prefix = table.empty() ? "" : std::string(table) + ".";
  for (const MachineKey& known : MachineKeys()) {
    std::string_view name = known.name;
    if (name.substr(0, prefix.size()) != prefix) continue;
    name.remove_prefix(prefix.size());
    // Levenshtein distance, one row at a time.
    std::vector<std::size_t> row(name.size() + 1);
    for (std::size_t j = 0; j <= name.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= key.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= name.size(); ++j) {
        const std::size_t above = row[j];
        row[j] =
            std::min({row[j] + 1, row[j - 1] + 1, diagonal + (key[i - 1] == name[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    if (row.back() < best_distance) {
      best_distance = row.back();
      best = std::string(name);
    }
  }
  return best;
}

const ProfileValue* MachineProfile::Find(std::string_view key) const {
  for (const ProfileValue& value : values) {
    if (key == value.key->name) return &value;
  }
  return nullptr;
}

std::string FindMachineProfile(const std::string& name_or_file) {
  namespace fs = std::filesystem;
  const bool is_file =
      name_or_file.find('/') != std::string::npos ||
      (name_or_file.size() > 5 && name_or_file.compare(name_or_file.size() - 5, 5, ".toml") == 0);
  if (is_file) {
    if (!fs::is_regular_file(name_or_file)) {
      throw InputError("--machine: no profile file '" + name_or_file + "'");
    }
    return name_or_file;
  }
  if (name_or_file.empty() || name_or_file[0] == '.') {
    throw InputError("--machine: '" + name_or_file + "' is not a profile name or a .toml file");
  }
  // XDG Base Directory: $XDG_CONFIG_HOME must be an absolute path, else
  // it is ignored and $HOME/.config used.
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  fs::path config;
  if (xdg != nullptr && xdg[0] == '/') {
    config = xdg;
  } else if (home != nullptr && home[0] != '\0') {
    config = fs::path(home) / ".config";
  } else {
    throw InputError("--machine " + name_or_file +
                     ": neither XDG_CONFIG_HOME nor HOME is set; give the profile's file");
  }
  const fs::path path = config / "fdsurf" / "machines" / (name_or_file + ".toml");
  if (!fs::is_regular_file(path)) {
    throw InputError("--machine " + name_or_file + ": no profile " + path.string());
  }
  return path.string();
}

namespace {

// step, steps_per_mm and steps_per_in all say the step: one of them only.
void RefuseTwoSteps(const MachineProfile& profile) {
  const ProfileValue* first = nullptr;
  for (const ProfileValue& value : profile.values) {
    if (std::string_view(value.key->option) != "--step") continue;
    if (first == nullptr) {
      first = &value;
      continue;
    }
    throw InputError(profile.path + ":" + std::to_string(value.line) + ":" +
                     std::to_string(value.column) + ": key '" + value.key->name +
                     "': the step is already given by '" + first->key->name + "' on line " +
                     std::to_string(first->line) +
                     "; give one of step, steps_per_mm, steps_per_in");
  }
}

}  // namespace

MachineProfile ParseMachineProfile(std::string_view text, const std::string& path) {
  toml::table table;
  try {
    table = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(Where(path, e.source()) + ": " + std::string(e.description()));
  }
  MachineProfile profile;
  profile.path = path;
  ReadTable(table, "", path, &profile);
  RefuseTwoSteps(profile);
  // toml++ keeps a table's keys sorted; the file's order reads better.
  std::sort(profile.values.begin(), profile.values.end(),
            [](const ProfileValue& a, const ProfileValue& b) { return a.line < b.line; });
  return profile;
}

MachineProfile LoadMachineProfile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the machine profile");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseMachineProfile(text.str(), path);
}

std::string OptionText(const MachineProfile& profile, const ProfileValue& value,
                       const std::string& command_units) {
  const MachineKey& key = *value.key;
  if (!value.text.empty()) return value.text;  // kText, kInteger, kBool, kTextList
  if (key.type == KeyType::kStepsPer) {
    // The step, 1/N in the key's own unit, in the command's units; a step
    // that is no short decimal there is refused by --step's check.
    const std::string per = std::string(key.name).substr(std::string(key.name).size() - 2);
    std::string text;
    for (const double n : value.numbers) {
      const double step_mm = (per == "in" ? 25.4 : 1.0) / n;
      text += (text.empty() ? "" : ",") +
              FormatOptionNumber(command_units == "in" ? step_mm / 25.4 : step_mm);
    }
    return text;
  }
  double scale = 1;
  if (IsLength(key) && profile.units != command_units)
    scale = profile.units == "in" ? 25.4 : 1 / 25.4;
  std::string text;
  for (const double n : value.numbers) {
    if (!text.empty()) text += "x";
    text += FormatOptionNumber(n * scale);
  }
  return text;
}

std::string UnitText(const MachineKey& key, const std::string& command_units) {
  std::string unit = key.unit;
  if (unit.rfind("units", 0) == 0) unit.replace(0, 5, command_units);
  return unit.empty() ? unit : " " + unit;
}

std::string SourceOf(const MachineProfile& profile, const ProfileValue& value) {
  return profile.path + ":" + std::to_string(value.line);
}

void AddMachineOption(CLI::App* command, std::string* machine) {
  command->add_option("--machine", *machine,
                      "machine profile: NAME (~/.config/fdsurf/machines/NAME.toml) or FILE; "
                      "the command line overrides it (docs/machines.md)");
}

void ApplyMachineProfile(const MachineProfile& profile, CLI::App* command) {
  const CLI::Option* units_option = command->get_option_no_throw("--units");
  std::string units = "mm";
  if (units_option != nullptr) {
    units = units_option->count() > 0 ? units_option->results().back()
                                      : units_option->get_default_str();
  }
  for (const ProfileValue& value : profile.values) {
    CLI::Option* option = command->get_option_no_throw(value.key->option);
    if (option == nullptr || option->count() > 0) continue;
    if (IsLength(*value.key) && units != "mm" && units != "in") {
      // Converting into units not known yet would guess: refuse instead.
      throw InputError(profile.path + ":" + std::to_string(value.line) + ": key '" +
                       value.key->name + "': the command's units are not known yet; give --units");
    }
    const std::string text = OptionText(profile, value, units);
    const auto refuse = [&](const std::string& why) {
      std::string message = profile.path + ":" + std::to_string(value.line) + ":" +
                            std::to_string(value.column) + ": key '" + value.key->name + "' (";
      message += text + UnitText(*value.key, units) + " for " + value.key->option + "): ";
      message += why;
      return InputError(message);
    };
    try {
      if (value.key->check == KeyCheck::kQuantum) (void)Quantum::Parse(text, value.key->option);
      if (value.key->type == KeyType::kStepsPer) {
        std::stringstream steps(text);
        for (std::string step; std::getline(steps, step, ',');) {
          (void)Quantum::Parse(step, value.key->option);
        }
      }
      option->add_result(text);
      option->run_callback();
    } catch (const CLI::ParseError& e) {
      throw refuse(e.what());
    } catch (const InputError& e) {
      if (value.key->type != KeyType::kStepsPer) throw refuse(e.what());
      std::string why = "a step of 1/N ";
      why += std::string(value.key->name).substr(10);  // "mm" or "in" of steps_per_
      why += " for N = " + FormatOptionNumber(value.numbers.front());
      for (std::size_t k = 1; k < value.numbers.size(); ++k) {
        why += ", " + FormatOptionNumber(value.numbers[k]);
      }
      why += " (" + text;
      why += " " + units + ") is";
      why +=
          ", not a decimal of at most 9 significant digits and 9 decimals as a step must be "
          "(docs/precision.md): give 'step' in ";
      why += units + ", rounded to what your machine's drift allows";
      throw refuse(why);
    }
  }
}

void ApplyMachineOption(const std::string& machine, CLI::App* command) {
  if (machine.empty()) return;
  ApplyMachineProfile(LoadMachineProfile(FindMachineProfile(machine)), command);
}

}  // namespace fdsurf::host
