// The file-backed state store of a served device: atomic writes, every
// corrupt file kept aside numbered with a message naming it, symlinks written
// through, unknown versions refused, a lock against a second user, special
// files; and a StackShot 3X keeping its NVM across devices on one file.
#include "serve/file_state_store.h"

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "devices/stackshot3x/stackshot3x_test_support.h"

namespace moco::serve {
namespace {

using devices::testing::Read;
using devices::testing::SsBench;
using devices::testing::Write;
using stackshot::Action;
using stackshot::Command;

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

std::string Slurp(const std::filesystem::path& p);

// The i-th corrupt copy of `path`: .corrupt, .corrupt.1, ...
std::filesystem::path CorruptCopy(const std::filesystem::path& path, size_t i) {
  return path.string() + ".corrupt" + (i == 0 ? "" : "." + std::to_string(i));
}

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
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_),
                          std::filesystem::directory_iterator()),
            1)
      << "no temporary file left";
  const StateLoad l = FileStateStore(dir_ / "s.json").Load();
  ASSERT_EQ(l.status, StateLoad::Status::kLoaded);
  EXPECT_EQ(l.state, state);
  ASSERT_TRUE(store.Save({{"serial_number", 6}}));
  EXPECT_EQ(store.Load().state["serial_number"], 6);
}

TEST_F(StateStoreTest, EveryCorruptFileIsKeptAsideNumberedNoneOverwritten) {
  const auto path = dir_ / "s.json";
  const std::vector<std::string> texts = {"{\"a\": ", "[1, 2]", "\xFF\xFE", ""};
  for (size_t i = 0; i < texts.size(); ++i) {
    { std::ofstream(path) << texts[i]; }
    FileStateStore store(path);
    const StateLoad l = store.Load();
    ASSERT_EQ(l.status, StateLoad::Status::kCorrupt) << texts[i];
    const std::string copy = store.CorruptPath().string() + (i == 0 ? "" : "." + std::to_string(i));
    EXPECT_NE(l.message.find(path.string()), std::string::npos) << l.message;
    EXPECT_NE(l.message.find(copy), std::string::npos) << l.message;
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_EQ(store.Load().status, StateLoad::Status::kEmpty);
  }
  for (size_t i = 0; i < texts.size(); ++i) {
    EXPECT_EQ(Slurp(CorruptCopy(path, i)), texts[i]) << "copy " << i;
  }
}

TEST_F(StateStoreTest, UnwritableDirectoryFailsWithAReason) {
  FileStateStore store(dir_ / "missing-dir" / "s.json");
  EXPECT_FALSE(store.Save({{"a", 1}}));
  EXPECT_NE(store.last_error().find("missing-dir does not exist"), std::string::npos)
      << store.last_error();
}

TEST_F(StateStoreTest, ASymlinkedStateFileIsWrittenThroughAndStaysALink) {
  std::filesystem::create_directory(dir_ / "real");
  const auto target = dir_ / "real" / "nvm.json";
  { std::ofstream(target) << R"({"serial_number": 1})"; }
  const auto link = dir_ / "nvm.json";
  std::filesystem::create_symlink("real/nvm.json", link);
  FileStateStore store(link);
  ASSERT_EQ(store.Load().state["serial_number"], 1);
  ASSERT_TRUE(store.Save({{"serial_number", 2}})) << store.last_error();
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(FileStateStore(target).Load().state["serial_number"], 2);
  // A corrupt target is kept aside beside the target; the link stays.
  { std::ofstream(target) << "{"; }
  EXPECT_EQ(store.Load().status, StateLoad::Status::kCorrupt);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "real" / "nvm.json.corrupt"));
  EXPECT_TRUE(std::filesystem::is_symlink(link));
}

TEST_F(StateStoreTest, AnUnknownVersionIsRefusedLeftUntouchedAndNeverReplaced) {
  const auto path = dir_ / "s.json";
  const std::string text = R"({"format": "stackshot3x-nvm", "version": 99})";
  { std::ofstream(path) << text; }
  FileStateStore store(path);
  StateLoad first;
  const auto error = store.Open(&first);
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(path.string()), std::string::npos) << *error;
  EXPECT_NE(error->find("99"), std::string::npos) << *error;
  EXPECT_NE(error->find("--state"), std::string::npos) << *error;
  EXPECT_FALSE(store.Save({{"version", 1}}));
  EXPECT_EQ(Slurp(path), text);
  EXPECT_EQ(FileStateStore(path).Load().status, StateLoad::Status::kUnsupported);
}

TEST_F(StateStoreTest, OpenLocksTheFileAgainstASecondUser) {
  const auto path = dir_ / "s.json";
  FileStateStore first(path);
  StateLoad load;
  ASSERT_EQ(first.Open(&load), std::nullopt);
  EXPECT_EQ(load.status, StateLoad::Status::kEmpty);
  FileStateStore second(path);
  const auto error = second.Open(&load);
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(path.string()), std::string::npos) << *error;
  EXPECT_NE(error->find("--state PATH"), std::string::npos) << *error;
}

