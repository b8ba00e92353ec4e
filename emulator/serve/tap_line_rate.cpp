// A StackShot's line-rate change read from the traffic (see tap_line_rate.h).
#include "serve/tap_line_rate.h"

#include <variant>
#include <vector>

#include "wire/protocol.h"

namespace moco::serve {

LineRateFollower::LineRateFollower(wire::Protocol protocol) : dialect_(protocol) {}

void LineRateFollower::OnHostBytes(wire::ByteView bytes) {
  if (dialect_ != wire::Protocol::kStackshot) return;
  std::vector<stackshot::DecodedPacket> packets;
  host_.Feed(bytes, packets);
  for (const stackshot::DecodedPacket& d : packets) switch_.OnHostPacket(d.packet);
}

std::optional<LineChange> LineRateFollower::OnDeviceBytes(wire::ByteView bytes) {
  if (dialect_ != wire::Protocol::kStackshot) return std::nullopt;
  std::vector<stackshot::DecodedPacket> packets;
  device_.Feed(bytes, packets);
  for (const stackshot::DecodedPacket& d : packets) {
    if (!switch_.OnDevicePacket(d.packet)) continue;
    // Section 3: from here on the line carries DfMoco text at that dialect's rate.
    dialect_ = wire::Protocol::kStackshotDfmoco;
    return LineChange{dialect_, wire::Info(dialect_).line.baud};
  }
  return std::nullopt;
}

}  // namespace moco::serve
