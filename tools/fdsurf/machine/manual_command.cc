// SPDX-License-Identifier: MIT
#include "manual_command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli_options.h"
#include "../runners/runner.h"
#include "../runners/serial_session.h"
#include "../runners/usb_session.h"
#include "../serve/gpio_server.h"
#include "../stream_command.h"
#include "fdsurf/hal/serial_transport.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/text.h"
#include "fdsurf/sim/plotter.h"
#include "profile.h"

namespace fdsurf::host {
namespace {

const char* const kAxisLetters = "xyz";

// The settings `stream` would use: its options given the profile's values
// and then the command line's --device and --units.
struct Settings {
  StreamOptions stream;
  MachineOptions machine;
  int axes = 2;
  std::array<double, 3> step{};  // each axis's, in stream.units
  double coarsest_step = 0;      // the longest of the driven axes'
  MachineProfile profile;        // --machine's (no values without it)
};

void GiveOption(CLI::App* command, const std::string& flag, const std::string& value) {
  CLI::Option* option = command->get_option(flag);
  option->add_result(value);
  option->run_callback();
}

Settings Resolve(const ManualOptions& o) {
  CLI::App app;
  Settings s;
  CLI::App* stream = app.add_subcommand("stream");
  AddStreamOptions(stream, &s.stream);
  if (!o.units.empty()) GiveOption(stream, "--units", o.units);
  if (!o.device.empty()) GiveOption(stream, "--device", o.device);
  const std::pair<const char*, const std::string*> given[] = {{"--step", &o.step},
                                                              {"--travel", &o.travel},
                                                              {"--speed", &o.speed},
                                                              {"--accel", &o.accel},
                                                              {"--tick-hz", &o.tick_hz}};
  for (const auto& [flag, value] : given) {
    if (!value->empty()) GiveOption(stream, flag, *value);
  }
  if (o.require_homing) GiveOption(stream, "--require-homing", "true");
  if (!o.machine.empty()) {
    s.profile = LoadMachineProfile(FindMachineProfile(o.machine));
    ApplyMachineProfile(s.profile, stream);
  }
  s.stream.device = DeviceThroughServer(s.stream.device, o.quiet);
  s.machine = StreamMachine(s.stream);
  if (!(s.machine.travel[0] > 0)) {
    throw InputError(
        "machine commands need the machine's travel: give 'travel' in the profile "
        "(--machine) or --travel WxH on the command line");
  }
  s.axes = s.machine.travel[2] > 0 ? 3 : 2;
  for (int a = 0; a < 3; ++a) s.step[static_cast<std::size_t>(a)] = s.machine.StepOf(a).value();
  s.coarsest_step = s.machine.CoarsestStep(s.axes);
  return s;
}

std::int32_t ToSteps(double length, double step) {
  return static_cast<std::int32_t>(std::floor(length / step + 1e-9));
}

// stream's configuration (MachineConfigFor: steps, travel, limits, per-axis
// acceleration, servo widths, homing flag), with the speed limits fitted
// to the device's tick rate as stream fits a job (FitJobToDevice).
protocol::MachineConfig ConfigOf(const Settings& s, std::uint32_t tick_hz) {
  protocol::MachineConfig config = MachineConfigFor(s.machine, s.axes, s.stream.units);
  config.max_rate = std::min(config.max_rate, tick_hz);
  config.travel_rate = std::min(config.travel_rate, tick_hz);
  return config;
}

// One device connection: HELLO's answer, and jobs run to rest.
class Connection {
 public:
  virtual ~Connection() = default;
  virtual protocol::HelloReply Hello() = 0;
  /// Runs `commands` until executed and at rest: the status then.
  virtual protocol::StatusReport Run(const std::vector<protocol::Command>& commands) = 0;
  /// What to add to the output after a job (the simulator's view).
  virtual std::string Note(const Settings& /*s*/) { return ""; }
};

StreamJob JobOf(const std::vector<protocol::Command>& commands) {
  StreamJob job;
  job.commands = commands;
  for (const protocol::Command& command : commands) {
    job.labels.push_back(std::string("machine ") +
                         (command.type == protocol::MessageType::kConfig ? "config" : "command"));
  }
  return job;
}

// A device behind a transport loop (serial or usb): HELLO was answered when
// the connection was made; each job runs to rest through the loop.
class LoopConnection : public Connection {
 public:
  protocol::HelloReply Hello() override { return *loop().link().hello(); }
  protocol::StatusReport Run(const std::vector<protocol::Command>& commands) override {
    ProgressLine progress(false);
    if (loop().Run(JobOf(commands), &progress) != 0) {
      throw DeviceError("interrupted; the device was stopped");
    }
    return *loop().link().status();
  }

