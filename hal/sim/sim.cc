// SPDX-License-Identifier: MIT
#include "fdsurf/hal/sim.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace fdsurf {
namespace hal {

// ---------------------------------------------------------------- step/dir

SimStepDir::SimStepDir(SimClock& clock, uint8_t axes) : StepDirOutputs(axes), clock_(clock) {}

IoStatus SimStepDir::Check(uint8_t mask, const char* what) {
  if (axes() != 2 && axes() != 3) {
    last_error_ = "sim step/dir: " + std::to_string(axes()) + " axes (2 or 3 supported)";
    return IoStatus::kInvalidArgument;
  }
  if (injected_ != IoStatus::kOk) {
    const IoStatus status = injected_;
    injected_ = IoStatus::kOk;
    last_error_ = std::string("sim step/dir: injected ") + IoStatusName(status);
    return status;
  }
  if ((mask & ~axis_bits()) != 0) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", mask);
    last_error_ = std::string("sim step/dir: ") + what + " mask " + hex + " has bits beyond " +
                  std::to_string(axes()) + " axes";
    return IoStatus::kInvalidArgument;
  }
  return IoStatus::kOk;
}

IoStatus SimStepDir::DoSetEnabled(bool enabled) {
  if (const IoStatus status = Check(0, "enable"); status != IoStatus::kOk) return status;
  if (enabled != enabled_) {
    enabled_ = enabled;
    events_.push_back({clock_.now_us(), 0, negative_mask_, enabled_});
  }
  return IoStatus::kOk;
}

IoStatus SimStepDir::DoSetDirections(uint8_t negative_mask) {
  if (const IoStatus status = Check(negative_mask, "direction"); status != IoStatus::kOk) {
    return status;
  }
  if (negative_mask != negative_mask_) {
    negative_mask_ = negative_mask;
    events_.push_back({clock_.now_us(), 0, negative_mask_, enabled_});
  }
  return IoStatus::kOk;
}

IoStatus SimStepDir::DoStep(uint8_t axis_mask) {
  if (const IoStatus status = Check(axis_mask, "step"); status != IoStatus::kOk) return status;
  if (axis_mask == 0) return IoStatus::kOk;
  for (int axis = 0; axis < axes(); ++axis) {
    if ((axis_mask >> axis & 1) != 0) position_[axis] += (negative_mask_ >> axis & 1) != 0 ? -1 : 1;
  }
  events_.push_back({clock_.now_us(), axis_mask, negative_mask_, enabled_});
  return IoStatus::kOk;
}

// ---------------------------------------------------------------- pen

IoStatus SimPen::DoSetPen(bool down) {
  if (injected_ != IoStatus::kOk) {
    const IoStatus status = injected_;
    injected_ = IoStatus::kOk;
    last_error_ = std::string("sim pen: injected ") + IoStatusName(status);
    return status;
  }
  if (down != down_) {
    down_ = down;
    events_.push_back({clock_.now_us(), down_});
  }
  return IoStatus::kOk;
}

// ---------------------------------------------------------------- pwm

IoStatus SimPwm::Injected() {
  const IoStatus status = injected_;
  injected_ = IoStatus::kOk;
  if (status != IoStatus::kOk)
    last_error_ = std::string("sim pwm: injected ") + IoStatusName(status);
  return status;
}

void SimPwm::Record(uint32_t period_us, uint32_t pulse_us, bool enabled) {
  if (period_us == period_us_ && pulse_us == pulse_us_ && enabled == enabled_) return;
  period_us_ = period_us;
  pulse_us_ = pulse_us;
  enabled_ = enabled;
  events_.push_back({clock_.now_us(), period_us_, pulse_us_, enabled_});
}

IoStatus SimPwm::DoSetPeriodMicros(uint32_t period_us) {
  if (const IoStatus status = Injected(); status != IoStatus::kOk) return status;
  if (period_us == 0 || period_us > max_period_us_ || period_us < pulse_us_) {
    last_error_ = "sim pwm: period " + std::to_string(period_us) + " us refused (1.." +
                  std::to_string(max_period_us_) + ", not below the pulse of " +
                  std::to_string(pulse_us_) + " us)";
    return IoStatus::kInvalidArgument;
  }
  Record(period_us, pulse_us_, enabled_);
  return IoStatus::kOk;
}

IoStatus SimPwm::DoSetPulseMicros(uint32_t pulse_us) {
  if (const IoStatus status = Injected(); status != IoStatus::kOk) return status;
  if (pulse_us > period_us_) {
    last_error_ = "sim pwm: pulse " + std::to_string(pulse_us) + " us is longer than the period (" +
                  std::to_string(period_us_) + " us)";
    return IoStatus::kInvalidArgument;
  }
  Record(period_us_, pulse_us, enabled_);
  return IoStatus::kOk;
}

IoStatus SimPwm::DoSetEnabled(bool enabled) {
  if (const IoStatus status = Injected(); status != IoStatus::kOk) return status;
  Record(period_us_, pulse_us_, enabled);
  return IoStatus::kOk;
}

