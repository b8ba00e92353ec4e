// What a DFMoco device's `hi` reply must advertise for a DFM rule or case to
// apply (dfmoco-protocol.txt "Hello (hi)"); DfmocoProtocol decides
// (conformance/protocols/dfmoco/dfmoco_protocol.cpp).
#ifndef MOCO_CONFORMANCE_RULES_DFMOCO_NEEDS_H_
#define MOCO_CONFORMANCE_RULES_DFMOCO_NEEDS_H_

#include "conformance/rules/needs.h"

namespace moco::conformance {

struct DfmocoNeeds : SharedNeeds {
  static constexpr Need kMotors{"dfmoco.motors", "hi: axes >= 1"};
  static constexpr Need kTwoMotors{"dfmoco.two-motors", "hi: axes >= 2"};
  static constexpr Need kJogVelocity{"dfmoco.jog-velocity", "hi: major version >= 2 (jm velocity)"};
  static constexpr Need kGoMotion{"dfmoco.go-motion", "hi: version >= 1.2.7 (go-motion)"};
  static constexpr Need kBlurRefusal{"dfmoco.blur-refusal", "hi: version >= 1.3.1 (bf -1)"};

  static constexpr Need kOwn[] = {kMotors, kTwoMotors, kJogVelocity, kGoMotion, kBlurRefusal};
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_DFMOCO_NEEDS_H_
