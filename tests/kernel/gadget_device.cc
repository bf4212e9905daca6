// SPDX-License-Identifier: MIT
// The plotter firmware as a Linux USB gadget, for the tests under QEMU
// (tests/kernel/README.md): Device<2> with recording step/dir/pen outputs,
// its link either
//
//   --acm TTY   the tty of a configfs `acm` function (/dev/ttyGS0), or
//   --ffs DIR   a mounted FunctionFS instance: this program writes its
//               descriptors (one vendor-specific interface, bulk OUT and
//               bulk IN), answers ep0's events and moves the bytes over
//               DIR/ep1 (OUT) and DIR/ep2 (IN).
//
//   gadget_device (--acm TTY | --ffs DIR) --report FILE [--tick-hz 20000]
//                 [--speedup 1] [--never-answer] [--time-limit-s 60]
//
// Prints "ready" once the link is open (for --ffs: once the descriptors are
// written, so the gadget can be bound to the UDC). On SIGTERM or the time
// limit it writes FILE (key value lines: executed commands, accepted
// commands, duplicates, HELLOs, steps per axis, the final position, a
// digest of every step and pen change in order, pen state, idle, FunctionFS
// ENABLE events, tty hang-ups) and exits 0.
// On SIGUSR1 it writes FILE as it is now and goes on. FILE is renamed into
// place, so a reader never sees half of one.
#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "fdsurf/device/device.h"
#include "fdsurf/hal/outputs.h"

namespace {

std::atomic<bool> g_quit{false};
std::atomic<bool> g_snapshot{false};
void OnSignal(int) { g_quit = true; }
void OnSnapshot(int) { g_snapshot = true; }

struct Options {
  std::string acm;
  std::string ffs;
  std::string report;
  uint32_t tick_hz = 20000;
  double speedup = 1;
  bool never_answer = false;
  double time_limit_s = 60;
};

// Counts steps per axis, keeps the position and folds every step and pen
// change, in order, into an FNV-1a digest (offset 14695981039346656037,
// prime 1099511628211): a step folds (axis mask | negative mask << 4), a pen
// change 0x81 (down) or 0x80 (up). tests/kernel/kernel_test.py folds the
// simulated plotter's waveform the same way.
class RecordingOutputs final : public fdsurf::hal::StepDirOutputs, public fdsurf::hal::PenOutput {
 public:
  RecordingOutputs() : StepDirOutputs(2) {}
  uint64_t steps[2] = {0, 0};
  int64_t position[2] = {0, 0};
  uint64_t digest = 14695981039346656037ull;
  bool pen_down = false;

 private:
  void Fold(uint8_t byte) {
    digest ^= byte;
    digest *= 1099511628211ull;
  }
  fdsurf::hal::IoStatus DoSetEnabled(bool) override { return fdsurf::hal::IoStatus::kOk; }
  fdsurf::hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    negative_ = negative_mask;
    return fdsurf::hal::IoStatus::kOk;
  }
  fdsurf::hal::IoStatus DoStep(uint8_t axis_mask) override {
    for (int a = 0; a < 2; ++a) {
      if (((axis_mask >> a) & 1u) == 0) continue;
      ++steps[a];
      position[a] += ((negative_ >> a) & 1u) != 0 ? -1 : 1;
    }
    Fold(static_cast<uint8_t>(axis_mask | (negative_ & axis_mask) << 4));
    return fdsurf::hal::IoStatus::kOk;
  }
  fdsurf::hal::IoStatus DoSetPen(bool down) override {
    pen_down = down;
    Fold(down ? 0x81 : 0x80);
    return fdsurf::hal::IoStatus::kOk;
  }
  FDSURF_NODISCARD const char* DoLastError() const override { return ""; }
  uint8_t negative_ = 0;
};

// A byte link to the host: Receive never blocks, Send may queue.
class Link {
 public:
  virtual ~Link() = default;
  virtual size_t Receive(uint8_t* data, size_t capacity) = 0;
  virtual void Send(const uint8_t* data, size_t size) = 0;
  // Waits at most 1 ms for bytes to receive.
  virtual void Wait() = 0;
};

