// SPDX-License-Identifier: MIT
// fdsurf_kernel_gpio_job: the host half of the GPIO test under QEMU arm64
// (docs/testing.md, "GPIO on arm64 under QEMU"). Plans a drawing with the
// tool's planner (BuildStreamJob), writes its commands as wire frames for
// fdsurf-gpio-stream in the guest (JOB), and runs the same commands on the
// simulated plotter at the guest's tick rate, writing what it drew as a
// waveform (REF) with the job's limits in its header, as
// `fdsurf stream --device sim --waveform` does, for fdsurf_waveform_check.
//
//   fdsurf_kernel_gpio_job --input FILE --job JOB --reference REF
//                          [--step MM] [--speed MM/S] [--accel MM/S2] [--tick-hz N]
//
// Prints "commands N moves M position X Y" (the simulated plotter's final
// position, in steps) on stdout. Exit 0; 2 for bad input or a job the
// simulated plotter did not finish.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/host/link.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"
#include "fdsurf/sim/plotter.h"
#include "fdsurf/sim/waveform.h"

namespace fdsurf::host {
namespace {

struct Options {
  std::string input;
  std::string job;
  std::string reference;
  std::string step = "0.05";
  double speed = 10;
  double accel = 400;
  std::uint32_t tick_hz = 500;
};

StreamJob PlanJob(const Options& o) {
  const PatchSet set = ReadPatchFile(o.input);
  ToolpathOptions drawing;
  drawing.view = *NamedView("top");
  MachineOptions machine;
  machine.step = Quantum::Parse(o.step, "step");
  machine.speed = o.speed;
  machine.accel = o.accel;
  return BuildStreamJob(set, drawing, machine, "mm");
}

void WriteJob(const StreamJob& job, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  std::vector<std::uint8_t> frame(protocol::kMaxEncodedFrameBytes);
  for (const protocol::Command& command : job.commands) {
    const std::size_t size = protocol::EncodeCommand(command, frame.data(), frame.size());
    out.write(reinterpret_cast<const char*>(frame.data()), static_cast<std::streamsize>(size));
  }
  out.close();
  if (!out) throw OutputError(path + ": cannot write the job");
}

// The job on the simulated plotter; its pins as REF.
void WriteReference(const StreamJob& job, const Options& o) {
  sim::PlotterOptions plotter_options;
  plotter_options.axes = job.config.axes;
  plotter_options.tick_hz = o.tick_hz;
  sim::SimulatedPlotter plotter(plotter_options);
  HostLink link;
  for (std::size_t k = 0; k < job.commands.size(); ++k) {
    if (!link.Enqueue(job.commands[k], job.labels[k]).ok()) {
      throw EngineError(job.labels[k] + ": the link refuses it");
    }
  }
  const sim::RunResult result = plotter.Run(link, 3'600'000'000ULL);
  if (!result.finished) throw EngineError("the simulated plotter did not finish: " + result.error);
  sim::WaveformHeader header;
  header.board = "sim";
  header.extra["axes"] = std::to_string(job.config.axes);
  header.extra["tick_hz"] = std::to_string(o.tick_hz);
  header.extra["max_rate"] = std::to_string(job.config.max_rate);
  header.extra["accel"] = std::to_string(job.config.accel);
  header.extra["pen_delay_ms"] = std::to_string(job.config.pen_delay_ms);
  header.extra["commands"] = std::to_string(job.commands.size());
  sim::WaveformWriteOptions write;
  write.axes = job.config.axes;
  std::ofstream out(o.reference, std::ios::binary);
  sim::WriteWaveform(
      out, header,
      sim::TransitionsFromEvents(header, plotter.step_events(), plotter.pen_events(), write));
  out.close();
  if (!out) throw OutputError(o.reference + ": cannot write the waveform");
  std::size_t moves = 0;
  for (const hal::StepDirEvent& e : plotter.step_events()) moves += e.axis_mask != 0 ? 1 : 0;
  const auto position = plotter.position();
  std::printf("commands %zu moves %zu position %lld %lld\n", job.commands.size(), moves,
              static_cast<long long>(position[0]), static_cast<long long>(position[1]));
}

}  // namespace
}  // namespace fdsurf::host

namespace {

int Main(int argc, char** argv) {
  fdsurf::host::Options o;
  CLI::App app("Plans a job for fdsurf-gpio-stream and the simulated plotter's waveform of it");
  app.add_option("--input", o.input, "the drawing (any format fdsurf reads)")->required();
  app.add_option("--job", o.job, "the job's commands as frames, for the guest")->required();
  app.add_option("--reference", o.reference, "the simulated plotter's waveform")->required();
  app.add_option("--step", o.step, "mm per motor step")->capture_default_str();
  app.add_option("--speed", o.speed, "path speed limit, mm/s")->capture_default_str();
  app.add_option("--accel", o.accel, "path acceleration limit, mm/s²")->capture_default_str();
  app.add_option("--tick-hz", o.tick_hz, "the device's tick rate")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    const fdsurf::host::StreamJob job = fdsurf::host::PlanJob(o);
    fdsurf::host::WriteJob(job, o.job);
    fdsurf::host::WriteReference(job, o);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf_kernel_gpio_job: error: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (...) {
    std::fprintf(stderr, "fdsurf_kernel_gpio_job: error: an unexpected exception\n");
    return 2;
  }
}
