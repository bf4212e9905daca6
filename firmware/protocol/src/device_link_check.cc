// SPDX-License-Identifier: MIT
// Instantiates DeviceLink under the core's freestanding flags with a minimal
// sink, so the header-only link is compiled (and held to the same rules) in
// every build of the core.
#include "fdsurf/config/nodiscard.h"
#include "fdsurf/protocol/device_link.h"

namespace fdsurf {
namespace protocol {
namespace {

struct NullSink {
  ErrorCode Accept(const Command& /*command*/, uint8_t* /*detail*/) { return ErrorCode::kNone; }
  FDSURF_NODISCARD uint8_t Credits() const { return 1; }
  FDSURF_NODISCARD uint8_t QueueCapacity() const { return 1; }
  FDSURF_NODISCARD uint8_t Features() const { return 0; }
  FDSURF_NODISCARD uint32_t TickHz() const { return 1; }
  FDSURF_NODISCARD uint8_t MaxAxes() const { return 2; }
  void FillStatus(StatusReport* /*report*/) const {}
  void Stop() {}
  void Pause() {}
  void Resume() {}
  void Halt() {}
  void Reset() {}
};

}  // namespace

template class DeviceLink<NullSink>;

}  // namespace protocol
}  // namespace fdsurf
