// SPDX-License-Identifier: MIT
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "../cli_options.h"
#include "fdsurf/hal/usb_transport.h"
#include "runner.h"
#include "transport_loop.h"
#include "usb_session.h"

namespace fdsurf::host {

UsbSession OpenUsbSession(const StreamOptions& o) {
  hal::UsbSelector selector;
  std::string error;
  if (!hal::ParseUsbDevice(o.device, &selector, &error)) throw InputError("--device: " + error);
  UsbSession session;
  if (hal::UsbTransport::Open(selector, hal::UsbOptions{}, &session.usb, &error) !=
      hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  session.name = "usb " + selector.ToString();
  TransportLoopOptions options;
  options.device = session.name;
  options.connect_timeout_ms = Milliseconds(o.connect_timeout_s);
  options.reconnect_timeout_ms = Milliseconds(o.reconnect_timeout_s);
  options.quiet = o.quiet;
  options.no_pause = o.no_pause;
  session.loop = std::make_unique<TransportLoop>(*session.usb, options);
  return session;
}

// A real-time loop against a USB controller (transport_loop.h): the host
// link over bulk transfers, reconnecting and resuming after an unplug, a
// pause for the pen change between layers, STOP on Ctrl-C.
int RunUsb(const StreamOptions& o, const StreamJob& job) {
  UsbSession session = OpenUsbSession(o);
  const InterruptGuard interrupts;
  TransportLoop& loop = *session.loop;
  std::optional<std::uint32_t> old_executed;
  if (o.resume_state) old_executed = loop.FinishOldSession(o.resume_state->session);
  if (!loop.Connect()) return 130;
  const StreamJob fitted = FitJobToDevice(job, *loop.link().hello(), session.name, o);
  std::optional<JobJournal> journal;
  const StreamJob to_run = JobWithJournal(o, job, fitted, old_executed, &loop, &journal);
  ProgressLine progress(ShowProgress(o.quiet));
  progress.SetSchedule(o.resume_state ? nullptr : o.schedule.get());
  const int code = RunKeepingJournal(&loop, to_run, &progress, &journal);
  if (code != 0 || o.quiet) return code;
  std::fprintf(stderr, "%s: %s drawn by %s; %llu frames sent (%llu resent)\n", o.file.c_str(),
               JobContents(job).c_str(), session.name.c_str(),
               static_cast<unsigned long long>(loop.link().stats().frames_sent),
               static_cast<unsigned long long>(loop.link().stats().retransmitted));
  return 0;
}

}  // namespace fdsurf::host
