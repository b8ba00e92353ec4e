// A StackShot line's switch to DfMoco mode (see stackshot_mode_switch.h).
#include "wire/stackshot_mode_switch.h"

#include <string>
#include <variant>
#include <vector>

#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::stackshot {

void DfmocoModeSwitch::OnHostPacket(const Packet& p) {
  if (p.command != static_cast<uint16_t>(Command::kRailConfigGlobalMode) ||
      p.action != static_cast<uint8_t>(Action::kWrite)) {
    return;
  }
  const auto c = DecodeHostPacket(p);
  if (!c.ok()) {
    requested_ = false;
    return;
  }
  const auto* mode = std::get_if<EnumValue<GlobalMode>>(&c->payload);
  // The latest mode write decides: a later write to another mode replaces it.
  requested_ = mode != nullptr && mode->value == GlobalMode::kMotionDfMoco;
}

bool DfmocoModeSwitch::OnDevicePacket(const Packet& p) {
  if (p.command != static_cast<uint16_t>(Command::kRailConfigGlobalMode) || !requested_) {
    return false;
  }
  requested_ = false;
  return p.action == static_cast<uint8_t>(Action::kRspOk);
}

namespace {

class DfmocoModeWatcher final : public wire::LineSwitchWatcher {
 public:
  std::optional<wire::LineSwitchAt> Feed(wire::Side side, wire::ByteView bytes) override {
    std::vector<DecodedPacket> packets;
    if (side == wire::Side::kHost) {
      host_.Feed(bytes, packets);
      for (const DecodedPacket& d : packets) switch_.OnHostPacket(d.packet);
      return std::nullopt;
    }
    if (!switch_.pending()) {
      device_.Feed(bytes, packets);
      return std::nullopt;
    }
    // The acknowledgement may end anywhere in this chunk: byte by byte.
    for (size_t i = 0; i < bytes.size(); ++i) {
      packets.clear();
      device_.Feed(bytes.subspan(i, 1), packets);
      for (const DecodedPacket& d : packets) {
        if (!switch_.OnDevicePacket(d.packet)) continue;
        // Section 3: from the next byte on, DFMoco text both ways.
        return wire::LineSwitchAt{
            i + 1, wire::Protocol::kStackshotDfmoco,
            "DfMoco mode: DFMoco text at " + std::to_string(kDfMocoBaudRate) + " baud"};
      }
    }
    return std::nullopt;
  }

 private:
  PacketDecoder host_{false};
  PacketDecoder device_{true};
  DfmocoModeSwitch switch_;
};

}  // namespace

std::unique_ptr<wire::LineSwitchWatcher> WatchDfmocoModeSwitch() {
  return std::make_unique<DfmocoModeWatcher>();
}

}  // namespace moco::stackshot
