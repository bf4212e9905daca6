// SPDX-License-Identifier: MIT
// A job's patches and curves planned on the host: PREPARED_CURVE commands
// that a device steps without a planner of its own (stream.h, PrepareOnHost).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/adaptive.h"
#include "fdsurf/host/errors.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/motion/path_generator.h"

namespace fdsurf::host {
namespace {

using protocol::Command;
using protocol::MessageType;

// Builds the new commands and their labels, and where each old command's
// commands start (for the layers).
template <int kDims>
class Preparer {
 public:
  explicit Preparer(const StreamJob& job) : job_(job) {}

  void Add(std::size_t index) {
    const Command& command = job_.commands[index];
    first_of_.push_back(commands_.size());
    switch (command.type) {
      case MessageType::kPatch:
        AddPatch(command, job_.labels[index]);
        break;
      case MessageType::kCurve:
        AddCurve(command, job_.labels[index]);
        break;
      default:
        Push(command, job_.labels[index]);
        Follow(command);
        break;
    }
  }

  // Moves the result into `job`.
  void Finish(StreamJob* job) {
    for (LayerStart& layer : job->layers) layer.command = first_of_[layer.command];
    job->commands = std::move(commands_);
    job->labels = std::move(labels_);
  }

 private:
  void Push(const Command& command, std::string label) {
    commands_.push_back(command);
    labels_.push_back(std::move(label));
  }

  // What a command passed through leaves: a PEN its pen state, a MOVE the
  // machine at its target; after anything else (HOME, MOTORS, CONFIG) the
  // host no longer knows where the machine is.
  void Follow(const Command& command) {
    if (command.type == MessageType::kPen) {
      pen_down_ = command.body.pen.down;
    } else if (command.type == MessageType::kMove) {
      std::array<std::int32_t, kDims> target{};
      for (int c = 0; c < kDims; ++c) {
        target[static_cast<std::size_t>(c)] = command.body.move.target[c];
      }
      at_ = target;
    } else {
      at_.reset();
    }
  }

  void Pen(bool down, const std::string& label) {
    if (pen_down_ == down) return;
    Command pen;
    pen.type = MessageType::kPen;
    pen.seq = 0;
    pen.body.pen.down = down;
    Push(pen, label + (down ? ": pen down" : ": pen up"));
    pen_down_ = down;
  }

  // The PREPARED_CURVE of a line, at the level the device's own planner
  // would choose.
  void PushPrepared(const PowerCurve1 (&line)[kDims], std::uint32_t tolerance_q8,
                    const std::string& label) {
    AdaptiveSettings settings;
    settings.mode = AdaptiveMode::kStepExact;
    settings.tolerance_q8 = tolerance_q8;
    PreparedAdaptiveCurve<kDims> prepared;
    const Status status = PrepareAdaptiveCurve(line, settings, &prepared);
    if (status != Status::kOk) {
      throw EngineError(label + ": " + StatusMessage(status) + " (planning it on the host)");
    }
    Command command;
    command.type = MessageType::kPreparedCurve;
    command.seq = 0;
    protocol::PreparedCurveCommand& body = command.body.prepared_curve;
    body.dims = static_cast<std::uint8_t>(kDims);
    body.level = prepared.finest_level;
    body.tolerance_q8 = tolerance_q8;
    for (int c = 0; c < protocol::kMaxAxes; ++c) {
      body.power[c] = c < kDims ? line[c] : PowerCurve1{};
    }
    Push(command, label);
    std::array<std::int32_t, kDims> end{};
    for (int c = 0; c < kDims; ++c) {
      const std::int64_t* k = line[c].c;
      end[static_cast<std::size_t>(c)] =
          RoundToQuanta(k[0] + k[1] + k[2] + k[3], kCoefficientFracBits);
    }
    at_ = end;
  }

  void AddCurve(const Command& command, const std::string& label) {
    const protocol::CurveCommand& curve = command.body.curve;
    CurveGeometry1 geometry[kDims];
    for (int c = 0; c < kDims; ++c) geometry[c] = curve.geometry[c];
    PowerCurve1 line[kDims];
    const Status status = CurvePowerCoefficients(geometry, curve.basis, line);
    if (status != Status::kOk) throw EngineError(label + ": " + StatusMessage(status));
    PushPrepared(line, curve.tolerance_q8, label);
  }

  // As PathGenerator draws a PATCH: per line, a pen-up travel to its start
  // unless the machine is there, a pen-down, the line; a pen-up at the end.
  void AddPatch(const Command& command, const std::string& label) {
    const protocol::PatchCommand& patch = command.body.patch;
    int line_number = 0;
    for (const IsolineFamily family : {IsolineFamily::kSLines, IsolineFamily::kTLines}) {
      const Status status =
          motion::ForEachDrawnLine<kDims>(patch, family, [&](const PowerCurve1(&line)[kDims]) {
            const std::string line_label = label + ", line " + std::to_string(++line_number);
            std::array<std::int32_t, kDims> start{};
            for (int c = 0; c < kDims; ++c) {
              start[static_cast<std::size_t>(c)] =
                  RoundToQuanta(line[c].c[3], kCoefficientFracBits);
            }
            if (!at_ || *at_ != start) {
              Pen(false, line_label);
              Command move;
              move.type = MessageType::kMove;
              move.seq = 0;
              for (int c = 0; c < protocol::kMaxAxes; ++c) {
                move.body.move.target[c] = c < kDims ? start[static_cast<std::size_t>(c)] : 0;
              }
              Push(move, line_label + ": travel to its start");
            }
            Pen(true, line_label);
            PushPrepared(line, patch.tolerance_q8, line_label);
            return true;
          });
      if (status != Status::kOk) throw EngineError(label + ": " + StatusMessage(status));
    }
    Pen(false, label);
  }

  const StreamJob& job_;
  std::vector<Command> commands_;
  std::vector<std::string> labels_;
  std::vector<std::size_t> first_of_;
  // The pen as the commands so far leave it, and where they leave the
  // machine, where the host knows it (not at the start of the job).
  std::optional<bool> pen_down_;
  std::optional<std::array<std::int32_t, kDims>> at_;
};

template <int kDims>
void Prepare(StreamJob* job) {
  Preparer<kDims> preparer(*job);
  for (std::size_t i = 0; i < job->commands.size(); ++i) preparer.Add(i);
  preparer.Finish(job);
}

}  // namespace

void PrepareOnHost(StreamJob* job) {
  if (job->config.axes == 3) {
    Prepare<3>(job);
  } else {
    Prepare<2>(job);
  }
}

}  // namespace fdsurf::host
