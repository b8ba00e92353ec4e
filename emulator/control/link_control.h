// What the control channel needs of a served device's link (docs/control.md
// "cut_link", "faults", "power_cycle" and the "link" part of "state"),
// owned by control so that control never names the transport: the serving
// layer (serve/link_control_adapter.h) implements it over a DeviceServer.
#ifndef MOCO_CONTROL_LINK_CONTROL_H_
#define MOCO_CONTROL_LINK_CONTROL_H_

#include <cstddef>
#include <cstdint>
#include <string>

#include "sim/line_faults.h"
#include "sim/scheduler.h"

namespace moco::control {

// What the link's fault injection did to one direction.
struct LinkFaultCounts {
  uint64_t bytes_in = 0;
  uint64_t dropped = 0;
  uint64_t corrupted = 0;
  uint64_t duplicated = 0;
  uint64_t delayed = 0;
};

// A snapshot of a link for the "state" reply.
struct LinkStatus {
  std::string endpoint;  // "pty /tmp/dmc16 -> /dev/pts/4", "tcp 127.0.0.1:5000"
  bool host_open = false;
  bool cut_active = false;
  size_t queued_bytes = 0;
  uint64_t bytes_from_host = 0;
  uint64_t bytes_to_device = 0;
  uint64_t bytes_from_device = 0;
  uint64_t bytes_to_host = 0;
  uint64_t overflowed = 0;
  uint64_t discarded = 0;
  uint64_t cut_dropped = 0;
  uint64_t reclaimed = 0;
  uint64_t connections = 0;
  bool faults_enabled = false;
  LinkFaultCounts faults_to_device;
  LinkFaultCounts faults_to_host;
};

// The link of one served device. Every call comes from the thread that owns
// the scheduler.
class LinkControl {
 public:
  virtual ~LinkControl() = default;

  // Where the device is served, as logged at start-up.
  virtual std::string Where() const = 0;
  // Nothing crosses either way for duration_ns (TCP: the host is disconnected).
  virtual void CutLink(sim::TimeNs duration_ns) = 0;
  // The device off now and on again after off_ns, through its link.
  virtual void PowerCycle(sim::TimeNs off_ns) = 0;
  // Replaces the link's fault injection (all rates 0: none).
  virtual void SetFaults(const sim::FaultConfig& config) = 0;
  virtual LinkStatus Status() = 0;
};

}  // namespace moco::control

#endif  // MOCO_CONTROL_LINK_CONTROL_H_
