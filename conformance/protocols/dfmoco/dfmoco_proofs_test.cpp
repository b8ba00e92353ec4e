// Proving tests of the DFMoco rules (dfmoco-protocol.txt; ERRATA dfmoco;
// FACTS "DFMoco"): the real emulated sketch with one fault planted at the
// wire (dfmoco_broken_device_testing.h), and the rule that names the fault
// failing with evidence. Faults live in the wire filter only, so the device
// code stays the sketch.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>

#include "conformance/protocols/dfmoco/dfmoco_broken_device_testing.h"

namespace moco::conformance::dfmoco_testing {
namespace {

using Lines = std::set<std::string>;

// ------------------------------------------------------------- lines

// "Messages are in ASCII text, with trailing \r\n": lines end in a bare \n.
void EndLinesWithBareLf(const std::string& line, const std::string&, sim::Scheduler&,
                        devices::ByteSink& out) {
  Write(out, line + "\n");
}

TEST(DfmocoProofs, BareLfLineEndsAreCaughtByLine001) {
  const RunReport r = RunBroken(EndLinesWithBareLf, Only("connect/*"));
  ExpectCaught(r, "DFM-LINE-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-LINE-001"});
}

// An Arduino that emits a NUL byte ahead of its boot `hi`.
void NulBeforeTheBootHi(const std::string& line, const std::string& last_command, sim::Scheduler&,
                        devices::ByteSink& out) {
  if (last_command.empty() && StartsWith(line, "hi")) {
    Write(out, std::string(1, '\0') + line + "\r\n");
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, ANulByteInALineIsCaughtByLine002) {
  const RunReport r = RunBroken(NulBeforeTheBootHi, Only("connect/*"));
  ExpectCaught(r, "DFM-LINE-002");
  // The line is no reply of the grammar either.
  EXPECT_EQ(FailedMusts(r), (Lines{"DFM-LINE-002", "DFM-LINE-004"}));
}

// The device stops half way through its answer to `mp 4` (the last command
// of connect/queries on the Uno's 4 motors) and never finishes the line.
void BreakOffTheLastAnswer(const std::string& line, const std::string& last_command,
                           sim::Scheduler&, devices::ByteSink& out) {
  if (last_command == "mp 4" && StartsWith(line, "mp")) {
    Write(out, line.substr(0, 3));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, ALineBrokenOffIsCaughtByLine003) {
  const RunReport r = RunBroken(BreakOffTheLastAnswer, Only("connect/queries"));
  ExpectCaught(r, "DFM-LINE-003");
  // The command whose answer was broken off is also unanswered.
  EXPECT_EQ(FailedMusts(r), (Lines{"DFM-LINE-003", "DFM-REPLY-001", "DFM-MP-001"}));
}

// Replies padded with a trailing space ("EXAMPLE: hi 1 8 1.2.7" has none).
void TrailingSpace(const std::string& line, const std::string&, sim::Scheduler&,
                   devices::ByteSink& out) {
  WriteLine(out, line + " ");
}

TEST(DfmocoProofs, ATrailingSpaceIsCaughtByLine006) {
  const RunReport r = RunBroken(TrailingSpace, Only("connect/*"));
  ExpectCaught(r, "DFM-LINE-006");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// ------------------------------------------------------------- hello

// The sketch keeps quiet at boot: its unprompted `hi` is dropped.
void NoBootHi(const std::string& line, const std::string& last_command, sim::Scheduler&,
              devices::ByteSink& out) {
  if (last_command.empty() && StartsWith(line, "hi")) return;
  WriteLine(out, line);
}

TEST(DfmocoProofs, NoUnpromptedHiAtBootIsCaughtByHi001) {
  const RunReport r = RunBroken(NoBootHi, Only("connect/*"));
  ExpectCaught(r, "DFM-HI-001");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// A sketch that waits for a newline in setup() and so swallows the first line
// after every start: its first `hi` goes unanswered. The host asks again
// after its timeout, as Dragonframe does; the miss fails the introduction's
// own rule and everything else is judged.
TEST(DfmocoProofs, AFirstHiSwallowedAtStartIsCaughtByHi008AndTheRestIsJudged) {
  const RunReport r = RunBroken(PassThrough, Only("connect/*"), {},
                                [swallowed = false](const std::string& line) mutable {
                                  if (swallowed) return line;
                                  swallowed = true;
                                  return std::string();
                                });
  ExpectCaught(r, "DFM-HI-008");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-HI-008"});
  EXPECT_FALSE(r.device.empty());
  EXPECT_EQ(r.rules.at("DFM-HI-002").status, Status::kPass);
  EXPECT_NE(r.rules.at("DFM-REPLY-001").status, Status::kFail);
  ASSERT_FALSE(r.cases.empty());
  EXPECT_EQ(r.cases.front().suite + "/" + r.cases.front().name, "connect/introduction");
  for (const CaseResult& c : r.cases) EXPECT_TRUE(c.applicable) << c.suite << "/" << c.name;
}

// Every `hi` line rewritten to `to`.
LineBreakage HiAs(std::string to) {
  return [to](const std::string& line, const std::string&, sim::Scheduler&,
              devices::ByteSink& out) { WriteLine(out, StartsWith(line, "hi") ? to : line); };
}

TEST(DfmocoProofs, AHiWithoutTheVersionIsCaughtByHi002) {
  const RunReport r = RunBroken(HiAs("hi 2 4"), Only("connect/*"));
  ExpectCaught(r, "DFM-HI-002");
}

TEST(DfmocoProofs, AMajorVersionOtherThanTheVersionsLeadIsCaughtByHi003) {
  const RunReport r = RunBroken(HiAs("hi 3 4 2.0.0"), Only("connect/*"));
  ExpectCaught(r, "DFM-HI-003");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-HI-003"});
}

TEST(DfmocoProofs, NoAxesAreCaughtByHi004) {
  const RunReport r = RunBroken(HiAs("hi 2 0 2.0.0"), Only("connect/*"));
  ExpectCaught(r, "DFM-HI-004");
}

TEST(DfmocoProofs, AVersionThatIsNotDottedDecimalIsCaughtByHi005) {
  const RunReport r = RunBroken(HiAs("hi 2 4 2.0.0-rc1"), Only("connect/*"));
  ExpectCaught(r, "DFM-HI-005");
}

// The `hi` answered on request names another version than the boot `hi`.
void AnotherHiOnRequest(const std::string& line, const std::string& last_command, sim::Scheduler&,
                        devices::ByteSink& out) {
  WriteLine(out, !last_command.empty() && StartsWith(line, "hi") ? "hi 2 4 2.0.1" : line);
}

TEST(DfmocoProofs, AHiThatChangesIsCaughtByHi006) {
  const RunReport r = RunBroken(AnotherHiOnRequest, Only("connect/*"));
  ExpectCaught(r, "DFM-HI-006");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-HI-006"});
}

// ------------------------------------------------------------- one reply per command

// Every `ms` answer sent twice.
void EveryMsTwice(const std::string& line, const std::string&, sim::Scheduler&,
                  devices::ByteSink& out) {
  WriteLine(out, line);
  if (StartsWith(line, "ms")) WriteLine(out, line);
}

TEST(DfmocoProofs, AnAnswerSentTwiceIsCaughtByReply002) {
  const RunReport r = RunBroken(EveryMsTwice, Only("connect/queries"));
  ExpectCaught(r, "DFM-REPLY-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-REPLY-002"});
}

// The sketch reads the unknown word `zz` as `sa` and answers it.
std::string ZzReadAsSa(const std::string& line) { return line == "zz" ? "sa" : line; }

TEST(DfmocoProofs, AnAnswerToAnUnknownWordIsCaughtByReply003) {
  const RunReport r = RunBroken(PassThrough, Only("errors/unknown"), {}, ZzReadAsSa);
  ExpectCaught(r, "DFM-REPLY-003");
}

// Each `pr` answer held back and sent after the line that follows it.
LineBreakage PrAnswersSwappedWithTheNext() {
  auto held = std::make_shared<std::string>();
  return
      [held](const std::string& line, const std::string&, sim::Scheduler&, devices::ByteSink& out) {
        if (held->empty() && StartsWith(line, "pr")) {
          *held = line;
          return;
        }
        WriteLine(out, line);
        if (!held->empty()) WriteLine(out, *held);
        held->clear();
      };
}

TEST(DfmocoProofs, AnswersOutOfOrderAreCaughtByReply004) {
  const RunReport r = RunBroken(PrAnswersSwappedWithTheNext(), Only("connect/pipelined"));
  ExpectCaught(r, "DFM-REPLY-004");
}

// `pr 1 v` answered for motor 2.
void PrAnswerForMotorTwo(const std::string& line, const std::string&, sim::Scheduler&,
                         devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "pr" && f[1] == "1") {
    WriteLine(out, "pr 2 " + f[2]);
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AnAnswerNamingAnotherMotorIsCaughtByReply005) {
  const RunReport r = RunBroken(PrAnswerForMotorTwo, Only("connect/pipelined"));
  ExpectCaught(r, "DFM-REPLY-005");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-REPLY-005"});
}

// ------------------------------------------------------------- motor status

// `ms` digits separated by spaces (ERRATA 2.3: "no spaces").
void SpacedMsDigits(const std::string& line, const std::string&, sim::Scheduler&,
                    devices::ByteSink& out) {
  if (!StartsWith(line, "ms")) {
    WriteLine(out, line);
    return;
  }
  std::string spaced = "ms";
  for (const char d : line.substr(3)) spaced += std::string(" ") + d;
  WriteLine(out, spaced);
}

TEST(DfmocoProofs, SpacedMsDigitsAreCaughtByMs001) {
  const RunReport r = RunBroken(SpacedMsDigits, Only("connect/queries"));
  ExpectCaught(r, "DFM-MS-001");
}

// Every `ms` digit forced to `digit` (motor 1 only when `first_only`).
LineBreakage MsDigitsAs(char digit, bool first_only) {
  return [=](const std::string& line, const std::string&, sim::Scheduler&, devices::ByteSink& out) {
    std::string l = line;
    if (StartsWith(l, "ms")) {
      for (size_t i = 3; i < l.size() && (!first_only || i == 3); ++i) l[i] = digit;
    }
    WriteLine(out, l);
  };
}

TEST(DfmocoProofs, MsShowingRestWhileAMotorMovesIsCaughtByMs003) {
  const RunReport r = RunBroken(MsDigitsAs('0', false), Only("motor/move"));
  ExpectCaught(r, "DFM-MS-003");
}

TEST(DfmocoProofs, MsShowingAMotorMovingAtRestIsCaughtByMs004) {
  const RunReport r = RunBroken(MsDigitsAs('1', true), Only("connect/queries"));
  ExpectCaught(r, "DFM-MS-004");
}

// ------------------------------------------------------------- move motor

// `mm m p` answered with p + 1.
void MmAnswerOffByOne(const std::string& line, const std::string&, sim::Scheduler&,
                      devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "mm") {
    WriteLine(out, "mm " + f[1] + " " + std::to_string(std::stol(f[2]) + 1));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AnMmAnswerWithAnotherTargetIsCaughtByMm001) {
  const RunReport r = RunBroken(MmAnswerOffByOne, Only("motor/move"));
  ExpectCaught(r, "DFM-MM-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-MM-001"});
}

// `mm m p` to where the motor rests answered `mm m p`, not `mp m p`.
void MmAnswerWhenAlreadyThere(const std::string& line, const std::string& last_command,
                              sim::Scheduler&, devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "mp" && last_command == "mm " + f[1] + " " + f[2]) {
    WriteLine(out, "mm " + f[1] + " " + f[2]);
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, MmAnsweredMmWhenAlreadyThereIsCaughtByMm002) {
  const RunReport r = RunBroken(MmAnswerWhenAlreadyThere, Only("motor/move"));
  ExpectCaught(r, "DFM-MM-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-MM-002"});
}

// The sketch drives a motor 7 steps past the target of `mm` and answers with
// the target commanded.
constexpr int32_t kOvershoot = 7;
std::string MmTargetPlusSeven(const std::string& line) {
  const auto f = Fields(line);
  if (f.size() != 3 || f[0] != "mm") return line;
  return "mm " + f[1] + " " + std::to_string(std::stol(f[2]) + kOvershoot);
}
void MmAnswerAsCommanded(const std::string& line, const std::string&, sim::Scheduler&,
                         devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "mm") {
    WriteLine(out, "mm " + f[1] + " " + std::to_string(std::stol(f[2]) - kOvershoot));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AMotorRestingPastItsTargetIsCaughtByMm003) {
  const RunReport r = RunBroken(MmAnswerAsCommanded, Only("motor/move"), {}, MmTargetPlusSeven);
  ExpectCaught(r, "DFM-MM-003");
}

// ------------------------------------------------------------- motor position

// Whether `line` is an unprompted `mp` report: no `mp`, `mm`, `np` or `zm`
// the host sent last asks for it.
bool IsReport(const std::string& line, const std::string& last_command) {
  const auto f = Fields(line);
  if (f.size() != 3 || f[0] != "mp") return false;
  const auto c = Fields(last_command);
  return !(c.size() >= 2 && c[1] == f[1] &&
           (c[0] == "mp" || c[0] == "mm" || c[0] == "np" || c[0] == "zm"));
}

// `mp m` answered one step off where the motor is.
void MpAnswerOffByOne(const std::string& line, const std::string& last_command, sim::Scheduler&,
                      devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "mp" && last_command == "mp " + f[1]) {
    WriteLine(out, "mp " + f[1] + " " + std::to_string(std::stol(f[2]) + 1));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AnMpAnswerOffTheRestingPositionIsCaughtByMp001) {
  const RunReport r = RunBroken(MpAnswerOffByOne, Only("motor/move"));
  ExpectCaught(r, "DFM-MP-001");
}

// No unprompted `mp` reports at all.
void NoReports(const std::string& line, const std::string& last_command, sim::Scheduler&,
               devices::ByteSink& out) {
  if (IsReport(line, last_command)) return;
  WriteLine(out, line);
}

TEST(DfmocoProofs, NoReportsWhileMovingAreCaughtByMp002) {
  const RunReport r = RunBroken(NoReports, Only("motor/move"));
  ExpectCaught(r, "DFM-MP-002");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// Unprompted reports carry a position far off the motor's path.
void ReportsOffThePath(const std::string& line, const std::string& last_command, sim::Scheduler&,
                       devices::ByteSink& out) {
  if (IsReport(line, last_command)) {
    const auto f = Fields(line);
    WriteLine(out, "mp " + f[1] + " " + std::to_string(std::stol(f[2]) + 100000));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AReportOffTheMotorsPathIsCaughtByMp006) {
  const RunReport r = RunBroken(ReportsOffThePath, Only("motor/move"));
  ExpectCaught(r, "DFM-MP-006");
}

// A report of motor 1 sent 2.5 s after each answer to `mp 4`, every motor at
// rest.
void AReportAtRest(const std::string& line, const std::string& last_command, sim::Scheduler& s,
                   devices::ByteSink& out) {
  WriteLine(out, line);
  if (last_command == "mp 4" && StartsWith(line, "mp 4")) {
    s.After(2500 * sim::kNsPerMs, [&out] { WriteLine(out, "mp 1 0"); });
  }
}

TEST(DfmocoProofs, AReportWhileEveryMotorRestsIsCaughtByMp007) {
  const RunReport r = RunBroken(AReportAtRest, Only("connect/queries"));
  ExpectCaught(r, "DFM-MP-007");
  EXPECT_TRUE(FailedMusts(r).empty());
}

// ------------------------------------------------------------- new position, zero

// The answer to each command `word ...` (its first line starting with
// `answer`) sent as `parse error`; any further such lines dropped.
LineBreakage RefuseEvery(std::string word, std::string answer) {
  auto refused = std::make_shared<bool>(false);
  return [word, answer, refused](const std::string& line, const std::string& last_command,
                                 sim::Scheduler&, devices::ByteSink& out) {
    if (!StartsWith(last_command, word)) {
      *refused = false;
    } else if (StartsWith(line, answer)) {
      if (!*refused) WriteLine(out, "parse error");
      *refused = true;
      return;
    }
    WriteLine(out, line);
  };
}

TEST(DfmocoProofs, AnNpRefusedIsCaughtByNp001) {
  const RunReport r = RunBroken(RefuseEvery("np", "mp"), Only("motor/np-zm"));
  ExpectCaught(r, "DFM-NP-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-NP-001"});
}

// The sketch sets one step more than `np m p` asks and answers with p.
std::string NpOneStepMore(const std::string& line) {
  const auto f = Fields(line);
  if (f.size() != 3 || f[0] != "np") return line;
  return "np " + f[1] + " " + std::to_string(std::stol(f[2]) + 1);
}
void NpAnswerAsCommanded(const std::string& line, const std::string& last_command, sim::Scheduler&,
                         devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "mp" && StartsWith(last_command, "np") &&
      last_command == "np " + f[1] + " " + f[2]) {
    WriteLine(out, "mp " + f[1] + " " + std::to_string(std::stol(f[2]) - 1));
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AnNpSettingAnotherPositionIsCaughtByNp002) {
  const RunReport r = RunBroken(NpAnswerAsCommanded, Only("motor/np-zm"), {}, NpOneStepMore);
  ExpectCaught(r, "DFM-NP-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-NP-002"});
}

TEST(DfmocoProofs, AZmRefusedIsCaughtByZm001) {
  const RunReport r = RunBroken(RefuseEvery("zm", "mp"), Only("motor/np-zm"));
  ExpectCaught(r, "DFM-ZM-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-ZM-001"});
}

// The sketch reads `zm 1` as `np 1 7` and answers `mp 1 0`.
std::string ZmReadAsNpSeven(const std::string& line) { return line == "zm 1" ? "np 1 7" : line; }
void NpSevenAnsweredAsZero(const std::string& line, const std::string& last_command,
                           sim::Scheduler&, devices::ByteSink& out) {
  WriteLine(out, last_command == "np 1 7" && line == "mp 1 7" ? "mp 1 0" : line);
}

TEST(DfmocoProofs, AZmLeavingTheMotorOffZeroIsCaughtByZm002) {
  const RunReport r = RunBroken(NpSevenAnsweredAsZero, Only("motor/np-zm"), {}, ZmReadAsNpSeven);
  ExpectCaught(r, "DFM-ZM-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-ZM-002"});
}

