// SPDX-License-Identifier: MIT
// fdsurf_simavr_board: an AVR board's image under simavr, as the emulator
// harness of boards/README (docs/boards.md) describes. The boards
// (avr_boards.h): mega2560-ramps (the default) and uno-cnc-shield.
//
//   fdsurf_simavr_board --elf IMAGE.elf --uart-socket PATH --waveform OUT
//                       [--board mega2560-ramps|uno-cnc-shield]
//                       [--time-limit-s N] [--measures OUT.tsv] [--speed realtime|max]
//                       [--endstop-start X,Y[,Z]] [--endstop-triggered-level 1|0]
//                       [--profile OUT.tsv]
//
// USART0 is bridged to a Unix-domain stream socket at PATH (one client at a
// time; the next is accepted when it leaves). Received bytes enter simavr's
// UART at its byte timing under its XON/XOFF input flow control, so none is
// lost by the emulator. Every change of the board's step/dir/enable pins and
// of its servo pin (the Mega's D11 = PB5 = OC1A, the Uno's D11 = PB3 = OC2A)
// goes to OUT with its emulated time in ns (waveform format 1). With
// --measures: the step interrupt's cycles, late ticks, the main loop's
// cycles per emitted point, the painted stack's high-water mark, flash and
// static RAM, as a TSV (../README.md).
// With --endstop-start: a simulated carriage on each axis, starting the
// given number of steps above its min switch (below 0: past it) (the Mega:
// X_MIN D3 = PE5, Y_MIN D14 = PJ1, Z_MIN D18 = PD3; the Uno: X D9 = PB1,
// Y D10 = PB2, Z D12 = PB4); every STEP pulse moves it one step (DIR high:
// towards the switch), and the switch's input pin is driven to the
// triggered level (default 1, the images' default for normally-closed
// switches) at and below position 0, to the other level above it. Without
// it, every min input is held at its released level. The Mega's max inputs
// (X_MAX D2 = PE4, Y_MAX D15 = PJ0, Z_MAX D19 = PD2) are always held
// released (the Uno has none). Each switch change and the carriage's final
// position go to stderr ("carriage ...").
// With --profile: the emulated cycles spent at each instruction address
// (flash byte address, hex; a row "asleep" for the core asleep), interrupts
// included, as a TSV for
// profile_report.py to sum per function (docs/performance.md).
// Exits 0 on SIGTERM/SIGINT or at the time limit, having flushed OUT.
#include <avr_ioport.h>
#include <avr_uart.h>
#include <poll.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_interrupts.h>
#include <sim_io.h>
#include <sim_irq.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "avr_boards.h"
#include "board_measures.h"

namespace {

constexpr std::uint32_t kCpuHz = 16'000'000;
// Emulated cycles between two looks at the socket: 125 us, under one byte
// time at 250 000 bit/s x 3 (simavr's UART takes 64 bytes ahead).
constexpr std::uint64_t kSliceCycles = 2'000;

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

struct Options {
  const fdsurf::board::AvrBoard* board = fdsurf::board::FindAvrBoard("mega2560-ramps");
  std::string elf;
  std::string socket_path;
  std::string waveform;
  std::string measures;
  std::string profile;
  double time_limit_s = 0;  // 0: none
  bool realtime = true;
  std::vector<long> endstop_start;  // steps above each min switch; empty: no carriage
  int triggered_level = 1;
};

[[noreturn]] void Usage(const std::string& why) {
  std::fprintf(stderr,
               "fdsurf_simavr_board: %s\nusage: fdsurf_simavr_board --elf IMAGE.elf "
               "--uart-socket PATH --waveform OUT [--board NAME] [--time-limit-s N] "
               "[--measures OUT.tsv] "
               "[--speed realtime|max] [--endstop-start X,Y[,Z]] "
               "[--endstop-triggered-level 1|0] [--profile OUT.tsv]\n",
               why.c_str());
  std::exit(2);
}

// "X,Y" or "X,Y,Z": whole numbers of steps (below 0: the carriage starts
// past the switch's trigger point, as one pushed there by hand).
std::vector<long> ParseStart(const std::string& value) {
  std::vector<long> steps;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    const std::size_t comma = std::min(value.find(',', begin), value.size());
    const std::string field = value.substr(begin, comma - begin);
    char* end = nullptr;
    const long n = std::strtol(field.c_str(), &end, 10);
    if (field.empty() || *end != 0 || n < -1000000 || n > 1000000) {
      Usage("--endstop-start: '" + field + "' is not a whole number of steps, -10^6..10^6");
    }
    steps.push_back(n);
    begin = comma + 1;
  }
  if (steps.size() < 2 || steps.size() > 3) Usage("--endstop-start: X,Y or X,Y,Z");
  return steps;
}

