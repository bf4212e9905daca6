// SPDX-License-Identifier: MIT
#include "fdsurf/status.h"

namespace fdsurf {

const char* StatusMessage(Status status) {
  switch (status) {
    case Status::kOk:
      return "ok";
    case Status::kInvalidArgument:
      return "invalid argument";
    case Status::kGridOutOfRange:
      return "grid out of range";
    case Status::kGeometryOutOfRange:
      return "geometry out of range";
    case Status::kPrecisionUnreachable:
      return "precision unreachable";
    case Status::kToleranceUnreachable:
      return "tolerance below what whole-quantum output can meet";
  }
  return "unknown status";
}

}  // namespace fdsurf
