// SPDX-License-Identifier: MIT
// Size group "device_uno": the firmware of size/device_prepared.cc (no
// planner, 64-bit tables only, small frames) sized as the Arduino Uno would
// hold it (issue 17): Device<2, 2, 64>, 2 queued commands, a 64-entry
// lookahead and 96 bytes of replies. On the ATmega328P the image is linked
// even when it does not fit (--noinhibit-exec), so that the report says by
// how much.
#define FDSURF_SIZE_DEVICE_QUEUE 2
#define FDSURF_SIZE_DEVICE_LOOKAHEAD 64
#define FDSURF_SIZE_DEVICE_REPLY_BYTES 96
#include "device_prepared.cc"
