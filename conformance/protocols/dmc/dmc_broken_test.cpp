// Deliberately broken DMC-16s (the real device behind a filter on its output)
// are caught by the rule that names the fault; the random suite shrinks a
// failing sequence and saves it as a session file.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include "conformance/core/patience_testing.h"
#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dmc/dmc_broken_device_testing.h"
#include "conformance/protocols/dmc/dmc_protocol.h"
#include "devices/faulty_sink.h"
#include "devices/registry.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

using namespace dmc_testing;  // BrokenDmc16, RunBroken, Reencode, PassThrough

TEST(BrokenDevice, UnbrokenWrapperPassesEverything) {
  const RunReport r = RunBroken(PassThrough);
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
}

// How the device's bytes are cut into writes never changes a verdict.
RC_GTEST_PROP(BrokenDevice, AnyChunkingOfTheOutputKeepsEveryVerdict, ()) {
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 40));
  RunOptions o;
  o.cases = "connect/*,errors/*,motor/reset-position";
  auto index = std::make_shared<size_t>(0);
  const RunReport whole = RunBroken(PassThrough, o);
  const RunReport cut = RunBroken(
      [cuts, index](const dmc::FrameRef&, wire::Bytes raw, sim::Scheduler&,
                    devices::ByteSink& out) {
        size_t at = 0;
        while (at < raw.size()) {
          const size_t n = cuts.empty() ? 1 : cuts[(*index)++ % cuts.size()];
          const size_t len = std::min(n, raw.size() - at);
          out.Write(wire::ByteView(raw.data() + at, len));
          at += len;
        }
      },
      o);
  RC_ASSERT(ExitCode(cut) == 0);
  RC_ASSERT(whole.rules.size() == cut.rules.size());
  for (const auto& [id, s] : whole.rules) RC_ASSERT(cut.rules.at(id).status == s.status);
}

TEST(BrokenDevice, CorruptedChecksumIsCaughtByCsum001) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorStatus))
          raw.back() = static_cast<uint8_t>(raw.back() + 1);
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-CSUM-001");
  EXPECT_EQ(ExitCode(r), 1);
  // The evidence quotes the bad frame's bytes.
  for (const CaseResult& c : r.cases) {
    auto it = c.outcomes.find("DMC-CSUM-001");
    if (it != c.outcomes.end() && !it->second.evidence.empty()) {
      EXPECT_EQ(it->second.evidence[0].hex.rfind("4446", 0), 0u);
      EXPECT_EQ(it->second.evidence[0].hex.size(), 2u * (dmc::kHeaderSize + 5 + dmc::kCheckSize));
    }
  }
}

TEST(BrokenDevice, DroppedAckIsCaughtByAck001) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (ToWire(MsgType::kMotorStop) | dmc::kFlagAck)) return;
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-001");
  EXPECT_EQ(ExitCode(r), 1);
}

TEST(BrokenDevice, WrongIdIsCaughtByAck003) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (ToWire(MsgType::kMotorResetPosition) | dmc::kFlagAck)) {
          raw = Reencode(f, f.id + 0x100, f.data);
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-003");
  EXPECT_EQ(ExitCode(r), 1);
}

TEST(BrokenDevice, DuplicateAnswerIsCaughtByAck002) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        out.Write(raw);
        if (f.type == ToWire(MsgType::kMotorMove)) out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-002");
}

TEST(BrokenDevice, DelayedPositionReportIsCaughtByPos002) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler& s, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorGetPosition) && f.id < DmcHost::kFirstHostId) {
          s.After(350 * sim::kNsPerMs, [&out, raw] { out.Write(raw); });
          return;
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-POS-002");
  // POS-002 is a SHOULD: the run still passes on its MUST rules unless others broke.
  EXPECT_EQ(FindRule("DMC-POS-002")->level, Level::kShould);
}

