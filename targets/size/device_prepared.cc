// SPDX-License-Identifier: MIT
// Size group "device_prepared": the whole plotter firmware of size/device.cc
// (Device<2, 4, 256>, the same main loop and HAL stand-ins), linked with the
// core built without the device's planner (FDSURF_DEVICE_PLANNER=0,
// fdsurf/protocol/messages.h): it takes PREPARED_CURVE, MOVE, PEN, HOME and
// MOTORS, and refuses PATCH and CURVE. The difference from "device" is what
// the planner costs; what is left is what a small chip must hold (issue 17,
// the Arduino Uno).
#include "device.cc"
