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
#include "stream_command.h"

namespace fdsurf::host {
namespace {

int Main(int argc, char** argv) {
  CLI::App app{
      "fdsurf: bicubic patches evaluated by fixed-point forward differences, with a proven "
      "0.51-quantum error bound."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("fdsurf ") + FDSURF_VERSION,
                       "Print the version and exit");

  GridOptions sample_options;
  CLI::App* sample = app.add_subcommand(
      "sample",
      "Print every grid point of every patch as CSV: patch,i,j,x,y,z (s = i/N, t = j/M).");
  AddGridOptions(sample, &sample_options);
  sample
      ->add_option("--engine", sample_options.engine,
                   "fixed: forward differences, exact multiples of Q; double: the reference")
      ->check(CLI::IsMember({"fixed", "double"}))
      ->capture_default_str();

  GridOptions check_options;
  CLI::App* check = app.add_subcommand(
      "check", "Compare the fixed engine with the double reference on every grid point.");
  AddGridOptions(check, &check_options);

  PlotOptions plot_options;
  CLI::App* plot = app.add_subcommand(
      "plot",
      "Draw the patches as a wireframe of isolines for a plotter or CNC: SVG, G-code, HPGL.");
  AddPlotOptions(plot, &plot_options, false);
  PlotOptions render_options;
  CLI::App* render = app.add_subcommand("render", "Draw the patches' isolines as a PNG picture.");
  AddPlotOptions(render, &render_options, true);

  StreamOptions stream_options;
  CLI::App* stream = app.add_subcommand(
      "stream",
      "Stream the patches to a plotter (default: the simulated one), which evaluates them by "
      "forward differences and draws them; report what it drew.");
  AddStreamOptions(stream, &stream_options);

  JoinsOptions joins_options;
  CLI::App* joins = app.add_subcommand(
      "joins", "Report for every shared edge of the patches whether the join is C0, G1 or C1.");
  AddJoinsOptions(joins, &joins_options);

  // CLI11 would only say "a subcommand is required" for a mistyped command.
  const std::string first = argc > 1 ? argv[1] : "";
  if (argc > 1 && argv[1][0] != '-' && first != "sample" && first != "check" && first != "plot" &&
      first != "render" && first != "stream" && first != "joins") {
    std::fprintf(
        stderr,
        "fdsurf: error: unknown command '%s' (expected sample, check, plot, render, stream or "
        "joins)\n",
        argv[1]);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (sample->parsed()) return RunSample(sample_options);
    if (check->parsed()) return RunCheck(check_options);
    if (plot->parsed()) return RunPlot(plot_options, false);
    if (render->parsed()) return RunPlot(render_options, true);
    if (stream->parsed()) return RunStream(stream_options);
    if (joins->parsed()) return RunJoins(joins_options);
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
