// A line's change of protocol and rate read from the traffic (see tap_line_rate.h).
#include "serve/tap_line_rate.h"

namespace moco::serve {

LineRateFollower::LineRateFollower(wire::Protocol protocol)
    : dialect_(protocol), watcher_(wire::WatchLineSwitches(protocol)) {}

void LineRateFollower::OnHostBytes(wire::ByteView bytes) {
  if (watcher_ == nullptr) return;
  // A host never completes a switch: the device's acknowledgement does.
  (void)watcher_->Feed(wire::Side::kHost, bytes);
}

std::optional<LineChange> LineRateFollower::OnDeviceBytes(wire::ByteView bytes) {
  if (watcher_ == nullptr) return std::nullopt;
  const std::optional<wire::LineSwitchAt> at = watcher_->Feed(wire::Side::kDevice, bytes);
  if (!at) return std::nullopt;
  // From here on the line carries the new protocol at its rate.
  dialect_ = at->protocol;
  watcher_ = wire::WatchLineSwitches(dialect_);
  if (watcher_ != nullptr && at->offset < bytes.size()) {
    (void)watcher_->Feed(wire::Side::kDevice, bytes.subspan(at->offset));
  }
  return LineChange{dialect_, wire::Info(dialect_).line.baud, at->offset};
}

}  // namespace moco::serve