TEST_F(StateStoreTest, OpenHandsItsLoadToTheDeviceToo) {
  const auto path = dir_ / "s.json";
  { std::ofstream(path) << "{"; }
  FileStateStore store(path);
  StateLoad first;
  ASSERT_EQ(store.Open(&first), std::nullopt);
  ASSERT_EQ(first.status, StateLoad::Status::kCorrupt);
  const StateLoad again = store.Load();
  EXPECT_EQ(again.status, StateLoad::Status::kCorrupt);
  EXPECT_EQ(again.message, first.message);
  EXPECT_EQ(store.Load().status, StateLoad::Status::kEmpty);
}

TEST_F(StateStoreTest, AFifoAsStateIsWrittenInPlaceAndStaysAFifo) {
  // --state /dev/null keeps nothing; a FIFO proves the same path without
  // putting a real device node at risk.
  const auto fifo = dir_ / "state.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  FileStateStore store(fifo);
  StateLoad first;
  ASSERT_EQ(store.Open(&first), std::nullopt);
  EXPECT_EQ(first.status, StateLoad::Status::kEmpty);
  std::string received;
  std::thread reader([&] { received = Slurp(fifo); });
  EXPECT_TRUE(store.Save({{"serial_number", 3}})) << store.last_error();
  reader.join();
  EXPECT_TRUE(std::filesystem::is_fifo(std::filesystem::symlink_status(fifo)));
  EXPECT_NE(received.find("\"serial_number\": 3"), std::string::npos) << received;
  EXPECT_FALSE(std::filesystem::exists(fifo.string() + ".corrupt"));
  EXPECT_FALSE(std::filesystem::exists(fifo.string() + ".lock"));
}

TEST_F(StateStoreTest, ADirectoryIsRefusedAtOpenAndLeftAlone) {
  const auto d = dir_ / "state-dir";
  std::filesystem::create_directory(d);
  FileStateStore store(d);
  StateLoad first;
  const auto error = store.Open(&first);
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("is a directory"), std::string::npos) << *error;
  EXPECT_TRUE(std::filesystem::is_directory(d));
  EXPECT_FALSE(std::filesystem::exists(d.string() + ".corrupt"));
}

// --- persistence through the file store -------------------------------------------

class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("ss3x_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

TEST(Stackshot3xTest, NewDeviceOnTheSameFileStoreKeepsNvm) {
  TempDir dir;
  const auto file = dir.path() / "nvm.json";
  {
    FileStateStore store(file);
    SsBench b({}, &store);
    ASSERT_EQ(b.Status(Write(Command::kSerialNumber, 0, stackshot::U32Value{777})), Action::kRspOk);
    ASSERT_EQ(b.Status(Write(Command::kNvmAccess, 0, stackshot::NvmWrite{31, 5})), Action::kRspOk);
    ASSERT_EQ(b.Status(Write(Command::kRailConfigTorque, 1, stackshot::U8Value{3})),
              Action::kRspOk);
    ASSERT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{7})), Action::kRspOk);
  }
  EXPECT_TRUE(std::filesystem::exists(file));
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".partial"));
  FileStateStore store(file);
  SsBench b({}, &store);
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kSerialNumber)).payload).value,
            777u);
  EXPECT_EQ(b.Status(Write(Command::kSerialNumber, 0, stackshot::U32Value{1})), Action::kFailed);
  EXPECT_EQ(std::get<stackshot::U32Value>(
                b.AskRead(Read(Command::kNvmAccess, 0, stackshot::NvmRead{31})).payload)
                .value,
            5u);
  EXPECT_EQ(
      std::get<stackshot::U8Value>(b.AskRead(Read(Command::kRailConfigTorque, 1)).payload).value,
      10);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{7})), Action::kRspOk);
  EXPECT_EQ(
      std::get<stackshot::U8Value>(b.AskRead(Read(Command::kRailConfigTorque, 1)).payload).value,
      3);
}

TEST(Stackshot3xTest, CorruptStateFileIsKeptAsideAndDefaultsUsed) {
  TempDir dir;
  const auto file = dir.path() / "nvm.json";
  { std::ofstream(file) << "{\"serial_number\": 12,"; }
  FileStateStore store(file);
  SsBench b({}, &store);
  EXPECT_TRUE(std::filesystem::exists(file.string() + ".corrupt"));
  EXPECT_NE(b.dev->StoreError().find(file.string()), std::string::npos);
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kSerialNumber)).payload).value,
            0xFFFFFFFFu);
  ASSERT_FALSE(b.dev->Log().empty());
  EXPECT_NE(b.dev->Log()[0].find("corrupt"), std::string::npos);
  // The device goes on with a fresh, readable file.
  EXPECT_EQ(store.Load().status, StateLoad::Status::kLoaded);
}

}  // namespace
}  // namespace moco::serve
