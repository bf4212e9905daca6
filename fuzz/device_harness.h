// SPDX-License-Identifier: MIT
// The device under fuzzing: a Device<2> (the queue and lookahead the
// simulated plotter uses) with the in-memory HAL outputs, driven as the
// simulator's loop drives it (sim/src/plotter.cc): bytes in, replies out,
// Fill(), Tick(). Shared by fuzz_device_bytes and fuzz_device_frames.
//
// Checks, besides the sanitizers:
//  - the device never faults (StatusReport::state kFault): every queued
//    command was accepted, and the firmware claims execution never meets a
//    refusal; the simulated outputs never fail, so a fault is a defect;
//  - no frame costs more than kWorkBudgetNs of this thread's CPU time
//    (CLOCK_THREAD_CPUTIME_ID: what the thread computed, not how busy the
//    shared machine is), and a watchdog traps a frame, or a run of ticks
//    (Fill() and Tick()), that goes past kWatchdogSeconds (so a
//    pathological input is a finding with its input saved, not a libFuzzer
//    timeout much later).
//
// Two known defects (issue 12, being fixed) are reported only when the
// environment has FDSURF_FUZZ_KNOWN_DEFECTS=1 (or the build defines it);
// fuzz/README.md says how each is recognised.
#pragma once

#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fdsurf/adaptive.h"
#include "fdsurf/device/device.h"
#include "fdsurf/hal/sim.h"
#include "fdsurf/protocol/codec.h"
#include "fdsurf/protocol/frame.h"
#include "fdsurf/protocol/messages.h"

namespace fdsurf::fuzz {

constexpr std::uint32_t kTickHz = 40000;
constexpr std::uint64_t kTickUs = 1'000'000 / kTickHz;
// Thread CPU time one frame (all OnByte calls of it) may take. The most a
// frame can cost since validation is bounded (docs/motion.md) is a PATCH of
// 1025×1025 lines whose hulls all cross the travel: about 1 ms in a Release
// build and 46 ms in this one (ASan + UBSan + libFuzzer's coverage); before
// the bound it took 1.2 s in Release. 250 ms leaves room for a slow machine
// and still catches any validation that steps lines point by point.
constexpr std::int64_t kWorkBudgetNs = 250'000'000;
constexpr int kWatchdogSeconds = 2;
// Above this many (lines x travel), a patch or curve whose hull crosses the
// travel limit is known defect 2's slow case (issue 12 measured some 36 ns
// per stepped point uninstrumented).
constexpr std::int64_t kCheapHullCrossing = std::int64_t{1} << 17;
constexpr std::int64_t kOneStep = std::int64_t{1} << kCoefficientFracBits;

using FuzzDevice = device::Device<2, 8, 1024>;

// Known defect 1 ("long-move"): an accepted straight move longer than 2^26
// steps faults with kPlannerRefused, detail 4 (Status::kPrecisionUnreachable).
// Known defect 2 ("slow-validation"): validating a PATCH (or CURVE) whose
// line's control hull crosses the travel limit steps the whole line, for
// every line.
// FDSURF_FUZZ_KNOWN_DEFECTS=1 (or "all") reports both; a comma-separated
// list of the names reports those; the compile definition reports both.
enum class KnownDefect { kLongMove, kSlowValidation };

inline bool KnownDefectReported(KnownDefect defect) {
#ifdef FDSURF_FUZZ_KNOWN_DEFECTS
  (void)defect;
  return true;
#else
  static const std::string value = [] {
    const char* v = std::getenv("FDSURF_FUZZ_KNOWN_DEFECTS");
    return std::string(v != nullptr ? v : "");
  }();
  if (value == "1" || value == "all") return true;
  const char* name = defect == KnownDefect::kLongMove ? "long-move" : "slow-validation";
  return ("," + value + ",").find(std::string(",") + name + ",") != std::string::npos;
#endif
}

[[noreturn]] inline void DeviceFinding(const char* what, long long a = 0, long long b = 0) {
  std::fprintf(stderr, "FINDING: %s (%lld, %lld)\n", what, a, b);
  __builtin_trap();
}

inline std::int64_t ThreadCpuNs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

// A one-shot timer on this thread's CPU time; SIGXCPU-style trap when a
// single call runs away. Armed around each frame and each run of ticks.
class Watchdog {
 public:
  // Set while a frame that hits known defect 2 is handled, for the message.
  static inline volatile sig_atomic_t in_known_defect2 = 0;

