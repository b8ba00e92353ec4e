// The host's side of the link (see host_link.h).
#include "conformance/core/host_link.h"

namespace moco::conformance {

void HostLink::Write(wire::ByteView bytes) {
  WriteWithoutReading(bytes);
  Pump(Now());
}

void HostLink::WriteWithoutReading(wire::ByteView bytes) {
  if (StopRequested() != 0) {
    lost_ = true;
    return;
  }
  traffic_.push_back(Chunk{Now(), true, wire::Bytes(bytes.begin(), bytes.end())});
  if (!target_.Send(bytes)) lost_ = true;
}

void HostLink::WriteBytewise(wire::ByteView bytes) {
  for (const uint8_t b : bytes) Write(wire::ByteView(&b, 1));
}

void HostLink::Pump(TimeNs deadline_ns) {
  if (lost_) return;
  // A stop request (SIGINT, SIGTERM, SIGHUP) ends every wait at once, on any
  // target: the case under way is dropped and the reports are written.
  if (StopRequested() != 0) {
    lost_ = true;
    return;
  }
  wire::Bytes in;
  if (!target_.Receive(deadline_ns, in)) lost_ = true;
  if (!in.empty()) {
    traffic_.push_back(Chunk{Now(), false, in});
    on_bytes_(in);
  }
}

void HostLink::Idle(TimeNs duration_ns) {
  const TimeNs until = Now() + duration_ns;
  while (!lost_ && Now() < until) Pump(until);
}

}  // namespace moco::conformance
