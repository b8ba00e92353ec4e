// Runs one mutated host session against a freshly powered in-process device
// in virtual time and judges the invariants every device must keep whatever
// the host sends (dmc-v2-protocol.txt "Message Format", "MSG_FLAG_ACK";
// the DFMoco reply grammar; StackShot 3X sections 2 and 4.1): no crash, every
// device message well formed, every DMC request answered exactly once with its
// ID, a legal type and a legal code, at most one StackShot reply per request
// with a legal status, and the device still answering its greeting afterwards.
#ifndef MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
#define MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_

#include <cstdint>
#include <memory>
#include <string>

#include "conformance/fuzz/mutator.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

struct FuzzVerdict {
  bool ok = true;
  std::string violation;  // the invariant broken and what was seen; empty when ok
  size_t messages = 0;    // host messages sent
  size_t replies = 0;     // device messages received
};

class FuzzExecutor {
 public:
  // `target` is an in-process target of a device speaking `protocol`; it is
  // restarted (powered afresh, time 0) before every run.
  FuzzExecutor(Protocol protocol, std::unique_ptr<InProcessTarget> target);
  ~FuzzExecutor();

  // Opens the target; an error message (bad model or profile) or nullopt.
  std::optional<std::string> Open();
  FuzzVerdict Run(const Messages& messages);

  // Virtual time a run leaves between two host messages; DMC and DFMoco get
  // 1 ms, StackShot 3 ms (more than the 2 ms inter-frame gap, so a partial
  // packet is dropped before the next one).
  TimeNs gap_ns() const { return gap_ns_; }

 private:
  FuzzVerdict RunDmc(const Messages& messages);
  FuzzVerdict RunDfmoco(const Messages& messages);
  FuzzVerdict RunStackshot(const Messages& messages);

  Protocol protocol_;
  std::unique_ptr<InProcessTarget> target_;
  TimeNs gap_ns_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