  Watchdog() {
    struct sigaction action {};
    action.sa_handler = [](int) {
      static const char message[] = "FINDING: one call ran past the watchdog (thread CPU time)\n";
      static const char known[] =
          "FINDING: known defect 2: a frame's validation ran past the watchdog (thread CPU time)\n";
      if (in_known_defect2 != 0) {
        (void)!write(2, known, sizeof known - 1);
      } else {
        (void)!write(2, message, sizeof message - 1);
      }
      __builtin_trap();
    };
    sigaction(SIGVTALRM, &action, nullptr);
    sigevent event{};
    event.sigev_notify = SIGEV_SIGNAL;
    event.sigev_signo = SIGVTALRM;
    ok_ = timer_create(CLOCK_THREAD_CPUTIME_ID, &event, &timer_) == 0;
  }
  void Arm() { Set(kWatchdogSeconds); }
  void Disarm() { Set(0); }

 private:
  void Set(int seconds) {
    if (!ok_) return;
    itimerspec spec{};
    spec.it_value.tv_sec = seconds;
    timer_settime(timer_, 0, &spec, nullptr);
  }
  timer_t timer_{};
  bool ok_ = false;
};

inline Watchdog& TheWatchdog() {
  static Watchdog watchdog;
  return watchdog;
}

// Totals over a run, printed at exit with FDSURF_FUZZ_STATS=1 in the
// environment: to see that inputs get past the decoder into execution.
struct RunStats {
  std::uint64_t inputs = 0;
  std::uint64_t accepted = 0;
  std::uint64_t executed = 0;
  std::uint64_t moves = 0;
  std::uint64_t ticks = 0;
  std::uint64_t faults = 0;  // known ones, when not reported
  std::uint64_t errors[protocol::kLastErrorCode + 1] = {};
  std::int64_t slowest_frame_ns = 0;

  static RunStats& Get() {
    static RunStats* stats = [] {
      auto* s = new RunStats;
      if (std::getenv("FDSURF_FUZZ_STATS") != nullptr) std::atexit(Print);
      return s;
    }();
    return *stats;
  }
  static void Print() {
    const RunStats& s = Get();
    std::fprintf(
        stderr,
        "stats: %llu inputs, %llu commands accepted, %llu executed, %llu unit moves, "
        "%llu ticks, %llu known faults, slowest frame %.3f ms\nstats: ERROR replies by code:",
        static_cast<unsigned long long>(s.inputs), static_cast<unsigned long long>(s.accepted),
        static_cast<unsigned long long>(s.executed), static_cast<unsigned long long>(s.moves),
        static_cast<unsigned long long>(s.ticks), static_cast<unsigned long long>(s.faults),
        s.slowest_frame_ns / 1e6);
    for (int code = 0; code <= protocol::kLastErrorCode; ++code) {
      std::fprintf(stderr, " %d:%llu", code, static_cast<unsigned long long>(s.errors[code]));
    }
    std::fprintf(stderr, "\n");
  }
};

class DeviceHarness {
 public:
  DeviceHarness() : steps_(clock_, 2), pen_(clock_), device_(kTickHz) { ++RunStats::Get().inputs; }
  ~DeviceHarness() {
    RunStats& stats = RunStats::Get();
    stats.accepted += device_.link_stats().commands_accepted;
    stats.executed += device_.executed();
    stats.moves += device_.motion().moves();
    if (Faulted()) ++stats.faults;
  }
  DeviceHarness(const DeviceHarness&) = delete;
  DeviceHarness& operator=(const DeviceHarness&) = delete;

  FuzzDevice& device() { return device_; }

  // Feeds bytes (frames, or any run of raw bytes) and checks their cost:
  // the whole run is timed, which bounds every single OnByte() call in it
  // (only a frame's delimiter makes the device do work). A frame that would
  // hit known defect 2 expensively is dropped (its delimiter replaced by a
  // COBS error) unless that defect is reported.
  void Feed(const std::uint8_t* data, std::size_t size) {
    Dump(data, size);
    bool slow_is_known = false;
    std::int64_t snooping = 0;  // the harness's own work, not charged to the device
    TheWatchdog().Arm();
    const std::int64_t start = ThreadCpuNs();
    for (std::size_t i = 0; i < size; ++i) {
      if (!snoop_.OnByte(data[i])) {
        device_.OnByte(data[i]);
        continue;
      }
      FollowSession();
      const std::int64_t snoop_start = ThreadCpuNs();
      const bool known = SnoopedFrameIsKnownDefect2();
      snooping += ThreadCpuNs() - snoop_start;
      if (known) {
        slow_is_known = true;
        if (!KnownDefectReported(KnownDefect::kSlowValidation)) {
          device_.OnByte(0x02);  // a block that runs into the delimiter
          device_.OnByte(0x00);
          continue;
        }
        Watchdog::in_known_defect2 = 1;
      }
      device_.OnByte(data[i]);
      Watchdog::in_known_defect2 = 0;
    }
    const std::int64_t spent = ThreadCpuNs() - start - snooping;
    TheWatchdog().Disarm();
    RunStats::Get().slowest_frame_ns = std::max(RunStats::Get().slowest_frame_ns, spent);
    if (spent > kWorkBudgetNs) {
      DeviceFinding(slow_is_known ? "known defect 2: a frame's validation exceeded the budget (ns)"
                                  : "bytes took more than the work budget (ns, budget)",
                    spent, kWorkBudgetNs);
    }
  }