// ------------------------------------------------------------- stop motor

TEST(DfmocoProofs, AnSmRefusedIsCaughtBySm001) {
  const RunReport r = RunBroken(RefuseEvery("sm", "sm"), Only("motor/stop"));
  ExpectCaught(r, "DFM-SM-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-SM-001"});
}

// The sketch reads `from` as `to` and answers `to`'s echo as `answer`.
struct Misread {
  std::string from, to, echo, answer;
};
std::string ReadAs(const Misread& m, const std::string& line) {
  return line == m.from ? m.to : line;
}
LineBreakage AnswerAs(const Misread& m) {
  return [m](const std::string& line, const std::string& last_command, sim::Scheduler&,
             devices::ByteSink& out) {
    WriteLine(out, last_command == m.to && line == m.echo ? m.answer : line);
  };
}
RunReport RunMisread(const Misread& m, const char* cases) {
  return RunBroken(AnswerAs(m), Only(cases), {},
                   [m](const std::string& line) { return ReadAs(m, line); });
}

TEST(DfmocoProofs, AnSmThatDoesNotStopIsCaughtBySm002) {
  const RunReport r = RunMisread({"sm 1", "pr 1 4999", "pr 1 4999", "sm 1"}, "motor/stop");
  ExpectCaught(r, "DFM-SM-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-SM-002"});
}

