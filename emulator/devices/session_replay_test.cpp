// Golden sessions (fixtures/sessions/*.jsonl, docs/sessions.md) recorded
// against an emulated device in virtual time are replayed into a fresh device
// of the same model: the host side at its recorded times, and the device must
// write the recorded bytes at the recorded times.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "devices/registry.h"
#include "devices/test_support.h"
#include "session/session.h"
#include "sim/scheduler.h"

namespace moco::devices {
namespace {

std::filesystem::path SourceDir() {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

void Replay(const std::string& file, const std::string& model) {
  const auto loaded = session::LoadSession(SourceDir() / "fixtures/sessions" / file);
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded))
      << std::get<session::SessionError>(loaded).message;
  const session::Session& session = std::get<session::Session>(loaded);
  ASSERT_EQ(session.header.clock, "virtual");
  sim::Scheduler scheduler;
  testing::RecordingSink out(scheduler);
  auto device = CreateDevice(model, "", scheduler, out);
  device->PowerOn();
  std::vector<testing::RecordingSink::Chunk> want;
  for (const session::SessionEntry& e : session.entries) {
    if (e.is_event) continue;
    if (e.from == session::Origin::kDevice) {
      want.push_back({e.t_ns, std::string(e.bytes.begin(), e.bytes.end())});
      continue;
    }
    scheduler.RunUntil(e.t_ns);
    device->OnHostBytes(e.bytes);
  }
  scheduler.RunUntil(session.entries.back().t_ns);
  ASSERT_EQ(out.chunks.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(out.chunks[i].bytes, want[i].bytes) << file << " device chunk " << i;
    EXPECT_EQ(out.chunks[i].t_ns, want[i].t_ns) << file << " device chunk " << i;
  }
}

TEST(SessionReplay, Dmc16Workflow) { Replay("dmc16-workflow.jsonl", "dmc16"); }
// A live run at 2 fps: position updates every 100 ms in the pre-roll, between
// the frames and in the post-roll (dmc-v2-protocol.txt MSG_MOTOR_GET_POSITION),
// beside the report at each frame (MSG_RT_GO).
TEST(SessionReplay, Dmc16LiveRunAtALowFrameRate) { Replay("dmc16-live-run.jsonl", "dmc16"); }
TEST(SessionReplay, Stackshot3xWorkflow) { Replay("stackshot3x-workflow.jsonl", "stackshot3x"); }

}  // namespace
}  // namespace moco::devices
