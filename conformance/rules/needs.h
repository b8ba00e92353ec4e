// What a device must have for a rule or a case to apply. Each protocol
// declares its own needs beside its rule table (rules/<p>_needs.h: a struct
// deriving from SharedNeeds, its needs as members and in kOwn) and its traits
// (conformance/protocols/<p>/<p>_protocol.cpp) decide whether a device meets
// them; the needs every protocol shares are here. A need's text is what the
// catalogue and the reports print.
#ifndef MOCO_CONFORMANCE_RULES_NEEDS_H_
#define MOCO_CONFORMANCE_RULES_NEEDS_H_

#include <string_view>

namespace moco::conformance {

struct Need {
  std::string_view id;    // unique over every protocol: "dmc.motors"
  std::string_view text;  // "MOTOR COUNT >= 1" ("-" for nothing)

  friend constexpr bool operator==(const Need& a, const Need& b) { return a.id == b.id; }
};

// The needs of any protocol. A protocol's needs derive from these, so a rule
// table or a case list reads every need it may use through one name.
struct SharedNeeds {
  // Applies to every device.
  static constexpr Need kNothing{"nothing", "-"};
  // The target watches the firmware's pins (simavr with --board): the runner
  // asks the target, not the protocol.
  static constexpr Need kPins{"pins", "watched pins (a simavr: target with --board)"};
  static constexpr Need kShared[] = {kNothing, kPins};
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_NEEDS_H_
