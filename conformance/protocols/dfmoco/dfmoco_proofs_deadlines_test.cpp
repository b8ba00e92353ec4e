// Proving tests of the DFMoco reply deadlines and the outgoing queue
// (DFM-DL-*, DFM-QUEUE-001; dfmoco-protocol.txt "Messages", "Notes"; FACTS
// "DFMoco"): the real emulated sketch with one fault planted at the wire
// (dfmoco_broken_device_testing.h). An answer held back is written later in
// virtual time by the filter; nothing is timed by the wall clock.
#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <string>

#include "conformance/protocols/dfmoco/dfmoco_broken_device_testing.h"

namespace moco::conformance::dfmoco_testing {
namespace {

using Lines = std::set<std::string>;

// Past the default deadline of 250 ms (--deadline-ms), well inside the
// answer timeout of 2 s: late, not missing.
constexpr sim::TimeNs kLateNs = 400 * sim::kNsPerMs;

// Each answer starting with `answer` to a command starting with `word` goes
// out 400 ms after the sketch wrote it.
LineBreakage AnswersLate(std::string word, std::string answer) {
  return [word, answer](const std::string& line, const std::string& last_command, sim::Scheduler& s,
                        devices::ByteSink& out) {
    if (StartsWith(last_command, word) && StartsWith(line, answer)) {
      s.After(kLateNs, [&out, line] { WriteLine(out, line); });
      return;
    }
    WriteLine(out, line);
  };
}

TEST(DfmocoProofsDeadlines, TheSketchMeetsEveryDeadlineAndAnswersTheBatch) {
  ExpectTheSketchPasses(
      "connect/hi,connect/queries,connect/pipelined,motor/pulse-rate,gomotion/blur",
      {"DFM-DL-001", "DFM-DL-002", "DFM-DL-003", "DFM-DL-004", "DFM-QUEUE-001"});
}

TEST(DfmocoProofsDeadlines, HiAnsweredLateIsCaughtByDl001) {
  const RunReport r = RunBroken(AnswersLate("hi", "hi"), Only("connect/hi"));
  ExpectCaught(r, "DFM-DL-001");
  EXPECT_TRUE(FailedMusts(r).empty());
}

TEST(DfmocoProofsDeadlines, MsAnsweredLateIsCaughtByDl002) {
  const RunReport r = RunBroken(AnswersLate("ms", "ms"), Only("connect/queries"));
  ExpectCaught(r, "DFM-DL-002");
  EXPECT_TRUE(FailedMusts(r).empty());
  EXPECT_EQ(r.rules.at("DFM-DL-001").status, Status::kPass);
}

TEST(DfmocoProofsDeadlines, PrAnsweredLateIsCaughtByDl003) {
  const RunReport r = RunBroken(AnswersLate("pr", "pr"), Only("motor/pulse-rate"));
  ExpectCaught(r, "DFM-DL-003");
  EXPECT_TRUE(FailedMusts(r).empty());
  EXPECT_EQ(r.rules.at("DFM-DL-002").status, Status::kPass);
}

// Only the answer is late: the sketch starts the move when `go` arrives, so
// the go-motion keeps its timing (DFM-GO-006 holds).
TEST(DfmocoProofsDeadlines, GoAnsweredLateIsCaughtByDl004) {
  const RunReport r = RunBroken(AnswersLate("go", "go"), Only("gomotion/blur"));
  ExpectCaught(r, "DFM-DL-004");
  EXPECT_TRUE(FailedMusts(r).empty());
  EXPECT_EQ(r.rules.at("DFM-GO-006").status, Status::kPass);
}

TEST(DfmocoProofsDeadlines, BfAnsweredLateIsCaughtByDl004) {
  const RunReport r = RunBroken(AnswersLate("bf", "bf"), Only("gomotion/blur"));
  ExpectCaught(r, "DFM-DL-004");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// A device whose queue holds eleven answers: of the twelve commands of one
// write (the last is `mp 4` on the Uno) the last answer is dropped.
LineBreakage DropTheTwelfthAnswer() {
  auto dropped = std::make_shared<bool>(false);
  return [dropped](const std::string& line, const std::string&, sim::Scheduler&,
                   devices::ByteSink& out) {
    if (!*dropped && StartsWith(line, "mp 4")) {
      *dropped = true;
      return;
    }
    WriteLine(out, line);
  };
}

TEST(DfmocoProofsDeadlines, OneOfTwelveAnswersDroppedIsCaughtByQueue001) {
  const RunReport r = RunBroken(DropTheTwelfthAnswer(), Only("connect/pipelined"));
  ExpectCaught(r, "DFM-QUEUE-001");
  // The command without an answer is also unanswered; the others keep their order.
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-REPLY-001"});
  EXPECT_EQ(r.rules.at("DFM-REPLY-004").status, Status::kPass);
}

}  // namespace
}  // namespace moco::conformance::dfmoco_testing
