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

// How often a line is halved at most for a device of 64-bit tables; each
// halving makes a piece's table about 16 times smaller, so the teapot's
// lines need at most a few.
constexpr int kMaxSplitDepth = 16;

// round(numerator / 2^bits), halves up (C++20's >> of a negative value is
// the floor).
std::int64_t RoundShifted(__int128 numerator, int bits) {
  if (bits == 0) return static_cast<std::int64_t>(numerator);
  return static_cast<std::int64_t>((numerator + (__int128{1} << (bits - 1))) >> bits);
}

// The piece of `line` over [i/2^k, (i+1)/2^k] as power coefficients in v
// from 0 to 1: x(u0 + v/2^k) with u0 = i/2^k, each coefficient times 2^(3k)
// exact in __int128 (four terms below 2^95 each for |coefficients| < 2^47 and k ≤ 16), then
// rounded once.
template <int kDims>
void PieceOf(const PowerCurve1 (&line)[kDims], int k, std::uint64_t i,
             PowerCurve1 (&piece)[kDims]) {
  const __int128 u = i;
  const __int128 w = __int128{1} << k;
  for (int c = 0; c < kDims; ++c) {
    const __int128 a = line[c].c[0];
    const __int128 b = line[c].c[1];
    const __int128 cc = line[c].c[2];
    const __int128 d = line[c].c[3];
    const __int128 scaled[4] = {
        a,
        3 * a * u + b * w,
        3 * a * u * u + 2 * b * u * w + cc * w * w,
        a * u * u * u + b * u * u * w + cc * u * w * w + d * w * w * w,
    };
    for (int j = 0; j < 4; ++j) piece[c].c[j] = RoundShifted(scaled[j], 3 * k);
  }
}

// The pieces of one PREPARED_CURVE for a device of 64-bit tables, in order.
template <int kDims>
class Splitter {
 public:
  Splitter(const protocol::PreparedCurveCommand& line, const std::int32_t* travel,
           const std::string& label)
      : line_(line), travel_(travel), label_(label) {
    for (int c = 0; c < kDims; ++c) whole_[c] = line.power[c];
    settings_.mode = AdaptiveMode::kStepExact;
    settings_.tolerance_q8 = line.tolerance_q8;
  }

  std::vector<protocol::PreparedCurveCommand> Pieces() {
    if (motion::HullWithinTravel(whole_, travel_) && TableAt(whole_, line_.level) == Status::kOk) {
      return {line_};
    }
    Split(0, 0);
    return std::move(pieces_);
  }

 private:
  // The device's check of the piece's table at `level`: relative to its
  // first point, as the device steps it (motion::RelativeToFirstPoint), in
  // 64 bits.
  FDSURF_NODISCARD Status TableAt(const PowerCurve1 (&piece)[kDims], int level) const {
    PowerCurve1 relative[kDims];
    std::int32_t first[kDims];
    motion::RelativeToFirstPoint(piece, relative, first);
    PreparedAdaptiveCurve<kDims, std::int64_t> narrow;
    return PrepareAdaptiveCurveAtLevel(relative, level, settings_, &narrow);
  }

  // The piece at the level this host's planner chooses for it, if the
  // device takes it there; else its halves, or an error at the last depth.
  void Split(int k, std::uint64_t i) {
    PowerCurve1 piece[kDims];
    PieceOf(whole_, k, i, piece);
    PreparedAdaptiveCurve<kDims> planned;
    Status status = PrepareAdaptiveCurve(piece, settings_, &planned);
    if (status == Status::kOk) status = TableAt(piece, planned.finest_level);
    // A hull that crosses the travel's edge is refused by such a device
    // (motion::HullWithinTravel): halved like a table that does not fit.
    const bool inside = motion::HullWithinTravel(piece, travel_);
    if (status == Status::kOk && inside) {
      protocol::PreparedCurveCommand command = line_;
      command.level = planned.finest_level;
      for (int c = 0; c < kDims; ++c) command.power[c] = piece[c];
      pieces_.push_back(command);
      return;
    }
    if ((status != Status::kOk && status != Status::kPrecisionUnreachable) || k == kMaxSplitDepth) {
      const std::string why =
          status != Status::kOk ? StatusMessage(status) : "its hull crosses the edge of the travel";
      throw EngineError(label_ + ": " + why + " (a piece of 1/2^" + std::to_string(k) +
                        " of it, for a device of 64-bit tables)");
    }
    Split(k + 1, 2 * i);
    Split(k + 1, 2 * i + 1);
  }

  const protocol::PreparedCurveCommand& line_;
  const std::int32_t* travel_;
  const std::string& label_;
  AdaptiveSettings settings_;
  PowerCurve1 whole_[kDims];
  std::vector<protocol::PreparedCurveCommand> pieces_;
};

template <int kDims>
void SplitEach(StreamJob* job) {
  std::vector<Command> commands;
  std::vector<std::string> labels;
  std::vector<std::size_t> first_of;
  for (std::size_t index = 0; index < job->commands.size(); ++index) {
    const Command& command = job->commands[index];
    first_of.push_back(commands.size());
    if (command.type != MessageType::kPreparedCurve) {
      commands.push_back(command);
      labels.push_back(job->labels[index]);
      continue;
    }
    const std::vector<protocol::PreparedCurveCommand> pieces =
        Splitter<kDims>(command.body.prepared_curve, job->config.travel_steps, job->labels[index])
            .Pieces();
    for (std::size_t j = 0; j < pieces.size(); ++j) {
      Command piece = command;
      piece.body.prepared_curve = pieces[j];
      commands.push_back(piece);
      labels.push_back(pieces.size() == 1
                           ? job->labels[index]
                           : job->labels[index] + ", piece " + std::to_string(j + 1) + " of " +
                                 std::to_string(pieces.size()));
    }
  }
  for (LayerStart& layer : job->layers) layer.command = first_of[layer.command];
  job->commands = std::move(commands);
  job->labels = std::move(labels);
}

}  // namespace

void SplitForSixtyFourBitTables(StreamJob* job) {
  if (job->config.axes == 3) {
    SplitEach<3>(job);
  } else {
    SplitEach<2>(job);
  }
}

void PrepareOnHost(StreamJob* job) {
  if (job->config.axes == 3) {
    Prepare<3>(job);
  } else {
    Prepare<2>(job);
  }
}

}  // namespace fdsurf::host