Options ParseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) Usage(arg + ": needs a value");
    const std::string value = argv[++i];
    if (arg == "--elf") {
      o.elf = value;
    } else if (arg == "--board") {
      o.board = fdsurf::board::FindAvrBoard(value);
      if (o.board == nullptr) {
        Usage("--board: '" + value + "' is not one of " + fdsurf::board::AvrBoardNames());
      }
    } else if (arg == "--uart-socket") {
      o.socket_path = value;
    } else if (arg == "--waveform") {
      o.waveform = value;
    } else if (arg == "--measures") {
      o.measures = value;
    } else if (arg == "--profile") {
      o.profile = value;
    } else if (arg == "--time-limit-s") {
      char* end = nullptr;
      o.time_limit_s = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != 0 || !(o.time_limit_s > 0)) {
        Usage("--time-limit-s: '" + value + "' is not a positive number of seconds");
      }
    } else if (arg == "--endstop-start") {
      o.endstop_start = ParseStart(value);
    } else if (arg == "--endstop-triggered-level") {
      if (value != "0" && value != "1") Usage("--endstop-triggered-level: 0 or 1");
      o.triggered_level = value == "1" ? 1 : 0;
    } else if (arg == "--speed") {
      if (value != "realtime" && value != "max") Usage("--speed: realtime or max");
      o.realtime = value == "realtime";
    } else {
      Usage("unknown option " + arg);
    }
  }
  if (o.elf.empty() || o.socket_path.empty() || o.waveform.empty()) {
    Usage("--elf, --uart-socket and --waveform are required");
  }
  return o;
}

// --- The UART bridge -------------------------------------------------------

class UartBridge {
 public:
  bool Listen(const std::string& path, std::string* error);
  void Attach(avr_t* avr);
  /// Accepts, reads and writes without waiting; feeds the UART while it
  /// takes bytes.
  void Service();
  /// Waits up to `timeout_ms` for the socket (for pacing to real time).
  void Wait(int timeout_ms);
  void Close();
  [[nodiscard]] std::uint64_t bytes_in() const { return bytes_in_; }
  [[nodiscard]] std::uint64_t bytes_out() const { return bytes_out_; }

 private:
  static void OnOutput(avr_irq_t*, std::uint32_t value, void* param);
  static void OnXon(avr_irq_t*, std::uint32_t, void* param);
  static void OnXoff(avr_irq_t*, std::uint32_t value, void* param);
  void Feed();
  void Drop();

  std::string path_;
  int listen_fd_ = -1;
  int client_fd_ = -1;
  avr_irq_t* input_ = nullptr;
  bool xoff_ = true;  // until the firmware enables its receiver
  std::deque<std::uint8_t> to_board_;
  std::vector<std::uint8_t> to_client_;
  std::uint64_t bytes_in_ = 0;
  std::uint64_t bytes_out_ = 0;
};

bool UartBridge::Listen(const std::string& path, std::string* error) {
  sockaddr_un address{};
  if (path.size() >= sizeof address.sun_path) {
    *error = path + ": too long for a Unix socket path";
    return false;
  }
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  (void)unlink(path.c_str());
  if (listen_fd_ < 0 ||
      bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      listen(listen_fd_, 1) != 0) {
    *error = path + ": " + std::strerror(errno);
    return false;
  }
  path_ = path;
  return true;
}

void UartBridge::Attach(avr_t* avr) {
  std::uint32_t flags = 0;  // no console echo, no sleeping while polled
  avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  input_ = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), OnOutput,
                          this);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), OnXon,
                          this);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), OnXoff,
                          this);
}

