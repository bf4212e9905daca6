// SPDX-License-Identifier: MIT
#include "machine_command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>

#include "../cli_options.h"
#include "../commands.h"
#include "../stream_command.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/host/text.h"
#include "fdsurf/host/writers.h"
#include "profile.h"

namespace fdsurf::host {
namespace {

// stream and plot with their real options: the defaults shown are theirs,
// and every value shown went through their checks.
struct Targets {
  StreamOptions stream_options;
  PlotOptions plot_options;
  CLI::App app;
  CLI::App* stream = nullptr;
  CLI::App* plot = nullptr;

  Targets() {
    stream = app.add_subcommand("stream");
    AddStreamOptions(stream, &stream_options);
    plot = app.add_subcommand("plot");
    AddPlotOptions(plot, &plot_options, false);
  }

  // Gives `flag` the command line's `text` on both commands that have it.
  void Give(const std::string& flag, const std::string& text) {
    for (CLI::App* command : {stream, plot}) {
      CLI::Option* option = command->get_option_no_throw(flag);
      if (option == nullptr) continue;
      try {
        option->add_result(text);
        option->run_callback();
      } catch (const CLI::ParseError& e) {
        throw InputError(flag + ": " + e.what());
      }
    }
  }

  // The built-in default of `flag` in `units`: CLI11's default text, or for
  // the options whose default is converted for --units (left empty in CLI11)
  // the library's mm default converted as the commands convert it.
  FDSURF_NODISCARD std::string DefaultOf(const std::string& flag, const std::string& units) const {
    for (const CLI::App* command : {stream, plot}) {
      const CLI::Option* option = command->get_option_no_throw(flag);
      if (option != nullptr && !option->get_default_str().empty()) {
        return option->get_default_str();
      }
    }
    return UnitDefaultOf(flag, units);
  }