  // The session the host side is in (protocol version 2): replies carry its
  // tag, and the snooping decoder must see the frames the device will.
  void SetSession(std::uint32_t session) {
    replies_.set_session(session);
    snoop_.set_session(session);
  }

  // Replies, as the host would read them; `on_reply` sees each decoded one.
  template <typename OnReply>
  void Drain(OnReply&& on_reply) {
    std::uint8_t buffer[64];
    for (;;) {
      const std::size_t n = device_.ReadOutput(buffer, sizeof buffer);
      if (n == 0) return;
      for (std::size_t i = 0; i < n; ++i) {
        if (!replies_.OnByte(buffer[i])) continue;
        protocol::Reply reply;
        // The device's own replies must decode: a reply the host cannot read is a defect.
        if (!protocol::DecodeReply(replies_.frame(), &reply).ok()) {
          DeviceFinding("the device sent a reply that does not decode", replies_.frame().type);
        }
        if (reply.type == protocol::MessageType::kError &&
            static_cast<int>(reply.body.error.code) <= protocol::kLastErrorCode) {
          ++RunStats::Get().errors[static_cast<int>(reply.body.error.code)];
        }
        on_reply(reply);
      }
    }
  }
  void Drain() {
    Drain([](const protocol::Reply&) {});
  }

  // `ticks` rounds of the main loop and the step timer.
  // The watchdog covers the whole run (timing each Fill() would cost four
  // system calls per tick); a run is at most some 60,000 ticks.
  void Run(std::uint32_t ticks) {
    TheWatchdog().Arm();
    RunTicks(ticks);
    TheWatchdog().Disarm();
  }

  void RunTicks(std::uint32_t ticks) {
    for (std::uint32_t t = 0; t < ticks; ++t) {
      device_.Fill();
      CheckNoFault();
      if (device_.Tick(steps_, pen_) != hal::IoStatus::kOk) {
        DeviceFinding("a simulated output failed", steps_.LastError()[0]);
      }
      clock_.Advance(kTickUs);
      ++RunStats::Get().ticks;
      if ((t & 0x3FFF) == 0) {
        steps_.ClearEvents();  // memory stays bounded; positions are kept
        pen_.ClearEvents();
      }
      if (device_.Idle()) return;
    }
  }

  void CheckNoFault() const {
    protocol::StatusReport report{};
    device_.FillStatus(&report);
    if (report.state != protocol::DeviceState::kFault) return;
    const bool known1 =
        report.error == protocol::ErrorCode::kPlannerRefused &&
        report.error_detail == static_cast<std::uint8_t>(Status::kPrecisionUnreachable) &&
        long_travel_configured_;
    if (known1 && !KnownDefectReported(KnownDefect::kLongMove)) return;
    DeviceFinding(known1 ? "known defect 1: an accepted command faulted the device (error, detail)"
                         : "an accepted command faulted the device (error, detail)",
                  static_cast<int>(report.error), report.error_detail);
  }

  // Whether a configuration with a travel of at least 2^26 steps on some
  // axis was accepted in this run: only then can a straight move of more
  // than 2^26 steps exist (known defect 1).
  void NoteTravel(const protocol::MachineConfig& config) {
    for (int a = 0; a < 2; ++a) {
      if (config.travel_steps[a] >= (std::int32_t{1} << 25)) long_travel_configured_ = true;
    }
  }

  // With FDSURF_FUZZ_DUMP=FILE, every byte fed is appended to FILE: how the
  // seeds of fuzz_device_bytes are made from fuzz_device_frames inputs
  // (fuzz/README.md).
  static void Dump(const std::uint8_t* data, std::size_t size) {
    static std::FILE* file = [] {
      const char* path = std::getenv("FDSURF_FUZZ_DUMP");
      return path != nullptr ? std::fopen(path, "ab") : nullptr;
    }();
    if (file != nullptr) {
      std::fwrite(data, 1, size, file);
      std::fflush(file);
    }
  }