// The gadget side of CDC-ACM: a tty, raw, non-blocking. When the gadget
// is unbound from its UDC the kernel hangs this tty up (u_serial's
// disconnect): reads then return 0 and the file must be opened again.
class TtyLink final : public Link {
 public:
  bool Open(const std::string& path) {
    path_ = path;
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd_ < 0) {
      if (hangups_ == 0) {
        std::fprintf(stderr, "gadget_device: cannot open %s: %s\n", path.c_str(),
                     std::strerror(errno));
      }
      return false;
    }
    termios tio{};
    tcgetattr(fd_, &tio);
    cfmakeraw(&tio);
    tcsetattr(fd_, TCSANOW, &tio);
    return true;
  }
  ~TtyLink() override {
    if (fd_ >= 0) close(fd_);
  }
  size_t Receive(uint8_t* data, size_t capacity) override {
    if (fd_ < 0 && !Open(path_)) return 0;
    const ssize_t n = read(fd_, data, capacity);
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
      ++hangups_;
      close(fd_);
      fd_ = -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return 0;
  }
  FDSURF_NODISCARD uint32_t hangups() const { return hangups_; }
  void Send(const uint8_t* data, size_t size) override {
    while (size > 0 && fd_ >= 0 && !g_quit) {
      const ssize_t n = write(fd_, data, size);
      if (n > 0) {
        data += n;
        size -= static_cast<size_t>(n);
      } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
        return;  // the host is gone: the protocol resends what it missed
      } else {
        pollfd p{fd_, POLLOUT, 0};
        (void)poll(&p, 1, 1);
      }
    }
  }
  void Wait() override {
    pollfd p{fd_, POLLIN, 0};
    (void)poll(&p, fd_ >= 0 ? 1 : 0, 1);
  }

 private:
  std::string path_;
  int fd_ = -1;
  uint32_t hangups_ = 0;
};

// The FunctionFS descriptors: full and high speed, each one vendor-specific
// interface with a bulk OUT (ep1) and a bulk IN (ep2) endpoint.
struct __attribute__((packed)) SpeedDescriptors {
  usb_interface_descriptor interface;
  usb_endpoint_descriptor_no_audio out;
  usb_endpoint_descriptor_no_audio in;
};
struct __attribute__((packed)) FfsDescriptors {
  usb_functionfs_descs_head_v2 header;
  uint32_t fs_count;
  uint32_t hs_count;
  SpeedDescriptors fs;
  SpeedDescriptors hs;
};
struct __attribute__((packed)) FfsStrings {
  usb_functionfs_strings_head header;
  uint16_t language;
  char interface_name[sizeof "fdsurf plotter"];
};

SpeedDescriptors SpeedSet(uint16_t max_packet) {
  SpeedDescriptors d{};
  d.interface.bLength = sizeof d.interface;
  d.interface.bDescriptorType = USB_DT_INTERFACE;
  d.interface.bNumEndpoints = 2;
  d.interface.bInterfaceClass = USB_CLASS_VENDOR_SPEC;
  d.interface.iInterface = 1;
  for (usb_endpoint_descriptor_no_audio* e : {&d.out, &d.in}) {
    e->bLength = sizeof *e;
    e->bDescriptorType = USB_DT_ENDPOINT;
    e->bmAttributes = USB_ENDPOINT_XFER_BULK;
    e->wMaxPacketSize = max_packet;  // little-endian host and bus
  }
  d.out.bEndpointAddress = 1 | USB_DIR_OUT;
  d.in.bEndpointAddress = 2 | USB_DIR_IN;
  return d;
}

// Whole-packet writes do not end a bulk IN transfer: the host's read waits
// for a short packet. Every write here is shorter than 64 bytes (full
// speed's packet; high speed's 512 is a multiple of it) or not a multiple
// of it, so each ends with a short packet.
size_t ShortChunk(size_t size) {
  const size_t chunk = std::min<size_t>(size, 511);
  return chunk != 0 && chunk % 64 == 0 ? chunk - 1 : chunk;
}

