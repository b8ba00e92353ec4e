// When a device behind a recording tap changes its line rate, read from the
// traffic itself: a StackShot 3X acknowledging CC_RAIL_CONFIG_GLOBAL_MODE =
// GLOBAL_MODE_MOTION_DFMOCO leaves the binary protocol at 38400 baud for the
// DfMoco dialect at 57600 (stackshot-protocol.txt section 1.1.17 and section
// 3; ERRATA 3.7). Pure: bytes in, a new line out.
#ifndef MOCO_SERVE_TAP_LINE_RATE_H_
#define MOCO_SERVE_TAP_LINE_RATE_H_

#include <cstdint>
#include <optional>

#include "wire/bytes.h"
#include "wire/protocol.h"
#include "wire/stackshot_frame.h"
#include "wire/stackshot_mode_switch.h"

namespace moco::serve {

// The line a device switched to: its dialect from now on and its baud rate.
struct LineChange {
  wire::Protocol dialect = wire::Protocol::kStackshot;
  uint32_t baud = 0;
};

// Follows one link's traffic in both directions. The switch takes effect
// after the device's acknowledgement: the acknowledgement itself still
// travels at the old rate (the device answers in the old dialect, then
// switches). A refused request (any status but RSP_OK) switches nothing. A
// mode loaded from a config slot (CC_RAIL_CONFIG_LOAD) is not visible in the
// traffic; a tap learns it from the host's own change of its port's speed.
// Protocols with one fixed line (DMC v2, DFMoco) never change.
class LineRateFollower {
 public:
  explicit LineRateFollower(wire::Protocol protocol);

  // Bytes the host sent, in any chunking.
  void OnHostBytes(wire::ByteView bytes);
  // Bytes the device sent, in any chunking; returns the change these bytes
  // complete, if any.
  std::optional<LineChange> OnDeviceBytes(wire::ByteView bytes);

  wire::Protocol dialect() const { return dialect_; }

 private:
  wire::Protocol dialect_;
  stackshot::PacketDecoder host_{false};
  stackshot::PacketDecoder device_{true};
  stackshot::DfmocoModeSwitch switch_;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_TAP_LINE_RATE_H_
