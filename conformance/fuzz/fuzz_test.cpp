// Laws of the session mutator (splitting round-trips, repair makes frames
// decode, determinism), the fuzz executor (recorded sessions keep every
// invariant, broken devices are caught) and replay (golden sessions match;
// positions and times outside the tolerances do not).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "conformance/fuzz/campaign.h"
#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/mutator.h"
#include "conformance/fuzz/replay.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/registry.h"
#include "devices/faulty_sink.h"
#include "devices/registry.h"
#include "session/session.h"
#include "wire/dmc.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"

namespace moco::conformance {
namespace {

std::string Fixture(const std::string& rel) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return std::string(root ? root : ".") + "/fixtures/sessions/" + rel;
}

Seed LoadOrDie(const std::string& name) {
  auto s = LoadSeed(Fixture(name));
  if (const auto* e = std::get_if<std::string>(&s)) ADD_FAILURE() << *e;
  return std::get<Seed>(s);
}

session::Session SessionOrDie(const std::string& name) {
  auto s = session::LoadSession(Fixture(name));
  if (const auto* e = std::get_if<session::SessionError>(&s)) ADD_FAILURE() << e->message;
  return std::get<session::Session>(s);
}

// --- splitting and repair -------------------------------------------------------------

RC_GTEST_PROP(SplitHostStream, JoinGivesTheStreamBackForEveryProtocol,
              (const std::vector<uint8_t>& stream, uint8_t which)) {
  const Protocol p = kAllProtocols[which % 3];
  RC_ASSERT(wire::JoinMessages(wire::SplitMessages(p, wire::Side::kHost, stream)) == stream);
}

TEST(SplitHostStream, RecordedDmcSessionIsWholeFramesThatDecode) {
  const Seed s = LoadOrDie("dmc16-workflow.jsonl");
  ASSERT_GE(s.messages.size(), 10u);
  // Every message is a whole frame; one was recorded damaged on purpose (its
  // note: "a damaged frame (ERR_CHECKSUM)").
  size_t damaged = 0;
  for (const wire::Bytes& m : s.messages) {
    ASSERT_GE(m.size(), 12u);
    EXPECT_EQ(m.size(), 12u + static_cast<size_t>(m[8] | (m[9] << 8)));
    damaged += !dmc::DecodeFrame(m).ok();
  }
  EXPECT_EQ(damaged, 1u);
}

TEST(SplitHostStream, DfmocoLinesKeepTheirLineEnds) {
  const std::string text = "hi\r\nmm 1 200\r\nms";
  const Messages m = wire::SplitMessages(Protocol::kDfmoco, wire::Side::kHost,
                                         wire::Bytes(text.begin(), text.end()));
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(std::string(m[1].begin(), m[1].end()), "mm 1 200\r\n");
  EXPECT_EQ(std::string(m[2].begin(), m[2].end()), "ms");  // unterminated, kept
}

RC_GTEST_PROP(RepairMessage, ADmcHeaderWithAnyLengthAndCheckDecodesAfterRepair,
              (uint32_t id, uint16_t type, uint16_t bad_length, const std::vector<uint8_t>& data)) {
  wire::Bytes m = {'D', 'F'};
  for (int k = 0; k < 4; ++k) m.push_back(static_cast<uint8_t>(id >> (8 * k)));
  m.push_back(static_cast<uint8_t>(type));
  m.push_back(static_cast<uint8_t>(type >> 8));
  m.push_back(static_cast<uint8_t>(bad_length));
  m.push_back(static_cast<uint8_t>(bad_length >> 8));
  m.insert(m.end(), data.begin(), data.end());
  m.push_back(0x12);
  m.push_back(0x34);
  wire::Info(Protocol::kDmc).repair(m);
  const auto f = dmc::DecodeFrame(m);
  RC_ASSERT(f.ok());
  RC_ASSERT(f.value().id == id);
  RC_ASSERT(f.value().type == type);
}

RC_GTEST_PROP(RepairMessage, AStackshotPacketIsSealedWithTheRightLength,
              (uint16_t command, uint8_t action, const std::vector<uint8_t>& data)) {
  const size_t n = std::min<size_t>(data.size(), stackshot::kMaxDataBytes);
  wire::Bytes m = {stackshot::kSyncHost, static_cast<uint8_t>(command >> 8),
                   static_cast<uint8_t>(command), action, static_cast<uint8_t>(n)};
  m.insert(m.end(), data.begin(), data.begin() + static_cast<ptrdiff_t>(n));
  m.push_back(0x00);  // a checksum that is most likely wrong
  wire::Info(Protocol::kStackshot).repair(m);
  const auto p = stackshot::DecodePacket(m);
  RC_ASSERT(p.ok());
  RC_ASSERT(p.value().command == command);
  RC_ASSERT(stackshot::ChecksumMatches(p.value(), stackshot::kDefaultChecksum));
  RC_ASSERT(p.value().data == wire::Bytes(data.begin(), data.begin() + static_cast<ptrdiff_t>(n)));
}

TEST(SessionMutator, SameSeedSameMutants) {
  const Seed s = LoadOrDie("dmc16-workflow.jsonl");
  SessionMutator a(Protocol::kDmc, 42), b(Protocol::kDmc, 42), c(Protocol::kDmc, 43);
  bool differs_from_other_seed = false;
  for (int i = 0; i < 50; ++i) {
    Messages ma = s.messages, mb = s.messages, mc = s.messages;
    a.Mutate(ma, {});
    b.Mutate(mb, {});
    c.Mutate(mc, {});
    EXPECT_EQ(ma, mb);
    EXPECT_EQ(a.last_mutations(), b.last_mutations());
    differs_from_other_seed = differs_from_other_seed || ma != mc;
  }
  EXPECT_TRUE(differs_from_other_seed);
}

TEST(SessionMutator, MostDmcMutantsStillFrameAndCheckSoTheyReachTheDevice) {
  const Seed s = LoadOrDie("dmc16-workflow.jsonl");
  SessionMutator mut(Protocol::kDmc, 7);
  size_t frames = 0, good = 0, changed = 0;
  for (int i = 0; i < 500; ++i) {
    Messages m = s.messages;
    mut.Mutate(m, {});
    changed += m != s.messages;
    for (const wire::Bytes& f : m) {
      ++frames;
      good += dmc::DecodeFrame(f).ok();
    }
  }
  // A few mutations change nothing (a swap of a message with itself, a
  // delete of the last message left).
  EXPECT_GE(changed, 450u);
  // Frames that do not decode: the one recorded damaged (1 in 28) and the
  // deliberately broken mutants (bad checksum, cut), a few percent together.
  EXPECT_GE(static_cast<double>(good) / static_cast<double>(frames), 0.90);
  EXPECT_LT(good, frames);
}

TEST(SessionMutator, MutantsStayWithinTheirBounds) {
  const Seed s = LoadOrDie("dfmoco-uno-workflow.jsonl");
  SessionMutator mut(Protocol::kDfmoco, 3);
  for (int i = 0; i < 2000; ++i) {
    Messages m = s.messages;
    for (int k = 0; k < 5; ++k) mut.Mutate(m, {s.messages});
    ASSERT_LE(m.size(), SessionMutator::kMaxMessages);
    for (const wire::Bytes& write : m) ASSERT_LE(write.size(), SessionMutator::kMaxBurstBytes);
  }
  // The protocol's own mutation keeps one line within the line bound.
  MutationSource source(3);
  for (int i = 0; i < 2000; ++i) {
    wire::Bytes line = s.messages[source.Below(s.messages.size())];
    for (int k = 0; k < 5; ++k) FindFuzzHooks(Protocol::kDfmoco)->mutate(source, line);
    ASSERT_LE(line.size(), DfmocoProtocol::kMaxFuzzLine + 2);
  }
}

// The timing mutation: a pause is an empty message, put in by a share of
// the mutations that set_pause_percent gives (a later mutation of the same
// mutant may take it out again); none at 0.
TEST(SessionMutator, PausesComeAtTheShareAskedFor) {
  const Seed s = LoadOrDie("dfmoco-uno-workflow.jsonl");
  for (const uint32_t percent : {0u, SessionMutator::kDefaultPausePercent, 30u}) {
    SessionMutator mut(Protocol::kDfmoco, 5);
    mut.set_pause_percent(percent);
    int with_pause = 0;
    for (int i = 0; i < 2000; ++i) {
      Messages m = s.messages;
      mut.Mutate(m, {});
      const bool noted =
          std::ranges::find(mut.last_mutations(), "pause") != mut.last_mutations().end();
      const bool has = std::ranges::find(m, wire::Bytes()) != m.end();
      if (has) {
        EXPECT_TRUE(noted) << "an empty message comes only from a pause";
      }
      with_pause += has;
    }
    // 1-4 mutations a mutant (2.5 on average).
    if (percent == 0) {
      EXPECT_EQ(with_pause, 0);
    } else if (percent == 1) {
      EXPECT_GT(with_pause, 10);
      EXPECT_LT(with_pause, 100);
    } else {
      EXPECT_GT(with_pause, 800);
    }
  }
}

// --- the executor -----------------------------------------------------------------------

// The golden session of each protocol and the emulated device it was recorded from.
struct RecordedCase {
  const char* file;
  Protocol protocol;
  const char* model;
};
constexpr RecordedCase kRecorded[] = {
    {"dmc16-workflow.jsonl", Protocol::kDmc, "dmc16"},
    {"dfmoco-uno-workflow.jsonl", Protocol::kDfmoco, "dfmoco"},
    {"stackshot3x-workflow.jsonl", Protocol::kStackshot, "stackshot3x"}};

TEST(FuzzExecutor, EveryRecordedSessionKeepsTheInvariants) {
  for (const RecordedCase& k : kRecorded) {
    FuzzExecutor ex(k.protocol, InProcessTarget::ForModel(k.model, ""));
    ASSERT_FALSE(ex.Open().has_value());
    const FuzzVerdict v = ex.Run(LoadOrDie(k.file).messages);
    EXPECT_TRUE(v.ok) << k.file << ": " << v.violation;
    EXPECT_GT(v.replies, 5u) << k.file;
  }
}

// Each protocol's run waits out a pause (an empty message) reading, and
// sends nothing: the session takes the pauses' time longer, and still keeps
// the invariants.
TEST(FuzzExecutor, EveryProtocolWaitsOutAPause) {
  for (const RecordedCase& k : kRecorded) {
    const TimeNs pause = FindFuzzHooks(k.protocol)->pause_ns;
    EXPECT_GE(pause, 100 * sim::kNsPerMs) << k.file;
    Messages messages = LoadOrDie(k.file).messages;
    FuzzExecutor plain(k.protocol, InProcessTarget::ForModel(k.model, ""));
    ASSERT_FALSE(plain.Open().has_value());
    const FuzzVerdict without = plain.Run(messages);
    messages.insert(messages.begin() + 2, 2, wire::Bytes());
    FuzzExecutor paused(k.protocol, InProcessTarget::ForModel(k.model, ""));
    ASSERT_FALSE(paused.Open().has_value());
    const FuzzVerdict with = paused.Run(messages);
    EXPECT_TRUE(with.ok) << k.file << ": " << with.violation;
    EXPECT_EQ(with.messages, without.messages) << k.file << ": a pause is no message";
    EXPECT_GE(with.simulated_ns, without.simulated_ns + 2 * pause - 20 * sim::kNsPerMs) << k.file;
  }
}

TEST(FuzzExecutor, ACampaignOverEveryProtocolFindsNoViolationInTheEmulator) {
  for (const RecordedCase& k : kRecorded) {
    FuzzExecutor ex(k.protocol, InProcessTarget::ForModel(k.model, ""));
    ASSERT_FALSE(ex.Open().has_value());
    FuzzOptions o;
    o.runs = 300;
    o.seed = 11;
    const FuzzReport r = RunFuzz(ex, k.protocol, {LoadOrDie(k.file)}, o);
    EXPECT_EQ(r.execs, 301u);
    for (const FuzzFailure& f : r.failures) ADD_FAILURE() << k.file << ": " << f.violation;
  }
}

// A DMC-16 that never answers MOTOR_STATUS: the ACK rule must catch it.
class MuteStatusDmc16 final : public devices::Device {
 public:
  MuteStatusDmc16(sim::Scheduler& s, devices::ByteSink& out)
      : filter_(out,
                [](const dmc::FrameRef& f, devices::ByteSink& to) {
                  const auto type = static_cast<uint16_t>(f.type & ~dmc::kFlagAck);
                  if (type == dmc::ToWire(dmc::MsgType::kMotorStatus)) return;  // dropped
                  to.Write(f.raw);
                }),
        inner_(devices::CreateDevice("dmc16", "", s, filter_)) {
    RelayLineSwitchesOf(*inner_);
  }
  std::string_view Model() const override { return "dmc16-mute-status"; }
  devices::DeviceLine Line() const override { return inner_->Line(); }
  void PowerOn() override { inner_->PowerOn(); }
  void PowerOff() override { inner_->PowerOff(); }
  bool Powered() const override { return inner_->Powered(); }
  void OnHostBytes(wire::ByteView bytes) override { inner_->OnHostBytes(bytes); }
  void OnHostLink(bool open) override { inner_->OnHostLink(open); }