// The gadget side of the vendor interface over FunctionFS. Endpoint reads
// and writes block (FunctionFS files have no poll), so a thread reads ep1
// into `received_`, one writes `to_send_` to ep2, and one answers ep0.
class FfsLink final : public Link {
 public:
  bool Open(const std::string& dir) {
    ep0_ = open((dir + "/ep0").c_str(), O_RDWR);
    if (ep0_ < 0) return Error("open " + dir + "/ep0");
    FfsDescriptors descriptors{};
    descriptors.header.magic = FUNCTIONFS_DESCRIPTORS_MAGIC_V2;
    descriptors.header.length = sizeof descriptors;
    descriptors.header.flags = FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC;
    descriptors.fs_count = descriptors.hs_count = 3;
    descriptors.fs = SpeedSet(64);
    descriptors.hs = SpeedSet(512);
    if (write(ep0_, &descriptors, sizeof descriptors) != sizeof descriptors) {
      return Error("write the descriptors to " + dir + "/ep0");
    }
    FfsStrings strings{};
    strings.header.magic = FUNCTIONFS_STRINGS_MAGIC;
    strings.header.length = sizeof strings;
    strings.header.str_count = 1;
    strings.header.lang_count = 1;
    strings.language = 0x0409;
    std::memcpy(strings.interface_name, "fdsurf plotter", sizeof strings.interface_name);
    if (write(ep0_, &strings, sizeof strings) != sizeof strings) {
      return Error("write the strings to " + dir + "/ep0");
    }
    out_ = open((dir + "/ep1").c_str(), O_RDWR);
    in_ = open((dir + "/ep2").c_str(), O_RDWR);
    if (out_ < 0 || in_ < 0) return Error("open " + dir + "/ep1 and ep2");
    threads_.emplace_back([this] { AnswerEp0(); });
    threads_.emplace_back([this] { ReadOut(); });
    threads_.emplace_back([this] { WriteIn(); });
    return true;
  }
  ~FfsLink() override {
    // The threads sit in blocking reads and writes; the process exits with
    // them (SIGTERM already set g_quit), so they are left detached.
    for (std::thread& t : threads_) t.detach();
  }
  size_t Receive(uint8_t* data, size_t capacity) override {
    const std::lock_guard<std::mutex> lock(mutex_);
    const size_t n = std::min(capacity, received_.size());
    std::copy_n(received_.begin(), n, data);
    received_.erase(received_.begin(), received_.begin() + static_cast<ptrdiff_t>(n));
    return n;
  }
  void Send(const uint8_t* data, size_t size) override {
    const std::lock_guard<std::mutex> lock(mutex_);
    to_send_.insert(to_send_.end(), data, data + size);
  }
  void Wait() override { std::this_thread::sleep_for(std::chrono::microseconds(500)); }

  FDSURF_NODISCARD uint32_t enables() const { return enables_; }

 private:
  bool Error(const std::string& what) {
    std::fprintf(stderr, "gadget_device: cannot %s: %s\n", what.c_str(), std::strerror(errno));
    return false;
  }

  // ENABLE/DISABLE come with every bind and unbind; a SETUP request (none
  // is defined for this interface) is refused with a stall: the read or
  // write of ep0 against the request's direction.
  void AnswerEp0() {
    usb_functionfs_event events[4];
    while (!g_quit) {
      const ssize_t n = read(ep0_, events, sizeof events);
      if (n <= 0) {
        if (n < 0 && errno != EINTR) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      for (size_t i = 0; i < static_cast<size_t>(n) / sizeof events[0]; ++i) {
        if (events[i].type == FUNCTIONFS_ENABLE) ++enables_;
        if (events[i].type != FUNCTIONFS_SETUP) continue;
        uint8_t none = 0;
        if ((events[i].u.setup.bRequestType & USB_DIR_IN) != 0) {
          (void)!read(ep0_, &none, 0);
        } else {
          (void)!write(ep0_, &none, 0);
        }
      }
    }
  }

  // A read of one high-speed packet's size completes with every packet.
  void ReadOut() {
    uint8_t packet[512];
    while (!g_quit) {
      const ssize_t n = read(out_, packet, sizeof packet);
      if (n > 0) {
        const std::lock_guard<std::mutex> lock(mutex_);
        received_.insert(received_.end(), packet, packet + n);
      } else if (n < 0) {
        // ESHUTDOWN while unbound, until the next ENABLE.
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
  }

  // What could not be written while unbound is dropped: the host resends.
  void WriteIn() {
    std::vector<uint8_t> chunk;
    while (!g_quit) {
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        const size_t n = ShortChunk(to_send_.size());
        chunk.assign(to_send_.begin(), to_send_.begin() + static_cast<ptrdiff_t>(n));
        to_send_.erase(to_send_.begin(), to_send_.begin() + static_cast<ptrdiff_t>(n));
      }
      if (chunk.empty()) {
        std::this_thread::sleep_for(std::chrono::microseconds(500));
        continue;
      }
      (void)!write(in_, chunk.data(), chunk.size());
    }
  }

  int ep0_ = -1;
  int out_ = -1;
  int in_ = -1;
  std::mutex mutex_;
  std::deque<uint8_t> received_;
  std::deque<uint8_t> to_send_;
  std::atomic<uint32_t> enables_{0};
  std::vector<std::thread> threads_;
};

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--never-answer") {
      o->never_answer = true;
    } else if (arg == "--acm" && has_value) {
      o->acm = argv[++i];
    } else if (arg == "--ffs" && has_value) {
      o->ffs = argv[++i];
    } else if (arg == "--report" && has_value) {
      o->report = argv[++i];
    } else if (arg == "--tick-hz" && has_value) {
      o->tick_hz = static_cast<uint32_t>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--speedup" && has_value) {
      o->speedup = std::strtod(argv[++i], nullptr);
    } else if (arg == "--time-limit-s" && has_value) {
      o->time_limit_s = std::strtod(argv[++i], nullptr);
    } else {
      std::fprintf(stderr, "gadget_device: unknown or incomplete option '%s'\n", arg.c_str());
      return false;
    }
  }
  if (o->acm.empty() == o->ffs.empty() || o->report.empty() || o->tick_hz == 0 ||
      !(o->speedup > 0)) {
    std::fprintf(stderr,
                 "gadget_device: one of --acm TTY or --ffs DIR, and --report FILE, are required; "
                 "--tick-hz and --speedup > 0\n");
    return false;
  }
  return true;
}

