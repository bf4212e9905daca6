// SPDX-License-Identifier: MIT
#include "fdsurf/host/stream.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include "fdsurf/adaptive.h"
#include "fdsurf/host/constructions.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/host/reference.h"
#include "fdsurf/host/text.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/codec.h"
#include "stream_internal.h"

namespace fdsurf::host {
namespace {

using Vec = std::array<double, 3>;

// A point of the file in steps, each axis in its own, through the job's map.
Vec ToSteps(const Point3& model, const StreamJob& job) {
  Vec out = job.page.map.Apply(model);
  for (std::size_t c = 0; c < 3; ++c) out[c] /= job.steps[c].value();
  if (job.page.dims == 2) out[2] = 0;
  return out;
}

Vec InSteps(const Patch& patch, const StreamJob& job, double s, double t) {
  return ToSteps(EvaluateReference(patch, s, t), job);
}

double Distance(const Vec& a, const Vec& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// Where a patch's drawing starts and ends: the device draws s-lines then
// t-lines, every odd-numbered line of a family reversed.
std::array<Vec, 2> Ends(const Patch& patch, const StreamJob& job, int lines_s, int lines_t) {
  const Vec start = InSteps(patch, job, 0, 0);
  if (lines_t >= 2) {
    const bool reversed = ((lines_t - 1) & 1) != 0;
    return {start, InSteps(patch, job, reversed ? 0 : 1, 1)};
  }
  const bool reversed = ((lines_s - 1) & 1) != 0;
  return {start, InSteps(patch, job, 1, reversed ? 0 : 1)};
}

// A machine's travel (`round_up` false) holds its whole steps only; the
// page's, when no travel is given (`round_up` true), holds the page: a line
// that reaches the page's exact edge at 3818.66 steps draws a point at 3819.
std::int32_t TravelSteps(double length, const Quantum& step, const std::string& units,
                         const std::string& field, bool round_up) {
  const double exact = length / step.value();
  const double steps = round_up ? std::ceil(exact - 1e-9) : std::floor(exact + 1e-9);
  if (!(steps >= 1)) {
    throw OptionError(field, FormatNumber(length) + " " + units,
                      "is less than one step of " + step.Format(1) + " " + units);
  }
  // The device plans every straight move inside a travel of at most this
  // many steps, and refuses a larger travel (motion::TravelPlannable).
  constexpr std::int32_t kMost = motion::kMaxPlannableTravelSteps;
  if (steps > kMost) {
    throw OptionError(field, FormatNumber(length) + " " + units,
                      "is more than the device can travel: at most " + std::to_string(kMost) +
                          " steps of " + step.Format(1) + " " + units + " = " +
                          FormatNumber(kMost * step.value()) + " " + units +
                          " (use a coarser --step)");
  }
  return static_cast<std::int32_t>(steps);
}

// The servo pen's widths: both 0 (a switch pen) or each a pulse a hobby
// servo takes, 500..2500 µs (the protocol's range).
void SetServoPulses(const MachineOptions& machine, protocol::MachineConfig* config) {
  const bool switch_pen = machine.servo_up_us == 0 && machine.servo_down_us == 0;
  const struct {
    const char* field;
    int us;
  } pulses[] = {{"servo pulse up", machine.servo_up_us},
                {"servo pulse down", machine.servo_down_us}};
  for (const auto& pulse : pulses) {
    if (!switch_pen && (pulse.us < 500 || pulse.us > 2500)) {
      throw OptionError(pulse.field, std::to_string(pulse.us) + " µs",
                        pulse.us == 0 ? "is 0 while the other is not (both 0: a switch pen)"
                                      : "is outside 500..2500 (a servo's pulse widths)");
    }
  }
  config->servo_up_us = static_cast<std::uint16_t>(machine.servo_up_us);
  config->servo_down_us = static_cast<std::uint16_t>(machine.servo_down_us);
}

// Axis c's acceleration limit in steps/s²: its own, else twice the path's
// (`accel`, steps/s²); refused unless above the path's, whose excess is
// what turning may use.
std::uint32_t AxisAccelSteps(const MachineOptions& machine, double accel, double step,
                             const std::string& units, int c) {
  const double given = machine.axis_accel[static_cast<std::size_t>(c)];
  const double steps = given > 0 ? std::floor(given / step) : 2 * accel;
  if (!(steps > accel && steps < 4e9)) {
    throw OptionError(std::string("axis accel ") + "XYZ"[c],
                      FormatNumber(given > 0 ? given : 2 * machine.accel) + " " + units + "/s²",
                      "is not above the path's accel (" + FormatNumber(machine.accel) + " " +
                          units + "/s²): the excess is what turning may use");
  }
  return static_cast<std::uint32_t>(steps);
}

// The machine configuration: travel (the page's unless given), steps per
// meter, speed and acceleration in steps, the pen delay and servo widths.
protocol::MachineConfig ConfigFor(const MachineOptions& machine, const Toolpath& page,
                                  const std::string& units) {
  protocol::MachineConfig config{};
  config.axes = static_cast<std::uint8_t>(page.dims);
  // The device measures its path in steps: the limits in steps of the
  // coarsest axis hold along every direction (docs/machines.md).
  const double step = machine.CoarsestStep(page.dims);
  const double extent[3] = {page.width, page.height, page.depth};
  const char* const fields[3] = {"travel X", "travel Y", "travel Z"};
  for (int c = 0; c < 3; ++c) {
    config.steps_per_meter[c] = 0;
    config.travel_steps[c] = 0;
    if (c >= page.dims) continue;
    const Quantum& axis_step = machine.StepOf(c);
    const double travel =
        machine.travel[c] > 0 ? machine.travel[c] : std::max(extent[c], axis_step.value());
    if (travel < extent[c] - 1e-9) {
      throw OptionError(fields[c], FormatNumber(travel) + " " + units,
                        "is smaller than the page (" + FormatNumber(extent[c]) + " " + units + ")");
    }
    config.travel_steps[c] = TravelSteps(travel, axis_step, units, fields[c],
                                         /*round_up=*/!(machine.travel[c] > 0));
    const double meters = axis_step.value() * (units == "in" ? 0.0254 : 0.001);
    config.steps_per_meter[c] = static_cast<std::uint32_t>(std::lround(1 / meters));
  }
  const double max_rate = std::floor(machine.speed / step);
  const double travel_speed = machine.travel_speed > 0 ? machine.travel_speed : machine.speed;
  const double travel_rate = std::floor(travel_speed / step);
  const double accel = std::floor(machine.accel / step);
  if (!(max_rate >= 1 && max_rate < 4e9)) {
    throw OptionError("speed", FormatNumber(machine.speed) + " " + units + "/s",
                      "is not 1 step/s or more");
  }
  if (!(travel_rate >= 1 && travel_rate < 4e9)) {
    throw OptionError("travel speed", FormatNumber(travel_speed) + " " + units + "/s",
                      "is not 1 step/s or more");
  }
  if (!(accel >= 1 && accel < 4e9)) {
    throw OptionError("accel", FormatNumber(machine.accel) + " " + units + "/s²",
                      "is not 1 step/s² or more");
  }
  if (machine.pen_delay_ms < 0 || machine.pen_delay_ms > 65535) {
    throw OptionError("pen delay", std::to_string(machine.pen_delay_ms) + " ms",
                      "is outside 0..65535");
  }
  config.max_rate = static_cast<std::uint32_t>(max_rate);
  config.accel = static_cast<std::uint32_t>(accel);
  config.pen_delay_ms = static_cast<std::uint16_t>(machine.pen_delay_ms);
  // Protocol 3 fields: the pen-up speed limit, and each axis's limit, whose
  // excess over the path's acceleration the device leaves for turning.
  config.travel_rate = static_cast<std::uint32_t>(travel_rate);
  for (int c = 0; c < page.dims; ++c) {
    config.axis_accel[c] = AxisAccelSteps(machine, accel, machine.StepOf(c).value(), units, c);
  }
  SetServoPulses(machine, &config);
  config.flags = machine.homing_required ? protocol::kConfigFlagHomingRequired : 0;
  return config;
}

// The PATCH command of one patch; its edge lines that an earlier patch drew
// (found in `drawn`) are left out through skip_lines.
protocol::Command PatchCommandFor(const Patch& patch, const ToolpathOptions& t,
                                  const MachineOptions& machine, StreamJob* job,
                                  DrawnCurves* drawn) {
  protocol::Command command;
  command.type = protocol::MessageType::kPatch;
  command.seq = 0;
  protocol::PatchCommand& body = command.body.patch;
  body.basis = patch.basis;
  body.dims = static_cast<std::uint8_t>(t.dims);
  body.lines_s = static_cast<std::uint16_t>(t.lines_s);
  body.lines_t = static_cast<std::uint16_t>(t.lines_t);
  body.tolerance_q8 = job->tolerance_q8;
  for (auto& axis : body.geometry) axis = PatchGeometry1{};
  PatchToQuanta(patch, job->page.map, job->steps, t.dims, body.geometry);
  body.skip_lines = 0;
  struct Edge {
    IsolineFamily family;
    double at;
    std::uint8_t skip_bit;
  };
  static constexpr Edge kEdges[4] = {
      {IsolineFamily::kSLines, 0.0, protocol::kSkipFirstSLine},
      {IsolineFamily::kSLines, 1.0, protocol::kSkipLastSLine},
      {IsolineFamily::kTLines, 0.0, protocol::kSkipFirstTLine},
      {IsolineFamily::kTLines, 1.0, protocol::kSkipLastTLine},
  };
  for (const Edge& edge : kEdges) {
    if ((edge.family == IsolineFamily::kSLines ? t.lines_s : t.lines_t) < 2) continue;
    const SampledCurve samples =
        SampleIsoline(patch, job->page.map, machine.step.value(), t.dims, edge.family, edge.at);
    if (IsPoint(samples)) continue;  // a pole: the device leaves it out anyway
    if (drawn->CheckAndAdd(samples)) {
      body.skip_lines = static_cast<std::uint8_t>(body.skip_lines | edge.skip_bit);
      ++job->shared_edges_skipped;
    }
  }
  return command;
}

// A curve drawn the other way round, exactly: a Bézier's control points in
// reverse order; a Hermite's ends swapped and its tangents swapped and
// negated. Other bases are not reversed (CurveReversible).
bool CurveReversible(const Curve& curve) {
  return curve.basis == Basis::kBezier || curve.basis == Basis::kHermite;
}

Curve Reversed(const Curve& curve) {
  Curve out = curve;
  if (curve.basis == Basis::kBezier) {
    out.g = {curve.g[3], curve.g[2], curve.g[1], curve.g[0]};
  } else {
    out.g[0] = curve.g[1];
    out.g[1] = curve.g[0];
    for (int c = 0; c < 3; ++c) {
      out.g[2][static_cast<std::size_t>(c)] = -curve.g[3][static_cast<std::size_t>(c)];
      out.g[3][static_cast<std::size_t>(c)] = -curve.g[2][static_cast<std::size_t>(c)];
    }
  }
  return out;
}

// One curve as the device will get it: the CURVE command, and its first and
// last points as the device computes them (integer steps).
struct DeviceCurve {
  protocol::Command command;
  std::array<std::int32_t, 3> start{};
  std::array<std::int32_t, 3> end{};
};

DeviceCurve ToDevice(const Curve& curve, const ToolpathOptions& t, const StreamJob& job) {
  DeviceCurve out;
  protocol::Command& command = out.command;
  command.type = protocol::MessageType::kCurve;
  command.seq = 0;
  protocol::CurveCommand& body = command.body.curve;
  body.basis = curve.basis;
  body.dims = static_cast<std::uint8_t>(t.dims);
  body.tolerance_q8 = job.tolerance_q8;
  for (auto& axis : body.geometry) axis = CurveGeometry1{};
  CurveToQuanta(curve, job.page.map, job.steps, t.dims, body.geometry);
  PowerCurve1 power[protocol::kMaxAxes];
  const Status status = CurvePowerCoefficients(body.geometry, curve.basis, power);
  if (status != Status::kOk) {
    throw EngineError(curve.origin + ": " + StatusMessage(status) + "; use a coarser step");
  }
  for (int a = 0; a < protocol::kMaxAxes; ++a) {
    const auto& k = power[a].c;
    out.start[static_cast<std::size_t>(a)] = RoundToQuanta(k[3], kCoefficientFracBits);
    out.end[static_cast<std::size_t>(a)] =
        RoundToQuanta(k[0] + k[1] + k[2] + k[3], kCoefficientFracBits);
  }
  return out;
}

// One curve in the drawing order: its index and whether it is drawn reversed.
struct CurveVisit {
  std::size_t curve = 0;
  bool reversed = false;
};

// The order of one layer's curves (file order within it). With keep_order,
// file order. Otherwise chains (maximal runs of curves that meet end to end,
// as the device rounds them) are ordered by nearest neighbour from `from`,
// reversed when every curve of the layer can be reversed exactly.
std::vector<CurveVisit> OrderLayer(const std::vector<std::size_t>& curves,
                                   const std::vector<DeviceCurve>& device, bool keep_order,
                                   bool reversible, const PlanPoint& from) {
  std::vector<CurveVisit> order;
  if (keep_order) {
    for (const std::size_t c : curves) order.push_back(CurveVisit{c, false});
    return order;
  }
  std::vector<std::vector<std::size_t>> chains;
  for (const std::size_t c : curves) {
    if (chains.empty() || device[chains.back().back()].end != device[c].start)
      chains.emplace_back();
    chains.back().push_back(c);
  }
  const auto point = [](const std::array<std::int32_t, 3>& p) {
    return PlanPoint{static_cast<double>(p[0]), static_cast<double>(p[1]),
                     static_cast<double>(p[2])};
  };
  std::vector<std::array<PlanPoint, 2>> ends;
  ends.reserve(chains.size());
  for (const auto& chain : chains) {
    ends.push_back({point(device[chain.front()].start), point(device[chain.back()].end)});
  }
  for (const Visit& visit : OrderNearestNeighbour(ends, reversible, PlanMetric::kSpace, from)) {
    const auto& chain = chains[visit.index];
    if (visit.reversed) {
      for (std::size_t k = chain.size(); k-- > 0;) order.push_back(CurveVisit{chain[k], true});
    } else {
      for (const std::size_t c : chain) order.push_back(CurveVisit{c, false});
    }
  }
  return order;
}

// A curve of the file through `emit`. A straight curve is one MOVE with the
// pen down: the device draws the straight line from where it is (the
// curve's rounded start) to the same rounded end point that the CURVE would
// end at.
void DrawCurve(const DeviceCurve& curve, bool straight, std::size_t index,
               const std::string& origin, CurveEmitter* emit, StreamJob* job) {
  const std::string name = std::to_string(index) + " (" + origin + ")";
  if (straight) {
    protocol::Command line;
    line.type = protocol::MessageType::kMove;
    line.seq = 0;
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      line.body.move.target[a] = curve.end[static_cast<std::size_t>(a)];
    }
    emit->Draw(line, curve.start, curve.end, "line " + name);
  } else {
    emit->Draw(curve.command, curve.start, curve.end, "curve " + name);
  }
  job->curves.push_back(index);
}

// The file's curves, layer by layer in layer order (each layer's start
// recorded in job->layers when the file has layers), within a layer in the
// order of OrderLayer. A pen-up move only where a curve does not start where
// the one before ended (so a chain is drawn in one stroke).
void AddCurveCommands(const PatchSet& set, const ToolpathOptions& t, StreamJob* job) {
  std::vector<DeviceCurve> device;
  device.reserve(set.curves.size());
  std::map<int, std::vector<std::size_t>> by_layer;
  for (std::size_t c = 0; c < set.curves.size(); ++c) {
    device.push_back(ToDevice(set.curves[c], t, *job));
    by_layer[set.layers.empty() ? 0 : set.curves[c].layer].push_back(c);
  }
  CurveEmitter emit(job);
  for (const auto& [layer, curves] : by_layer) {
    if (!set.layers.empty()) {
      emit.Pen(false);
      const std::size_t at = job->commands.size();
      const auto named = static_cast<std::size_t>(layer);
      job->layers.push_back(LayerStart{at, named < set.layers.size() ? set.layers[named] : ""});
    }
    bool reversible = true;
    for (const std::size_t c : curves) reversible = reversible && CurveReversible(set.curves[c]);
    for (const CurveVisit& visit :
         OrderLayer(curves, device, set.keep_order, reversible, emit.At())) {
      const Curve& curve = set.curves[visit.curve];
      const DeviceCurve drawn =
          visit.reversed ? ToDevice(Reversed(curve), t, *job) : device[visit.curve];
      DrawCurve(drawn, curve.straight, visit.curve, curve.origin, &emit, job);
    }
  }
  emit.Pen(false);
}

const char* const kAxisNames[3] = {"X", "Y", "Z"};

// The exact range (steps) of one axis of a line with integer power
// coefficients in 2^-16 steps, from the ends and the derivative's roots.
std::array<long double, 2> LineRange(const PowerCurve1& line) {
  const long double a = line.c[0] / 65536.0L;
  const long double b = line.c[1] / 65536.0L;
  const long double c = line.c[2] / 65536.0L;
  const long double d = line.c[3] / 65536.0L;
  const auto f = [&](long double u) { return ((a * u + b) * u + c) * u + d; };
  std::array<long double, 2> range{std::min(f(0), f(1)), std::max(f(0), f(1))};
  const auto consider = [&](long double u) {
    if (u > 0 && u < 1) range = {std::min(range[0], f(u)), std::max(range[1], f(u))};
  };
  const long double disc = 4 * b * b - 12 * a * c;
  if (a == 0) {
    if (b != 0) consider(-c / (2 * b));
  } else if (disc >= 0) {
    consider((-2 * b + std::sqrt(disc)) / (6 * a));
    consider((-2 * b - std::sqrt(disc)) / (6 * a));
  }
  return range;
}

// The exact range, per axis, of the lines a PATCH or CURVE command draws,
// as the device computes them (the same walker and coefficients), in steps.
template <int kDims>
std::array<std::array<long double, 2>, 3> CommandRange(const protocol::Command& command) {
  std::array<std::array<long double, 2>, 3> range{};
  for (auto& r : range) r = {HUGE_VALL, -HUGE_VALL};
  const auto add = [&](const PowerCurve1(&line)[kDims]) {
    for (int c = 0; c < kDims; ++c) {
      const auto r = LineRange(line[c]);
      range[c] = {std::min(range[c][0], r[0]), std::max(range[c][1], r[1])};
    }
  };
  PowerCurve1 line[kDims];
  if (command.type == protocol::MessageType::kCurve) {
    CurveGeometry1 geometry[kDims];
    for (int c = 0; c < kDims; ++c) geometry[c] = command.body.curve.geometry[c];
    if (CurvePowerCoefficients(geometry, command.body.curve.basis, line) == Status::kOk) add(line);
    return range;
  }
  const protocol::PatchCommand& patch = command.body.patch;
  PatchGeometry1 geometry[kDims];
  for (int c = 0; c < kDims; ++c) geometry[c] = patch.geometry[c];
  for (const IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
    const std::uint16_t lines = family == IsolineFamily::kSLines ? patch.lines_s : patch.lines_t;
    IsolineWalker<kDims> walker;
    if (lines < 2 || IsolineWalker<kDims>::Create(geometry, patch.basis, family, lines, &walker) !=
                         Status::kOk) {
      continue;
    }
    while (walker.Next(line)) add(line);
  }
  return range;
}

// The message for a command the device would refuse, in the user's units,
// with the exact range of the command's lines for a travel refusal.
template <int kDims>
[[noreturn]] void ThrowRefusal(const StreamJob& job, std::size_t index, protocol::ErrorCode error,
                               std::uint8_t detail) {
  const protocol::Command& command = job.commands[index];
  const std::string units = " " + job.page.units;
  std::string message = job.labels[index] + ": ";
  if (error == protocol::ErrorCode::kPlannerRefused) {
    message += StatusMessage(static_cast<Status>(detail));
    message += " (the device's planner would refuse it); use a coarser step or a larger tolerance";
    throw EngineError(message);
  }
  if (error != protocol::ErrorCode::kOutOfTravel) {
    message += "the device would refuse it: ";
    message += protocol::ErrorName(error);
    throw EngineError(message);
  }
  const int axis = detail & 3;
  const double step = job.steps[static_cast<std::size_t>(axis)].value();
  const std::string travel =
      "the travel 0.." + FormatNumber(job.config.travel_steps[axis] * step) + units;
  if (command.type == protocol::MessageType::kMove) {
    message += "the move to " + std::string(kAxisNames[axis]) + " = " +
               FormatNumber(command.body.move.target[axis] * step) + units + " is outside " +
               travel;
    throw EngineError(message);
  }
  const auto range = CommandRange<kDims>(command)[static_cast<std::size_t>(axis)];
  message += "its lines run over " + std::string(kAxisNames[axis]) + " = " +
             FormatNumber(static_cast<double>(range[0]) * step) + ".." +
             FormatNumber(static_cast<double>(range[1]) * step) + units;
  if ((detail & motion::kUndecidedTravel) != 0) {
    message += ", too close to the edge of " + travel +
               " for the device to prove it inside; move it in by a step or two";
  } else {
    message += ", outside " + travel + " (points round to whole steps)";
  }
  throw EngineError(message);
}

// What the device will say to each command, asked of the device's own
// validation (motion::ValidateCommand) with the configuration the job sends,
// before anything is sent: a job that passes is never refused by the device
// for its travel or its planner.
template <int kDims>
void CheckAsTheDeviceWill(const StreamJob& job) {
  for (std::size_t i = 0; i < job.commands.size(); ++i) {
    if (job.commands[i].type == protocol::MessageType::kConfig) continue;
    std::uint8_t detail = 0;
    const protocol::ErrorCode error =
        motion::ValidateCommand<kDims>(job.commands[i], job.config, &detail);
    if (error != protocol::ErrorCode::kNone) ThrowRefusal<kDims>(job, i, error, detail);
  }
}

}  // namespace

namespace {

// A machine whose origin is another corner of the page sees the drawing
// mirrored in X and/or Y: its map from the file mirrors that axis about the
// page's width or height rounded up to whole steps (so that whole steps
// stay whole, and the drawing stays within 0..travel).
void MirrorForTheOrigin(MachineOrigin origin, StreamJob* job) {
  const bool mirror[2] = {
      origin == MachineOrigin::kBottomRight || origin == MachineOrigin::kTopRight,
      origin == MachineOrigin::kTopLeft || origin == MachineOrigin::kTopRight};
  const double extent[2] = {job->page.width, job->page.height};
  OutputMap& map = job->page.map;
  for (int a = 0; a < 2; ++a) {
    if (!mirror[a]) continue;
    const double step = job->steps[static_cast<std::size_t>(a)].value();
    const auto steps = static_cast<std::int64_t>(std::ceil(extent[a] / step - 1e-9));
    job->mirror_steps[a] = std::max<std::int64_t>(steps, 1);
    std::array<double, 3>& axis = a == 0 ? map.view.right : map.view.up;
    for (double& c : axis) c = -c;
    map.offset[a] = static_cast<double>(job->mirror_steps[a]) * step - map.offset[a];
  }
}

}  // namespace

protocol::MachineConfig MachineConfigFor(const MachineOptions& machine, int dims,
                                         const std::string& units) {
  Toolpath travel;
  travel.dims = dims;
  travel.width = machine.travel[0];
  travel.height = machine.travel[1];
  travel.depth = dims == 3 ? machine.travel[2] : 0;
  return ConfigFor(machine, travel, units);
}

std::optional<StreamPlan> ParseStreamPlan(const std::string& text) {
  if (text == "lines") return StreamPlan::kLines;
  if (text == "patches") return StreamPlan::kPatches;
  return std::nullopt;
}

std::optional<MachineOrigin> ParseMachineOrigin(const std::string& text) {
  if (text == "bottom-left") return MachineOrigin::kBottomLeft;
  if (text == "top-left") return MachineOrigin::kTopLeft;
  if (text == "bottom-right") return MachineOrigin::kBottomRight;
  if (text == "top-right") return MachineOrigin::kTopRight;
  return std::nullopt;
}

namespace {

// `quantum` as a multiple of the decimal 10^-decimals (decimals at least
// the quantum's own).
std::int64_t MantissaAt(const Quantum& quantum, int decimals) {
  std::int64_t mantissa = quantum.mantissa();
  for (int d = quantum.decimals(); d < decimals; ++d) mantissa *= 10;
  return mantissa;
}

}  // namespace

Quantum PageQuantum(const StreamJob& job) {
  const int dims = job.page.dims;
  int decimals = 0;
  for (int a = 0; a < dims; ++a) {
    decimals = std::max(decimals, job.steps[static_cast<std::size_t>(a)].decimals());
  }
  std::int64_t common = 0;
  for (int a = 0; a < dims; ++a) {
    common = std::gcd(common, MantissaAt(job.steps[static_cast<std::size_t>(a)], decimals));
  }
  if (common == MantissaAt(job.steps[0], decimals)) return job.steps[0];
  // common · 10^-decimals as text: at most 9 significant digits, since it
  // divides a step's mantissa.
  std::string digits = std::to_string(common);
  if (decimals > 0) {
    if (static_cast<int>(digits.size()) <= decimals) {
      digits.insert(0, static_cast<std::size_t>(decimals + 1) - digits.size(), '0');
    }
    digits.insert(digits.size() - static_cast<std::size_t>(decimals), ".");
  }
  return Quantum::Parse(digits, "the drawing's quantum");
}

std::array<std::int64_t, 3> PagePosition(const StreamJob& job,
                                         const std::array<std::int64_t, 3>& machine) {
  const Quantum page = PageQuantum(job);
  std::array<std::int64_t, 3> out = PageSteps(job, machine);
  for (std::size_t a = 0; a < 3; ++a) {
    const int decimals = std::max(page.decimals(), job.steps[a].decimals());
    out[a] *= MantissaAt(job.steps[a], decimals) / MantissaAt(page, decimals);
  }
  return out;
}

std::array<std::int64_t, 3> PageSteps(const StreamJob& job, std::array<std::int64_t, 3> machine) {
  for (std::size_t a = 0; a < 2; ++a) {
    if (job.mirror_steps[a] != 0) machine[a] = job.mirror_steps[a] - machine[a];
  }
  return machine;
}

StreamJob BuildStreamJob(const PatchSet& set, const ToolpathOptions& options,
                         const MachineOptions& machine, const std::string& units, StreamPlan plan) {
  ToolpathOptions t = options;
  t.quantum = machine.step;
  StreamJob job;
  job.page = PlanPage(set, t, units);
  for (int a = 0; a < 3; ++a) job.steps[static_cast<std::size_t>(a)] = machine.StepOf(a);
  if (t.dims == 3) {
    // The device's axes run from 0: put the bottom of the surface at Z = 0.
    job.page.map.offset[2] += job.page.depth;
  }
  MirrorForTheOrigin(machine.origin, &job);
  job.config = ConfigFor(machine, job.page, units);
  job.tolerance_steps = t.tolerance / machine.CoarsestStep(t.dims);
  job.tolerance_q8 =
      static_cast<std::uint32_t>(std::min(std::floor(job.tolerance_steps * 256), 4294967295.0));

  protocol::Command configure;
  configure.type = protocol::MessageType::kConfig;
  configure.seq = 0;
  configure.body.config = job.config;
  job.commands.push_back(configure);
  job.labels.emplace_back("the machine configuration");

  // An edge line that a patch before it draws is left out of a patch (PATCH
  // skip_lines): before it in file order for the lines plan (plot's order
  // before planning), in drawing order for the patches plan.
  DrawnCurves drawn_edges;
  if (plan == StreamPlan::kLines) {
    std::vector<protocol::Command> patches;
    std::vector<std::string> labels;
    for (std::size_t p = 0; p < set.patches.size(); ++p) {
      const Patch& patch = set.patches[p];
      patches.push_back(PatchCommandFor(patch, t, machine, &job, &drawn_edges));
      labels.push_back("patch " + std::to_string(p) + " (" + patch.origin + ")");
      job.patches.push_back(StreamedPatch{p, t.lines_s, t.lines_t});
    }
    AddPlannedLines(patches, labels, t.dims, &job);
  } else {
    // The patches, nearest neighbour first from the origin; the device fixes
    // the order of the lines inside a patch, so a patch is never reversed.
    std::vector<std::array<PlanPoint, 2>> ends;
    ends.reserve(set.patches.size());
    for (const Patch& patch : set.patches) ends.push_back(Ends(patch, job, t.lines_s, t.lines_t));
    for (const Visit& visit : OrderNearestNeighbour(ends, false, PlanMetric::kSpace)) {
      const Patch& patch = set.patches[visit.index];
      job.commands.push_back(PatchCommandFor(patch, t, machine, &job, &drawn_edges));
      job.labels.push_back("patch " + std::to_string(visit.index) + " (" + patch.origin + ")");
      job.patches.push_back(StreamedPatch{visit.index, t.lines_s, t.lines_t});
    }
  }
  AddCurveCommands(set, t, &job);
  if (t.dims == 3) {
    CheckAsTheDeviceWill<3>(job);
  } else {
    CheckAsTheDeviceWill<2>(job);
  }
  return job;
}

namespace {

using StrokeCubic = std::array<std::array<double, 3>, 4>;

// Whether a cubic's control points lie within `slack` of the segment from
// its first to its last point: then every point of the curve lies on that
// segment (convex hull) and the segment is all drawn, so one straight move
// draws it.
bool StraightCubic(const StrokeCubic& b, double slack) {
  Vec chord{};
  for (int c = 0; c < 3; ++c) chord[c] = b[3][c] - b[0][c];
  const double length = Distance(b[0], b[3]);
  if (length == 0) return false;
  for (const std::size_t k : {std::size_t{1}, std::size_t{2}}) {
    Vec from_start{};
    for (int c = 0; c < 3; ++c) from_start[c] = b[k][c] - b[0][c];
    const double along =
        (from_start[0] * chord[0] + from_start[1] * chord[1] + from_start[2] * chord[2]) / length;
    if (along < -slack || along > length + slack) return false;
    Vec foot{};
    for (int c = 0; c < 3; ++c) foot[c] = b[0][c] + chord[c] * (along / length);
    if (Distance(b[k], foot) > slack) return false;
  }
  return true;
}

// The planned visible strokes as curves on the page, each cubic shifted by
// `z_shift` along Z (3-D).
std::vector<Curve> CurvesOfStrokes(const PatchSet& set, const Toolpath& path, double z_shift) {
  std::vector<Curve> curves;
  const double straight_slack = 1e-6 * path.quantum.value();
  for (std::size_t k = 0; k < path.strokes.size(); ++k) {
    const Stroke& stroke = path.strokes[k];
    if (stroke.cubics.empty()) {
      throw EngineError("hidden lines: visible piece " + std::to_string(k) +
                        " has lost its exact cubics; it cannot be streamed as curves");
    }
    const std::string from = stroke.curve >= 0
                                 ? set.curves[static_cast<std::size_t>(stroke.curve)].origin
                                 : set.patches[stroke.patch].origin;
    for (std::size_t j = 0; j < stroke.cubics.size(); ++j) {
      Curve curve;
      curve.basis = Basis::kBezier;
      for (std::size_t i = 0; i < 4; ++i) {
        curve.g[i] = stroke.cubics[j][i];
        if (path.dims == 3) curve.g[i][2] += z_shift;
      }
      curve.layer = stroke.layer;
      curve.straight = StraightCubic(stroke.cubics[j], straight_slack);
      curve.origin =
          "visible piece " + std::to_string(k) + "." + std::to_string(j) + ", from " + from;
      curves.push_back(std::move(curve));
    }
  }
  return curves;
}

}  // namespace

VisibleCurves VisibleCurvesOf(const PatchSet& set, const ToolpathOptions& options,
                              const MachineOptions& machine, const std::string& units) {
  VisibleCurves out;
  ToolpathOptions t = options;
  t.quantum = machine.step;
  t.mode = StepMode::kAdaptive;  // as plot draws; the samples of visibility
  Toolpath path = BuildToolpath(set, t, units);
  out.hidden = HiddenLineDefaults(t.tolerance);
  out.report = RemoveHiddenLines(set, out.hidden, &path);
  out.plan = PlanStrokes(set, &path);
  if (path.strokes.empty()) throw InputError("--hidden remove: nothing of the drawing is visible");

  out.set.units = units;
  out.set.layers = set.layers;
  out.set.page = std::array<double, 2>{path.width, path.height};
  out.set.keep_order = true;  // PlanStrokes' order (nearest neighbour, 2-opt)
  out.options = options;
  out.options.view = *NamedView("top");
  out.options.units_scale = 1;
  out.options.origin = PageOrigin::kKeep;
  out.options.fit.reset();
  out.machine = machine;
  out.set.curves = CurvesOfStrokes(set, path, 0);
  if (t.dims == 3) {
    // BuildStreamJob puts the bottom of a drawing at Z = 0, adding its
    // depth: the whole drawing's (path.depth) for the whole drawing, the
    // pieces' own for these. Shift the pieces by the difference, so that
    // they end up where the whole drawing's job draws them, on its Z travel.
    const double pieces_depth = PlanPage(out.set, out.options, units).depth;
    out.set.curves = CurvesOfStrokes(set, path, path.depth - pieces_depth);
    if (out.machine.travel[2] <= 0) {
      out.machine.travel[2] = std::max(path.depth, machine.StepOf(2).value());
    }
  }
  return out;
}

namespace {

// The polyline of u ↦ at(u), u ∈ [0, 1], in steps: subdivided until each
// chord is within chord_steps of the curve at its midpoint and quarter points
// and at most 8 steps long (a cubic piece this short has no room for an
// undetected bulge).
template <typename At>
std::vector<Vec> RefinedPolyline(const At& at, double chord_steps) {
  std::vector<Vec> points{at(0)};
  std::function<void(double, const Vec&, double, const Vec&, int)> refine =
      [&](double u0, const Vec& p0, double u1, const Vec& p1, int depth) {
        const Vec mid = at((u0 + u1) / 2);
        double worst = 0;
        for (const double f : {0.25, 0.5, 0.75}) {
          const Vec q = f == 0.5 ? mid : at(u0 + f * (u1 - u0));
          Vec chord{};
          for (int c = 0; c < 3; ++c) chord[c] = p0[c] + f * (p1[c] - p0[c]);
          worst = std::max(worst, Distance(q, chord));
        }
        if (depth < 24 && (worst > chord_steps || Distance(p0, p1) > 8)) {
          refine(u0, p0, (u0 + u1) / 2, mid, depth + 1);
          refine((u0 + u1) / 2, mid, u1, p1, depth + 1);
        } else {
          points.push_back(p1);
        }
      };
  refine(0, points[0], 1, at(1), 0);
  return points;
}

}  // namespace

std::vector<std::vector<std::array<double, 3>>> ReferenceLines(const PatchSet& set,
                                                               const StreamJob& job,
                                                               double chord_steps) {
  std::vector<std::vector<Vec>> lines;
  for (const StreamedPatch& streamed : job.patches) {
    const Patch& patch = set.patches[streamed.patch];
    const auto add_family = [&](int count, bool s_lines) {
      for (int i = 0; i < count; ++i) {
        const double fixed = static_cast<double>(i) / (count - 1);
        const auto at = [&](double u) {
          return s_lines ? InSteps(patch, job, fixed, u) : InSteps(patch, job, u, fixed);
        };
        std::vector<Vec> points = RefinedPolyline(at, chord_steps);
        double length = 0;
        for (std::size_t k = 1; k < points.size(); ++k)
          length += Distance(points[k - 1], points[k]);
        if (length > 1e-9) lines.push_back(std::move(points));
      }
    };
    add_family(streamed.lines_s, true);
    add_family(streamed.lines_t, false);
  }
  // The curves the same way (they were sampled at 20,000 points each, which
  // made the comparison of a mesh's thousands of short curves slow).
  for (const std::size_t c : job.curves) {
    const auto at = [&](double u) { return ToSteps(EvaluateCurve(set.curves[c], u), job); };
    lines.push_back(RefinedPolyline(at, chord_steps));
  }
  return lines;
}

}  // namespace fdsurf::host