 private:
  devices::FaultySink filter_;
  std::unique_ptr<devices::Device> inner_;
};

TEST(FuzzExecutor, ADeviceThatSwallowsAnAnswerIsCaughtAndTheMutantShrinks) {
  FuzzExecutor ex(Protocol::kDmc,
                  std::make_unique<InProcessTarget>(
                      "dmc16-mute-status", [](sim::Scheduler& s, devices::ByteSink& out) {
                        return std::make_unique<MuteStatusDmc16>(s, out);
                      }));
  ASSERT_FALSE(ex.Open().has_value());
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("mococheck-fuzz-test-" + std::to_string(getpid()));
  FuzzOptions o;
  o.runs = 20;
  o.crash_dir = dir.string();
  o.device = "dmc16";
  const FuzzReport r = RunFuzz(ex, Protocol::kDmc, {LoadOrDie("dmc16-workflow.jsonl")}, o);
  ASSERT_FALSE(r.failures.empty());
  const FuzzFailure& f = r.failures.front();
  EXPECT_NE(f.violation.find("DMC-ACK-001"), std::string::npos) << f.violation;
  // Shrunk to the one request that goes unanswered: MOTOR_STATUS.
  ASSERT_EQ(f.messages.size(), 1u);
  EXPECT_EQ(dmc::DecodeFrame(f.messages[0]).value().type, dmc::ToWire(dmc::MsgType::kMotorStatus));
  // Saved as a session that loads again with the same host message.
  auto again = LoadSeed(f.saved_path);
  ASSERT_TRUE(std::holds_alternative<Seed>(again)) << f.saved_path;
  EXPECT_EQ(std::get<Seed>(again).messages, f.messages);
  std::filesystem::remove_all(dir);
}

// --- replay -------------------------------------------------------------------------------

TEST(Replay, GoldenDeviceSessionsMatchTheirDevicesExactly) {
  for (const RecordedCase& k : kRecorded) {
    auto target = InProcessTarget::ForModel(k.model, "");
    ASSERT_FALSE(target->Open().has_value());
    const ReplayResult r = Replay(SessionOrDie(k.file), k.protocol, *target, {});
    EXPECT_TRUE(r.ok()) << k.file << "\n" << ReplayText(r);
    EXPECT_EQ(r.matched, r.expected_messages);
    EXPECT_GT(r.matched, 30u);
  }
}

// The workflow session with one recorded position report moved by `delta`
// steps on motor 1 (re-sealed), or with every device time after 1 s shifted.
session::Session Perturbed(int32_t delta, TimeNs shift_ns) {
  session::Session s = SessionOrDie("dmc16-workflow.jsonl");
  bool done = delta == 0;
  for (session::SessionEntry& e : s.entries) {
    if (e.is_event || e.from != session::Origin::kDevice) continue;
    if (e.t_ns > 1'000'000'000) e.t_ns += shift_ns;
    if (done) continue;
    auto f = dmc::DecodeFrame(e.bytes);
    if (!f.ok()) continue;
    auto m = dmc::DecodeDeviceMessage(f.value());
    if (!m.ok()) continue;
    auto* pos = std::get_if<dmc::MotorPositionReport>(&m.value());
    if (pos == nullptr || pos->positions_steps.empty() || pos->positions_steps[0] == 0) continue;
    pos->positions_steps[0] += delta;
    e.bytes = dmc::Encode(f.value().id, dmc::DeviceMessage{*pos});
    done = true;
  }
  EXPECT_TRUE(done);
  return s;
}

TEST(Replay, APositionOffByMoreThanTheToleranceIsADifference) {
  auto target = InProcessTarget::ForModel("dmc16", "");
  ASSERT_FALSE(target->Open().has_value());
  const session::Session s = Perturbed(3, 0);
  const ReplayResult strict = Replay(s, Protocol::kDmc, *target, {});
  ASSERT_EQ(strict.differences.size(), 1u) << ReplayText(strict);
  EXPECT_NE(strict.differences[0].why.find("3 steps off"), std::string::npos)
      << strict.differences[0].why;
  ReplayOptions loose;
  loose.position_steps = 3;
  EXPECT_TRUE(Replay(s, Protocol::kDmc, *target, loose).ok());
}

TEST(Replay, ALateMessageIsADifferenceUnlessWithinTheTimeTolerance) {
  auto target = InProcessTarget::ForModel("dmc16", "");
  ASSERT_FALSE(target->Open().has_value());
  const session::Session s = Perturbed(0, 4 * sim::kNsPerMs);
  const ReplayResult strict = Replay(s, Protocol::kDmc, *target, {});
  ASSERT_FALSE(strict.ok());
  EXPECT_NE(strict.differences[0].why.find("from the recorded time"), std::string::npos);
  ReplayOptions loose;
  loose.time_ms = 4;
  EXPECT_TRUE(Replay(s, Protocol::kDmc, *target, loose).ok())
      << ReplayText(Replay(s, Protocol::kDmc, *target, loose));
}

TEST(Replay, AnUnrecordedDeviceMessageIsADifferenceWhereItArrives) {
  session::Session s = SessionOrDie("dmc16-workflow.jsonl");
  // Drop the third recorded device chunk (one frame): the device will send it anyway.
  size_t seen = 0;
  for (auto it = s.entries.begin(); it != s.entries.end(); ++it) {
    if (!it->is_event && it->from == session::Origin::kDevice && ++seen == 3) {
      ASSERT_EQ(SplitDeviceChunks(Protocol::kDmc, {{it->t_ns, it->bytes}}).size(), 1u);
      s.entries.erase(it);
      break;
    }
  }
  auto target = InProcessTarget::ForModel("dmc16", "");
  ASSERT_FALSE(target->Open().has_value());
  const ReplayResult r = Replay(s, Protocol::kDmc, *target, {});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.differences.front().index, 2u) << ReplayText(r);
  EXPECT_EQ(r.observed_messages, r.expected_messages + 1);
}

}  // namespace
}  // namespace moco::conformance
