// SPDX-License-Identifier: MIT
#include "fdsurf/hal/io_status.h"

namespace fdsurf {
namespace hal {

const char* IoStatusName(IoStatus status) {
  switch (status) {
    case IoStatus::kOk:
      return "ok";
    case IoStatus::kTimeout:
      return "timeout";
    case IoStatus::kDisconnected:
      return "disconnected";
    case IoStatus::kNotFound:
      return "not found";
    case IoStatus::kBusy:
      return "busy";
    case IoStatus::kPermissionDenied:
      return "permission denied";
    case IoStatus::kInvalidArgument:
      return "invalid argument";
    case IoStatus::kIoError:
      return "I/O error";
  }
  return "unknown status";
}

}  // namespace hal
}  // namespace fdsurf
