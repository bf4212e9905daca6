// SPDX-License-Identifier: MIT
// StreamPlan::kLines: the lines of a job's patches planned as `fdsurf plot`
// plans its strokes, each sent as the CURVE the device would draw for it.
//
// The device draws a PATCH's lines in an order of its own (s-lines, then
// t-lines, every other line reversed) and lifts the pen between any two that
// do not meet; it cannot carry a stroke on into the next patch. Sent as
// curves, the lines can be drawn in any order and either direction: lines
// that meet end to end (an isoline continued across a patch edge, as around
// the teapot's body) become one pen-down stroke, and the strokes are ordered
// by nearest neighbour, 2-opt and Or-opt, plan.h's stages, the ones plot uses.
//
// Each CURVE carries the power coefficients that the device's own walker
// (IsolineWalker, as motion::ForEachDrawnLine walks it) forms for the
// PATCH's line, in 2^-16 steps, as
// a power-basis curve, whose conversion is the identity: the device steps
// the same table it would have stepped for the PATCH, and a reversed line is
// reversed exactly (motion::ReverseCurve). The bound of the drawing is the
// PATCH's, line for line.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fdsurf/adaptive.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/plan.h"
#include "fdsurf/motion/path_generator.h"
#include "stream_internal.h"

namespace fdsurf::host {
namespace {

using Steps = std::array<std::int32_t, 3>;

// One line a PATCH draws: its coefficients (2^-16 steps) and its ends as the
// device rounds them.
template <int kDims>
struct DrawnLine {
  PowerCurve1 power[kDims];
  Steps start{};
  Steps end{};
  std::string label;
};

template <int kDims>
Steps RoundedAt(const PowerCurve1 (&line)[kDims], bool at_end) {
  Steps out{};
  for (int c = 0; c < kDims; ++c) {
    const std::int64_t* k = line[c].c;
    const std::int64_t value = at_end ? k[0] + k[1] + k[2] + k[3] : k[3];
    out[static_cast<std::size_t>(c)] = RoundToQuanta(value, kCoefficientFracBits);
  }
  return out;
}

// Every line the PATCH commands draw, as the device's walker forms them
// (poles and skipped edges left out, motion::ForEachDrawnLine's rules), in
// the order and direction `fdsurf plot` draws them before planning: patch by
// patch, s-lines then t-lines, each from u = 0. Given the same pieces in the
// same order, plan.h's stages make the same plan as plot's.
template <int kDims>
std::vector<DrawnLine<kDims>> LinesOf(const std::vector<protocol::Command>& patches,
                                      const std::vector<std::string>& labels) {
  std::vector<DrawnLine<kDims>> lines;
  for (std::size_t p = 0; p < patches.size(); ++p) {
    const protocol::PatchCommand& patch = patches[p].body.patch;
    PatchGeometry1 geometry[kDims];
    for (int c = 0; c < kDims; ++c) geometry[c] = patch.geometry[c];
    for (const IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
      const std::uint16_t count = family == IsolineFamily::kSLines ? patch.lines_s : patch.lines_t;
      if (count == 0) continue;
      IsolineWalker<kDims> walker;
      const Status status =
          IsolineWalker<kDims>::Create(geometry, patch.basis, family, count, &walker);
      if (status != Status::kOk) throw EngineError(labels[p] + ": " + StatusMessage(status));
      DrawnLine<kDims> line;
      for (std::uint16_t index = 0; walker.Next(line.power); ++index) {
        if (motion::IsPoint(line.power) ||
            motion::IsSkippedEdge(patch.skip_lines, family, index, count)) {
          continue;
        }
        line.start = RoundedAt(line.power, false);
        line.end = RoundedAt(line.power, true);
        line.label = labels[p] + ", " + (family == IsolineFamily::kSLines ? "s" : "t") + "-line " +
                     std::to_string(index);
        lines.push_back(line);
      }
    }
  }
  return lines;
}

PlanPoint ToPlan(const Steps& p) {
  return {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
}

// The CURVE that draws `line` (reversed when `reversed`): power basis, the
// coefficients as its geometry.
template <int kDims>
protocol::Command CurveCommandOf(const DrawnLine<kDims>& line, bool reversed,
                                 std::uint32_t tolerance_q8) {
  PowerCurve1 power[kDims];
  for (int c = 0; c < kDims; ++c) power[c] = line.power[c];
  if (reversed) motion::ReverseCurve<kDims>(power);
  protocol::Command command;
  command.type = protocol::MessageType::kCurve;
  command.seq = 0;
  protocol::CurveCommand& body = command.body.curve;
  body.basis = Basis::kPower;
  body.dims = static_cast<std::uint8_t>(kDims);
  body.tolerance_q8 = tolerance_q8;
  for (auto& axis : body.geometry) axis = CurveGeometry1{};
  for (int c = 0; c < kDims; ++c) {
    for (int i = 0; i < 4; ++i) body.geometry[c].g[i] = GeometryFixed::FromRaw(power[c].c[i]);
  }
  return command;
}

template <int kDims>
void AddLines(const std::vector<protocol::Command>& patches, const std::vector<std::string>& labels,
              StreamJob* job) {
  const std::vector<DrawnLine<kDims>> lines = LinesOf<kDims>(patches, labels);
  std::vector<std::array<std::array<std::int64_t, 3>, 2>> exact_ends;
  exact_ends.reserve(lines.size());
  for (const DrawnLine<kDims>& line : lines) {
    exact_ends.push_back({std::array<std::int64_t, 3>{line.start[0], line.start[1], line.start[2]},
                          std::array<std::int64_t, 3>{line.end[0], line.end[1], line.end[2]}});
  }
  const std::vector<std::vector<Visit>> chains = ChainTouching(exact_ends);
  const auto entry = [&](const Visit& v) {
    return v.reversed ? lines[v.index].end : lines[v.index].start;
  };
  const auto exit = [&](const Visit& v) {
    return v.reversed ? lines[v.index].start : lines[v.index].end;
  };
  std::vector<std::array<PlanPoint, 2>> chain_ends;
  chain_ends.reserve(chains.size());
  for (const std::vector<Visit>& chain : chains) {
    chain_ends.push_back({ToPlan(entry(chain.front())), ToPlan(exit(chain.back()))});
  }
  // A pen's travel is in the plane; a 3-D job's machine travels in space.
  const PlanMetric metric = kDims == 3 ? PlanMetric::kSpace : PlanMetric::kPlane;
  const PlanPoint origin{0, 0, 0};
  std::vector<Visit> order = OrderNearestNeighbour(chain_ends, true, metric, origin);
  ImproveOrder(chain_ends, metric, origin, &order);

  CurveEmitter emit(job);
  const auto draw = [&](const Visit& v) {
    const DrawnLine<kDims>& line = lines[v.index];
    emit.Draw(CurveCommandOf(line, v.reversed, job->tolerance_q8), entry(v), exit(v),
              line.label + (v.reversed ? " (reversed)" : ""));
  };
  for (const Visit& visit : order) {
    const std::vector<Visit>& chain = chains[visit.index];
    // A chain entered at its end: its lines in reverse order, each reversed.
    for (std::size_t k = 0; k < chain.size(); ++k) {
      const Visit& v = chain[visit.reversed ? chain.size() - 1 - k : k];
      draw(Visit{v.index, v.reversed != visit.reversed});
    }
  }
  emit.Pen(false);
}

}  // namespace

void AddPlannedLines(const std::vector<protocol::Command>& patches,
                     const std::vector<std::string>& labels, int dims, StreamJob* job) {
  if (dims == 3) {
    AddLines<3>(patches, labels, job);
  } else {
    AddLines<2>(patches, labels, job);
  }
}

}  // namespace fdsurf::host