void UartBridge::OnOutput(avr_irq_t*, std::uint32_t value, void* param) {
  auto* self = static_cast<UartBridge*>(param);
  ++self->bytes_out_;
  if (self->client_fd_ >= 0) self->to_client_.push_back(static_cast<std::uint8_t>(value));
}

void UartBridge::OnXon(avr_irq_t*, std::uint32_t, void* param) {
  auto* self = static_cast<UartBridge*>(param);
  self->xoff_ = false;
  self->Feed();
}

void UartBridge::OnXoff(avr_irq_t*, std::uint32_t value, void* param) {
  static_cast<UartBridge*>(param)->xoff_ = value != 0;
}

// simavr raises XOFF from inside the input IRQ once its FIFO is full.
void UartBridge::Feed() {
  while (!xoff_ && !to_board_.empty()) {
    const std::uint8_t byte = to_board_.front();
    to_board_.pop_front();
    ++bytes_in_;
    avr_raise_irq(input_, byte);
  }
}

void UartBridge::Drop() {
  close(client_fd_);
  client_fd_ = -1;
  to_client_.clear();
}

void UartBridge::Service() {
  if (client_fd_ < 0 && listen_fd_ >= 0) {
    client_fd_ = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  }
  if (client_fd_ >= 0 && to_board_.size() < 4096) {
    std::uint8_t buffer[1024];
    const ssize_t n = recv(client_fd_, buffer, sizeof buffer, 0);
    if (n > 0) {
      to_board_.insert(to_board_.end(), buffer, buffer + n);
    } else if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      Drop();  // the client left: bytes it sent stay on their way to the board
    }
  }
  if (client_fd_ >= 0 && !to_client_.empty()) {
    const ssize_t n = send(client_fd_, to_client_.data(), to_client_.size(), MSG_NOSIGNAL);
    if (n > 0) {
      to_client_.erase(to_client_.begin(), to_client_.begin() + n);
    } else if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      Drop();
    }
  }
  Feed();
}

void UartBridge::Wait(int timeout_ms) {
  pollfd fd{client_fd_ >= 0 ? client_fd_ : listen_fd_, POLLIN, 0};
  (void)poll(&fd, 1, timeout_ms);
}

void UartBridge::Close() {
  if (client_fd_ >= 0) Drop();
  if (listen_fd_ >= 0) {
    close(listen_fd_);
    (void)unlink(path_.c_str());
  }
  listen_fd_ = -1;
}

// --- The carriage and its min switches --------------------------------------

class Carriage {
 public:
  /// Drives every min input to its level; with `start` empty the switches
  /// stay released and nothing moves.
  void Attach(avr_t* avr, const fdsurf::board::AvrBoard& board, const std::vector<long>& start,
              int triggered_level);
  /// Drives the inputs again (the firmware's own PORT writes cannot have
  /// changed what the switch says for longer than a slice).
  void Reassert();
  void Report() const;

 private:
  struct Axis {
    fdsurf::board::AvrAxis pins;
    avr_irq_t* dir = nullptr;
    avr_irq_t* min = nullptr;
    avr_irq_t* max = nullptr;  // always released; nullptr: the board has none
    long position = 0;
    bool modelled = false;
    bool triggered = false;
    std::uint32_t step_level = 0;
    Carriage* carriage = nullptr;
  };
  static void OnStep(avr_irq_t* irq, std::uint32_t value, void* param);
  void Drive(Axis* axis);

  avr_t* avr_ = nullptr;
  int triggered_level_ = 1;
  Axis axes_[3];
};

avr_irq_t* PinIrq(avr_t* avr, const fdsurf::board::AvrPin& pin) {
  return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(pin.port), IOPORT_IRQ_PIN0 + pin.bit);
}