// Once `sm 1` is sent, the `ms` answers show motor 2 at rest as well.
LineBreakage MotorTwoRestsAfterSm() {
  auto stopped = std::make_shared<bool>(false);
  return [stopped](const std::string& line, const std::string& last_command, sim::Scheduler&,
                   devices::ByteSink& out) {
    if (last_command == "sm 1") *stopped = true;
    std::string l = line;
    if (*stopped && StartsWith(l, "ms") && l.size() > 4) l[4] = '0';
    WriteLine(out, l);
  };
}

TEST(DfmocoProofs, AnSmStoppingEveryMotorIsCaughtBySm003) {
  const RunReport r = RunBroken(MotorTwoRestsAfterSm(), Only("motor/stop"));
  ExpectCaught(r, "DFM-SM-003");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-SM-003"});
}

// ------------------------------------------------------------- stop all

TEST(DfmocoProofs, AnSaRefusedIsCaughtBySa001) {
  const RunReport r = RunBroken(RefuseEvery("sa", "sa"), Only("motor/stop-all"));
  ExpectCaught(r, "DFM-SA-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-SA-001"});
}

TEST(DfmocoProofs, AnSaStoppingOneMotorIsCaughtBySa002) {
  const RunReport r = RunMisread({"sa", "sm 1", "sm 1", "sa"}, "motor/stop-all");
  ExpectCaught(r, "DFM-SA-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-SA-002"});
}