TEST(BrokenDevice, SlowQueryAnswersMissTheirKindsDeadline) {
  const Breakage slow_status = [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler& s,
                                  devices::ByteSink& out) {
    if (f.type == ToWire(MsgType::kMotorStatus)) {
      s.After(100 * sim::kNsPerMs, [&out, raw] { out.Write(raw); });
      return;
    }
    out.Write(raw);
  };
  RunOptions o;
  o.cases = "connect/*";
  const RunReport lenient = RunBroken(slow_status, o);
  EXPECT_EQ(lenient.rules.at("DMC-DL-002").status, Status::kPass);  // 100 ms < 250 ms
  o.host.deadline_by_kind_ns["query"] = 50 * sim::kNsPerMs;
  const RunReport strict = RunBroken(slow_status, o);
  ExpectCaught(strict, "DMC-DL-002");
  EXPECT_EQ(strict.rules.at("DMC-DL-001").status, Status::kPass);  // HI keeps 250 ms
  EXPECT_EQ(ExitCode(strict), 0) << "deadlines are SHOULD rules";
}

TEST(BrokenDevice, SwallowedRtEndIsCaughtByRt005) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kRtEnd)) return;
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-RT-005");
  ExpectCaught(r, "DMC-GM-001");
  EXPECT_EQ(ExitCode(r), 1);
}

TEST(BrokenDevice, StatusBitsBeyondTheMotorsAreCaughtByStat002) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorStatus) && f.data.size() == 5) {
          wire::Bytes data(f.data.begin(), f.data.end());
          data[3] |= 0x80;  // motor 32 of a 16-motor device
          raw = Reencode(f, f.id, data);
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-STAT-002");
}

TEST(BrokenDevice, StrayBytesAreCaughtByFrame001) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        out.Write(raw);
        if (f.type == ToWire(MsgType::kHi)) out.Write(wire::Bytes{0x00, 0x0d, 0x0a});
      });
  ExpectCaught(r, "DMC-FRAME-001");
}

TEST(BrokenDevice, LegacyHiIsANoteNotAFailure) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kHi) && f.data.size() == dmc::kHiResponseSize) {
          raw = Reencode(f, f.id, f.data.first(dmc::kHiResponseLegacySize));
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-HI-003", Status::kNoted);
  EXPECT_EQ(r.rules.at("DMC-HI-002").status, Status::kPass);
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
}

TEST(BrokenDevice, ThirtyTwoBitAckCodesAreANote) {
  // The profile's ack_width_bits (FACTS: one dmc-lite firmware writes 32-bit codes).
  const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                  ("mococheck_ack32_" + std::to_string(getpid()) + ".json");
  {
    std::ofstream out(p);
    out << R"({"model": "dmc16", "ack_width_bits": 32})";
  }
  const RunReport r = RunBroken(PassThrough, {}, p.string());
  std::filesystem::remove(p);
  ExpectCaught(r, "DMC-ACK-006", Status::kNoted);
  EXPECT_EQ(r.rules.at("DMC-ACK-005").status, Status::kPass);
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
}

// The device time of a run: what its cases took on the target's clock.
TimeNs DeviceTime(const RunReport& r) {
  TimeNs t = 0;
  for (const CaseResult& c : r.cases) t += c.target_ns;
  return t;
}

// The MUST rules a run failed.
std::vector<std::string> FailedMusts(const RunReport& r) {
  std::vector<std::string> out;
  for (const auto& [id, s] : r.rules) {
    const Rule* rule = FindRule(id);
    if (s.status == Status::kFail && rule != nullptr && rule->level == Level::kMust) {
      out.push_back(id);
    }
  }
  return out;
}

