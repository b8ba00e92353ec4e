// `mococheck fuzz` against firmware under simavr (fuzz/executor.h): the
// firmware boots once, each run plays in a process forked from the booted
// state, the program counter's edges are counted into the coverage map, and
// firmware that stops is a finding of its own kind.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "conformance/fuzz/campaign.h"
#include "conformance/fuzz/executor.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

constexpr size_t kMap = size_t{64} << 10;

std::unique_ptr<Target> Firmware(const char* elf) {
  return std::make_unique<SimavrTarget>(SimavrSpec{elf, "", 0});
}

FuzzExecutor::Options Forked() {
  FuzzExecutor::Options o;
  o.fork = true;
  o.coverage_bytes = kMap;
  return o;
}

Messages Lines(std::initializer_list<const char*> lines) {
  Messages out;
  for (const char* l : lines) out.emplace_back(l, l + std::char_traits<char>::length(l));
  return out;
}

std::vector<uint8_t> Copy(std::span<const uint8_t> map) { return {map.begin(), map.end()}; }

size_t Reached(const std::vector<uint8_t>& map) {
  return static_cast<size_t>(std::count_if(map.begin(), map.end(), [](uint8_t c) { return c; }));
}

// A run starts where the boot left the firmware, whatever the run before did:
// the same session reaches the same edges the same number of times.
TEST(SimavrFuzz, EachForkedRunStartsFromTheBootedFirmwareAndCountsItsEdges) {
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  const Messages greet = Lines({"hi\r\n", "ms\r\n"});
  const Messages move = Lines({"hi\r\n", "pr 1 2000\r\n", "mm 1 400\r\n", "ms\r\n", "mp 1\r\n"});

  FuzzVerdict v = ex.Run(greet);
  ASSERT_TRUE(v.ok) << v.violation;
  const std::vector<uint8_t> first = Copy(ex.coverage());
  ASSERT_EQ(first.size(), kMap);
  EXPECT_GT(Reached(first), 50u) << "the boot's own code is not in a run's map; a run's is";

  v = ex.Run(move);
  ASSERT_TRUE(v.ok) << v.violation;
  const std::vector<uint8_t> moved = Copy(ex.coverage());
  EXPECT_GT(Reached(moved), Reached(first))
      << "a move runs the step and parse code a greeting does not";

  v = ex.Run(greet);
  ASSERT_TRUE(v.ok) << v.violation;
  EXPECT_EQ(Copy(ex.coverage()), first) << "the move's run left a trace in the next";
}

// The campaign keeps a mutant that reached new edges and mutates it further.
TEST(SimavrFuzz, ACampaignOnOurFirmwareGrowsItsCorpusAndFindsNothing) {
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  Seed seed;
  seed.path = "lines";
  seed.protocol = Protocol::kDfmoco;
  seed.messages = Lines(
      {"hi\r\n", "pr 1 3000\r\n", "mm 1 300\r\n", "ms\r\n", "mp 1\r\n", "zm 1\r\n", "sm 1\r\n"});
  FuzzOptions options;
  options.seed = 7;
  options.runs = 60;
  const FuzzReport r = RunFuzz(ex, Protocol::kDfmoco, {seed}, options);
  EXPECT_EQ(r.execs, 61u);
  for (const FuzzFailure& f : r.failures) ADD_FAILURE() << f.violation;
  EXPECT_TRUE(r.coverage);
  EXPECT_GT(r.edges, 100u);
  EXPECT_GT(r.corpus, 1u) << "no mutant of 60 reached an edge the seed did not";
}

// Firmware that stops (here: it says "bye" and sleeps with interrupts off) is
// a finding of its own kind, named as the target names it; forking from a
// firmware that stops while it boots (before its greeting's line has ended) is
// refused with the reason.
TEST(SimavrFuzz, FirmwareThatStopsIsAFindingOfItsOwnKind) {
  FuzzExecutor::Options here;
  here.coverage_bytes = kMap;
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_HALT_ELF), here);
  ASSERT_EQ(ex.Open(), std::nullopt);
  const FuzzVerdict v = ex.Run(Lines({"hi\r\n"}));
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.kind, FuzzVerdict::Kind::kFirmwareStopped);
  EXPECT_NE(v.violation.find("the firmware stopped: the core halted"), std::string::npos)
      << v.violation;
  EXPECT_EQ(FindingKindName(v.kind), "firmware-stopped");

  FuzzExecutor forked(Protocol::kDfmoco, Firmware(MOCO_HALT_ELF), Forked());
  const auto err = forked.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("the firmware stopped while it booted: the core halted"), std::string::npos)
      << *err;
}

// A stack that grows into .data/.bss stops the firmware: the planted bug
// clamps an over-fast pulse rate by recursion, a frame per step/s too many.
// The same session on the firmware without the bug stops nothing.
TEST(SimavrFuzz, AStackOverflowIsFoundAsTheFirmwareStoppingWithWhere) {
  const Messages session = Lines({"hi\r\n", "pr 1 30000\r\n", "ms\r\n"});
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_BUG_RECURSIVE_CLAMP_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  const FuzzVerdict v = ex.Run(session);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.kind, FuzzVerdict::Kind::kFirmwareStopped);
  EXPECT_NE(v.violation.find("the stack ran into .data/.bss"), std::string::npos) << v.violation;
  EXPECT_NE(v.violation.find("pc 0x"), std::string::npos) << v.violation;
  EXPECT_TRUE(ex.Run(Lines({"hi\r\n", "pr 1 20000\r\n"})).ok) << "a rate within the limit";

  FuzzExecutor good(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(good.Open(), std::nullopt);
  const FuzzVerdict clamped = good.Run(session);
  EXPECT_TRUE(clamped.ok) << clamped.violation;
}

// Fuzzing needs a device in virtual time and coverage a target that sees code.
TEST(SimavrFuzz, AnExecutorRefusesWhatItCannotFuzz) {
  FuzzExecutor::Options o;
  o.coverage_bytes = 1000;
  FuzzExecutor odd(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), o);
  const auto err = odd.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("not a power of two"), std::string::npos) << *err;

  FuzzExecutor::Options covered;
  covered.coverage_bytes = kMap;
  FuzzExecutor emulated(Protocol::kDfmoco, InProcessTarget::ForModel("dfmoco", ""), covered);
  const auto no_code = emulated.Open();
  ASSERT_TRUE(no_code.has_value());
  EXPECT_NE(no_code->find("cannot observe its device's code"), std::string::npos) << *no_code;
}

}  // namespace
}  // namespace moco::conformance