  // A new-session HELLO that the device will take: from then on the host
  // side reads replies (and snoops frames) of that session.
  void FollowSession() {
    const protocol::Frame& frame = snoop_.frame();
    if (static_cast<protocol::MessageType>(frame.type) != protocol::MessageType::kHello) return;
    protocol::Hello hello;
    if (!protocol::DecodeHello(frame, &hello).ok()) return;
    if ((hello.flags & protocol::kHelloFlagNewSession) != 0 && hello.session != 0) {
      SetSession(hello.session);
    }
  }

  // What the bytes fed so far say about the device (snoop_ sees them before
  // the device does): the last CONFIG decoded, taken as the one in force
  // (it may have been refused; then this errs on the safe side).
  bool SnoopedFrameIsKnownDefect2() {
    const protocol::Frame& frame = snoop_.frame();
    const auto type = static_cast<protocol::MessageType>(frame.type);
    if (type != protocol::MessageType::kConfig && type != protocol::MessageType::kPatch &&
        type != protocol::MessageType::kCurve) {
      return false;
    }
    protocol::Command command;
    if (!protocol::DecodeCommand(frame, &command).ok()) return false;
    if (type == protocol::MessageType::kConfig) {
      NoteTravel(command.body.config);
      for (int a = 0; a < 2; ++a) travel_[a] = command.body.config.travel_steps[a];
      return false;
    }
    return type == protocol::MessageType::kPatch ? PatchHitsKnownDefect2(command.body.patch)
                                                 : CurveHitsKnownDefect2(command.body.curve);
  }

  // Known defect 2: a line whose control hull crosses the travel limit
  // is stepped through to validate it. The same hull test as the device's
  // (firmware/motion/src/path_generator.cc WithinTravel), on every line.

  bool HullCrosses(const fdsurf::PowerCurve1 (&curve)[2]) const {
    for (int c = 0; c < 2; ++c) {
      const std::int64_t a = curve[c].c[0];
      const std::int64_t b = curve[c].c[1];
      const std::int64_t cc = curve[c].c[2];
      const std::int64_t d = curve[c].c[3];
      const std::int64_t hull[4] = {3 * d, 3 * d + cc, 3 * d + 2 * cc + b, 3 * (a + b + cc + d)};
      const std::int64_t low = -3 * (kOneStep / 2);
      const std::int64_t high = 3 * (std::int64_t{travel_[c]} * kOneStep + kOneStep / 2);
      for (const std::int64_t value : hull) {
        if (value < low || value >= high) return true;
      }
    }
    return false;
  }

  std::int64_t LargestTravel() const { return std::max<std::int64_t>({travel_[0], travel_[1], 1}); }

  bool PatchHitsKnownDefect2(const protocol::PatchCommand& patch) const {
    if (patch.dims != 2) return false;
    fdsurf::PatchGeometry1 geometry[2] = {patch.geometry[0], patch.geometry[1]};
    const std::int64_t cost = (std::int64_t{patch.lines_s} + patch.lines_t) * LargestTravel();
    if (cost <= kCheapHullCrossing) return false;
    for (const auto family : {fdsurf::IsolineFamily::kSLines, fdsurf::IsolineFamily::kTLines}) {
      const std::uint16_t lines =
          family == fdsurf::IsolineFamily::kSLines ? patch.lines_s : patch.lines_t;
      fdsurf::IsolineWalker<2> walker;
      if (lines == 0 || fdsurf::IsolineWalker<2>::Create(geometry, patch.basis, family, lines,
                                                         &walker) != fdsurf::Status::kOk) {
        continue;
      }
      fdsurf::PowerCurve1 curve[2];
      while (walker.Next(curve)) {
        if (HullCrosses(curve)) return true;
      }
    }
    return false;
  }

  bool CurveHitsKnownDefect2(const protocol::CurveCommand& curve) const {
    if (curve.dims != 2 || LargestTravel() <= kCheapHullCrossing) return false;
    fdsurf::CurveGeometry1 geometry[2] = {curve.geometry[0], curve.geometry[1]};
    fdsurf::PowerCurve1 power[2];
    if (fdsurf::CurvePowerCoefficients(geometry, curve.basis, power) != fdsurf::Status::kOk) {
      return false;
    }
    return HullCrosses(power);
  }

  bool Faulted() const {
    protocol::StatusReport report{};
    device_.FillStatus(&report);
    return report.state == protocol::DeviceState::kFault;
  }

 private:
  hal::SimClock clock_;
  hal::SimStepDir steps_;
  hal::SimPen pen_;
  FuzzDevice device_;
  protocol::FrameDecoderBuffer<> replies_;
  protocol::FrameDecoderBuffer<> snoop_;
  std::int32_t travel_[2] = {0, 0};
  bool long_travel_configured_ = false;
};

}  // namespace fdsurf::fuzz