 protected:
  virtual TransportLoop& loop() = 0;
};

class SerialConnection final : public LoopConnection {
 public:
  explicit SerialConnection(const StreamOptions& o) {
    hal::SerialSpec spec;
    std::string error;
    if (!hal::ParseSerialDevice(o.device, &spec, &error)) throw InputError("--device: " + error);
    if (spec.automatic) throw InputError("--device serial:auto: name the port, serial:PATH");
    bool interrupted = false;
    auto session = ProbeSerialPort(spec.path, spec.baud, Milliseconds(o.connect_timeout_s), o.quiet,
                                   &error, &interrupted);
    if (!session) throw DeviceError(error);
    session_ = std::move(*session);
  }

 private:
  TransportLoop& loop() override { return *session_.loop; }
  SerialSession session_;
};

// A USB device (usb, usb:VID:PID, usb:BUS-PORT): the same transport loop as
// `stream --device usb` (usb_session.h). The device keeps its position,
// homing and motors between invocations, as a serial one does.
class UsbConnection final : public LoopConnection {
 public:
  explicit UsbConnection(const StreamOptions& o) : session_(OpenUsbSession(o)) {
    if (!session_.loop->Connect()) throw DeviceError(session_.name + ": interrupted");
  }

 private:
  TransportLoop& loop() override { return *session_.loop; }
  UsbSession session_;
};

// The simulated plotter: its carriage starts a third of X's travel and a
// quarter of Y's (and of Z's) from the min switches.
class SimConnection final : public Connection {
 public:
  SimConnection(const StreamOptions& o, const Settings& s) {
    sim::PlotterOptions options;
    options.axes = s.axes;
    if (o.tick_hz != 0) options.tick_hz = o.tick_hz;
    options.endstops = true;
    for (int a = 0; a < s.axes; ++a) {
      const std::int32_t travel = ToSteps(s.machine.travel[static_cast<std::size_t>(a)],
                                          s.step[static_cast<std::size_t>(a)]);
      options.endstop_options.start_offset[a] = a == 0 ? travel / 3 : travel / 4;
    }
    plotter_ = std::make_unique<sim::SimulatedPlotter>(options);
  }
  protocol::HelloReply Hello() override {
    protocol::HelloReply hello{};
    hello.tick_hz = plotter_->options().tick_hz;
    hello.features = protocol::kFeatureEndstops;
    return hello;
  }
  protocol::StatusReport Run(const std::vector<protocol::Command>& commands) override {
    HostLink link(LinkOptions());
    for (const protocol::Command& command : commands) {
      const protocol::DecodeResult result = link.Enqueue(command);
      if (!result.ok()) throw EngineError("machine command: cannot be sent");
    }
    const sim::RunResult result = plotter_->Run(link, 3'600'000'000ull);
    if (!result.finished) throw DeviceError("sim: " + DecodeDeviceError(result.error));
    return *link.status();
  }
  std::string Note(const Settings& s) override {
    const hal::SimEndstops& switches = *plotter_->endstops();
    std::string note = "sim: the carriage stands";
    for (int a = 0; a < s.axes; ++a) {
      note += std::string(a == 0 ? " " : ", ") + kAxisLetters[a] + " " +
              FormatNumber(static_cast<double>(switches.real_position(a)) *
                           s.step[static_cast<std::size_t>(a)]);
    }
    return note + " " + s.stream.units + " from its min switches (it started at " +
           FormatNumber(static_cast<double>(switches.real_position(0) - plotter_->position()[0]) *
                        s.step[0]) +
           ", " +
           FormatNumber(static_cast<double>(switches.real_position(1) - plotter_->position()[1]) *
                        s.step[1]) +
           ")";
  }

