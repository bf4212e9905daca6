// SPDX-License-Identifier: MIT
// What stream.cc and line_plan.cc share: appending a drawing's commands to a
// job with the pen tracked, and the lines plan of the patches.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fdsurf/host/plan.h"
#include "fdsurf/host/stream.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::host {

/// Appends PEN, MOVE and drawing commands to a job, tracking the pen and
/// where the commands leave the machine: a pen-up travel only where a piece
/// does not start where the one before ended, so that pieces that meet are
/// drawn in one stroke.
class CurveEmitter {
 public:
  explicit CurveEmitter(StreamJob* job) : job_(job) {}

  /// A PEN command unless the pen is there already.
  void Pen(bool down) {
    if (down == pen_down_) return;
    protocol::Command command;
    command.type = protocol::MessageType::kPen;
    command.seq = 0;
    command.body.pen.down = down;
    job_->commands.push_back(command);
    job_->labels.emplace_back(down ? "pen down" : "pen up");
    pen_down_ = down;
  }

  /// A MOVE to `target` (steps) with the pen as it is.
  void Move(const std::array<std::int32_t, 3>& target, std::string label) {
    protocol::Command move;
    move.type = protocol::MessageType::kMove;
    move.seq = 0;
    for (int a = 0; a < protocol::kMaxAxes; ++a) {
      move.body.move.target[a] = target[static_cast<std::size_t>(a)];
    }
    job_->commands.push_back(move);
    job_->labels.push_back(std::move(label));
  }

  /// `command` (a CURVE, or a MOVE that draws a straight piece) drawing from
  /// `start` to `end` (steps, as the device rounds them) with the pen down,
  /// after a pen-up travel to `start` unless the machine is there.
  void Draw(const protocol::Command& command, const std::array<std::int32_t, 3>& start,
            const std::array<std::int32_t, 3>& end, const std::string& label) {
    if (!placed_ || start != at_) {
      Pen(false);
      Move(start, "travel to " + label);
    }
    Pen(true);
    job_->commands.push_back(command);
    job_->labels.push_back(label);
    at_ = end;
    placed_ = true;
  }

  /// Where the commands so far leave the machine (the origin before any).
  [[nodiscard]] PlanPoint At() const {
    return {static_cast<double>(at_[0]), static_cast<double>(at_[1]), static_cast<double>(at_[2])};
  }

 private:
  StreamJob* job_;
  bool pen_down_ = false;
  bool placed_ = false;
  std::array<std::int32_t, 3> at_{};
};

/// StreamPlan::kLines: appends the lines that the PATCH commands `patches`
/// (labelled `labels`) draw as CURVE commands, planned across the patches,
/// with their pen changes and travel; the pen up at the end. Throws
/// EngineError naming the patch for one whose lines the device's walker
/// refuses.
void AddPlannedLines(const std::vector<protocol::Command>& patches,
                     const std::vector<std::string>& labels, int dims, StreamJob* job);

}  // namespace fdsurf::host