// ------------------------------------------------------------- pulse rate

TEST(DfmocoProofs, APrAnswerWithAnotherRateIsCaughtByPr001) {
  const RunReport r =
      RunMisread({"pr 1 1000", "pr 1 1000", "pr 1 1000", "pr 1 999"}, "motor/pulse-rate");
  ExpectCaught(r, "DFM-PR-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-PR-001"});
}

TEST(DfmocoProofs, AnUnclampedPrAnswerIsCaughtByPr002) {
  const RunReport r = RunMisread({"pr 1 50", "pr 1 50", "pr 1 100", "pr 1 50"}, "motor/pulse-rate");
  ExpectCaught(r, "DFM-PR-002");
  EXPECT_TRUE(FailedMusts(r).empty());
}

TEST(DfmocoProofs, AMotorFasterThanItsPulseRateIsCaughtByPr003) {
  const RunReport r =
      RunMisread({"pr 1 1000", "pr 1 19999", "pr 1 19999", "pr 1 1000"}, "motor/pulse-rate");
  ExpectCaught(r, "DFM-PR-003");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-PR-003"});
}

// ------------------------------------------------------------- motor numbers

// `pr 1 v` answered for motor 5, one above the Uno's 4 axes.
void PrAnswerForMotorFive(const std::string& line, const std::string&, sim::Scheduler&,
                          devices::ByteSink& out) {
  const auto f = Fields(line);
  if (f.size() == 3 && f[0] == "pr" && f[1] == "1") {
    WriteLine(out, "pr 5 " + f[2]);
    return;
  }
  WriteLine(out, line);
}