using Clock = std::chrono::steady_clock;

struct Run {
  const Options& o;
  Link& link;
  fdsurf::device::Device<2> device;
  RecordingOutputs outputs;
  uint64_t ticks_done = 0;
  uint64_t bytes_in = 0;

  Run(const Options& options, Link& l) : o(options), link(l), device(options.tick_hz) {}

  void Service() {
    uint8_t buffer[512];
    const size_t n = link.Receive(buffer, sizeof buffer);
    bytes_in += n;
    if (!o.never_answer) {
      for (size_t i = 0; i < n; ++i) device.OnByte(buffer[i]);
    }
    for (size_t got; (got = device.ReadOutput(buffer, sizeof buffer)) > 0;) link.Send(buffer, got);
  }

  // The ticks due by now at the speed-up; a lag of more than 100000 ticks
  // (TCG is slow) is dropped rather than caught up in a burst.
  void Tick(Clock::time_point start) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const auto due = static_cast<uint64_t>(elapsed * o.tick_hz * o.speedup);
    for (int budget = 4096; ticks_done < due && budget > 0; --budget, ++ticks_done) {
      (void)device.Tick(outputs, outputs);
    }
    ticks_done = std::max(ticks_done, due > 100000 ? due - 100000 : 0);
  }

  void Report(uint32_t enables, uint32_t hangups) const {
    const std::string temporary = o.report + ".new";
    FILE* f = std::fopen(temporary.c_str(), "w");
    if (f == nullptr) return;
    const auto& stats = device.link_stats();
    std::fprintf(f, "executed %u\naccepted %u\nduplicates %u\nhellos %u\n", device.executed(),
                 stats.commands_accepted, stats.duplicates, stats.hellos);
    std::fprintf(f, "steps_x %llu\nsteps_y %llu\nposition %lld,%lld\ndigest %016llx\n",
                 static_cast<unsigned long long>(outputs.steps[0]),
                 static_cast<unsigned long long>(outputs.steps[1]),
                 static_cast<long long>(outputs.position[0]),
                 static_cast<long long>(outputs.position[1]),
                 static_cast<unsigned long long>(outputs.digest));
    std::fprintf(f, "pen_down %d\nidle %d\nbytes_in %llu\nenables %u\nhangups %u\n",
                 outputs.pen_down ? 1 : 0, device.Idle() ? 1 : 0,
                 static_cast<unsigned long long>(bytes_in), enables, hangups);
    std::fclose(f);
    std::rename(temporary.c_str(), o.report.c_str());
  }
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!ParseOptions(argc, argv, &o)) return 2;
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  struct sigaction snapshot {};
  snapshot.sa_handler = OnSnapshot;
  sigaction(SIGUSR1, &snapshot, nullptr);
  signal(SIGPIPE, SIG_IGN);
  TtyLink tty;
  FfsLink ffs;
  Link* link = &tty;
  if (!o.acm.empty() ? !tty.Open(o.acm) : !ffs.Open(o.ffs)) return 1;
  if (o.acm.empty()) link = &ffs;
  std::printf("ready\n");
  std::fflush(stdout);
  auto run = std::make_unique<Run>(o, *link);
  const Clock::time_point start = Clock::now();
  while (!g_quit && std::chrono::duration<double>(Clock::now() - start).count() < o.time_limit_s) {
    link->Wait();
    run->Service();
    run->device.Fill();
    run->Tick(start);
    if (g_snapshot.exchange(false)) run->Report(ffs.enables(), tty.hangups());
  }
  run->Report(ffs.enables(), tty.hangups());
  // The FunctionFS threads are blocked in the kernel; leave without joining.
  std::fflush(nullptr);
  _exit(0);
}
