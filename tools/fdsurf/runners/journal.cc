// SPDX-License-Identifier: MIT
#include "journal.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "fdsurf/host/errors.h"
#include "fdsurf/motion/entry.h"
#include "fdsurf/motion/path_generator.h"
#include "fdsurf/protocol/codec.h"

namespace fdsurf::host {
namespace {

constexpr const char* kMagic = "fdsurf-journal";
constexpr const char* kVersion = "1";

std::uint64_t Fold(std::uint64_t hash, std::uint8_t byte) {
  return (hash ^ byte) * 1099511628211ull;
}

std::string Hex(std::uint64_t value, int digits) {
  char text[24];
  std::snprintf(text, sizeof text, "%0*" PRIx64, digits, value);
  return text;
}

// Where the device's own path generator leaves the pen and the position
// after each of the job's first `count` commands.
template <int kDims>
void Replay(const StreamJob& job, std::size_t count, std::array<std::int32_t, 3>* position,
            bool* pen_down) {
  motion::PathGenerator<kDims> generator;
  const std::int32_t origin[3] = {0, 0, 0};
  generator.Reset(origin, false);
  bool down = false;
  for (std::size_t k = 0; k < count; ++k) {
    const protocol::Command& command = job.commands[k];
    if (command.type == protocol::MessageType::kConfig) continue;
    generator.Start(command);
    for (std::uint8_t entry = 0; generator.Next(&entry);) {
      const motion::EntryKind kind = motion::KindOf(entry);
      if (kind == motion::EntryKind::kPenDown) down = true;
      if (kind == motion::EntryKind::kPenUp) down = false;
    }
    if (generator.failed()) {
      throw EngineError(job.labels[k] + ": the device's path generator refused it on replay");
    }
  }
  for (int a = 0; a < 3; ++a) (*position)[static_cast<std::size_t>(a)] = 0;
  for (int a = 0; a < kDims; ++a) {
    (*position)[static_cast<std::size_t>(a)] = generator.position()[a];
  }
  *pen_down = down;
}

protocol::Command PenCommand(bool down) {
  protocol::Command command;
  command.type = protocol::MessageType::kPen;
  command.body.pen.down = down;
  return command;
}

// "key value" lines of a journal, with their line numbers.
struct Field {
  std::string value;
  int line = 0;
};

std::map<std::string, Field> ReadFields(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the journal: " + std::strerror(errno));
  std::map<std::string, Field> fields;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.empty()) continue;
    const std::size_t space = text.find(' ');
    const std::string key = text.substr(0, space);
    const std::string value = space == std::string::npos ? "" : text.substr(space + 1);
    if (line == 1 && (key != kMagic || value != kVersion)) {
      throw InputError(path + ":1: not an fdsurf journal (it starts '" + text.substr(0, 40) +
                       "', not '" + kMagic + " " + kVersion + "')");
    }
    if (!fields.emplace(key, Field{value, line}).second) {
      std::string message = path;
      message += ":" + std::to_string(line) + ": " + key + ": given twice";
      throw InputError(message);
    }
  }
  if (fields.empty()) throw InputError(path + ": empty: not an fdsurf journal");
  return fields;
}

// The unsigned number under `key` (base 10, or 16 when `hex`).
std::uint64_t Number(const std::string& path, const std::map<std::string, Field>& fields,
                     const std::string& key, bool hex = false) {
  const auto it = fields.find(key);
  if (it == fields.end()) throw InputError(path + ": the key '" + key + "' is missing");
  const std::string& value = it->second.value;
  char* end = nullptr;
  errno = 0;
  const unsigned long long n = std::strtoull(value.c_str(), &end, hex ? 16 : 10);
  if (value.empty() || *end != '\0' || errno != 0 || value[0] == '-') {
    throw InputError(path + ":" + std::to_string(it->second.line) + ": " + key + ": '" + value +
                     "' is not " + (hex ? "a hexadecimal" : "a whole") + " number");
  }
  return n;
}

}  // namespace

std::uint64_t JobHash(const StreamJob& job) {
  std::uint64_t hash = 1469598103934665603ull;
  std::vector<std::uint8_t> body(protocol::kMaxFrameBytes);
  for (const protocol::Command& command : job.commands) {
    hash = Fold(hash, static_cast<std::uint8_t>(command.type));
    const std::size_t size = protocol::EncodeCommandBody(command, body.data(), body.size());
    for (std::size_t i = 0; i < size; ++i) hash = Fold(hash, body[i]);
  }
  return hash;
}

JournalState ReadJournal(const std::string& path) {
  const std::map<std::string, Field> fields = ReadFields(path);
  JournalState s;
  s.job_hash = Number(path, fields, "job", true);
  s.commands = Number(path, fields, "commands");
  s.session = static_cast<std::uint32_t>(Number(path, fields, "session", true));
  s.first = Number(path, fields, "first");
  s.prefix = Number(path, fields, "prefix");
  s.executed = Number(path, fields, "executed");
  s.pen_down = Number(path, fields, "pen") != 0;
  const auto position = fields.find("position");
  if (position == fields.end()) throw InputError(path + ": the key 'position' is missing");
  std::istringstream xyz(position->second.value);
  long long p[3] = {0, 0, 0};
  if (!(xyz >> p[0] >> p[1] >> p[2])) {
    throw InputError(path + ":" + std::to_string(position->second.line) +
                     ": position: three whole numbers of steps expected, not '" +
                     position->second.value + "'");
  }
  for (std::size_t a = 0; a < 3; ++a) s.position[a] = static_cast<std::int32_t>(p[a]);
  if (s.executed > s.commands || s.first > s.commands) {
    const Field& f = fields.at(s.executed > s.commands ? "executed" : "first");
    throw InputError(path + ":" + std::to_string(f.line) + ": " +
                     (s.executed > s.commands ? "executed" : "first") + ": " + f.value +
                     " is more than the job's " + std::to_string(s.commands) + " commands");
  }
  return s;
}