TEST(DfmocoProofs, AMotorAboveTheAxesIsCaughtByMotor001) {
  const RunReport r = RunBroken(PrAnswerForMotorFive, Only("motor/pulse-rate"));
  ExpectCaught(r, "DFM-MOTOR-001");
  EXPECT_EQ(FailedMusts(r), (Lines{"DFM-MOTOR-001", "DFM-REPLY-005"}));
}

// The sketch reads `np 1 p` as `np 1 p` and `np 2 555`, and keeps the second
// answer to itself.
std::string NpAlsoSetsMotorTwo(const std::string& line) {
  return StartsWith(line, "np 1") ? line + "\r\nnp 2 555" : line;
}
void NoMotorTwoAnswer(const std::string& line, const std::string& last_command, sim::Scheduler&,
                      devices::ByteSink& out) {
  if (last_command == "np 2 555" && line == "mp 2 555") return;
  WriteLine(out, line);
}

TEST(DfmocoProofs, ACommandShiftingAnotherMotorIsCaughtByMotor002) {
  const RunReport r = RunBroken(NoMotorTwoAnswer, Only("motor/np-zm"), {}, NpAlsoSetsMotorTwo);
  ExpectCaught(r, "DFM-MOTOR-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-MOTOR-002"});
}

// ------------------------------------------------------------- jog

