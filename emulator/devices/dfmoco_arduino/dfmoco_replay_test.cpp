// Replays the host side of fixtures/sessions/dfmoco-uno-workflow.jsonl
// (docs/sessions.md) into the emulated DFMoco Uno in virtual time and checks
// that the device writes the recorded bytes, at the recorded times.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "devices/dfmoco_arduino/dfmoco_arduino.h"
#include "devices/dfmoco_arduino/dfmoco_test_support.h"
#include "session/session.h"

namespace moco::devices {
namespace {

std::filesystem::path SourceDir() {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

std::string Text(const wire::Bytes& b) { return std::string(b.begin(), b.end()); }

TEST(DfmocoReplay, UnoWorkflowMatchesByteForByte) {
  const auto loaded =
      session::LoadSession(SourceDir() / "fixtures/sessions/dfmoco-uno-workflow.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded))
      << std::get<session::SessionError>(loaded).message;
  const session::Session& session = std::get<session::Session>(loaded);
  ASSERT_EQ(session.header.protocol, wire::Protocol::kDfmoco);
  ASSERT_EQ(session.header.device, "dfmoco-uno");
  ASSERT_EQ(session.header.clock, "virtual");
  ASSERT_FALSE(session.entries.empty());

  testing::Bench b(LoadDfmocoProfile(SourceDir() / "fixtures/profiles/dfmoco-uno.json"));
  std::vector<testing::RecordingSink::Chunk> want;
  for (const session::SessionEntry& e : session.entries) {
    ASSERT_FALSE(e.is_event);
    if (e.from == session::Origin::kDevice) {
      want.push_back({e.t_ns, Text(e.bytes)});
      continue;
    }
    b.RunUntil(e.t_ns);
    b.dev.OnHostBytes(e.bytes);
  }
  b.RunUntil(session.entries.back().t_ns);
  ASSERT_EQ(b.sink.chunks.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(b.sink.chunks[i].bytes, want[i].bytes) << "device chunk " << i;
    EXPECT_EQ(b.sink.chunks[i].t_ns, want[i].t_ns) << "device chunk " << i << ": " << want[i].bytes;
  }
}

}  // namespace
}  // namespace moco::devices
