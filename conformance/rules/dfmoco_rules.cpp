// The DFMoco rule catalogue (the DFMoco spec; FACTS "DFMoco"): the sketch's
// reply grammar, `mp` while moving and the dialect differences.
#include "conformance/rules/catalogue.h"

namespace moco::conformance {

const std::vector<Rule>& DfmocoRules() {
  static const std::vector<Rule> rules = {};
  return rules;
}

}  // namespace moco::conformance
