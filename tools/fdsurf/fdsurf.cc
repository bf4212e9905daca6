// SPDX-License-Identifier: MIT
// fdsurf: the command-line tool. Every command validates its whole input
// before it writes anything, so an error leaves stdout empty. Exit codes: 0
// done, 1 a bound or limit broken, 2 bad input or output, 3 the engine or the
// device refused, 4 an internal error.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "cli_options.h"
#include "commands.h"
#include "construct_commands.h"
#include "fdsurf/host/errors.h"
#include "fdsurf_version.h"
#include "machine/machine_command.h"
#include "machine/manual_command.h"
#include "machine/profile.h"
#include "serve/serve_command.h"
#include "stream_command.h"

namespace fdsurf::host {
namespace {

// Every command's options and its CLI11 subcommand.
struct Commands {
  GridOptions sample_options;
  GridOptions check_options;
  PlotOptions plot_options;
  PlotOptions render_options;
  StreamOptions stream_options;
  JoinsOptions joins_options;
  PortsOptions ports_options;
  MachineShowOptions machine_show_options;
  ManualOptions manual_options;
  ServeOptions serve_options;
  std::string manual_action;  // home, jog, ... when one was parsed
  /// --machine of stream and plot (machine/profile.h).
  std::string stream_machine;
  std::string plot_machine;
  CLI::App* sample = nullptr;
  CLI::App* check = nullptr;
  CLI::App* plot = nullptr;
  CLI::App* render = nullptr;
  CLI::App* stream = nullptr;
  CLI::App* joins = nullptr;
  CLI::App* ports = nullptr;
  CLI::App* machine = nullptr;
  CLI::App* machine_show = nullptr;
  CLI::App* serve = nullptr;
};

void AddCommands(CLI::App* app, Commands* c) {
  c->sample = app->add_subcommand(
      "sample",
      "Print every grid point of every patch as CSV: patch,i,j,x,y,z (s = i/N, t = j/M).");
  AddGridOptions(c->sample, &c->sample_options);
  c->sample
      ->add_option("--engine", c->sample_options.engine,
                   "fixed: forward differences, exact multiples of Q; double: the reference")
      ->check(CLI::IsMember({"fixed", "double"}))
      ->capture_default_str();
  c->check = app->add_subcommand(
      "check", "Compare the fixed engine with the double reference on every grid point.");
  AddGridOptions(c->check, &c->check_options);
  c->plot = app->add_subcommand(
      "plot",
      "Draw the patches as a wireframe of isolines for a plotter or CNC: SVG, G-code, HPGL.");
  AddPlotOptions(c->plot, &c->plot_options, false);
  AddMachineOption(c->plot, &c->plot_machine);
  c->render = app->add_subcommand("render", "Draw the patches' isolines as a PNG picture.");
  AddPlotOptions(c->render, &c->render_options, true);
  c->stream = app->add_subcommand(
      "stream",
      "Stream the patches to a plotter (default: the simulated one), which evaluates them by "
      "forward differences and draws them; report what it drew.");
  AddStreamOptions(c->stream, &c->stream_options);
  AddMachineOption(c->stream, &c->stream_machine);
  c->joins = app->add_subcommand(
      "joins", "Report for every shared edge of the patches whether the join is C0, G1 or C1.");
  AddJoinsOptions(c->joins, &c->joins_options);
  c->ports = app->add_subcommand(
      "ports",
      "List the serial ports (USB VID:PID, serial number, product); --probe asks each "
      "for the fdsurf firmware.");
  AddPortsOptions(c->ports, &c->ports_options);
  c->machine = app->add_subcommand(
      "machine", "Machine profiles and manual control: home, jog, goto (docs/machines.md).");
  c->machine->require_subcommand(1);
  c->machine_show = c->machine->add_subcommand(
      "show", "Print the effective machine settings and where each came from.");
  AddMachineShowOptions(c->machine_show, &c->machine_show_options);
  AddManualCommands(c->machine, &c->manual_options, &c->manual_action);
  c->serve = app->add_subcommand(
      "serve",
      "Be the board of a machine on this host's GPIO lines: the device runs here and serves the "
      "protocol on a pty, for --device serial:PATH (docs/machines.md).");
  AddServeOptions(c->serve, &c->serve_options);
}

// CLI11 would only say "a subcommand is required" for a mistyped command.
bool IsUnknownCommand(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return false;
  const std::string first = argv[1];
  return first != "sample" && first != "check" && first != "plot" && first != "render" &&
         first != "stream" && first != "joins" && first != "ports" && first != "machine" &&
         first != "serve";
}

// Runs the parsed command; the library's errors become messages and exit
// codes (2 bad input or output, 3 the engine refused). A --machine profile
// fills in the options the command line left out before anything runs.
int RunParsed(Commands& c) {
  try {
    if (c.plot->parsed()) ApplyMachineOption(c.plot_machine, c.plot);
    if (c.stream->parsed()) ApplyMachineOption(c.stream_machine, c.stream);
    if (c.serve->parsed()) ApplyMachineOption(c.serve_options.machine, c.serve);
    if (c.sample->parsed()) return RunSample(c.sample_options);
    if (c.check->parsed()) return RunCheck(c.check_options);
    if (c.plot->parsed()) return RunPlot(c.plot_options, false);
    if (c.render->parsed()) return RunPlot(c.render_options, true);
    if (c.stream->parsed()) return RunStream(c.stream_options);
    if (c.joins->parsed()) return RunJoins(c.joins_options);
    if (c.ports->parsed()) return RunPorts(c.ports_options);
    if (c.machine_show->parsed()) return RunMachineShow(c.machine_show_options);
    if (!c.manual_action.empty()) return RunManual(c.manual_action, c.manual_options);
    if (c.serve->parsed()) return RunServe(c.serve_options);
  } catch (const OptionError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.MessageFor(FlagFor(e.field())).c_str());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const EngineError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  }
  return 1;
}

int Main(int argc, char** argv) {
  CLI::App app{
      "fdsurf: bicubic patches evaluated by fixed-point forward differences, with a proven "
      "0.51-quantum error bound."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("fdsurf ") + FDSURF_VERSION,
                       "Print the version and exit");
  Commands commands;
  AddCommands(&app, &commands);
  if (IsUnknownCommand(argc, argv)) {
    std::fprintf(
        stderr,
        "fdsurf: error: unknown command '%s' (expected sample, check, plot, render, stream, "
        "joins, ports, machine or serve)\n",
        argv[1]);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0: CLI11 prints them.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    // Everything else is bad arguments: the tool's own prefix and code 2,
    // like every other refusal.
    const std::string help = argc >= 2 && argv[1][0] != '-'
                                 ? std::string("fdsurf ") + argv[1] + " --help"
                                 : std::string("fdsurf --help");
    std::fprintf(stderr, "fdsurf: error: %s (see %s)\n", e.what(), help.c_str());
    return 2;
  }
  return RunParsed(commands);
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  try {
    return fdsurf::host::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf: internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "fdsurf: internal error\n");
  }
  return 4;
}
