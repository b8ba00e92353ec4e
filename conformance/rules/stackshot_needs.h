// What a StackShot device must report for an SS rule or case to apply
// (stackshot-protocol.txt 1.1.10-1.1.15); StackshotProtocol decides
// (conformance/protocols/stackshot/stackshot_cases.cpp, SsApplies).
#ifndef MOCO_CONFORMANCE_RULES_STACKSHOT_NEEDS_H_
#define MOCO_CONFORMANCE_RULES_STACKSHOT_NEEDS_H_

#include "conformance/rules/needs.h"

namespace moco::conformance {

struct StackshotNeeds : SharedNeeds {
  static constexpr Need kThreeAxes{"stackshot.three-axes", "axes X, Y and Z (StackShot 3X)"};

  static constexpr Need kOwn[] = {kThreeAxes};
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_STACKSHOT_NEEDS_H_
