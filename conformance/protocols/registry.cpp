// The protocol registry (see registry.h).
#include "conformance/protocols/registry.h"

#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dmc/dmc_protocol.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"

namespace moco::conformance {
namespace {

template <typename Traits>
constexpr ProtocolRunner RunnerOf() {
  ProtocolRunner r{Traits::kProtocol,
                   &Traits::Rules,
                   &Run<Traits>,
                   [] { return CaseInfos(Traits::Cases()); },
                   &Traits::Fuzz,
                   {},
                   {}};
  if constexpr (requires { Traits::kDialects; }) {
    r.dialects = Traits::kDialects;
    r.auto_picks = Traits::kAutoPicks;
  }
  return r;
}

const ProtocolRunner kRunners[] = {
    RunnerOf<DmcProtocol>(),
    RunnerOf<DfmocoProtocol>(),
    RunnerOf<StackshotProtocol>(),
};

}  // namespace

std::span<const ProtocolRunner> Runners() { return kRunners; }

const ProtocolRunner* FindRunner(Protocol p) {
  for (const ProtocolRunner& r : kRunners) {
    if (r.protocol == p) return &r;
  }
  return nullptr;
}

const FuzzHooks* FindFuzzHooks(Protocol p) {
  for (const ProtocolRunner& r : kRunners) {
    for (const FuzzHooks& h : r.fuzz()) {
      if (h.protocol == p) return &h;
    }
  }
  return nullptr;
}

}  // namespace moco::conformance
