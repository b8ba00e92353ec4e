// The StackShot 3X rule catalogue (the StackShot 3X protocol spec; ERRATA
// stackshot; FACTS "StackShot"): packets, status codes and persistence.
#include "conformance/rules/catalogue.h"

namespace moco::conformance {

const std::vector<Rule>& StackshotRules() {
  static const std::vector<Rule> rules = {};
  return rules;
}

}  // namespace moco::conformance
