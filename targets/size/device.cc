// SPDX-License-Identifier: MIT
// Size group "device": the whole plotter firmware as an MCU build links it:
// the engine (set-up, isoline walker, step-exact adaptive stepping), the wire
// protocol (COBS/CRC-32 framing, the codec, DeviceLink), the command queue,
// the path generator and the motion loop, in fdsurf::device::Device<2, 4, 256>
// (2 axes, 4 queued commands, a 256-entry lookahead), driven through the HAL
// interfaces by a main loop. The device object is static, so its RAM shows
// in .bss; the stack its set-up needs does not.
#include "fdsurf/device/device.h"
#include "../image/image.h"

// A pure virtual function is never called here (every HAL class below
// overrides all of them); the abstract bases' vtables still name it.
extern "C" void __cxa_pure_virtual() {
  for (;;) {
  }
}

namespace fdsurf {
namespace image {
namespace {

// Memory-mapped stand-ins for a UART and GPIO ports, so that nothing is
// optimised away.
volatile uint8_t g_uart;
volatile uint8_t g_pins;
volatile uint16_t g_ticks = 100;

class UartTransport final : public hal::Transport {
 public:
  UartTransport() = default;
  ~UartTransport() = default;

 private:
  hal::IoStatus DoWrite(const uint8_t* data, size_t size, uint32_t) override {
    for (size_t i = 0; i < size; ++i) g_uart = data[i];
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoRead(uint8_t* data, size_t capacity, size_t* received, uint32_t) override {
    *received = 0;
    if (capacity == 0 || g_uart == 0) return hal::IoStatus::kTimeout;
    data[0] = g_uart;
    *received = 1;
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoReconnect(uint32_t) override { return hal::IoStatus::kOk; }
  const char* DoLastError() const override { return ""; }
};

class PortOutputs final : public hal::StepDirOutputs, public hal::PenOutput {
 public:
  PortOutputs() : hal::StepDirOutputs(2) {}
  ~PortOutputs() = default;

 private:
  hal::IoStatus DoSetEnabled(bool enabled) override {
    g_pins = enabled ? 0x80 : 0;
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetDirections(uint8_t negative_mask) override {
    g_pins = static_cast<uint8_t>(negative_mask << 2);
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoStep(uint8_t axis_mask) override {
    g_pins = axis_mask;
    g_pins = 0;
    return hal::IoStatus::kOk;
  }
  hal::IoStatus DoSetPen(bool down) override {
    g_pins = down ? 0x40 : 0;
    return hal::IoStatus::kOk;
  }
  const char* DoLastError() const override { return ""; }
};

#ifndef FDSURF_SIZE_DEVICE_FRAME_BYTES
#define FDSURF_SIZE_DEVICE_FRAME_BYTES protocol::kMaxFrameBytes
#endif
#ifndef FDSURF_SIZE_DEVICE_QUEUE
#define FDSURF_SIZE_DEVICE_QUEUE 4
#endif
#ifndef FDSURF_SIZE_DEVICE_LOOKAHEAD
#define FDSURF_SIZE_DEVICE_LOOKAHEAD 256
#endif
#ifndef FDSURF_SIZE_DEVICE_REPLY_BYTES
#define FDSURF_SIZE_DEVICE_REPLY_BYTES 256
#endif
device::Device<2, FDSURF_SIZE_DEVICE_QUEUE, FDSURF_SIZE_DEVICE_LOOKAHEAD, device::SingleThreadLock,
               FDSURF_SIZE_DEVICE_FRAME_BYTES, FDSURF_SIZE_DEVICE_REPLY_BYTES>
    g_device(40000);
UartTransport g_transport;
PortOutputs g_outputs;

}  // namespace

int RunImage(bool) {
  for (uint16_t i = 0; i < g_ticks; ++i) {
    // The size image links the device code and does not act on results: the
    // UART and port outputs here never fail, and a failure would fault the
    // device itself (kFault in its status report).
    (void)g_device.Service(g_transport);
    g_device.Fill();
    (void)g_device.Tick(g_outputs, g_outputs);
  }
  return 0;
}

}  // namespace image
}  // namespace fdsurf