// ---------------------------------------------------------------- transport pair

SimTransportPair::SimTransportPair(SimClock& clock, const SimLinkOptions& options)
    : clock_(clock),
      options_(options),
      host_(*this, "host", to_device_, to_host_),
      device_(*this, "device", to_host_, to_device_) {}

void SimTransportPair::UpdatePlug() {
  if (!connected_ && replug_scheduled_ && clock_.now_us() >= replug_at_us_) {
    connected_ = true;
    replug_scheduled_ = false;
  }
}

bool SimTransportPair::connected() {
  UpdatePlug();
  return connected_;
}

void SimTransportPair::Disconnect() {
  connected_ = false;
  replug_scheduled_ = false;
  ++generation_;  // both ends must Reconnect() once the link is back
  for (Direction* direction : {&to_device_, &to_host_}) {
    direction->chunks.clear();
    direction->in_flight = 0;
    direction->busy_until_us = 0;
  }
}

void SimTransportPair::PlugIn() {
  connected_ = true;
  replug_scheduled_ = false;
}

void SimTransportPair::PlugInAt(uint64_t t_us) {
  if (connected_) return;
  replug_scheduled_ = true;
  replug_at_us_ = t_us;
  UpdatePlug();
}

IoStatus SimTransportPair::Endpoint::Fail(IoStatus status, const std::string& detail) {
  last_error_ = std::string("sim link (") + name_ + " end): " + detail;
  return status;
}

bool SimTransportPair::Endpoint::Usable() {
  return pair_.connected() && generation_ == pair_.generation_;
}

IoStatus SimTransportPair::Endpoint::DoWrite(const uint8_t* data, size_t size,
                                             uint32_t /*timeout_ms*/) {
  if (data == nullptr && size > 0) return Fail(IoStatus::kInvalidArgument, "null data");
  if (!Usable()) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  if (size == 0) return IoStatus::kOk;
  const SimLinkOptions& options = pair_.options_;
  if (options.max_in_flight != 0 && out_.in_flight + size > options.max_in_flight) {
    return Fail(IoStatus::kTimeout, std::to_string(size) +
                                        " bytes do not fit: " + std::to_string(out_.in_flight) +
                                        " of " + std::to_string(options.max_in_flight) +
                                        " bytes in flight (the other end is not reading)");
  }
  const uint64_t start_us = std::max(pair_.clock_.now_us(), out_.busy_until_us);
  uint64_t duration_us = 0;
  if (options.bytes_per_second != 0) {
    duration_us = (static_cast<uint64_t>(size) * 1000000u + options.bytes_per_second - 1) /
                  options.bytes_per_second;
  }
  out_.busy_until_us = start_us + duration_us;
  out_.chunks.push_back(
      {out_.busy_until_us + options.latency_us, std::vector<uint8_t>(data, data + size), 0});
  out_.in_flight += size;
  return IoStatus::kOk;
}

IoStatus SimTransportPair::Endpoint::DoRead(uint8_t* data, size_t capacity, size_t* received,
                                            uint32_t /*timeout_ms*/) {
  if (received != nullptr) *received = 0;
  if (data == nullptr || received == nullptr || capacity == 0) {
    return Fail(IoStatus::kInvalidArgument, "null buffer or zero capacity");
  }
  if (!Usable()) return Fail(IoStatus::kDisconnected, "disconnected; call Reconnect()");
  const uint64_t now_us = pair_.clock_.now_us();
  size_t count = 0;
  while (count < capacity && !in_.chunks.empty() && in_.chunks.front().ready_us <= now_us) {
    Chunk& chunk = in_.chunks.front();
    const size_t take = std::min(capacity - count, chunk.bytes.size() - chunk.offset);
    std::copy_n(chunk.bytes.begin() + static_cast<ptrdiff_t>(chunk.offset), take, data + count);
    chunk.offset += take;
    count += take;
    if (chunk.offset == chunk.bytes.size()) in_.chunks.pop_front();
  }
  in_.in_flight -= count;
  *received = count;
  if (count == 0) {
    if (in_.chunks.empty()) return Fail(IoStatus::kTimeout, "nothing to read");
    return Fail(IoStatus::kTimeout,
                "nothing to read until t = " + std::to_string(in_.chunks.front().ready_us) + " us");
  }
  return IoStatus::kOk;
}

IoStatus SimTransportPair::Endpoint::DoReconnect(uint32_t timeout_ms) {
  SimTransportPair& pair = pair_;
  if (!pair.connected()) {
    const uint64_t deadline_us = pair.clock_.now_us() + uint64_t{timeout_ms} * 1000u;
    if (!pair.replug_scheduled_ || pair.replug_at_us_ > deadline_us) {
      pair.clock_.Set(deadline_us);
      return Fail(IoStatus::kTimeout,
                  "not plugged back within " + std::to_string(timeout_ms) + " ms");
    }
    pair.clock_.Set(pair.replug_at_us_);
    pair.UpdatePlug();
  }
  generation_ = pair.generation_;
  return IoStatus::kOk;
}

}  // namespace hal
}  // namespace fdsurf
