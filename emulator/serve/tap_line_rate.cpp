// A StackShot's line-rate change read from the traffic (see tap_line_rate.h).
#include "serve/tap_line_rate.h"

#include <variant>
#include <vector>

#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::serve {

LineRateFollower::LineRateFollower(wire::Protocol protocol) : dialect_(protocol) {}

void LineRateFollower::OnHostBytes(wire::ByteView bytes) {
  if (dialect_ != wire::Protocol::kStackshot) return;
  std::vector<stackshot::DecodedPacket> packets;
  host_.Feed(bytes, packets);
  for (const stackshot::DecodedPacket& d : packets) {
    if (d.packet.command != static_cast<uint16_t>(stackshot::Command::kRailConfigGlobalMode) ||
        d.packet.action != static_cast<uint8_t>(stackshot::Action::kWrite)) {
      continue;
    }
    const auto c = stackshot::DecodeHostPacket(d.packet);
    if (!c.ok()) {
      switch_requested_ = false;
      continue;
    }
    const auto* mode = std::get_if<stackshot::EnumValue<stackshot::GlobalMode>>(&c->payload);
    // The latest mode write decides: a later write to another mode replaces it.
    switch_requested_ = mode != nullptr && mode->value == stackshot::GlobalMode::kMotionDfMoco;
  }
}

std::optional<LineChange> LineRateFollower::OnDeviceBytes(wire::ByteView bytes) {
  if (dialect_ != wire::Protocol::kStackshot) return std::nullopt;
  std::vector<stackshot::DecodedPacket> packets;
  device_.Feed(bytes, packets);
  for (const stackshot::DecodedPacket& d : packets) {
    if (d.packet.command != static_cast<uint16_t>(stackshot::Command::kRailConfigGlobalMode)) {
      continue;
    }
    if (!switch_requested_) continue;
    switch_requested_ = false;
    if (d.packet.action != static_cast<uint8_t>(stackshot::Action::kRspOk)) continue;
    // Section 3: from here on the line carries DfMoco text at 57600.
    dialect_ = wire::Protocol::kStackshotDfmoco;
    return LineChange{dialect_, stackshot::kDfMocoBaudRate};
  }
  return std::nullopt;
}

}  // namespace moco::serve