void Carriage::Attach(avr_t* avr, const fdsurf::board::AvrBoard& board,
                      const std::vector<long>& start, int triggered_level) {
  avr_ = avr;
  triggered_level_ = triggered_level;
  for (std::size_t a = 0; a < 3; ++a) {
    Axis* axis = &axes_[a];
    axis->pins = board.axes[a];
    axis->carriage = this;
    axis->modelled = a < start.size();
    axis->position = axis->modelled ? start[a] : 1;
    axis->dir = PinIrq(avr, axis->pins.dir);
    axis->min = PinIrq(avr, axis->pins.min);
    axis->max = axis->pins.has_max ? PinIrq(avr, axis->pins.max) : nullptr;
    if (axis->modelled) avr_irq_register_notify(PinIrq(avr, axis->pins.step), OnStep, axis);
    Drive(axis);
  }
}

// A rising STEP edge moves the carriage one step; DIR high is negative.
void Carriage::OnStep(avr_irq_t*, std::uint32_t value, void* param) {
  auto* axis = static_cast<Axis*>(param);
  const std::uint32_t level = value & 1u;
  const bool rising = level == 1 && axis->step_level == 0;
  axis->step_level = level;
  if (!rising) return;
  axis->position += (axis->dir->value & 1u) != 0 ? -1 : 1;
  axis->carriage->Drive(axis);
}

void Carriage::Drive(Axis* axis) {
  const bool triggered = axis->modelled && axis->position <= 0;
  if (triggered != axis->triggered) {
    std::fprintf(stderr, "fdsurf_simavr_board: %c min switch %s at position %ld, %.6f s\n",
                 axis->pins.name, triggered ? "triggered" : "released", axis->position,
                 static_cast<double>(avr_->cycle) / kCpuHz);
  }
  axis->triggered = triggered;
  avr_raise_irq(axis->min, triggered ? triggered_level_ : 1 - triggered_level_);
  if (axis->max != nullptr) avr_raise_irq(axis->max, 1 - triggered_level_);
}

void Carriage::Reassert() {
  for (Axis& axis : axes_) {
    const std::uint32_t level = axis.triggered ? triggered_level_ : 1 - triggered_level_;
    if (axis.min->value != level) avr_raise_irq(axis.min, level);
    const std::uint32_t released = 1 - triggered_level_;
    if (axis.max != nullptr && axis.max->value != released) avr_raise_irq(axis.max, released);
  }
}

void Carriage::Report() const {
  std::fprintf(stderr, "fdsurf_simavr_board: carriage");
  for (const Axis& axis : axes_) {
    if (axis.modelled) std::fprintf(stderr, " %c %ld", axis.pins.name, axis.position);
  }
  std::fprintf(stderr, "\n");
}

// --- Running ---------------------------------------------------------------

struct Emulator {
  avr_t* avr = nullptr;
  elf_firmware_t firmware{};
};

bool LoadImage(const std::string& path, const char* mcu, Emulator* emulator) {
  if (elf_read_firmware(path.c_str(), &emulator->firmware) != 0) {
    std::fprintf(stderr, "fdsurf_simavr_board: %s: cannot read the ELF image\n", path.c_str());
    return false;
  }
  emulator->avr = avr_make_mcu_by_name(mcu);
  if (emulator->avr == nullptr) return false;
  avr_init(emulator->avr);
  emulator->avr->log = LOG_ERROR;
  emulator->firmware.frequency = kCpuHz;
  avr_load_firmware(emulator->avr, &emulator->firmware);
  emulator->avr->frequency = kCpuHz;
  return true;
}

std::uint64_t NowNs() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

// Cycles per instruction word, for --profile.
class Profile {
 public:
  void Add(avr_flashaddr_t pc, bool asleep, std::uint64_t cycles) {
    if (asleep) {
      asleep_ += cycles;
      return;
    }
    const std::size_t word = pc / 2;
    if (word >= cycles_.size()) cycles_.resize(word + 1, 0);
    cycles_[word] += cycles;
  }
  [[nodiscard]] bool Write(const std::string& path) const {
    FILE* file = std::fopen(path.c_str(), "w");
    if (file == nullptr) return false;
    std::fputs("address\tcycles\n", file);
    std::fprintf(file, "asleep\t%llu\n", static_cast<unsigned long long>(asleep_));
    for (std::size_t word = 0; word < cycles_.size(); ++word) {
      if (cycles_[word] == 0) continue;
      std::fprintf(file, "%zx\t%llu\n", word * 2, static_cast<unsigned long long>(cycles_[word]));
    }
    return std::fclose(file) == 0;
  }

