// A StackShot line's switch to DfMoco mode (see stackshot_mode_switch.h).
#include "wire/stackshot_mode_switch.h"

#include <variant>

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

}  // namespace moco::stackshot
