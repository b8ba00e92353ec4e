// libFuzzer entry over the session mutator and the fuzz executor (see
// mutator.h, executor.h), for ClusterFuzzLite / OSS-Fuzz: an input is a host
// byte stream of one protocol (MOCO_FUZZ_PROTOCOL: its name in the wire
// protocol table, "dmc", "dfmoco" or "stackshot"), cut into messages and played against a fresh
// in-process device; a broken invariant aborts with its description. The custom mutator is the
// structure-aware one `mococheck fuzz` uses, so mutants keep valid lengths and checksums and reach
// the device's message logic.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/mutator.h"
#include "devices/registry.h"
#include "wire/protocol.h"

namespace {

using moco::conformance::FuzzExecutor;
using moco::conformance::InProcessTarget;
using moco::conformance::Messages;
using moco::conformance::Protocol;
using moco::conformance::SessionMutator;

#ifndef MOCO_FUZZ_PROTOCOL
#define MOCO_FUZZ_PROTOCOL "dmc"
#endif

// The protocol by its name in the wire table, and the first emulated device
// model that speaks it.
Protocol FuzzedProtocol() {
  const auto p = moco::wire::ParseProtocol(MOCO_FUZZ_PROTOCOL);
  if (!p) {
    std::fprintf(stderr, "session_fuzz: unknown protocol %s\n", MOCO_FUZZ_PROTOCOL);
    std::abort();
  }
  return *p;
}

std::string ModelFor(Protocol p) {
  for (const auto& m : moco::devices::DeviceModels()) {
    if (m.protocol == p) return std::string(m.name);
  }
  std::fprintf(stderr, "session_fuzz: no device model speaks %s\n", MOCO_FUZZ_PROTOCOL);
  std::abort();
}

const Protocol kProtocol = FuzzedProtocol();

constexpr size_t kMaxInput = 64 * 1024;

FuzzExecutor& Executor() {
  static FuzzExecutor* executor = [] {
    auto* e = new FuzzExecutor(kProtocol, InProcessTarget::ForModel(ModelFor(kProtocol), ""));
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
  Messages messages = moco::wire::SplitMessages(kProtocol, moco::wire::Side::kHost, {data, size});
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
  return SessionMutator::MutateStream(kProtocol, data, size, max_size, seed);
}
