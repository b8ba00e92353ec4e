// Faults that only the control channel brings out (in-process: the runner
// closes a limit switch, drives a general I/O input): each is caught by the
// rule that names it.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dmc/dmc_broken_device_testing.h"

namespace moco::conformance {
namespace {

using namespace dmc_testing;  // BrokenDmc16, RunBroken, PassThrough
using proof::ExpectCaught;

RunOptions Only(const char* cases) {
  RunOptions o;
  o.cases = cases;
  return o;
}

// Only the failing rules of a run.
std::set<std::string> Failed(const RunReport& r) {
  std::set<std::string> out;
  for (const auto& [id, s] : r.rules) {
    if (s.status == Status::kFail) out.insert(id);
  }
  return out;
}

TEST(ControlFaults, TheSoundDeviceReportsLimitsAndInputs) {
  const RunReport r = RunBroken(PassThrough, Only("limits/hard,io/gio-in-change"));
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
  for (const char* id : {"DMC-LIM-007", "DMC-GIO-005", "DMC-GIO-002", "DMC-UNS-003"}) {
    EXPECT_EQ(r.rules.at(id).status, Status::kPass) << id;
  }
}

TEST(ControlFaults, AHardLimitThatIsNeverReportedIsCaughtByLim007Alone) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type != ToWire(MsgType::kMotorHardStop)) out.Write(raw);
      },
      Only("limits/hard"));
  ExpectCaught(r, "DMC-LIM-007");
  EXPECT_EQ(Failed(r), std::set<std::string>{"DMC-LIM-007"});
}

TEST(ControlFaults, AHardLimitReportedAsAnEStopIsCaughtByLim007) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorHardStop)) {
          const uint8_t general[1] = {0};  // REASON 0 without MOTOR: well formed, wrong
          out.Write(Reencode(f, f.id, general));
          return;
        }
        out.Write(raw);
      },
      Only("limits/hard"));
  ExpectCaught(r, "DMC-LIM-007");
  EXPECT_EQ(r.rules.at("DMC-UNS-003").status, Status::kPass) << "the message itself is sound";
}

TEST(ControlFaults, AHardStopNamingAnUpperLimitWithoutItsMotorIsCaughtByUns003) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorHardStop) && f.data.size() == 2) {
          const uint8_t no_motor[1] = {f.data[0]};
          out.Write(Reencode(f, f.id, no_motor));
          return;
        }
        out.Write(raw);
      },
      Only("limits/hard"));
  ExpectCaught(r, "DMC-UNS-003");
}

TEST(ControlFaults, AnInputChangeThatIsNeverSentIsCaughtByGio005Alone) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type != ToWire(MsgType::kGioIn)) out.Write(raw);
      },
      Only("io/gio-in-change"));
  ExpectCaught(r, "DMC-GIO-005");
  EXPECT_EQ(Failed(r), std::set<std::string>{"DMC-GIO-005"});
}

TEST(ControlFaults, AnInputChangeSentWithBitsBeyondTheInputsIsCaughtByGio002) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kGioIn) && f.data.size() == 4) {
          wire::Bytes d(f.data.begin(), f.data.end());
          d[0] |= 0x80;  // input 32 of a device with 8 (whichever byte order):
          d[3] |= 0x80;  // a bit it does not have
          out.Write(Reencode(f, f.id, d));
          return;
        }
        out.Write(raw);
      },
      Only("io/gio-in-change"));
  ExpectCaught(r, "DMC-GIO-002");
}

}  // namespace
}  // namespace moco::conformance