 private:
  static std::string UnitDefaultOf(const std::string& flag, const std::string& units) {
    const MachineOptions machine;
    const GcodeOptions gcode;
    const std::pair<const char*, double> lengths[] = {{"--speed", machine.speed},
                                                      {"--accel", machine.accel},
                                                      {"--pen-up", gcode.pen_up_z},
                                                      {"--pen-down", gcode.pen_down_z},
                                                      {"--feed", gcode.feed},
                                                      {"--plunge-feed", gcode.plunge_feed},
                                                      {"--travel-rate", gcode.travel_rate},
                                                      {"--junction-deviation", 0.01}};
    for (const auto& [name, mm] : lengths) {
      if (flag == name) return FormatNumber(DefaultIn(mm, units));
    }
    if (flag == "--step") {
      const Quantum step = DefaultStepIn(machine.step, units);
      return step.Format(1);
    }
    // machine home's defaults (manual_command.cc).
    if (flag == "--rate") return FormatNumber(DefaultIn(5, units));
    if (flag == "--backoff") return FormatNumber(DefaultIn(1, units));
    if (flag == "--axes") return "all";
    if (flag == "--toward") return "min";
    if (flag == "--require-homing") return "false";
    if (flag == "--machine-origin") return "bottom-left";
    if (flag == "--travel") return "the page";
    if (flag == "--travel-speed") return "--speed";
    if (flag == "--axis-accel") return "twice --accel";
    if (flag == "--accel-x" || flag == "--accel-y" || flag == "--accel-z") return "--axis-accel";
    if (flag == "--tick-hz") return "the device's";
    return "(built in)";
  }
};

// `text` padded with spaces to `width` characters: printf's %-10s counts
// bytes, and "mm/s²" is 6 bytes but 5 characters.
std::string PadTo(const std::string& text, std::size_t width) {
  std::size_t characters = 0;
  for (const char c : text) {
    if ((static_cast<unsigned char>(c) & 0xC0) != 0x80) ++characters;  // not a continuation byte
  }
  return text + std::string(characters < width ? width - characters : 0, ' ');
}

// `path` with $HOME written as "~", as a user would type it.
std::string ForShow(const std::string& path) {
  const char* home = std::getenv("HOME");
  if (home == nullptr || home[0] == '\0') return path;
  const std::string prefix = std::string(home) + "/";
  return path.rfind(prefix, 0) == 0 ? "~/" + path.substr(prefix.size()) : path;
}

// The profile's steps_per_mm or steps_per_in, nullptr when it has neither.
const ProfileValue* StepsPerOf(const MachineProfile& profile) {
  for (const ProfileValue& value : profile.values) {
    if (value.key->type == KeyType::kStepsPer) return &value;
  }
  return nullptr;
}

}  // namespace

void AddMachineShowOptions(CLI::App* command, MachineShowOptions* options) {
  AddMachineOption(command, &options->machine);
  command->add_option("--units", options->units, "units of the settings shown (default mm)")
      ->check(CLI::IsMember({"mm", "in"}));
  const auto& keys = MachineKeys();
  options->values.resize(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    // steps_per_mm and steps_per_in feed --step: the profile's keys only.
    if (keys[i].option[0] == '\0' || keys[i].type == KeyType::kStepsPer) continue;
    if (keys[i].type == KeyType::kBool) {
      command->add_flag(keys[i].option, options->values[i], keys[i].help);
    } else {
      command->add_option(keys[i].option, options->values[i], keys[i].help);
    }
  }
}

int RunMachineShow(const MachineShowOptions& options) {
  Targets targets;
  const std::string units =
      options.units.empty() ? targets.DefaultOf("--units", "") : options.units;
  if (!options.units.empty()) targets.Give("--units", options.units);
  const auto& keys = MachineKeys();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (!options.values[i].empty()) targets.Give(keys[i].option, options.values[i]);
  }
  MachineProfile profile;
  if (!options.machine.empty()) {
    profile = LoadMachineProfile(FindMachineProfile(options.machine));
    ApplyMachineProfile(profile, targets.stream);
    ApplyMachineProfile(profile, targets.plot);
    std::printf("profile %s (its lengths in %s)\n", ForShow(profile.path).c_str(),
                profile.units.c_str());
  } else {
    std::printf("no profile (--machine NAME|FILE)\n");
  }
  std::printf("units %s (%s)\n", units.c_str(), options.units.empty() ? "default" : "command line");
  // The key and option columns as wide as their longest entry
  // (servo_pulse_down, --servo-pulse-down), so that every row lines up.
  int key_width = 3;
  int option_width = 6;
  for (const MachineKey& key : keys) {
    key_width = std::max(key_width, static_cast<int>(std::strlen(key.name)));
    option_width = std::max(option_width, static_cast<int>(std::strlen(key.option)));
  }
  std::printf("%-*s %-20s %-10s %-*s %s\n", key_width, "key", "value", "unit", option_width,
              "option", "source");
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const MachineKey& key = keys[i];
    if (key.option[0] == '\0') continue;
    const ProfileValue* in_profile = profile.Find(key.name);
    if (key.type == KeyType::kStepsPer) {
      if (in_profile == nullptr) continue;
      std::string counts;
      for (const double n : in_profile->numbers)
        counts += (counts.empty() ? "" : ",") + FormatNumber(n);
      std::printf("%-*s %-20s %s %-*s %s\n", key_width, key.name, counts.c_str(),
                  PadTo(key.unit, 10).c_str(), option_width, key.option,
                  ("profile " + ForShow(SourceOf(profile, *in_profile))).c_str());
      continue;
    }
    if (in_profile == nullptr && std::string_view(key.option) == "--step") {
      in_profile = StepsPerOf(profile);  // the step as steps per unit
    }
    std::string value;
    std::string source;
    if (!options.values[i].empty()) {
      value = options.values[i];
      source = "command line";
    } else if (in_profile != nullptr) {
      value = OptionText(profile, *in_profile, units);
      source = "profile " + ForShow(SourceOf(profile, *in_profile));
      if (in_profile->key != &key) source += std::string(" (") + in_profile->key->name + ")";
    } else {
      value = targets.DefaultOf(key.option, units);
      source = "default";
    }
    const std::string unit = UnitText(key, units);
    std::printf("%-*s %-20s %s %-*s %s\n", key_width, key.name, value.c_str(),
                PadTo(unit.empty() ? "-" : unit.substr(1), 10).c_str(), option_width, key.option,
                source.c_str());
  }
  return 0;
}

}  // namespace fdsurf::host
