// What a DMC v2 device's MSG_HI must advertise for a DMC rule or case to
// apply (dmc-v2-protocol.txt "Capabilities"); DmcProtocol decides
// (conformance/protocols/dmc/dmc_protocol.cpp).
#ifndef MOCO_CONFORMANCE_RULES_DMC_NEEDS_H_
#define MOCO_CONFORMANCE_RULES_DMC_NEEDS_H_

#include "conformance/rules/needs.h"

namespace moco::conformance {

struct DmcNeeds : SharedNeeds {
  static constexpr Need kMotors{"dmc.motors", "MOTOR COUNT >= 1"};
  static constexpr Need kTwoMotors{"dmc.two-motors", "MOTOR COUNT >= 2"};
  static constexpr Need kDmx{"dmc.dmx", "DMX COUNT >= 1"};
  static constexpr Need kGioOut{"dmc.gio-out", "GIO OUT COUNT >= 1"};
  static constexpr Need kGioIn{"dmc.gio-in", "GIO INPUT COUNT >= 1"};
  static constexpr Need kHwLimits{"dmc.hw-limits", "HW LIMIT COUNT >= 1, MOTOR COUNT >= 1"};
  static constexpr Need kRealTime{"dmc.real-time", "capability 0x0001 (real-time)"};
  static constexpr Need kGoMotion{"dmc.go-motion", "capability 0x0002 (go-motion)"};
  static constexpr Need kGoMotion2{"dmc.go-motion-2", "capability 0x0080 (go-motion 2)"};
  static constexpr Need kLooping{"dmc.looping", "capability 0x0200 (looping)"};
  static constexpr Need kVirtual{"dmc.virtual", "a virtual capability (0x0004-0x0020)"};
  static constexpr Need kNoVirtual{"dmc.no-virtual", "no virtual capability"};
  static constexpr Need kVirtualBoomRig{"dmc.virtual-boom-rig",
                                        "capability 0x0004 (boom-swing-track), MOTOR COUNT >= 6"};
  static constexpr Need kAimPoint{"dmc.aim-point", "capability 0x0040 (aim point)"};
  static constexpr Need kCoupleMotors{"dmc.couple-motors",
                                      "capability 0x0100 (couple motors), MOTOR COUNT >= 2"};
  static constexpr Need kRtDmx{"dmc.rt-dmx", "capability 0x0001 (real-time), DMX COUNT >= 1"};
  static constexpr Need kRtTriggers{"dmc.rt-triggers",
                                    "capability 0x0001 (real-time), GIO OUT COUNT >= 1"};
  static constexpr Need kRtCamera{"dmc.rt-camera",
                                  "capabilities 0x0001 (real-time) and 0x0400 (camera trigger)"};

  static constexpr Need kOwn[] = {
      kMotors,         kTwoMotors, kDmx,          kGioOut,  kGioIn,      kHwLimits,
      kRealTime,       kGoMotion,  kGoMotion2,    kLooping, kVirtual,    kNoVirtual,
      kVirtualBoomRig, kAimPoint,  kCoupleMotors, kRtDmx,   kRtTriggers, kRtCamera,
  };
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_DMC_NEEDS_H_