 private:
  std::vector<std::uint64_t> cycles_;
  std::uint64_t asleep_ = 0;
};

// Runs until a signal, the time limit or a crash; true unless it crashed.
bool RunLoop(const Options& o, Emulator* emulator, UartBridge* bridge, Carriage* carriage,
             Profile* profile) {
  avr_t* avr = emulator->avr;
  const std::uint64_t limit =
      o.time_limit_s > 0 ? static_cast<std::uint64_t>(o.time_limit_s * kCpuHz) : UINT64_MAX;
  const std::uint64_t wall_start = NowNs();
  while (g_stop == 0 && avr->cycle < limit) {
    const std::uint64_t slice_end = avr->cycle + kSliceCycles;
    while (avr->cycle < slice_end) {
      const avr_flashaddr_t pc = avr->pc;
      const bool asleep = avr->state == cpu_Sleeping;
      const std::uint64_t before = avr->cycle;
      const int state = avr_run(avr);
      if (profile != nullptr) profile->Add(pc, asleep, avr->cycle - before);
      if (state == cpu_Done || state == cpu_Crashed) {
        std::fprintf(stderr, "fdsurf_simavr_board: the core stopped (%s) at cycle %llu\n",
                     state == cpu_Crashed ? "crashed" : "done",
                     static_cast<unsigned long long>(avr->cycle));
        return false;
      }
    }
    bridge->Service();
    carriage->Reassert();
    if (o.realtime) {
      // Never ahead of the wall clock: the host's timeouts are wall time.
      const std::uint64_t emulated_ns = avr->cycle * 125 / 2;
      const std::uint64_t wall_ns = NowNs() - wall_start;
      if (emulated_ns > wall_ns + 1'000'000) {
        bridge->Wait(static_cast<int>((emulated_ns - wall_ns) / 1'000'000));
      }
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = ParseOptions(argc, argv);
  // libsimavr prints its progress on stdout, which is for "ready" only.
  std::fflush(stdout);
  FILE* out = fdopen(dup(STDOUT_FILENO), "w");
  if (out == nullptr || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) return 2;
  Emulator emulator;
  if (!LoadImage(o.elf, o.board->mcu, &emulator)) return 2;
  fdsurf::board::Recorder recorder(*o.board);
  std::string error;
  if (!recorder.Open(o.waveform, &error)) {
    std::fprintf(stderr, "fdsurf_simavr_board: %s\n", error.c_str());
    return 2;
  }
  recorder.Attach(emulator.avr);
  UartBridge bridge;
  bridge.Attach(emulator.avr);
  Carriage carriage;
  carriage.Attach(emulator.avr, *o.board, o.endstop_start, o.triggered_level);
  if (!bridge.Listen(o.socket_path, &error)) {
    std::fprintf(stderr, "fdsurf_simavr_board: --uart-socket %s\n", error.c_str());
    return 2;
  }
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);
  std::fputs("ready\n", out);
  std::fflush(out);
  Profile profile;
  const bool ok = RunLoop(o, &emulator, &bridge, &carriage, o.profile.empty() ? nullptr : &profile);
  if (!o.profile.empty() && !profile.Write(o.profile)) {
    std::fprintf(stderr, "fdsurf_simavr_board: --profile %s: cannot write it\n", o.profile.c_str());
    return 2;
  }
  bridge.Close();
  if (!o.endstop_start.empty()) carriage.Report();
  recorder.Finish(emulator.avr);
  if (!o.measures.empty()) {
    fdsurf::board::ImageFacts facts{emulator.firmware.flashsize, emulator.firmware.datasize,
                                    emulator.firmware.bsssize};
    if (!recorder.WriteMeasures(o.measures, emulator.avr, facts, bridge.bytes_in(),
                                bridge.bytes_out(), &error)) {
      std::fprintf(stderr, "fdsurf_simavr_board: --measures %s\n", error.c_str());
      return 2;
    }
  }
  std::fclose(out);
  return ok ? 0 : 1;
}
