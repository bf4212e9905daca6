// SPDX-License-Identifier: MIT
#include "board_measures.h"

#include <avr_ioport.h>
#include <avr_timer.h>
#include <avr_uart.h>
#include <sim_elf.h>
#include <sim_interrupts.h>
#include <sim_io.h>
#include <sim_irq.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace fdsurf::board {
namespace {

constexpr std::uint8_t kStackPaint = 0xA5;
constexpr std::uint8_t kWatchdogResetFlag = 0x08;  // MCUSR.WDRF

Recorder* g_recorder = nullptr;  // for simavr's sleep hook

}  // namespace

void CycleStats::Add(std::uint64_t cycles, std::uint64_t started_at) {
  ++count;
  sum += cycles;
  if (cycles < min) min = cycles;
  if (cycles > max) {
    max = cycles;
    max_at = started_at;
  }
}

Recorder::~Recorder() {
  if (file_ != nullptr) std::fclose(file_);
}

bool Recorder::Open(const std::string& path, std::string* error) {
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) {
    *error = "--waveform " + path + ": " + std::strerror(errno);
    return false;
  }
  path_ = path;
  // The pen: the image's default servo pulses (its board_config.h).
  std::fprintf(file_,
               "# fdsurf-waveform 1\n# board %s\n# dir_negative_level 1\n"
               "# enable_active_level 0\n# pen servo %u %u\n",
               board_.name, static_cast<unsigned>(board_.servo_up_us),
               static_cast<unsigned>(board_.servo_down_us));
  return true;
}

void Recorder::Attach(avr_t* avr) {
  avr_ = avr;
  g_recorder = this;
  for (int i = 0; i < kSignals; ++i) {
    const bool servo = std::string(board_.signals[i].name) == "SERVO";
    signals_[i] = Signal{board_.signals[i], this, false, 0, servo && board_.servo_timer.timer != 0};
    Signal* s = &signals_[i];
    if (s->timer_driven) {
      avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TIMER_GETIRQ(board_.servo_timer.timer),
                                            TIMER_IRQ_OUT_COMP + board_.servo_timer.compare),
                              OnServoTimer, s);
    }
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(s->line.pin.port),
                                          IOPORT_IRQ_PIN0 + s->line.pin.bit),
                            OnPin, s);
    avr_irq_register_notify(
        avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(s->line.pin.port), IOPORT_IRQ_DIRECTION_ALL),
        OnDirection, s);
  }
  avr_irq_t* tick = avr_get_interrupt_irq(avr, board_.tick_vector);
  avr_irq_register_notify(tick + AVR_INT_IRQ_PENDING, OnTickPending, this);
  avr_irq_register_notify(tick + AVR_INT_IRQ_RUNNING, OnTickRunning, this);
  avr_irq_register_notify(avr_get_interrupt_irq(avr, board_.rx_vector) + AVR_INT_IRQ_RUNNING,
                          OnRxRunning, this);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT), OnUartIn,
                          this);
  avr->sleep = OnSleep;
  avr_register_io_write(avr, board_.gpior0, OnBoot, this);
}

// The firmware's first instructions copy MCUSR (why it reset) to GPIOR0.
void Recorder::OnBoot(avr_t* avr, avr_io_addr_t addr, std::uint8_t value, void* param) {
  auto* r = static_cast<Recorder*>(param);
  avr->data[addr] = value;
  ++r->boots_;
  if ((value & kWatchdogResetFlag) != 0) {
    ++r->watchdog_resets_;
    std::fprintf(stderr, "fdsurf_simavr_board: watchdog reset at %.6f s\n",
                 static_cast<double>(avr->cycle) / 16e6);
  }
}

void Recorder::Write(const Signal& signal) {
  if (file_ == nullptr) return;
  // 16 MHz: 62.5 ns a cycle.
  std::fprintf(file_, "%llu %s %d\n", static_cast<unsigned long long>(avr_->cycle * 125 / 2),
               signal.line.name, signal.level);
}

void Recorder::Record(Signal* s, int level) {
  if (!s->started || level == s->level) return;
  s->level = level;
  Write(*s);
  if (s->line.step && level == 1 && in_tick_) stepped_ = true;
}

bool Recorder::ServoTimerConnected() const {
  return (avr_->data[board_.servo_timer.tccra] & board_.servo_timer.connect_mask) != 0;
}

void Recorder::OnPin(avr_irq_t*, std::uint32_t value, void* param) {
  auto* s = static_cast<Signal*>(param);
  // A timer-driven pin follows its timer while connected (OnServoTimer).
  if (s->timer_driven && s->recorder->ServoTimerConnected()) return;
  s->recorder->Record(s, (value & 1u) != 0 ? 1 : 0);
}