TEST(BrokenDevice, EveryAckUnderAWrongIdFailsAck003AloneAndTheRunKeepsItsPace) {
  // (A specific response of a kind the device also sends unprompted, such
  // as a position report, cannot be told from an unsolicited one by its ID.)
  const RunReport good = RunBroken(PassThrough);
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        // (ERR_CHECKSUM answers keep the ID as received: they are judged
        // by DMC-CSUM-003, and a wrong ID there answers no request at all.)
        const bool checksum_error = f.data.size() >= 2 &&
                                    f.data[0] == (ToWire(dmc::AckCode::kErrChecksum) & 0xff) &&
                                    f.data[1] == 0;
        if ((f.type & dmc::kFlagAck) != 0 && !checksum_error) {
          raw = Reencode(f, f.id + 0x100, f.data);
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-003");
  // The answers are taken by Type: none waits out its timeout, and the
  // run's rules are judged on them (the fault fails its own rule only).
  EXPECT_EQ(r.rules.at("DMC-ACK-001").status, Status::kPass);
  EXPECT_EQ(FailedMusts(r), std::vector<std::string>{"DMC-ACK-003"}) << ConsoleReport(r, false);
  EXPECT_LE(DeviceTime(r), 2 * DeviceTime(good));
}

TEST(BrokenDevice, PositionsSentUnderIdZeroBeforeAnAckOkAreReadAndOnlyTheFormFails) {
  // The reference firmware answers MOTOR_GET_POSITION this way (FACTS DMC v2).
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorGetPosition) && f.id >= DmcHost::kFirstHostId) {
          out.Write(Reencode(f, 0, f.data));
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{f.type, ToWire(dmc::AckCode::kOk)}});
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-008");
  for (const char* rule :
       {"DMC-MOVE-003", "DMC-POS-006", "DMC-RT-002", "DMC-RT-003", "DMC-STOP-001", "DMC-LIM-004"}) {
    EXPECT_EQ(r.rules.at(rule).status, Status::kPass) << rule << "\n" << ConsoleReport(r, false);
  }
}

TEST(BrokenDevice, AMoveAnsweredAckOkFailsTheFormAndItsMotionIsStillJudged) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorMove)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{f.type, ToWire(dmc::AckCode::kOk)}});
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-008");
  ExpectCaught(r, "DMC-MOVE-001");
  for (const char* rule : {"DMC-MOVE-003", "DMC-MOVE-004", "DMC-POS-004", "DMC-LIM-004"}) {
    EXPECT_EQ(r.rules.at(rule).status, Status::kPass) << rule << "\n" << ConsoleReport(r, false);
  }
}

TEST(BrokenDevice, PositionUpdatesThatStopAreCaughtByUns002) {
  // A device whose updates stall (here: never sent) while the host ACKs none.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorGetPosition) && f.id < DmcHost::kFirstHostId) return;
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-UNS-002");
}

TEST(BrokenDevice, AMaximumFrameAnsweredErrChecksumIsCaughtByErr012) {
  // A buffer too small for 1048 bytes cuts the frame and finds its checksum bad.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (0x0077 | dmc::kFlagAck)) {
          raw = dmc::Encode(
              f.id, dmc::DeviceMessage{dmc::Ack{0x0077, ToWire(dmc::AckCode::kErrChecksum)}});
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ERR-012");
}

TEST(BrokenDevice, AnRtEndSentWithTheGoAckIsCaughtByTheGoMotionRules) {
  // The exposure is 200 ms: an RT_END right after GO ended no exposure.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        out.Write(raw);
        if (f.type == (ToWire(MsgType::kRtGo) | dmc::kFlagAck)) {
          out.Write(dmc::Encode(7, dmc::DeviceMessage{dmc::RtEnd{}}));
        }
      });
  ExpectCaught(r, "DMC-GM-001");
  ExpectCaught(r, "DMC-GM-002");
}

TEST(BrokenDevice, TheReferenceFirmwaresAimPointCodeIsANoteNotAListedCode) {
  // FACTS DMC v2: dmc-lite's extra code 0x0019; here every ERR_UNSUPPORTED.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
        const auto* a = m.ok() ? std::get_if<dmc::Ack>(&m.value()) : nullptr;
        if (a != nullptr && a->code == ToWire(dmc::AckCode::kErrUnsupported)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{a->type, 0x0019}});
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-012", Status::kNoted);
  EXPECT_EQ(r.rules.at("DMC-ACK-007").status, Status::kPass);
}

std::string WriteProfile(const std::string& name, const std::string& json) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                  ("mococheck_" + name + "_" + std::to_string(getpid()) + ".json");
  std::ofstream(p) << json;
  return p.string();
}

TEST(BrokenDevice, ASecondStopAllThatDeceleratesAsTheFirstIsCaughtByStop004) {
  // hard_stop_multiple 1: the "hard stop" decelerates as a normal one.
  const std::string profile =
      WriteProfile("softhard", R"({"model": "dmc16", "motion": {"hard_stop_multiple": 1}})");
  const RunReport r = RunBroken(PassThrough, {}, profile);
  std::filesystem::remove(profile);
  ExpectCaught(r, "DMC-STOP-004");
}

