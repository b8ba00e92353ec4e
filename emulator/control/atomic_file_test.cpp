// Tests for whole-file replacement (atomic_file.h): the file holds exactly the
// text, replaces a previous one, and a failure leaves the old state and no
// temporary file behind, with a message naming the path and the reason.
#include "control/atomic_file.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace moco::control {
namespace {

namespace fs = std::filesystem;

// A fresh empty directory, removed with everything in it at the end.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            ("moco_atomic_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path_)) names.push_back(e.path().filename());
    return names;
  }

 private:
  fs::path path_;
};

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(WriteFileAtomically, WritesExactlyTheTextAndLeavesNoTemporaryFile) {
  TempDir dir;
  const fs::path p = dir.path() / "plot.svg";
  EXPECT_EQ(WriteFileAtomically(p.string(), "<svg/>\n"), std::nullopt);
  EXPECT_EQ(Read(p), "<svg/>\n");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"plot.svg"});
}

TEST(WriteFileAtomically, ReplacesAPreviousFile) {
  TempDir dir;
  const fs::path p = dir.path() / "r.json";
  ASSERT_EQ(WriteFileAtomically(p.string(), "a much longer first version\n"), std::nullopt);
  ASSERT_EQ(WriteFileAtomically(p.string(), "v2"), std::nullopt);
  EXPECT_EQ(Read(p), "v2");
  ASSERT_EQ(WriteFileAtomically(p.string(), ""), std::nullopt);
  EXPECT_EQ(fs::file_size(p), 0u);
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"r.json"});
}

TEST(WriteFileAtomically, AMissingDirectoryIsReportedWithThePathAndTheReason) {
  TempDir dir;
  const fs::path p = dir.path() / "missing" / "r.json";
  const auto error = WriteFileAtomically(p.string(), "x");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(p.string()), std::string::npos) << *error;
  EXPECT_NE(error->find(std::strerror(ENOENT)), std::string::npos) << *error;
  EXPECT_TRUE(dir.Names().empty());
}

TEST(WriteFileAtomically, AFailedRenameLeavesTheTargetAsItWasAndRemovesTheTemporaryFile) {
  TempDir dir;
  // A non-empty directory where the file should go: the rename must fail.
  const fs::path p = dir.path() / "out.svg";
  fs::create_directories(p);
  std::ofstream(p / "keep.txt") << "previous";
  const auto error = WriteFileAtomically(p.string(), "new text");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(p.string()), std::string::npos) << *error;
  EXPECT_NE(error->find(std::strerror(EISDIR)), std::string::npos) << *error;
  EXPECT_TRUE(fs::is_directory(p));
  EXPECT_EQ(Read(p / "keep.txt"), "previous");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"out.svg"});
}

// Law: whatever bytes are written (NULs, any length), the file holds exactly
// the last text written, and only the file is left in the directory.
RC_GTEST_PROP(WriteFileAtomically, TheFileHoldsExactlyTheLastTextWritten,
              (const std::string& first, const std::string& second)) {
  TempDir dir;
  const fs::path p = dir.path() / "f";
  RC_ASSERT(WriteFileAtomically(p.string(), first) == std::nullopt);
  RC_ASSERT(Read(p) == first);
  RC_ASSERT(WriteFileAtomically(p.string(), second) == std::nullopt);
  RC_ASSERT(Read(p) == second);
  RC_ASSERT(dir.Names() == std::vector<std::string>{"f"});
}

}  // namespace
}  // namespace moco::control