TEST(DfmocoProofs, AJmRefusedIsCaughtByJm001) {
  const RunReport r = RunBroken(RefuseEvery("jm", "jm"), Only("motor/jog"));
  ExpectCaught(r, "DFM-JM-001");
  EXPECT_EQ(FailedMusts(r), (Lines{"DFM-JM-001", "DFM-JM-003"}));
}

// The sketch jogs 50 steps past the destination of `jm m dest`.
std::string JogFiftyPast(const std::string& line) {
  const auto f = Fields(line);
  if (f.size() != 3 || f[0] != "jm") return line;
  return "jm " + f[1] + " " + std::to_string(std::stol(f[2]) + 50);
}

TEST(DfmocoProofs, AJogPastItsDestinationIsCaughtByJm002) {
  const RunReport r = RunBroken(PassThrough, Only("motor/jog"), {}, JogFiftyPast);
  ExpectCaught(r, "DFM-JM-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-JM-002"});
}

// `jm m dest v` answered `parse error`.
void JogVelocityRefused(const std::string& line, const std::string& last_command, sim::Scheduler&,
                        devices::ByteSink& out) {
  WriteLine(out, Fields(last_command).size() == 4 && StartsWith(last_command, "jm") &&
                         StartsWith(line, "jm")
                     ? "parse error"
                     : line);
}