TEST(BrokenDevice, MotorsThatHaltAtStopAllAreCaughtByStop005) {
  // What the host sees of a device that halts: every position after a
  // STOP_ALL's answer is the one before it, until the next move.
  struct Seen {
    bool halted = false;
    std::vector<int32_t> last;
  };
  auto seen = std::make_shared<Seen>();
  const RunReport r = RunBroken(
      [seen](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (ToWire(MsgType::kMotorStopAll) | dmc::kFlagAck)) seen->halted = true;
        if (f.type == ToWire(MsgType::kMotorMove)) seen->halted = false;
        if (f.type == ToWire(MsgType::kMotorGetPosition)) {
          auto m = dmc::DecodeDeviceMessage(f.type, f.data);
          if (m.ok()) {
            auto report = std::get<dmc::MotorPositionReport>(m.value());
            if (seen->halted && !seen->last.empty()) {
              report.positions_steps = seen->last;
              raw = dmc::Encode(f.id, dmc::DeviceMessage{report});
            } else {
              seen->last = report.positions_steps;
            }
          }
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-STOP-005");
}

TEST(BrokenDevice, APositionUpdateSentBeforeTheResetPositionAckIsCaughtByRst002) {
  // "After changing the internal position and responding to this message":
  // here the update goes out first and the ACK after it.
  auto held = std::make_shared<wire::Bytes>();
  const RunReport r = RunBroken(
      [held](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (ToWire(MsgType::kMotorResetPosition) | dmc::kFlagAck)) {
          *held = raw;
          return;
        }
        out.Write(raw);
        if (!held->empty() && f.type == ToWire(MsgType::kMotorGetPosition)) {
          out.Write(*held);
          held->clear();
        }
      });
  ExpectCaught(r, "DMC-RST-002");
}

TEST(BrokenDevice, AStopLoopAckedButIgnoredIsCaughtByLoop001) {
  // The device ACKs STOP_LOOP OK and plays on: the request reaches it as a
  // MOTOR_STATUS under the same ID, whose answer goes out as STOP_LOOP's ACK.
  auto ids = std::make_shared<std::set<uint32_t>>();
  const InputBreakage in = [ids](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    const auto f = dmc::DecodeFrame(bytes);  // the host writes whole frames in-process
    if (f.ok() && f.value().type == ToWire(MsgType::kRtStopLoop)) {
      ids->insert(f.value().id);
      out = dmc::Encode(f.value().id, dmc::HostMessage{dmc::MotorStatusRequest{}});
    }
    return out;
  };
  const RunReport r = RunBroken(
      [ids](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (ids->count(f.id) != 0 && f.type == ToWire(MsgType::kMotorStatus)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{ToWire(MsgType::kRtStopLoop),
                                                              ToWire(dmc::AckCode::kOk)}});
        }
        out.Write(raw);
      },
      [] {
        RunOptions o;
        o.cases = "rt/stop-loop";
        return o;
      }(),
      "", in);
  ExpectCaught(r, "DMC-LOOP-001");
}

// A device whose live-run reports fall on its own tick carries fractional
// MOVE TIMEs ("in thousandths of a frame": dmc-lite's 10080, 10520): every
// unsolicited update of a run here is 80 thousandths past its frame. The
// ping-pong still runs, and STOP_LOOP still ends it at frame 0.
TEST(BrokenDevice, FractionalMoveTimesAreStillALoopStoppedAtItsEndPoint) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorGetPosition) && f.id < DmcHost::kFirstHostId) {
          auto m = dmc::DecodeDeviceMessage(f.type, f.data);
          if (m.ok()) {
            if (auto* p = std::get_if<dmc::MotorPositionReport>(&m.value());
                p != nullptr && p->move_time_x1000 > 0 && p->move_time_x1000 % 1000 == 0) {
              p->move_time_x1000 += 80;
              raw = dmc::Encode(f.id, dmc::DeviceMessage{*p});
            }
          }
        }
        out.Write(raw);
      },
      [] {
        RunOptions o;
        o.cases = "rt/stop-loop";
        return o;
      }());
  ASSERT_TRUE(r.rules.count("DMC-LOOP-001"));
  EXPECT_EQ(r.rules.at("DMC-LOOP-001").status, Status::kPass) << ConsoleReport(r, false);
}

