// SPDX-License-Identifier: MIT
// The job journal of `fdsurf stream --journal FILE` and `--resume FILE`
// (docs/protocol.md, "Job journal"): which of a job's commands the device
// has executed, as the device reports it (STATUS), written to FILE as it
// goes (a temporary file, fsync'ed, renamed over FILE: a reader never sees
// half of one, a power cut leaves the previous one).
//
// The file is text, one `key value` a line:
//
//   fdsurf-journal 1
//   job 9f3c2a7d51e0b846        the job's identity (JobHash)
//   commands 5                   commands in the job
//   session 1a2b3c4d             the link session running it (hex)
//   first 0                      job index of the session's first job command
//   prefix 0                     commands the session sent before it
//   executed 3                   job commands executed (0..commands)
//   position 1200 800 0          the device's last reported position, steps
//   pen 0                        the pen then (1 down)
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fdsurf/host/stream.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::host {

/// A 64-bit FNV-1a hash of every command of the job, type and encoded body
/// (CONFIG included, so the machine settings are part of it).
std::uint64_t JobHash(const StreamJob& job);

/// What a journal says.
struct JournalState {
  std::uint64_t job_hash = 0;
  std::size_t commands = 0;
  std::uint32_t session = 0;
  std::size_t first = 0;
  std::size_t prefix = 0;
  std::size_t executed = 0;
  std::array<std::int32_t, 3> position{0, 0, 0};
  bool pen_down = false;
};

/// Reads `path`. InputError naming the file, the line and the key for a
/// file that is not a journal, a key missing, repeated or out of range.
JournalState ReadJournal(const std::string& path);

/// `path`'s journal must be of `job` (same hash and command count):
/// InputError saying so otherwise.
void CheckJournalMatches(const std::string& path, const JournalState& state, const StreamJob& job);

/// The job commands executed when the session that `state` records reports
/// `session_executed` sequenced commands executed.
std::size_t JobExecuted(const JournalState& state, std::uint32_t session_executed);

/// The rest of `job` after its first `executed` commands: its CONFIG, the
/// pen lifted, a MOVE to where command `executed` - 1 ends (the host runs
/// the device's own path generator over the commands before), the pen
/// lowered again if it was down there, then commands [executed, end). So
/// nothing is drawn twice and nothing is left out. Layers are shifted.
/// `*prefix` is the count of commands before the job's own.
StreamJob ResumedJob(const StreamJob& job, std::size_t executed, std::size_t* prefix);

/// Writes the journal of one session as the device reports progress.
class JobJournal {
 public:
  /// `first`, `prefix`: as in JournalState (0, 0 for a job from its start).
  JobJournal(std::string path, const StreamJob& original, std::size_t first, std::size_t prefix);
  /// The session once the link has one.
  void SetSession(std::uint32_t session) { state_.session = session; }
  /// Takes a STATUS report; writes the file when the executed count changed
  /// and `interval` has passed since the last write, or when `force`.
  /// EngineError when the file cannot be written.
  void Record(const protocol::StatusReport& status, bool force = false);
  /// Writes what it has now.
  void Flush();
  FDSURF_NODISCARD const JournalState& state() const { return state_; }
  /// The file it writes.
  FDSURF_NODISCARD const std::string& path() const { return path_; }

 private:
  using Clock = std::chrono::steady_clock;
  std::string path_;
  JournalState state_;
  bool dirty_ = true;
  Clock::time_point last_write_{};
  std::chrono::milliseconds interval_{200};
};

}  // namespace fdsurf::host