// The output compare's level as the timer sets and clears it (at BOTTOM
// and at the match in fast PWM); simavr raises it only while connected.
void Recorder::OnServoTimer(avr_irq_t*, std::uint32_t value, void* param) {
  auto* s = static_cast<Signal*>(param);
  if (!s->recorder->ServoTimerConnected()) return;
  s->recorder->Record(s, (value & 1u) != 0 ? 1 : 0);
}

// A line enters the waveform when the firmware makes it an output, with the
// level its PORT bit drives.
void Recorder::OnDirection(avr_irq_t*, std::uint32_t value, void* param) {
  auto* s = static_cast<Signal*>(param);
  if (s->started || (value & (1u << s->line.pin.bit)) == 0) return;
  s->started = true;
  s->level = (s->recorder->avr_->data[s->line.pin.out] >> s->line.pin.bit) & 1;
  s->recorder->Write(*s);
}

std::uint64_t Recorder::TickPeriod() const {
  static const std::uint16_t kPrescale[8] = {0, 1, 8, 64, 256, 1024, 0, 0};
  const std::uint16_t prescale = kPrescale[avr_->data[board_.tick_tccrb] & 7u];
  const std::uint16_t top = static_cast<std::uint16_t>(avr_->data[board_.tick_ocra] |
                                                       (avr_->data[board_.tick_ocra + 1] << 8));
  return static_cast<std::uint64_t>(top + 1u) * prescale;
}

void Recorder::OnTickPending(avr_irq_t*, std::uint32_t value, void* param) {
  auto* r = static_cast<Recorder*>(param);
  if (value == 0) return;
  const std::uint64_t now = r->avr_->cycle;
  const std::uint64_t period = r->TickPeriod();
  // A compare match while the flag was still set raises nothing: the gap
  // between two matches shows it.
  if (r->last_pending_ != 0 && period != 0 && now - r->last_pending_ > period + period / 2) {
    r->lost_ticks_ += (now - r->last_pending_ + period / 2) / period - 1;
  }
  r->last_pending_ = now;
  r->pending_at_ = now;
}

void Recorder::OnTickRunning(avr_irq_t*, std::uint32_t value, void* param) {
  auto* r = static_cast<Recorder*>(param);
  const std::uint64_t now = r->avr_->cycle;
  if (value != 0) {
    r->running_at_ = now;
    r->in_tick_ = true;
    r->stepped_ = false;
    const std::uint64_t latency = now - r->pending_at_;
    r->latency_.Add(latency, r->pending_at_);
    if (latency >= r->TickPeriod()) ++r->late_ticks_;
    return;
  }
  if (!r->in_tick_) return;
  r->in_tick_ = false;
  const std::uint64_t cycles = now - r->running_at_;
  r->tick_.Add(cycles, r->running_at_);
  r->now_.isr += cycles;
  if (!r->stepped_) return;
  r->stepping_tick_.Add(cycles, r->running_at_);
  ++r->now_.points;
  r->now_.cycle = now;
  if (!r->drawing_) r->first_step_ = r->now_;
  r->drawing_ = true;
  r->last_step_ = r->now_;
}

void Recorder::OnRxRunning(avr_irq_t*, std::uint32_t value, void* param) {
  auto* r = static_cast<Recorder*>(param);
  if (value != 0) {
    r->rx_at_ = r->avr_->cycle;
    return;
  }
  const std::uint64_t cycles = r->avr_->cycle - r->rx_at_;
  r->rx_.Add(cycles, r->rx_at_);
  r->now_.isr += cycles;
}

void Recorder::OnUartIn(avr_irq_t*, std::uint32_t, void* param) {
  ++static_cast<Recorder*>(param)->now_.bytes_in;
}

// simavr's raw core: a sleeping core skips to its next timer event and
// adds 1 + `cycles` to avr->cycle. No real-time sleeping here: the harness
// paces itself.
void Recorder::OnSleep(avr_t*, avr_cycle_count_t cycles) {
  if (g_recorder != nullptr) g_recorder->now_.sleep += cycles + 1;
}

void Recorder::Finish(avr_t*) {
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
  }
}

std::uint32_t Recorder::StackHighWater(avr_t* avr, const ImageFacts& facts) const {
  const std::uint16_t heap_start =
      static_cast<std::uint16_t>(board_.ram_start + facts.data + facts.bss);
  std::uint16_t p = heap_start;
  while (p <= board_.ram_end && avr->data[p] == kStackPaint) ++p;
  return static_cast<std::uint32_t>(board_.ram_end - p + 1);
}