TEST(BrokenDevice, GoMotionThatDoesNotMoveIsCaughtByTheGoMotionRules) {
  // The device reads every blur motor's POS A and POS B as the frame's
  // position: the shutter opens on a rig that stands still.
  const InputBreakage in = [](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    const auto f = dmc::DecodeFrame(bytes);  // the host writes whole frames in-process
    if (!f.ok()) return out;
    auto m = dmc::DecodeHostMessage(f.value());
    if (!m.ok()) return out;
    auto still = [](std::vector<dmc::BlurMotor>& motors) {
      for (dmc::BlurMotor& b : motors) {
        b.pos_a_steps = b.pos_b_steps = (b.pos_a_steps + b.pos_b_steps) / 2;
      }
    };
    if (auto* s1 = std::get_if<dmc::RtShootFrame>(&m.value())) {
      still(s1->motors);
      out = dmc::Encode(f.value().id, dmc::HostMessage{*s1});
    } else if (auto* s2 = std::get_if<dmc::RtShootFrame2>(&m.value())) {
      still(s2->motors);
      out = dmc::Encode(f.value().id, dmc::HostMessage{*s2});
    }
    return out;
  };
  RunOptions o;
  o.cases = "gomotion/*";
  const RunReport r = RunBroken(PassThrough, o, "", in);
  ExpectCaught(r, "DMC-GM-001");
  ExpectCaught(r, "DMC-GM-002");
}

TEST(BrokenDevice, AFrameReportDroppedFromALiveRunIsCaughtByRt004) {
  // Frame 5's report (MOVE TIME 5000) never goes out.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorGetPosition) && f.id < DmcHost::kFirstHostId) {
          const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
          if (m.ok() && std::get<dmc::MotorPositionReport>(m.value()).move_time_x1000 == 5000) {
            return;
          }
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-RT-004");
}

TEST(BrokenDevice, AcksWithoutTheAckBitAreCaughtByAck009) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if ((f.type & dmc::kFlagAck) != 0) {
          wire::Bytes plain;
          dmc::EncodeFrame(f.id, static_cast<uint16_t>(f.type & ~dmc::kFlagAck), f.data, plain);
          raw = plain;
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-ACK-009");
  EXPECT_EQ(ExitCode(r), 1);
}

TEST(BrokenDevice, AMotorStatusThatNeverShowsMotionIsCaughtByStat004) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorStatus) && f.data.size() == 5) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorStatusResponse{0, 0}});
        }
        out.Write(raw);
      });
  ExpectCaught(r, "DMC-STAT-004");
  EXPECT_EQ(ExitCode(r), 1);
}

// A device that sends its position updates on its own tick, as dmc-lite does
// on its 20 ms velocity tick (calibration): each unsolicited update is held to
// the next 60 ms boundary of the device's clock, and only the newest held one
// goes out. A move's final update then arrives up to 60 ms after the motor
// stopped and after a correct "not moving" MOTOR_STATUS: the motion's end
// reported late, not a stale status.
RunOptions MotorMoveOnly() {
  RunOptions o;
  o.cases = "motor/move";
  return o;
}

Breakage UpdatesOnATick(sim::TimeNs tick_ns) {
  struct Held {
    wire::Bytes raw;
    bool armed = false;
  };
  return
      [tick_ns, held = std::shared_ptr<Held>()](const dmc::FrameRef& f, wire::Bytes raw,
                                                sim::Scheduler& s, devices::ByteSink& out) mutable {
        if (!held) held = std::make_shared<Held>();  // one per device: each copy starts empty
        if (f.type != ToWire(MsgType::kMotorGetPosition) || f.id >= DmcHost::kFirstHostId) {
          out.Write(raw);
          return;
        }
        held->raw = std::move(raw);
        if (held->armed) return;
        held->armed = true;
        const sim::TimeNs wait = tick_ns - s.Now() % tick_ns;
        s.After(wait, [h = held, &out] {
          h->armed = false;
          out.Write(h->raw);
        });
      };
}

TEST(BrokenDevice, AFinalUpdateOnTheDevicesOwnTickIsNoStaleStatus) {
  const RunReport r = RunBroken(UpdatesOnATick(60 * sim::kNsPerMs), MotorMoveOnly());
  ASSERT_TRUE(r.rules.count("DMC-STAT-004"));
  EXPECT_EQ(r.rules.at("DMC-STAT-004").status, Status::kPass) << ConsoleReport(r, false);
}

