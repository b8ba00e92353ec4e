// Non-volatile state stores: atomic file writes, corrupt files kept aside
// with a message naming the file, and the in-memory store.
#include "devices/stackshot3x/state_store.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

namespace moco::devices {
namespace {

class StateStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("ss3x_store_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

std::string Slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(StateStoreTest, MissingFileIsEmpty) {
  FileStateStore store(dir_ / "none.json");
  EXPECT_EQ(store.Load().status, StateLoad::Status::kEmpty);
}

TEST_F(StateStoreTest, SaveThenLoadRoundTripsAndLeavesNoPartialFile) {
  FileStateStore store(dir_ / "s.json");
  const nlohmann::json state = {{"serial_number", 5}, {"log", {"a", "b"}}};
  ASSERT_TRUE(store.Save(state));
  EXPECT_FALSE(std::filesystem::exists(store.PartialPath()));
  const StateLoad l = FileStateStore(dir_ / "s.json").Load();
  ASSERT_EQ(l.status, StateLoad::Status::kLoaded);
  EXPECT_EQ(l.state, state);
  ASSERT_TRUE(store.Save({{"serial_number", 6}}));
  EXPECT_EQ(store.Load().state["serial_number"], 6);
}

TEST_F(StateStoreTest, CorruptFileIsMovedAsideWithAMessageNamingIt) {
  const auto path = dir_ / "s.json";
  for (const char* text : {"{\"a\": ", "[1, 2]", "\xFF\xFE"}) {
    { std::ofstream(path) << text; }
    FileStateStore store(path);
    const StateLoad l = store.Load();
    ASSERT_EQ(l.status, StateLoad::Status::kCorrupt) << text;
    EXPECT_NE(l.message.find(path.string()), std::string::npos) << l.message;
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_EQ(Slurp(store.CorruptPath()), text);
    EXPECT_EQ(store.Load().status, StateLoad::Status::kEmpty);
  }
}

TEST_F(StateStoreTest, UnwritableDirectoryFailsWithAReason) {
  FileStateStore store(dir_ / "missing-dir" / "s.json");
  EXPECT_FALSE(store.Save({{"a", 1}}));
  EXPECT_NE(store.last_error().find("s.json.partial"), std::string::npos);
}

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
