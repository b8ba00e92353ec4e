// The fuzz executor (see executor.h): what a run plays and judges is the
// protocol's (its FuzzHooks, conformance/protocols/registry.h).
#include "conformance/fuzz/executor.h"

#include "conformance/protocols/registry.h"

namespace moco::conformance {

FuzzExecutor::FuzzExecutor(Protocol protocol, std::unique_ptr<InProcessTarget> target)
    : protocol_(protocol), hooks_(FindFuzzHooks(protocol)), target_(std::move(target)) {}

FuzzExecutor::~FuzzExecutor() = default;

std::optional<std::string> FuzzExecutor::Open() { return target_->Open(); }

TimeNs FuzzExecutor::gap_ns() const { return hooks_ == nullptr ? 0 : hooks_->gap_ns; }

FuzzVerdict FuzzExecutor::Run(const Messages& messages) {
  if (hooks_ == nullptr || hooks_->run == nullptr) {
    return Violation("the " + std::string(wire::Info(protocol_).title) + " protocol is not fuzzed",
                     0, 0);
  }
  target_->Restart();
  return hooks_->run(*target_, messages, hooks_->gap_ns);
}

}  // namespace moco::conformance
