// Proving tests of the DFMoco error rules (DFM-ERR-*; FACTS "DFMoco": "A
// wrong argument count, an invalid motor, or `bf`/`go` while a motor moves
// answer `parse error`. 40 or more arguments answer `error: too many
// args`."): the real emulated sketch with one fault planted at the wire
// (dfmoco_broken_device_testing.h).
#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <string>

#include "conformance/protocols/dfmoco/dfmoco_broken_device_testing.h"

namespace moco::conformance::dfmoco_testing {
namespace {

using Lines = std::set<std::string>;

// Each `from` line the sketch writes goes out as `to`.
LineBreakage LineAs(std::string from, std::string to) {
  return [from, to](const std::string& line, const std::string&, sim::Scheduler&,
                    devices::ByteSink& out) { WriteLine(out, line == from ? to : line); };
}

TEST(DfmocoProofsErrors, TheSketchAnswersEveryErrorAsFactsSay) {
  ExpectTheSketchPasses(
      "errors/*", {"DFM-ERR-001", "DFM-ERR-002", "DFM-ERR-003", "DFM-ERR-004", "DFM-ERR-005"});
}

// The sketch's two error lines swapped one way: a wrong argument count
// answered `error: too many args`.
TEST(DfmocoProofsErrors, AWrongArgumentCountAnsweredTooManyArgsIsCaughtByErr001) {
  const RunReport r =
      RunBroken(LineAs("parse error", "error: too many args"), Only("errors/arguments"));
  ExpectCaught(r, "DFM-ERR-001");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// The sketch takes a motor above its axes for the last axis (the Uno's 4)
// in `sm` and `pr`, and answers for it: no `parse error`.
std::string MotorFiveReadAsFour(const std::string& line) {
  const auto f = Fields(line);
  if (f.size() >= 2 && (f[0] == "sm" || f[0] == "pr") && f[1] == "5") {
    return f[0] + " 4" + line.substr(f[0].size() + 2);
  }
  return line;
}

TEST(DfmocoProofsErrors, AMotorAboveTheAxesTakenAsTheLastIsCaughtByErr002) {
  const RunReport r = RunBroken(PassThrough, Only("errors/bad-motor"), {}, MotorFiveReadAsFour);
  ExpectCaught(r, "DFM-ERR-002");
  // Stopping a resting motor and setting its pulse rate move nothing.
  EXPECT_TRUE(FailedMusts(r).empty());
}

// The sketch's two error lines swapped the other way: 40 or more arguments
// answered `parse error`.
TEST(DfmocoProofsErrors, FortyArgumentsAnsweredParseErrorIsCaughtByErr003) {
  const RunReport r =
      RunBroken(LineAs("error: too many args", "parse error"), Only("errors/too-many-args"));
  ExpectCaught(r, "DFM-ERR-003");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// The sketch moves motor 4 on `mm 5 500` and still answers `parse error`.
std::string MoveFiveReadAsFour(const std::string& line) {
  return line == "mm 5 500" ? "mm 4 500" : line;
}
void MoveFourAnsweredAsRefused(const std::string& line, const std::string& last_command,
                               sim::Scheduler&, devices::ByteSink& out) {
  WriteLine(out, last_command == "mm 4 500" && line == "mm 4 500" ? "parse error" : line);
}

TEST(DfmocoProofsErrors, ARefusedCommandThatMovesAMotorIsCaughtByErr004) {
  const RunReport r =
      RunBroken(MoveFourAnsweredAsRefused, Only("errors/bad-motor"), {}, MoveFiveReadAsFour);
  ExpectCaught(r, "DFM-ERR-004");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-ERR-004"});
  // The answer is the right one: only the motion is wrong.
  EXPECT_EQ(r.rules.at("DFM-ERR-002").status, Status::kPass);
}

// After an unknown word (`zz`) the sketch refuses the next command it
// answers: its `ms` answer goes out as `parse error`.
std::pair<InputBreakage, LineBreakage> RefuseTheCommandAfterZz() {
  auto after_zz = std::make_shared<bool>(false);
  InputBreakage in = [after_zz](const std::string& line) {
    if (line == "zz") *after_zz = true;
    return line;
  };
  LineBreakage b = [after_zz](const std::string& line, const std::string&, sim::Scheduler&,
                              devices::ByteSink& out) {
    if (*after_zz && StartsWith(line, "ms")) {
      *after_zz = false;
      WriteLine(out, "parse error");
      return;
    }
    WriteLine(out, line);
  };
  return {in, b};
}

TEST(DfmocoProofsErrors, ACommandRefusedAfterAnUnknownWordIsCaughtByErr005) {
  const auto [in, b] = RefuseTheCommandAfterZz();
  const RunReport r = RunBroken(b, Only("errors/unknown"), {}, in);
  ExpectCaught(r, "DFM-ERR-005");
  // The refused `ms` also fails its own answer rule.
  EXPECT_EQ(FailedMusts(r), (Lines{"DFM-ERR-005", "DFM-MS-001"}));
  EXPECT_EQ(r.rules.at("DFM-REPLY-003").status, Status::kPass);
}

}  // namespace
}  // namespace moco::conformance::dfmoco_testing
