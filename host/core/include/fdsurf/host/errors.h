// SPDX-License-Identifier: MIT
// The host library's errors, in one place. Each is a std::runtime_error whose
// message is complete for a person: it names the file and line, the patch,
// or the option, and what was wrong. The command-line tool maps them to its
// exit codes (2 for bad input, 3 for a device that refuses, 1 for a broken
// bound); the library never prints.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include "fdsurf/config/nodiscard.h"

namespace fdsurf::host {

/// Bad input: the message names the file and the place ("f.bpt:12: ...").
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An option (ToolpathOptions, MachineOptions) that cannot be met. `field`
/// names it as the library knows it ("tolerance", "lines", "fit", "travel X",
/// "speed", "accel", "pen delay", "view", "quantum", "step"), `value` shows
/// the value with its units (may be empty) and `problem` says what is wrong.
/// what() is "FIELD VALUE PROBLEM", or "FIELD: PROBLEM" without a value; a
/// front end that spells the field differently (a command-line flag) rebuilds
/// the message from the parts.
class OptionError : public InputError {
 public:
  OptionError(std::string field, std::string value, std::string problem)
      : InputError(Compose(field, value, problem)),
        field_(std::move(field)),
        value_(std::move(value)),
        problem_(std::move(problem)) {}

  FDSURF_NODISCARD const std::string& field() const { return field_; }
  FDSURF_NODISCARD const std::string& value() const { return value_; }
  FDSURF_NODISCARD const std::string& problem() const { return problem_; }

  /// The message with `name` in place of the field.
  FDSURF_NODISCARD std::string MessageFor(const std::string& name) const {
    return Compose(name, value_, problem_);
  }

 private:
  static std::string Compose(const std::string& field, const std::string& value,
                             const std::string& problem) {
    return value.empty() ? field + ": " + problem : field + " " + value + " " + problem;
  }

  std::string field_;
  std::string value_;
  std::string problem_;
};

/// The fixed-point engine refused a patch or curve; the message names its
/// origin and the engine's status.
class EngineError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad construction input (mismatched corners, too few curves,
/// non-increasing parameters, ...). The message does not name the file; the
/// reader adds the JSON path.
class ConstructionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An output that could not be written; the message names the path.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fdsurf::host
