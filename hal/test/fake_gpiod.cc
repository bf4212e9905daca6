// SPDX-License-Identifier: MIT
#include "fake_gpiod.h"

#include <gpiod.h>

#include <cerrno>
#include <string>

#include "fdsurf/hal/monotonic_clock.h"

namespace fdsurf::hal::testing {

FakeGpio* g_fake_gpio = nullptr;

FakeGpioChip& FakeGpio::AddChip(const std::string& descriptor, unsigned count) {
  FakeGpioChip& chip = chips[descriptor];
  chip.lines.resize(count);
  for (unsigned i = 0; i < count; ++i) chip.lines[i].offset = i;
  return chip;
}

namespace {

FakeGpioChip* Chip(gpiod_chip* chip) { return reinterpret_cast<FakeGpioChip*>(chip); }
FakeGpioLine* Line(gpiod_line* line) { return reinterpret_cast<FakeGpioLine*>(line); }

}  // namespace
}  // namespace fdsurf::hal::testing

using fdsurf::hal::testing::Chip;
using fdsurf::hal::testing::g_fake_gpio;
using fdsurf::hal::testing::Line;

extern "C" {

gpiod_chip* __wrap_gpiod_chip_open_lookup(const char* descr) {
  g_fake_gpio->log.push_back(std::string("lookup ") + descr);
  auto it = g_fake_gpio->chips.find(descr);
  if (it == g_fake_gpio->chips.end()) {
    errno = g_fake_gpio->missing_errno;
    return nullptr;
  }
  it->second.open = true;
  return reinterpret_cast<gpiod_chip*>(&it->second);
}

void __wrap_gpiod_chip_close(gpiod_chip* chip) {
  g_fake_gpio->log.emplace_back("close");
  Chip(chip)->open = false;
}

unsigned int __wrap_gpiod_chip_num_lines(gpiod_chip* chip) {
  return static_cast<unsigned>(Chip(chip)->lines.size());
}

gpiod_line* __wrap_gpiod_chip_get_line(gpiod_chip* chip, unsigned int offset) {
  if (offset >= Chip(chip)->lines.size()) {
    errno = EINVAL;
    return nullptr;
  }
  return reinterpret_cast<gpiod_line*>(&Chip(chip)->lines[offset]);
}

bool __wrap_gpiod_line_is_used(gpiod_line* line) { return Line(line)->used; }

const char* __wrap_gpiod_line_consumer(gpiod_line* line) {
  return Line(line)->consumer.empty() ? nullptr : Line(line)->consumer.c_str();
}

int __wrap_gpiod_line_request_output(gpiod_line* line, const char* consumer, int default_val) {
  if (Line(line)->request_errno != 0) {
    errno = Line(line)->request_errno;
    return -1;
  }
  g_fake_gpio->log.push_back("request " + std::to_string(Line(line)->offset) + " " + consumer +
                             " " + std::to_string(default_val));
  Line(line)->requested = true;
  Line(line)->request = g_fake_gpio->next_request++;
  Line(line)->value = default_val;
  return 0;
}

int __wrap_gpiod_line_request_bulk_output(gpiod_line_bulk* bulk, const char* consumer,
                                          const int* default_vals) {
  std::string offsets;
  std::string values;
  for (unsigned i = 0; i < bulk->num_lines; ++i) {
    if (Line(bulk->lines[i])->request_errno != 0) {
      errno = Line(bulk->lines[i])->request_errno;
      return -1;  // the kernel grants all lines of one request or none
    }
    offsets += (i > 0 ? "," : "") + std::to_string(Line(bulk->lines[i])->offset);
    values += (i > 0 ? "," : "") + std::to_string(default_vals[i]);
  }
  g_fake_gpio->log.push_back("request " + offsets + " " + consumer + " " + values);
  const int request = g_fake_gpio->next_request++;
  for (unsigned i = 0; i < bulk->num_lines; ++i) {
    Line(bulk->lines[i])->requested = true;
    Line(bulk->lines[i])->request = request;
    Line(bulk->lines[i])->value = default_vals[i];
  }
  return 0;
}

// Like libgpiod 1.6: one ioctl on the first line's request, so every line
// must belong to that same request (else EINVAL here; libgpiod refuses too).
int __wrap_gpiod_line_set_value_bulk(gpiod_line_bulk* bulk, const int* values) {
  std::string entry = "set ";
  int fail_errno = 0;
  for (unsigned i = 0; i < bulk->num_lines; ++i) {
    const auto* line = Line(bulk->lines[i]);
    entry += (i > 0 ? "," : "") + std::to_string(line->offset) + "=" + std::to_string(values[i]);
    if (line->set_errno != 0 && (line->set_fails_for < 0 || line->set_fails_for == values[i])) {
      fail_errno = line->set_errno;
    }
    if (!line->requested || line->request != Line(bulk->lines[0])->request) fail_errno = EINVAL;
  }
  g_fake_gpio->log.push_back(entry + (fail_errno != 0 ? " (fails)" : ""));
  g_fake_gpio->set_times_us.push_back(fdsurf::hal::MonotonicClock::Now());
  if (fail_errno != 0) {
    errno = fail_errno;
    return -1;
  }
  for (unsigned i = 0; i < bulk->num_lines; ++i) Line(bulk->lines[i])->value = values[i];
  for (unsigned i = 0; i < bulk->num_lines && g_fake_gpio->on_set; ++i) {
    g_fake_gpio->on_set(Line(bulk->lines[i])->offset, values[i]);
  }
  return 0;
}

int __wrap_gpiod_line_set_value(gpiod_line* line, int value) {
  const bool fails = Line(line)->set_errno != 0 &&
                     (Line(line)->set_fails_for < 0 || Line(line)->set_fails_for == value);
  g_fake_gpio->log.push_back("set " + std::to_string(Line(line)->offset) + "=" +
                             std::to_string(value) + (fails ? " (fails)" : ""));
  g_fake_gpio->set_times_us.push_back(fdsurf::hal::MonotonicClock::Now());
  if (!Line(line)->requested) {
    errno = EPERM;
    return -1;
  }
  if (fails) {
    errno = Line(line)->set_errno;
    return -1;
  }
  Line(line)->value = value;
  if (g_fake_gpio->on_set) g_fake_gpio->on_set(Line(line)->offset, value);
  return 0;
}

int __wrap_gpiod_line_request_input(gpiod_line* line, const char* consumer) {
  if (Line(line)->request_errno != 0) {
    errno = Line(line)->request_errno;
    return -1;
  }
  g_fake_gpio->log.push_back("input " + std::to_string(Line(line)->offset) + " " + consumer);
  Line(line)->requested = true;
  Line(line)->input = true;
  if (Line(line)->value < 0) Line(line)->value = 0;
  return 0;
}

int __wrap_gpiod_line_get_value(gpiod_line* line) {
  if (!Line(line)->requested) {
    errno = EPERM;
    return -1;
  }
  if (Line(line)->get_errno != 0) {
    errno = Line(line)->get_errno;
    return -1;
  }
  return Line(line)->value;
}

void __wrap_gpiod_line_release(gpiod_line* line) {
  g_fake_gpio->log.push_back("release " + std::to_string(Line(line)->offset));
  Line(line)->requested = false;
  Line(line)->request = 0;
}

}  // extern "C"
