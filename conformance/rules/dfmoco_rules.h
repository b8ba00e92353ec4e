// Applicability of the DFMoco rules (dfmoco-protocol.txt "Hello (hi)"; FACTS
// "DFMoco": dialects 1.2.7, 1.3.x, 2.0.0): what a device's `hi` reply
// advertises decides which DFM-* rules and cases apply.
#ifndef MOCO_CONFORMANCE_RULES_DFMOCO_RULES_H_
#define MOCO_CONFORMANCE_RULES_DFMOCO_RULES_H_

#include <array>
#include <optional>
#include <string_view>

#include "conformance/rules/catalogue.h"
#include "wire/dfmoco.h"

namespace moco::conformance {

// A dotted version "1.3.1" as {1, 3, 1} (missing parts are 0); nullopt when
// the text does not start with a number.
std::optional<std::array<int, 3>> ParseDfmocoVersion(std::string_view text);

// Whether DFMoco `rule` (or a case gated like one) applies to a device that
// answered `hi` with `hello`. Needs outside the DFMoco ones apply only when
// kNothing.
bool DfmocoApplies(const Rule& rule, const dfmoco::HelloReply& hello);
bool DfmocoApplies(Needs needs, const dfmoco::HelloReply& hello);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_DFMOCO_RULES_H_