 private:
  std::unique_ptr<sim::SimulatedPlotter> plotter_;
};

std::unique_ptr<Connection> Connect(const Settings& s) {
  const std::string& device = s.stream.device;
  if (device == "sim") return std::make_unique<SimConnection>(s.stream, s);
  if (device.rfind("serial:", 0) == 0) return std::make_unique<SerialConnection>(s.stream);
  if (device == "usb" || device.rfind("usb:", 0) == 0) {
    return std::make_unique<UsbConnection>(s.stream);
  }
  if (device.rfind("gpio:", 0) == 0) {
    throw InputError("--device " + device +
                     ": nothing holds this machine's position between commands: start `fdsurf "
                     "serve --device " +
                     device +
                     "` (it drives the lines and holds the machine while it runs; "
                     "docs/machines.md), then run this again");
  }
  throw InputError("--device " + device +
                   ": machine commands run on sim, usb[:VID:PID|:BUS-PORT] and serial:PATH "
                   "devices");
}

std::string Where(const Settings& s, const protocol::StatusReport& r) {
  std::string text = "position";
  std::string steps;
  for (int a = 0; a < s.axes; ++a) {
    text += std::string(a == 0 ? " " : ", ") + kAxisLetters[a] + " " +
            FormatNumber(r.position[a] * s.step[static_cast<std::size_t>(a)]);
    steps += (a == 0 ? "" : ", ") + std::to_string(r.position[a]);
  }
  text += " " + s.stream.units + " (steps " + steps + "); pen " + (r.pen_down ? "down" : "up") +
          "; motors " + ((r.flags & protocol::kStatusFlagMotorsEnabled) != 0 ? "on" : "off");
  std::string homed;
  std::string endstops;
  for (int a = 0; a < s.axes; ++a) {
    if ((r.flags & (protocol::kStatusFlagHomedX << a)) != 0) homed += kAxisLetters[a];
    if ((r.flags & (protocol::kStatusFlagEndstopX << a)) != 0) endstops += kAxisLetters[a];
  }
  return text + "; homed " + (homed.empty() ? "none" : homed) + "; endstops triggered " +
         (endstops.empty() ? "none" : endstops);
}

std::uint8_t AxisMask(const std::string& letters, int axes, const char* flag) {
  std::uint8_t mask = 0;
  for (const char c : letters) {
    const char* at = std::strchr(kAxisLetters, c);
    if (at == nullptr || c == '\0' || at - kAxisLetters >= axes) {
      throw InputError(std::string(flag) + ": '" + letters + "' is not a set of the axes " +
                       std::string(kAxisLetters, static_cast<std::size_t>(axes)));
    }
    mask = static_cast<std::uint8_t>(mask | 1u << (at - kAxisLetters));
  }
  if (mask == 0) throw InputError(std::string(flag) + ": name at least one axis");
  return mask;
}

// One homing setting as `home` uses it: the command line's flag, else the
// profile's [homing] key, else empty; `what` names where it came from.
struct HomingSetting {
  std::string text;
  std::string what;
};

HomingSetting HomingValue(const Settings& s, const char* flag, const std::string& given,
                          const char* key) {
  if (!given.empty()) return {given, flag};
  const ProfileValue* value = s.profile.Find(key);
  if (value == nullptr) return {"", flag};
  return {OptionText(s.profile, *value, s.stream.units),
          std::string(key) + " (" + SourceOf(s.profile, *value) + ")"};
}

// --toward / homing.toward: "min" or "max" for every homed axis, or one per
// machine axis ("min,max" on the command line, ["min", "max"] in a profile).
std::uint8_t TowardMaxMask(const HomingSetting& toward, const Settings& s, std::uint8_t axes) {
  if (toward.text.empty()) return 0;
  std::vector<std::string> items;
  std::stringstream list(toward.text);
  for (std::string item; std::getline(list, item, ',');) items.push_back(item);
  if (items.size() != 1 && items.size() != static_cast<std::size_t>(s.axes)) {
    throw InputError(toward.what + ": '" + toward.text + "' gives " + std::to_string(items.size()) +
                     " directions for " + std::to_string(s.axes) +
                     " axes (give one for all, or one per axis)");
  }
  std::uint8_t mask = 0;
  for (int a = 0; a < s.axes; ++a) {
    const std::string& item = items[items.size() == 1 ? 0 : static_cast<std::size_t>(a)];
    if (item != "min" && item != "max") {
      throw InputError(toward.what + ": '" + item + "' is not min or max");
    }
    if (item == "max") mask = static_cast<std::uint8_t>(mask | 1u << a);
  }
  return static_cast<std::uint8_t>(mask & axes);
}

// A length of the homing settings: the flag's, else the profile's, else
// `default_mm` in the command's units.
double HomingLength(const Settings& s, const std::optional<double>& given, const char* flag,
                    const char* key, double default_mm, std::string* what) {
  *what = flag;
  if (given) return *given;
  const HomingSetting value = HomingValue(s, flag, "", key);
  if (value.text.empty()) return DefaultIn(default_mm, s.stream.units);
  *what = value.what;
  return std::stod(value.text);
}

protocol::Command HomeOf(const ManualOptions& o, const Settings& s,
                         const protocol::MachineConfig& config, std::uint32_t tick_hz) {
  protocol::Command command;
  command.type = protocol::MessageType::kHome;
  protocol::HomeCommand& home = command.body.home;
  const HomingSetting axes = HomingValue(s, "--axes", o.axes, "homing.axes");
  home.axes = AxisMask(axes.text.empty() ? std::string(kAxisLetters, s.axes) : axes.text, s.axes,
                       axes.what.c_str());
  home.toward_max =
      TowardMaxMask(HomingValue(s, "--toward", o.toward, "homing.toward"), s, home.axes);
  std::string rate_from;
  std::string backoff_from;
  const double rate = HomingLength(s, o.rate, "--rate", "homing.rate", 5, &rate_from);
  const double backoff =
      HomingLength(s, o.backoff, "--backoff", "homing.backoff", 1, &backoff_from);
  // HOME has one rate and one back-off for every axis: the rate in steps of
  // the coarsest axis (no axis searches faster), the back-off in the finest
  // (a coarser axis backs off farther).
  const double finest = *std::min_element(s.step.begin(), s.step.begin() + s.axes);
  const double rate_steps = std::floor(rate / s.coarsest_step);
  if (!(rate_steps >= 1 && rate_steps <= tick_hz)) {
    throw InputError(rate_from + ": " + FormatNumber(rate) + " " + s.stream.units +
                     "/s is not between one step per second and the device's " +
                     std::to_string(tick_hz) + " steps/s");
  }
  home.rate = static_cast<std::uint32_t>(rate_steps);
  const std::int32_t backoff_steps = ToSteps(backoff, finest);
  if (backoff < 0 || backoff_steps > config.travel_steps[0]) {
    throw InputError(backoff_from + ": " + FormatNumber(backoff) + " " + s.stream.units +
                     " is not within the travel");
  }
  home.backoff = static_cast<std::uint32_t>(backoff_steps);
  return command;
}

}  // namespace

namespace {

double NumberArg(const std::string& action, const std::string& text) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size() && std::isfinite(value)) return value;
  } catch (const std::exception&) {
  }
  throw InputError("machine " + action + ": '" + text + "' is not a number");
}