// The same device whose MOTOR_STATUS says "not moving" while it still moves:
// the updates after the status go on changing, and DMC-STAT-004 fails.
TEST(BrokenDevice, AStatusOfRestWhileUpdatesGoOnChangingIsCaughtByStat004) {
  const Breakage tick = UpdatesOnATick(60 * sim::kNsPerMs);
  auto moved = std::make_shared<bool>(false);
  const RunReport r = RunBroken(
      [tick, moved](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler& s,
                    devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorStatus) && f.data.size() == 5 && f.data[0] != 0) {
          // Says "at rest" from the second moving status on.
          if (*moved) raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorStatusResponse{0, 0}});
          *moved = true;
        }
        tick(f, std::move(raw), s, out);
      },
      MotorMoveOnly());
  ExpectCaught(r, "DMC-STAT-004");
}

TEST(BrokenDevice, RandomSuiteShrinksAFailingSequenceAndSavesIt) {
  const std::filesystem::path session = std::filesystem::temp_directory_path() /
                                        ("mococheck_shrunk_" + std::to_string(getpid()) + ".jsonl");
  RunOptions o;
  o.cases = "random/*";
  o.random.seed = 7;
  o.random.steps = 40;
  o.random.session_path = session.string();
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == (ToWire(MsgType::kMotorStopAll) | dmc::kFlagAck))
          return;  // STOP_ALL unanswered
        out.Write(raw);
      },
      o);
  ASSERT_EQ(r.cases.size(), 1u);
  EXPECT_TRUE(r.cases[0].MustFailed());
  const auto& log = r.cases[0].log;
  const auto has = [&](const std::string& s) {
    return std::find(log.begin(), log.end(), s) != log.end();
  };
  EXPECT_TRUE(has("shrunk to 1 step(s):")) << ConsoleReport(r, true);
  EXPECT_TRUE(has("  MOTOR_STOP_ALL")) << ConsoleReport(r, true);
  auto loaded = session::LoadSession(session);
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const auto& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.header.protocol, wire::Protocol::kDmc);
  EXPECT_EQ(s.header.clock, "virtual");
  bool stop_all_sent = false;
  for (const auto& e : s.entries) {
    if (e.from != session::Origin::kHost) continue;
    auto f = dmc::DecodeFrame(e.bytes);
    stop_all_sent = stop_all_sent || (f.ok() && f->type == ToWire(MsgType::kMotorStopAll));
  }
  EXPECT_TRUE(stop_all_sent);
  std::filesystem::remove(session);
}

// A broken device is judged in at most twice the good device's time, with
// the same rules failing as when every answer is waited out: the answers it
// has stopped giving are not waited for (HostOptions::give_up_after_unanswered).
RunReport RunBrokenWith(const Breakage& b, const RunOptions& o) { return RunBroken(b, o); }

TEST(BrokenDevice, WrongChecksumsAreJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return RunBrokenWith(PassThrough, o); },
      [](const RunOptions& o) {
        return RunBrokenWith(
            [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
              // The introduction intact: the host knows the device and runs every case.
              if (f.type != ToWire(MsgType::kHi))
                raw.back() = static_cast<uint8_t>(raw.back() ^ 0x5a);
              out.Write(raw);
            },
            o);
      });
}

TEST(BrokenDevice, NoAnswerToOneMessageTypeIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return RunBrokenWith(PassThrough, o); },
      [](const RunOptions& o) {
        return RunBrokenWith(
            [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
              if (f.type != ToWire(MsgType::kMotorStatus)) out.Write(raw);
            },
            o);
      });
}

TEST(BrokenDevice, ADeviceThatStopsMidRunIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return RunBrokenWith(PassThrough, o); },
      [](const RunOptions& o) {
        auto written = std::make_shared<size_t>(0);
        return RunBrokenWith(
            [written](const dmc::FrameRef&, wire::Bytes raw, sim::Scheduler&,
                      devices::ByteSink& out) {
              if ((*written)++ < 2000) out.Write(raw);
            },
            o);
      });
}

}  // namespace
}  // namespace moco::conformance
