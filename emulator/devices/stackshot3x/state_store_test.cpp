// The in-memory non-volatile state store (the file store's tests are
// transport/file_state_store_test.cpp).
#include "devices/stackshot3x/state_store.h"

#include <gtest/gtest.h>

namespace moco::devices {
namespace {

TEST(MemoryStateStoreTest, KeepsTheLastSaveAndCanPlayCorrupt) {
  MemoryStateStore m;
  EXPECT_EQ(m.Load().status, StateLoad::Status::kEmpty);
  ASSERT_TRUE(m.Save({{"x", 1}}));
  EXPECT_EQ(m.Load().state["x"], 1);
  EXPECT_EQ(m.save_count(), 1u);
  m.SetCorrupt("bad");
  EXPECT_EQ(m.Load().status, StateLoad::Status::kCorrupt);
  EXPECT_EQ(m.Load().status, StateLoad::Status::kLoaded);
}

}  // namespace
}  // namespace moco::devices