// jog and goto: the target in steps, refused outside [0, travel].
protocol::Command MoveOf(const std::string& action, const ManualOptions& o, const Settings& s,
                         const protocol::MachineConfig& config, const protocol::StatusReport& now) {
  const std::size_t given = o.args.size();
  if (given < 2 || given > static_cast<std::size_t>(s.axes)) {
    throw InputError("machine " + action + ": give " + (action == "jog" ? "DX DY" : "X Y") +
                     (s.axes == 3 ? " [DZ]" : "") + " in " + s.stream.units);
  }
  protocol::Command command;
  command.type = protocol::MessageType::kMove;
  for (std::int32_t& target : command.body.move.target) target = 0;
  for (int a = 0; a < s.axes; ++a) {
    const bool has = static_cast<std::size_t>(a) < given;
    const double value = has ? NumberArg(action, o.args[static_cast<std::size_t>(a)]) : 0;
    const double step = s.step[static_cast<std::size_t>(a)];
    const double steps = action == "jog" ? now.position[a] + std::round(value / step)
                         : has           ? std::round(value / step)
                                         : now.position[a];
    if (!(steps >= 0 && steps <= config.travel_steps[a])) {
      throw InputError("machine " + action + ": the target " + kAxisLetters[a] + " " +
                       FormatNumber(steps * step) + " " + s.stream.units +
                       " is outside the travel 0.." + FormatNumber(config.travel_steps[a] * step) +
                       " " + s.stream.units);
    }
    command.body.move.target[a] = static_cast<std::int32_t>(steps);
  }
  return command;
}

