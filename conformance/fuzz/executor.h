// Runs one mutated host session against a freshly powered in-process device
// in virtual time and judges the invariants every device must keep whatever
// the host sends: no crash, every device message well formed, every request
// answered as its protocol says, and the device still answering its greeting
// afterwards. Each protocol states its own in its folder
// (conformance/protocols/*/*_fuzz_hooks.cpp).
#ifndef MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
#define MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_

#include <cstdint>
#include <memory>
#include <string>

#include "conformance/core/fuzz_protocol.h"
#include "conformance/fuzz/mutator.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

class FuzzExecutor {
 public:
  // `target` is an in-process target of a device speaking `protocol`; it is
  // restarted (powered afresh, time 0) before every run.
  FuzzExecutor(Protocol protocol, std::unique_ptr<InProcessTarget> target);
  ~FuzzExecutor();

  // Opens the target; an error message (bad model or profile) or nullopt.
  std::optional<std::string> Open();
  FuzzVerdict Run(const Messages& messages);

  // Virtual time a run leaves between two host messages (the protocol's
  // FuzzHooks::gap_ns).
  TimeNs gap_ns() const;

 private:
  Protocol protocol_;
  const FuzzHooks* hooks_;  // nullptr: the protocol has none
  std::unique_ptr<InProcessTarget> target_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
