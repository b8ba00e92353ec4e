// Non-volatile state stores (see state_store.h).
#include "devices/stackshot3x/state_store.h"

#include <utility>

namespace moco::devices {

StateLoad MemoryStateStore::Load() {
  StateLoad out;
  if (corrupt_) {
    out.status = StateLoad::Status::kCorrupt;
    out.message = *corrupt_;
    corrupt_.reset();
    return out;
  }
  if (saved_) {
    out.status = StateLoad::Status::kLoaded;
    out.state = *saved_;
  }
  return out;
}

bool MemoryStateStore::Save(const nlohmann::json& state) {
  saved_ = state;
  ++saves_;
  return true;
}

}  // namespace moco::devices
