// libFuzzer entry over the session mutator and the fuzz executor (see
// mutator.h, executor.h), for ClusterFuzzLite / OSS-Fuzz: an input is a host
// byte stream of one protocol (MOCO_FUZZ_PROTOCOL: 0 DMC v2, 1 DFMoco,
// 2 StackShot 3X), cut into messages and played against a fresh in-process
// device; a broken invariant aborts with its description. The custom
// mutator is the structure-aware one `mococheck fuzz` uses, so mutants keep
// valid lengths and checksums and reach the device's message logic.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/mutator.h"

namespace {

using moco::conformance::FuzzExecutor;
using moco::conformance::InProcessTarget;
using moco::conformance::Messages;
using moco::conformance::Protocol;
using moco::conformance::SessionMutator;

#if MOCO_FUZZ_PROTOCOL == 0
constexpr Protocol kProtocol = Protocol::kDmc;
constexpr const char* kModel = "dmc16";
#elif MOCO_FUZZ_PROTOCOL == 1
constexpr Protocol kProtocol = Protocol::kDfmoco;
constexpr const char* kModel = "dfmoco";
#else
constexpr Protocol kProtocol = Protocol::kStackshot;
constexpr const char* kModel = "stackshot3x";
#endif

constexpr size_t kMaxInput = 64 * 1024;

FuzzExecutor& Executor() {
  static FuzzExecutor* executor = [] {
    auto* e = new FuzzExecutor(kProtocol, InProcessTarget::ForModel(kModel, ""));
    if (auto err = e->Open()) {
      std::fprintf(stderr, "session_fuzz: %s\n", err->c_str());
      std::abort();
    }
    return e;
  }();
  return *executor;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > kMaxInput) return -1;
  Messages messages = moco::conformance::SplitHostStream(kProtocol, {data, size});
  if (messages.size() > SessionMutator::kMaxMessages) return -1;
  const auto verdict = Executor().Run(messages);
  if (!verdict.ok) {
    std::fprintf(stderr, "session_fuzz: invariant broken: %s\n", verdict.violation.c_str());
    std::abort();
  }
  return 0;
}

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int seed) {
  Messages messages = moco::conformance::SplitHostStream(kProtocol, {data, size});
  SessionMutator mutator(kProtocol, seed);
  mutator.Mutate(messages, {});
  moco::wire::Bytes out = moco::conformance::JoinMessages(messages);
  if (out.size() > max_size) out.resize(max_size);
  if (!out.empty()) std::memcpy(data, out.data(), out.size());
  return out.size();
}
