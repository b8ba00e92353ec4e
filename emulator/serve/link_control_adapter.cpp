// The control channel's view of a served device's link (see link_control_adapter.h).
#include "serve/link_control_adapter.h"

#include "transport/link.h"
#include "transport/link_faults.h"
#include "transport/traffic.h"

namespace moco::serve {
namespace {

control::LinkFaultCounts Counts(const transport::FaultCounts& c) {
  control::LinkFaultCounts out;
  out.bytes_in = c.bytes_in;
  out.dropped = c.dropped;
  out.corrupted = c.corrupted;
  out.duplicated = c.duplicated;
  out.delayed = c.delayed;
  return out;
}

}  // namespace

control::LinkStatus DeviceServerLink::Status() {
  transport::Link& link = server_.link();
  const transport::LinkStats& s = link.stats();
  control::LinkStatus out;
  out.endpoint = server_.Where();
  out.host_open = link.host_open();
  out.cut_active = link.cut_active();
  out.queued_bytes = link.queued_bytes();
  out.bytes_from_host = s.bytes_from_host;
  out.bytes_to_device = s.bytes_to_device;
  out.bytes_from_device = s.bytes_from_device;
  out.bytes_to_host = s.bytes_to_host;
  out.overflowed = s.overflowed;
  out.discarded = s.discarded;
  out.cut_dropped = s.cut_dropped;
  out.reclaimed = s.reclaimed;
  out.connections = s.connections;
  out.faults_enabled = link.faults().enabled();
  out.faults_to_device = Counts(link.faults().counts(transport::Direction::kToDevice));
  out.faults_to_host = Counts(link.faults().counts(transport::Direction::kToHost));
  return out;
}

}  // namespace moco::serve
