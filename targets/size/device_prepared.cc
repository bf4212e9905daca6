// SPDX-License-Identifier: MIT
// Size group "device_prepared": the whole plotter firmware of size/device.cc
// (Device<2, 4, 256>, the same main loop and HAL stand-ins), linked with the
// core built without the device's planner (FDSURF_DEVICE_PLANNER=0,
// fdsurf/protocol/messages.h): it takes PREPARED_CURVE, MOVE, PEN, HOME and
// MOTORS, and drops a PATCH or CURVE frame as overlong. The difference from "device" is what
// the planner costs; what is left is what a small chip must hold (issue 17,
// the Arduino Uno). Its frame buffer holds the largest of the commands it
// takes (protocol::kMaxPreparedFrameBytes), not a PATCH.
#define FDSURF_SIZE_DEVICE_FRAME_BYTES protocol::kMaxPreparedFrameBytes
#include "device.cc"