TEST(DfmocoProofs, AJogVelocityRefusedIsCaughtByJm003) {
  const RunReport r = RunBroken(JogVelocityRefused, Only("motor/jog"));
  ExpectCaught(r, "DFM-JM-003");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-JM-003"});
}

// ------------------------------------------------------------- inch

TEST(DfmocoProofs, AnImRefusedIsCaughtByIm001) {
  const RunReport r = RunBroken(RefuseEvery("im", "im"), Only("motor/inch"));
  ExpectCaught(r, "DFM-IM-001");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-IM-001"});
}

// The sketch reads `im 1 dest` as `sm 1` and answers `im 1`: nothing moves.
std::string InchReadAsStop(const std::string& line) {
  return StartsWith(line, "im 1") ? "sm 1" : line;
}
void StopAnsweredAsInch(const std::string& line, const std::string& last_command, sim::Scheduler&,
                        devices::ByteSink& out) {
  WriteLine(out, last_command == "sm 1" && line == "sm 1" ? "im 1" : line);
}

TEST(DfmocoProofs, AnInchThatMovesNothingIsCaughtByIm002) {
  const RunReport r = RunBroken(StopAnsweredAsInch, Only("motor/inch"), {}, InchReadAsStop);
  ExpectCaught(r, "DFM-IM-002");
  EXPECT_EQ(FailedMusts(r), Lines{"DFM-IM-002"});
}

// The sketch's first inch towards dest is a move to 980 steps short of dest
// (20 steps from where the case starts it), answered `im 1`.
std::pair<InputBreakage, LineBreakage> FirstInchTwentySteps() {
  auto moved = std::make_shared<std::string>();
  InputBreakage in = [moved](const std::string& line) {
    const auto f = Fields(line);
    if (!moved->empty() || f.size() != 3 || f[0] != "im") return line;
    *moved = "mm " + f[1] + " " + std::to_string(std::stol(f[2]) - 980);
    return *moved;
  };
  LineBreakage b = [moved](const std::string& line, const std::string& last_command,
                           sim::Scheduler&, devices::ByteSink& out) {
    if (!moved->empty() && last_command == *moved && StartsWith(line, "mm")) {
      WriteLine(out, "im 1");
      return;
    }
    WriteLine(out, line);
  };
  return {in, b};
}

TEST(DfmocoProofs, AnInchOfTwentyStepsIsCaughtByIm003) {
  const auto [in, b] = FirstInchTwentySteps();
  const RunReport r = RunBroken(b, Only("motor/inch"), {}, in);
  ExpectCaught(r, "DFM-IM-003");
  EXPECT_TRUE(FailedMusts(r).empty());
}

}  // namespace
}  // namespace moco::conformance::dfmoco_testing
