// SPDX-License-Identifier: MIT
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "../cli_options.h"
#include "fdsurf/hal/monotonic_clock.h"
#include "fdsurf/hal/usb_transport.h"
#include "runner.h"

namespace fdsurf::host {

// A real-time loop against a USB controller: the host link over bulk
// transfers, reconnecting and resuming after an unplug.
int RunUsb(const StreamOptions& o, const StreamJob& job) {
  hal::UsbSelector selector;
  std::string error;
  if (!hal::ParseUsbDevice(o.device, &selector, &error)) throw InputError("--device: " + error);
  std::unique_ptr<hal::UsbTransport> usb;
  if (hal::UsbTransport::Open(selector, hal::UsbOptions{}, &usb, &error) != hal::IoStatus::kOk) {
    throw DeviceError(error);
  }
  HostLink link(LinkOptions());
  Enqueue(job, &link);
  ProgressLine progress(ShowProgress(o.quiet));
  std::vector<std::uint8_t> out;
  std::uint8_t in[512];
  std::uint64_t last_progress = 0;
  while (!link.Finished() && !link.Failed()) {
    const std::uint64_t now = hal::MonotonicClock::Now();
    std::size_t got = 0;
    hal::IoStatus status = usb->Read(in, sizeof in, &got, 2);
    if (status == hal::IoStatus::kOk) link.OnBytes(in, got, now);
    out.clear();
    link.Poll(now, &out);
    if (status != hal::IoStatus::kDisconnected && !out.empty()) {
      status = usb->Write(out.data(), out.size(), 1000);
    }
    if (status == hal::IoStatus::kDisconnected) {
      if (!o.quiet)
        std::fprintf(stderr, "\nfdsurf: %s; waiting for it to come back\n", usb->LastError());
      if (usb->Reconnect(30'000) != hal::IoStatus::kOk) {
        throw DeviceError(std::string(usb->LastError()) + "; gave up after 30 s");
      }
      link.Resume();
    } else if (status != hal::IoStatus::kOk && status != hal::IoStatus::kTimeout) {
      throw DeviceError(usb->LastError());
    }
    if (now - last_progress > 250'000) {
      last_progress = now;
      progress.Show(link.status() ? link.status()->executed : 0, job.commands.size(),
                    link.stats().frames_sent, 0);
    }
  }
  progress.Finish();
  if (link.Failed())
    throw DeviceError(selector.ToString() + ": " + DecodeDeviceError(link.error()));
  if (!o.quiet) {
    std::fprintf(stderr, "%s: %zu patches drawn by usb %s; %llu frames sent (%llu resent)\n",
                 o.file.c_str(), job.patches.size(), selector.ToString().c_str(),
                 static_cast<unsigned long long>(link.stats().frames_sent),
                 static_cast<unsigned long long>(link.stats().retransmitted));
  }
  return 0;
}

}  // namespace fdsurf::host
