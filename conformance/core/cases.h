// What a protocol's cases are made of (every protocol under
// conformance/protocols/ instantiates these): a case names its suite, what
// the device must have for it to run, and a function over the context the
// runner builds for it.
#ifndef MOCO_CONFORMANCE_CORE_CASES_H_
#define MOCO_CONFORMANCE_CORE_CASES_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/verdicts.h"
#include "conformance/rules/catalogue.h"
#include "conformance/rules/needs.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// Options of the random sequence suite.
struct RandomOptions {
  uint64_t seed = 1;
  int steps = 40;            // requests per sequence
  std::string session_path;  // where a failing sequence is saved (empty: not saved)
};

// What a case works with: the protocol's host (which has greeted the device
// already) and what the device said of itself in that greeting.
template <typename Host, typename Device>
struct CaseContextOf {
  Host& host;
  Verdicts& v;
  const Device& device;
  Target& target;
  const HostOptions& host_options;
  const RandomOptions& random;
  std::vector<std::string>& log;  // lines for the report (transcripts, saved files)
};

template <typename ContextT>
struct CaseOf {
  using Context = ContextT;
  std::string suite;                   // "connect", "motor", ..., "random"
  std::string name;                    // unique within the suite
  Need needs = SharedNeeds::kNothing;  // the protocol's own (rules/<p>_needs.h) or shared
  std::string summary;
  std::function<void(ContextT&)> run;
};

// One line of `mococheck cases`.
struct CaseInfo {
  std::string suite;
  std::string name;
  std::string summary;
  std::string needs;  // "" when the case needs nothing
};

template <typename CaseT>
std::vector<CaseInfo> CaseInfos(const std::vector<CaseT>& cases) {
  std::vector<CaseInfo> out;
  for (const CaseT& k : cases) {
    out.push_back({k.suite, k.name, k.summary,
                   k.needs == SharedNeeds::kNothing ? std::string() : std::string(k.needs.text)});
  }
  return out;
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_CASES_H_