void CheckJournalMatches(const std::string& path, const JournalState& state, const StreamJob& job) {
  const std::uint64_t hash = JobHash(job);
  if (state.job_hash != hash || state.commands != job.commands.size()) {
    throw InputError(path + ": the journal is of another job (" + std::to_string(state.commands) +
                     " commands, hash " + Hex(state.job_hash, 16) + "; these arguments give " +
                     std::to_string(job.commands.size()) + " commands, hash " + Hex(hash, 16) +
                     "): --resume needs the same file and the same drawing and machine options");
  }
}

std::size_t JobExecuted(const JournalState& state, std::uint32_t session_executed) {
  if (session_executed <= state.prefix) return state.first;
  const std::size_t executed = state.first + (session_executed - state.prefix);
  return executed < state.commands ? executed : state.commands;
}

StreamJob ResumedJob(const StreamJob& job, std::size_t executed, std::size_t* prefix) {
  *prefix = 0;
  if (executed == 0) return job;  // not even the CONFIG: from the start
  std::array<std::int32_t, 3> end{0, 0, 0};
  bool pen_down = false;
  if (job.config.axes == 3) {
    Replay<3>(job, executed, &end, &pen_down);
  } else {
    Replay<2>(job, executed, &end, &pen_down);
  }
  StreamJob resumed = job;
  resumed.commands = {job.commands.front(), PenCommand(false)};  // CONFIG first, as always
  resumed.labels = {job.labels.front(), "resume: pen up"};
  protocol::Command move;
  move.type = protocol::MessageType::kMove;
  for (std::size_t a = 0; a < 3; ++a) move.body.move.target[a] = end[a];
  resumed.commands.push_back(move);
  resumed.labels.push_back("resume: travel to where command " + std::to_string(executed) +
                           " ended");
  if (pen_down) {
    resumed.commands.push_back(PenCommand(true));
    resumed.labels.emplace_back("resume: pen down");
  }
  *prefix = resumed.commands.size();
  for (std::size_t k = executed; k < job.commands.size(); ++k) {
    resumed.commands.push_back(job.commands[k]);
    resumed.labels.push_back(job.labels[k]);
  }
  // The layer under way goes on from the start; later ones keep their pauses.
  resumed.layers.clear();
  for (const LayerStart& layer : job.layers) {
    LayerStart shifted = layer;
    if (layer.command <= executed) {
      shifted.command = 0;
      if (!resumed.layers.empty()) resumed.layers.pop_back();
    } else {
      shifted.command = layer.command - executed + *prefix;
    }
    resumed.layers.push_back(shifted);
  }
  return resumed;
}

JobJournal::JobJournal(std::string path, const StreamJob& original, std::size_t first,
                       std::size_t prefix)
    : path_(std::move(path)) {
  state_.job_hash = JobHash(original);
  state_.commands = original.commands.size();
  state_.first = first;
  state_.prefix = prefix;
  state_.executed = first;
}

void JobJournal::Record(const protocol::StatusReport& status, bool force) {
  const std::size_t executed = JobExecuted(state_, status.executed);
  for (std::size_t a = 0; a < 3; ++a) state_.position[a] = status.position[a];
  state_.pen_down = status.pen_down;
  if (executed != state_.executed) {
    state_.executed = executed;
    dirty_ = true;
  }
  if (force || (dirty_ && Clock::now() - last_write_ >= interval_)) Flush();
}

void JobJournal::Flush() {
  const std::string temporary = path_ + ".new";
  std::string text = std::string(kMagic) + " " + kVersion + "\n";
  text += "job " + Hex(state_.job_hash, 16) + "\n";
  text += "commands " + std::to_string(state_.commands) + "\n";
  text += "session " + Hex(state_.session, 8) + "\n";
  text += "first " + std::to_string(state_.first) + "\n";
  text += "prefix " + std::to_string(state_.prefix) + "\n";
  text += "executed " + std::to_string(state_.executed) + "\n";
  text += "position " + std::to_string(state_.position[0]) + " " +
          std::to_string(state_.position[1]) + " " + std::to_string(state_.position[2]) + "\n";
  text += std::string("pen ") + (state_.pen_down ? "1" : "0") + "\n";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0 && ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ok = ok && ::fsync(fd) == 0;
  if (fd >= 0) ok = ::close(fd) == 0 && ok;
  ok = ok && std::rename(temporary.c_str(), path_.c_str()) == 0;
  if (!ok) throw EngineError(path_ + ": cannot write the journal: " + std::strerror(errno));
  dirty_ = false;
  last_write_ = Clock::now();
}

}  // namespace fdsurf::host
