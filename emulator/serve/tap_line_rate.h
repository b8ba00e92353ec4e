// When a device behind a recording tap changes its line, read from the
// traffic itself by the protocol's own watcher (wire/protocol.h
// LineSwitchWatcher): e.g. a StackShot 3X acknowledging
// CC_RAIL_CONFIG_GLOBAL_MODE = GLOBAL_MODE_MOTION_DFMOCO leaves the binary
// protocol at 38400 baud for the DfMoco dialect at 57600
// (stackshot-protocol.txt section 1.1.17 and section 3; ERRATA 3.7). Pure:
// bytes in, a new line out.
#ifndef MOCO_SERVE_TAP_LINE_RATE_H_
#define MOCO_SERVE_TAP_LINE_RATE_H_

#include <cstdint>
#include <memory>
#include <optional>

#include "wire/bytes.h"
#include "wire/protocol.h"

namespace moco::serve {

// The line a device switched to: its protocol from now on and its baud rate.
struct LineChange {
  wire::Protocol dialect = wire::Protocol::kDmc;
  uint32_t baud = 0;
  // How many bytes of the chunk that showed it came before the switch.
  size_t offset = 0;
};

// Follows one link's traffic in both directions. The switch takes effect
// after the device's acknowledgement: the acknowledgement itself still
// travels at the old rate (the device answers in the old protocol, then
// switches). A refused request switches nothing. A switch the traffic does
// not show (a StackShot's mode loaded from a config slot with
// CC_RAIL_CONFIG_LOAD, or set on its panel) is not followed; a tap learns the
// new rate from the host's own change of its port's speed. A protocol whose
// line never switches (DMC v2, DFMoco) never changes.
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
  std::unique_ptr<wire::LineSwitchWatcher> watcher_;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_TAP_LINE_RATE_H_