namespace {

// The USART's bit rate the firmware set (UBRRn, U2Xn), 10 bits a byte (8N1).
double UartBytesPerSecond(const avr_t* avr, const AvrBoard& board) {
  const unsigned ubrr = avr->data[board.ubrr] | ((avr->data[board.ubrr + 1] & 0x0Fu) << 8);
  const bool u2x = (avr->data[board.ucsra] & 0x02u) != 0;
  return 16e6 / ((u2x ? 8.0 : 16.0) * (ubrr + 1)) / 10.0;
}

void Row(std::FILE* f, const char* name, double value, const char* unit) {
  std::fprintf(f, "%s\t%.6g\t%s\n", name, value, unit);
}

void Stats(std::FILE* f, const char* name, const CycleStats& s) {
  const std::string n = name;
  Row(f, (n + "_count").c_str(), static_cast<double>(s.count), "interrupts");
  Row(f, (n + "_cycles_min").c_str(), s.count == 0 ? 0.0 : static_cast<double>(s.min), "cycles");
  Row(f, (n + "_cycles_mean").c_str(), s.Mean(), "cycles");
  Row(f, (n + "_cycles_max").c_str(), static_cast<double>(s.max), "cycles");
  Row(f, (n + "_max_at").c_str(), static_cast<double>(s.max_at) / 16e6, "s");
}

}  // namespace

bool Recorder::WriteMeasures(const std::string& path, avr_t* avr, const ImageFacts& facts,
                             std::uint64_t bridge_in, std::uint64_t bridge_out,
                             std::string* error) const {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    *error = path + ": " + std::strerror(errno);
    return false;
  }
  const std::uint64_t period = TickPeriod();
  const std::uint32_t stack = StackHighWater(avr, facts);
  std::fputs("measure\tvalue\tunit\n", f);
  Row(f, "flash", facts.flash, "bytes");
  Row(f, "static_ram", facts.data + facts.bss, "bytes");
  Row(f, "stack_high_water", stack, "bytes");
  Row(f, "ram_never_used", static_cast<double>(board_.RamBytes()) - facts.data - facts.bss - stack,
      "bytes");
  Row(f, "tick_hz", period == 0 ? 0.0 : 16e6 / static_cast<double>(period), "Hz");
  Row(f, "tick_period", static_cast<double>(period), "cycles");
  Stats(f, "tick_isr", tick_);
  Stats(f, "stepping_tick_isr", stepping_tick_);
  Row(f, "tick_latency_cycles_max", static_cast<double>(latency_.max), "cycles");
  Row(f, "tick_latency_max_at", static_cast<double>(latency_.max_at) / 16e6, "s");
  Row(f, "late_ticks", static_cast<double>(late_ticks_), "ticks");
  Row(f, "lost_ticks", static_cast<double>(lost_ticks_), "ticks");
  Stats(f, "rx_isr", rx_);
  if (board_.rx_overruns != 0) {
    Row(f, "rx_overruns", avr->data[board_.rx_overruns],
        "bytes lost to a full ring (255: or more)");
  }
  const Accumulated& a = first_step_;
  const Accumulated& b = last_step_;
  const double window = static_cast<double>(b.cycle - a.cycle);
  const double points = static_cast<double>(b.points - a.points);
  const double main_loop =
      window - static_cast<double>(b.sleep - a.sleep) - static_cast<double>(b.isr - a.isr);
  Row(f, "drawing_time", window / 16e6, "s");
  Row(f, "points", static_cast<double>(b.points), "ticks that step");
  Row(f, "main_loop_cycles_per_point", points > 0 ? main_loop / points : 0.0, "cycles");
  Row(f, "isr_cycles_per_point", points > 0 ? static_cast<double>(b.isr - a.isr) / points : 0.0,
      "cycles");
  Row(f, "asleep_while_drawing", window > 0 ? static_cast<double>(b.sleep - a.sleep) / window : 0,
      "fraction");
  Row(f, "link_bytes_in_per_s_drawing",
      window > 0 ? static_cast<double>(b.bytes_in - a.bytes_in) / (window / 16e6) : 0.0, "bytes/s");
  Row(f, "uart_capacity", UartBytesPerSecond(avr, board_), "bytes/s each way");
  Row(f, "uart_bytes_in", static_cast<double>(bridge_in), "bytes");
  Row(f, "uart_bytes_out", static_cast<double>(bridge_out), "bytes");
  Row(f, "boots", static_cast<double>(boots_), "starts");
  Row(f, "watchdog_resets", static_cast<double>(watchdog_resets_), "resets");
  Row(f, "emulated_time", static_cast<double>(avr->cycle) / 16e6, "s");
  std::fclose(f);
  return true;
}

}  // namespace fdsurf::board
