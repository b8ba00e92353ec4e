// The host's side of the link (see host_link.h).
#include "conformance/core/host_link.h"

#include <utility>

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

HostBase::HostBase(Target& target, Verdicts& verdicts, HostOptions options,
                   std::function<void(wire::ByteView)> on_bytes)
    : link_(target, std::move(on_bytes)), verdicts_(verdicts), options_(std::move(options)) {
  if (!options_.unanswered) options_.unanswered = std::make_shared<UnansweredRequests>();
}

std::string HostBase::Hopeless(std::string_view kind) const {
  const int limit = options_.give_up_after_unanswered;
  if (limit <= 0) return "";
  const UnansweredRequests& u = *options_.unanswered;
  if (u.in_a_row >= limit && !greeting_) {
    return "the device answered none of the last " + std::to_string(u.in_a_row) + " requests";
  }
  const auto it = u.by_kind.find(kind);
  if (it == u.by_kind.end() || it->second < limit) return "";
  return "the device left the last " + std::to_string(it->second) + " " + std::string(kind) +
         " requests unanswered";
}

void HostBase::Unanswered(std::string_view kind) {
  UnansweredRequests& u = *options_.unanswered;
  ++u.in_a_row;
  auto it = u.by_kind.find(kind);
  if (it == u.by_kind.end()) it = u.by_kind.emplace(std::string(kind), 0).first;
  ++it->second;
}

void HostBase::Answered(std::string_view kind) {
  UnansweredRequests& u = *options_.unanswered;
  u.in_a_row = 0;
  if (const auto it = u.by_kind.find(kind); it != u.by_kind.end()) u.by_kind.erase(it);
}

std::string HostBase::NotWaitedForSummary() const {
  if (not_waited_for_.empty()) return "";
  std::string s =
      "answers not waited for (the device had stopped giving them; each judged unanswered):";
  bool first = true;
  for (const auto& [kind, n] : not_waited_for_) {
    s += (first ? " " : ", ") + kind + " x" + std::to_string(n);
    first = false;
  }
  return s;
}

}  // namespace moco::conformance
