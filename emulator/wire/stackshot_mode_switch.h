// The one place a StackShot 3X line changes protocol: a host's write of
// CC_RAIL_CONFIG_GLOBAL_MODE = GLOBAL_MODE_MOTION_DFMOCO, acknowledged
// RSP_OK by the controller, leaves the binary protocol at 38400 baud for the
// DfMoco dialect at 57600 from the byte after the acknowledgement
// (stackshot-protocol.txt section 1.1.17 and section 3; ERRATA 3.7). The
// latest mode write decides; a refused write switches nothing. Followed by
// the transcripts (mocosim decode, reports) and the recording tap.
#ifndef MOCO_WIRE_STACKSHOT_MODE_SWITCH_H_
#define MOCO_WIRE_STACKSHOT_MODE_SWITCH_H_

#include <memory>

#include "wire/protocol.h"
#include "wire/stackshot_frame.h"

namespace moco::stackshot {

class DfmocoModeSwitch {
 public:
  // A whole packet the host sent.
  void OnHostPacket(const Packet& p);
  // A whole packet the controller sent; true when it acknowledges a switch
  // to DfMoco mode: the line carries DFMoco text from the next byte.
  bool OnDevicePacket(const Packet& p);
  // Whether a switch awaits the controller's answer.
  bool pending() const { return requested_; }

 private:
  bool requested_ = false;  // a DfMoco mode write awaits its answer
};

// A StackShot binary line's watcher: the acknowledged switch to DfMoco mode,
// found to the byte (the DFMoco text may follow the acknowledgement in the
// same chunk), as wire::Protocol::kStackshotDfmoco.
std::unique_ptr<wire::LineSwitchWatcher> WatchDfmocoModeSwitch();

}  // namespace moco::stackshot

#endif  // MOCO_WIRE_STACKSHOT_MODE_SWITCH_H_