// pen up|down, motors on|off.
protocol::Command SwitchOf(const std::string& action, const ManualOptions& o) {
  const char* on = action == "pen" ? "down" : "on";
  const char* off = action == "pen" ? "up" : "off";
  if (o.args.size() != 1 || (o.args[0] != on && o.args[0] != off)) {
    throw InputError("machine " + action + ": give " + on + " or " + off);
  }
  protocol::Command command;
  command.type = action == "pen" ? protocol::MessageType::kPen : protocol::MessageType::kMotors;
  if (action == "pen") {
    command.body.pen.down = o.args[0] == on;
  } else {
    command.body.motors.enabled = o.args[0] == on;
  }
  return command;
}

int Execute(const std::string& action, const ManualOptions& o, const Settings& s) {
  std::unique_ptr<Connection> connection = Connect(s);
  const protocol::HelloReply hello = connection->Hello();
  protocol::Command config;
  config.type = protocol::MessageType::kConfig;
  config.body.config = ConfigOf(s, hello.tick_hz);
  std::vector<protocol::Command> commands = {config};
  if (action == "home") {
    if ((hello.features & protocol::kFeatureEndstops) == 0) {
      throw DeviceError(s.stream.device + ": the device has no endstop inputs (HELLO features)");
    }
    commands.push_back(HomeOf(o, s, config.body.config, hello.tick_hz));
  } else if (action == "jog" || action == "goto") {
    const protocol::StatusReport now = connection->Run(commands);
    commands.push_back(MoveOf(action, o, s, config.body.config, now));
  } else if (action == "pen" || action == "motors") {
    commands.push_back(SwitchOf(action, o));
  } else if (!o.args.empty()) {
    throw InputError("machine where: takes no arguments");
  }
  const protocol::StatusReport report = connection->Run(commands);
  const std::string note = connection->Note(s);
  if (!note.empty() && !o.quiet) std::printf("%s\n", note.c_str());
  std::printf("%s\n", Where(s, report).c_str());
  return 0;
}

}  // namespace

void AddManualCommands(CLI::App* machine, ManualOptions* options, std::string* action) {
  const std::pair<const char*, const char*> commands[] = {
      {"home", "Home the axes against their endstops (HOME)."},
      {"jog", "Move by DX DY [DZ] (--units) from where the machine is."},
      {"goto", "Move to X Y [Z] (--units), within the travel."},
      {"pen", "Put the pen up or down."},
      {"motors", "Switch the stepper drivers off (forgets homing) or on."},
      {"where", "Print the position, pen, motors, homing and endstops."}};
  for (const auto& [name, help] : commands) {
    CLI::App* command = machine->add_subcommand(name, help);
    AddMachineOption(command, &options->machine);
    command->add_option("--device", options->device, "the device, as stream's --device");
    command->add_option("--units", options->units, "units of the arguments and the output")
        ->check(CLI::IsMember({"mm", "in"}));
    command->add_flag("--quiet,-q", options->quiet, "only the final position");
    command->add_option("--step", options->step, "as stream's --step");
    command->add_option("--travel", options->travel, "as stream's --travel (WxH[xD])");
    command->add_option("--speed", options->speed, "as stream's --speed");
    command->add_option("--accel", options->accel, "as stream's --accel");
    command->add_option("--tick-hz", options->tick_hz, "as stream's --tick-hz");
    command->add_flag("--require-homing", options->require_homing,
                      "the device refuses motion until homed (CONFIG flag)");
    if (std::string(name) == "home") {
      command->add_option("--axes", options->axes, "axes to home, e.g. xy (default all)");
      command->add_option("--toward", options->toward,
                          "min (default) or max, or one per axis: min,max[,min]");
      command->add_option("--rate", options->rate, "search speed, --units/s (default 5 mm/s)");
      command->add_option("--backoff", options->backoff,
                          "back-off from the switch, --units (default 1 mm)");
    } else {
      command->add_option("args", options->args, "arguments");
    }
    command->callback([action, command] { *action = command->get_name(); });
  }
}

int RunManual(const std::string& action, const ManualOptions& options) {
  const Settings settings = Resolve(options);
  try {
    return Execute(action, options, settings);
  } catch (const DeviceError& e) {
    std::string message = e.what();
    if (message.find("not homed") != std::string::npos) {
      message += " (run `fdsurf machine home` first)";
    }
    std::fprintf(stderr, "fdsurf: error: machine %s: %s\n", action.c_str(), message.c_str());
    return 3;
  }
}

}  // namespace fdsurf::host
