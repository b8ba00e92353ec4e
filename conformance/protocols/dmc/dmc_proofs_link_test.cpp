// Proving tests of the DMC v2 link rules (dmc-v2-protocol.txt "Message Format",
// "Computing and Validating the Checksum", "MSG_FLAG_ACK", "MSG_HI",
// "MSG_MOTOR_STATUS", "MSG_MOTOR_*" configuration, "MSG_DMX"; ERRATA 1.2-1.11):
// the real DMC-16 with one fault planted on its output or input fails the rule
// that names the fault, and few others.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dmc/dmc_broken_device_testing.h"
#include "conformance/protocols/dmc/dmc_protocol.h"

namespace moco::conformance {
namespace {

using proof::ExpectMustsFailed;
using proof::FailedMusts;

using namespace dmc_testing;  // BrokenDmc16, RunBroken, Reencode, PassThrough
using dmc::AckCode;

// ------------------------------------------------------------------ support

RunOptions Only(const std::string& cases) {
  RunOptions o;
  o.cases = cases;
  return o;
}

bool FromHost(const dmc::FrameRef& f) { return f.id >= DmcHost::kFirstHostId; }

// ------------------------------------------------------------------ DMC-FRAME

// After the answer to connect/queries' last request (GIO_IN), `extra` goes out.
Breakage AfterTheLastAnswer(wire::Bytes extra) {
  return [extra](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
    out.Write(raw);
    if (FromHost(f) && f.type == ToWire(MsgType::kGioIn)) out.Write(extra);
  };
}

TEST(DmcLinkProofs, AFrameLongerThanTheReceiveBufferIsCaughtByFrame002) {
  // A position update of 259 motors: 1040 data bytes, more than a 1048-byte
  // receive buffer holds after header and check bytes (ERRATA 1.2).
  wire::Bytes oversize;
  dmc::EncodeFrame(900, ToWire(MsgType::kMotorGetPosition),
                   wire::Bytes(dmc::kMaxDataLength + 4, 0x00), oversize);
  const RunReport r = RunBroken(AfterTheLastAnswer(oversize), Only("connect/queries"));
  ExpectCaught(r, "DMC-FRAME-002");
  // The frame's bytes, dropped by a receiver that hunts for the next 'D' 'F',
  // lie outside any frame.
  ExpectMustsFailed(r, {"DMC-FRAME-001", "DMC-FRAME-002"});
}

TEST(DmcLinkProofs, AFrameCutShortIsCaughtByFrame003) {
  // The device stops six bytes into an unsolicited HI and sends nothing more.
  wire::Bytes hi = dmc::Encode(901, dmc::DeviceMessage{dmc::HiResponse{}});
  hi.resize(dmc::kHeaderSize + 6);
  const RunReport r = RunBroken(AfterTheLastAnswer(hi), Only("connect/queries"));
  ExpectCaught(r, "DMC-FRAME-003");
  // The bytes of the frame never finished belong to no frame.
  ExpectMustsFailed(r, {"DMC-FRAME-001", "DMC-FRAME-003"});
}

TEST(DmcLinkProofs, ATypeWithBitsOutsideTheReferenceMaskIsCaughtByFrame004) {
  // The GIO_IN answer's Type carries bit 0x0400, which the reference parser
  // drops the frame for.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (FromHost(f) && f.type == ToWire(MsgType::kGioIn)) {
          wire::Bytes changed;
          dmc::EncodeFrame(f.id, static_cast<uint16_t>(f.type | 0x0400), f.data, changed);
          raw = changed;
        }
        out.Write(raw);
      },
      Only("connect/queries"));
  ExpectCaught(r, "DMC-FRAME-004");
  // Nor is it the Type of the request it answers.
  ExpectMustsFailed(r, {"DMC-ACK-004"});
}

TEST(DmcLinkProofs, ADataSectionThatFitsNoLayoutIsCaughtByFrame005) {
  // The GIO_IN answer carries a fifth byte after its 4-byte trigger word.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (FromHost(f) && f.type == ToWire(MsgType::kGioIn)) {
          wire::Bytes data(f.data.begin(), f.data.end());
          data.push_back(0);
          raw = Reencode(f, f.id, data);
        }
        out.Write(raw);
      },
      Only("connect/queries"));
  ExpectCaught(r, "DMC-FRAME-005");
  // The GIO_IN response's own layout rule.
  ExpectMustsFailed(r, {"DMC-FRAME-005", "DMC-GIO-001"});
}

// ------------------------------------------------------------------ DMC-CSUM

uint16_t Plain(uint16_t type) { return static_cast<uint16_t>(type & ~dmc::kFlagAck); }

// The response code when `f` is an ACK.
std::optional<uint32_t> CodeOf(const dmc::FrameRef& f) {
  if ((f.type & dmc::kFlagAck) == 0) return std::nullopt;
  const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
  if (!m.ok()) return std::nullopt;
  if (const auto* a = std::get_if<dmc::Ack>(&m.value())) return a->code;
  return std::nullopt;
}

wire::Bytes AckFrame(uint32_t id, uint16_t type, uint32_t code) {
  return dmc::Encode(id, dmc::DeviceMessage{dmc::Ack{type, code}});
}

// Every ACK for which `which(frame, code)` holds goes out with `code` instead.
Breakage Recode(std::function<bool(const dmc::FrameRef&, uint32_t)> which, uint32_t code) {
  return [which, code](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&,
                       devices::ByteSink& out) {
    if (const auto c = CodeOf(f); c && which(f, *c)) raw = AckFrame(f.id, Plain(f.type), code);
    out.Write(raw);
  };
}

bool IsErrChecksum(const dmc::FrameRef&, uint32_t code) {
  return code == ToWire(AckCode::kErrChecksum);
}

TEST(DmcLinkProofs, ACorruptedRequestAnsweredWithAnotherCodeIsCaughtByCsum002) {
  const RunReport r =
      RunBroken(Recode(IsErrChecksum, ToWire(AckCode::kErrGeneral)), Only("errors/checksum"));
  ExpectCaught(r, "DMC-CSUM-002");
  EXPECT_EQ(r.rules.at("DMC-CSUM-003").status, Status::kPass);
  ExpectMustsFailed(r, {"DMC-CSUM-002"});
}

TEST(DmcLinkProofs, AnErrChecksumUnderAnotherTypeIsCaughtByCsum003) {
  // The ERR_CHECKSUM answer keeps the ID but not the Type it received.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (const auto c = CodeOf(f); c && *c == ToWire(AckCode::kErrChecksum)) {
          raw = AckFrame(f.id, 0x0000, *c);
        }
        out.Write(raw);
      },
      Only("errors/checksum"));
  ExpectCaught(r, "DMC-CSUM-003");
  EXPECT_EQ(r.rules.at("DMC-CSUM-002").status, Status::kPass);
  // An ACK of Type 0 answers no request's Type.
  ExpectMustsFailed(r, {"DMC-ACK-004"});
}

TEST(DmcLinkProofs, AValidRequestAnsweredErrChecksumIsCaughtByCsum004) {
  // Requests too short for their layout (their checksums are good) refused
  // as if their check bytes were bad.
  const RunReport r = RunBroken(
      Recode([](const dmc::FrameRef&, uint32_t code) { return code != ToWire(AckCode::kOk); },
             ToWire(AckCode::kErrChecksum)),
      Only("errors/bad-length"));
  ExpectCaught(r, "DMC-CSUM-004");
  ExpectMustsFailed(r, {"DMC-CSUM-004"});
}

TEST(DmcLinkProofs, ADeviceThatLosesTheFrameAfterACorruptedOneIsCaughtByCsum005) {
  // After a frame whose checksum is bad the device's parser drops the next
  // frame as well.
  auto lose_next = std::make_shared<bool>(false);
  const InputBreakage in = [lose_next](wire::ByteView bytes) {
    if (*lose_next) {
      *lose_next = false;
      return wire::Bytes{};
    }
    if (dmc::WholeFrameAt(bytes) == bytes.size() && !dmc::ChecksumIsZero(bytes)) {
      *lose_next = true;
    }
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r = RunBroken(PassThrough, Only("errors/checksum"), "", in);
  ExpectCaught(r, "DMC-CSUM-005");
  EXPECT_EQ(r.rules.at("DMC-CSUM-002").status, Status::kPass);
  // The lost request goes unanswered.
  ExpectMustsFailed(r, {"DMC-CSUM-005", "DMC-ACK-001"});
}

// ------------------------------------------------------------------ DMC-ACK

bool IsAckOf(const dmc::FrameRef& f, MsgType t) { return f.type == (ToWire(t) | dmc::kFlagAck); }

TEST(DmcLinkProofs, AnAckUnderAnotherRequestsTypeIsCaughtByAck004) {
  // GIO_CAM acknowledged as if it were GIO_OUT.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (IsAckOf(f, MsgType::kGioCam)) {
          if (const auto c = CodeOf(f)) raw = AckFrame(f.id, ToWire(MsgType::kGioOut), *c);
        }
        out.Write(raw);
      },
      Only("io/gio"));
  ExpectCaught(r, "DMC-ACK-004");
  ExpectMustsFailed(r, {"DMC-ACK-004"});
}

TEST(DmcLinkProofs, AnAckWithAThreeByteCodeIsCaughtByAck005) {
  // GIO_CAM's OK written as three bytes.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (IsAckOf(f, MsgType::kGioCam)) {
          const wire::Bytes data = {0x10, 0x00, 0x00};
          raw = Reencode(f, f.id, data);
        }
        out.Write(raw);
      },
      Only("io/gio"));
  ExpectCaught(r, "DMC-ACK-005");
  // No response code can be read from it: GIO_CAM was not acknowledged OK.
  ExpectMustsFailed(r, {"DMC-ACK-005", "DMC-FRAME-005", "DMC-GIO-004"});
}

// Requests too short for their layout are refused; any error code will do.
bool IsRefusal(const dmc::FrameRef&, uint32_t code) { return code != ToWire(AckCode::kOk); }

TEST(DmcLinkProofs, ARefusalWithAnUnlistedCodeIsCaughtByAck007) {
  const RunReport r = RunBroken(Recode(IsRefusal, 0x0030), Only("errors/bad-length"));
  ExpectCaught(r, "DMC-ACK-007");
  ExpectMustsFailed(r, {"DMC-ACK-007"});
}

TEST(DmcLinkProofs, ALimitCodeForARequestThatMovesNothingIsCaughtByAck010) {
  // Short GIO_OUT, SET_SPEED and STOP refused with ERR_SOFT_UP.
  const RunReport r =
      RunBroken(Recode(IsRefusal, ToWire(AckCode::kErrSoftUp)), Only("errors/bad-length"));
  ExpectCaught(r, "DMC-ACK-010");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, AValidRequestRefusedIsCaughtByAck011) {
  // GIO_CAM, within every capability, refused with ERR_GENERAL.
  const RunReport r = RunBroken(
      Recode([](const dmc::FrameRef& f, uint32_t) { return IsAckOf(f, MsgType::kGioCam); },
             ToWire(AckCode::kErrGeneral)),
      Only("io/gio"));
  ExpectCaught(r, "DMC-ACK-011");
  // GIO_CAM's own clause.
  ExpectMustsFailed(r, {"DMC-GIO-004"});
}

// ------------------------------------------------------------------ DMC-DL

// Answers to requests whose Type passes `which` go out `by` late.
Breakage DelayAnswers(std::function<bool(uint16_t)> which, TimeNs by) {
  return [which, by](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler& s,
                     devices::ByteSink& out) {
    if (FromHost(f) && which(Plain(f.type))) {
      s.After(by, [&out, raw] { out.Write(raw); });
      return;
    }
    out.Write(raw);
  };
}

// 300 ms: past the default 250 ms deadline, well within the 2 s answer timeout.
constexpr TimeNs kLate = 300 * sim::kNsPerMs;

TEST(DmcLinkProofs, ALateHiIsCaughtByDl001) {
  const RunReport r =
      RunBroken(DelayAnswers([](uint16_t type) { return type == ToWire(MsgType::kHi); }, kLate),
                Only("connect/hi"));
  ExpectCaught(r, "DMC-DL-001");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ALateCommandAnswerIsCaughtByDl003) {
  const RunReport r =
      RunBroken(DelayAnswers([](uint16_t type) { return type == ToWire(MsgType::kGioCam); }, kLate),
                Only("io/gio"));
  ExpectCaught(r, "DMC-DL-003");
  EXPECT_EQ(r.rules.at("DMC-DL-002").status, Status::kPass);
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ALateUploadAnswerIsCaughtByDl004) {
  const RunReport r =
      RunBroken(DelayAnswers([](uint16_t type) { return type >= 0x0100 && type <= 0x0104; }, kLate),
                Only("rt/upload-position"));
  ExpectCaught(r, "DMC-DL-004");
  EXPECT_EQ(r.rules.at("DMC-DL-005").status, Status::kPass);
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ALateRealTimeAnswerIsCaughtByDl005) {
  const RunReport r = RunBroken(
      DelayAnswers([](uint16_t type) { return type == ToWire(MsgType::kRtPositionFrame); }, kLate),
      Only("rt/upload-position"));
  ExpectCaught(r, "DMC-DL-005");
  EXPECT_EQ(r.rules.at("DMC-DL-004").status, Status::kPass);
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ DMC-HI

// Every HI the device sends (answer or unsolicited) changed by `change`.
Breakage RewriteHi(std::function<void(dmc::HiResponse&)> change) {
  return
      [change](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kHi)) {
          auto m = dmc::DecodeDeviceMessage(f.type, f.data);
          if (m.ok()) {
            if (auto* hi = std::get_if<dmc::HiResponse>(&m.value())) {
              change(*hi);
              raw = dmc::Encode(f.id, dmc::DeviceMessage{*hi});
            }
          }
        }
        out.Write(raw);
      };
}

TEST(DmcLinkProofs, AHiAnsweredWithAnAckIsCaughtByHi001) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (FromHost(f) && f.type == ToWire(MsgType::kHi)) {
          raw = AckFrame(f.id, ToWire(MsgType::kHi), ToWire(AckCode::kErrGeneral));
        }
        out.Write(raw);
      },
      Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-001");
  ExpectMustsFailed(r, {"DMC-HI-001"});
}

// A device that misses the very first HI after it starts (still booting, its
// input not yet read): the host asks again after its timeout, as Dragonframe
// does; the miss fails the introduction's own rule and the rest is judged.
TEST(DmcLinkProofs, AFirstHiMissedIsCaughtByHi016AndTheRestIsJudged) {
  auto missed = std::make_shared<bool>(false);
  const RunReport r =
      RunBroken(PassThrough, Only("connect/*"), "", [missed](wire::ByteView bytes) -> wire::Bytes {
        bool hi = false;
        dmc::FrameDecoder dec;
        dec.Feed(bytes, [&](const dmc::FrameEvent& e) {
          const auto* f = std::get_if<dmc::FrameRef>(&e);
          hi = hi || (f != nullptr && f->type == ToWire(MsgType::kHi));
        });
        if (hi && !*missed) {
          *missed = true;
          return {};
        }
        return wire::Bytes(bytes.begin(), bytes.end());
      });
  ExpectCaught(r, "DMC-HI-016");
  ExpectMustsFailed(r, {"DMC-HI-016"});
  EXPECT_FALSE(r.device.empty());
  EXPECT_NE(r.rules.at("DMC-ACK-001").status, Status::kFail);
  ASSERT_FALSE(r.cases.empty());
  EXPECT_EQ(r.cases.front().suite + "/" + r.cases.front().name, "connect/introduction");
}

TEST(DmcLinkProofs, AHiResponseOfFiftyBytesIsCaughtByHi002) {
  // PROTOCOL VERSION written as one byte.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kHi) && f.data.size() == dmc::kHiResponseSize) {
          raw = Reencode(f, f.id, f.data.first(dmc::kHiResponseSize - 1));
        }
        out.Write(raw);
      },
      Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-002");
  ExpectMustsFailed(r, {"DMC-HI-002", "DMC-FRAME-005"});
}

TEST(DmcLinkProofs, EachHiCountBeyondItsRangeIsCaughtByItsRule) {
  // MSG_HI: MOTOR COUNT, GIO OUT, GIO INPUT and HW LIMIT COUNT 0-32, DMX COUNT 0-512.
  struct Fault {
    const char* rule;
    std::function<void(dmc::HiResponse&)> change;
  };
  const std::vector<Fault> faults = {
      {"DMC-HI-004", [](dmc::HiResponse& h) { h.motor_count = 33; }},
      {"DMC-HI-005", [](dmc::HiResponse& h) { h.dmx_count = 513; }},
      {"DMC-HI-006", [](dmc::HiResponse& h) { h.gio_out_count = 33; }},
      {"DMC-HI-007", [](dmc::HiResponse& h) { h.gio_in_count = 33; }},
      {"DMC-HI-008", [](dmc::HiResponse& h) { h.hw_limit_count = 33; }},
  };
  for (const Fault& fault : faults) {
    SCOPED_TRACE(fault.rule);
    const RunReport r = RunBroken(RewriteHi(fault.change), Only("connect/hi"));
    ExpectCaught(r, fault.rule);
    ExpectMustsFailed(r, {fault.rule});
  }
}

TEST(DmcLinkProofs, AProtocolVersionOtherThanTwoIsCaughtByHi009) {
  const RunReport r =
      RunBroken(RewriteHi([](dmc::HiResponse& h) { h.protocol_version = 3; }), Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-009");
  ExpectMustsFailed(r, {"DMC-HI-009"});
}

TEST(DmcLinkProofs, ANameWithBytesAfterItsEndIsCaughtByHi010) {
  // "DMC-16", its \0, then what an uncleared buffer held.
  const RunReport r = RunBroken(RewriteHi([](dmc::HiResponse& h) {
                                  h.name = dmc::HiResponse::MakeName("DMC-16");
                                  h.name[10] = 'x';
                                }),
                                Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-010");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, NoHiAtStartUpIsCaughtByHi011) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (!FromHost(f) && f.type == ToWire(MsgType::kHi)) return;
        out.Write(raw);
      },
      Only("connect/boot-hi"));
  ExpectCaught(r, "DMC-HI-011");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, AHiThatChangesFromOneRequestToTheNextIsCaughtByHi012) {
  // The name carries a count of the HIs sent.
  auto sent = std::make_shared<int>(0);
  const RunReport r =
      RunBroken(RewriteHi([sent](dmc::HiResponse& h) {
                  h.name = dmc::HiResponse::MakeName("DMC-16 #" + std::to_string(++*sent));
                }),
                Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-012");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ARealTimeDeviceHoldingNoFrameIsCaughtByHi014) {
  const RunReport r = RunBroken(RewriteHi([](dmc::HiResponse& h) { h.upload_frame_count = 0; }),
                                Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-014");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, GoMotionWithoutRealTimeMovesIsCaughtByHi015) {
  // The DMC-16's go-motion, looping and camera-trigger bits without 0x0001.
  const RunReport r =
      RunBroken(RewriteHi([](dmc::HiResponse& h) { h.capabilities &= ~dmc::kCapRealTime; }),
                Only("connect/hi"));
  ExpectCaught(r, "DMC-HI-015");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ DMC-STAT

// Every MOTOR_STATUS answer rewritten by `change` (its data in, new data out).
Breakage RewriteStatus(std::function<wire::Bytes(wire::Bytes)> change) {
  return
      [change](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (FromHost(f) && f.type == ToWire(MsgType::kMotorStatus)) {
          raw = Reencode(f, f.id, change(wire::Bytes(f.data.begin(), f.data.end())));
        }
        out.Write(raw);
      };
}

TEST(DmcLinkProofs, AMotorStatusWithoutItsDmxByteIsCaughtByStat001) {
  const RunReport r = RunBroken(RewriteStatus([](wire::Bytes d) {
                                  d.resize(4);
                                  return d;
                                }),
                                Only("connect/queries"));
  ExpectCaught(r, "DMC-STAT-001");
  ExpectMustsFailed(r, {"DMC-STAT-001", "DMC-FRAME-005"});
}

TEST(DmcLinkProofs, ADmxStatusOfTwoIsCaughtByStat003) {
  const RunReport r = RunBroken(RewriteStatus([](wire::Bytes d) {
                                  if (d.size() == 5) d[4] = 2;
                                  return d;
                                }),
                                Only("connect/queries"));
  ExpectCaught(r, "DMC-STAT-003");
  ExpectMustsFailed(r, {"DMC-STAT-003"});
}

// ------------------------------------------------------------------ DMC-CFG

// The host's bytes as one whole frame (the host writes whole frames in-process).
std::optional<dmc::Frame> WholeFrame(wire::ByteView bytes) {
  auto f = dmc::DecodeFrame(bytes);
  if (!f.ok()) return std::nullopt;
  return f.value();
}

bool IsOkFor(const dmc::FrameRef& f, uint32_t code, MsgType t) {
  return IsAckOf(f, t) && code == ToWire(AckCode::kOk);
}

// A device that reads every host request of type M as `change` leaves it.
template <typename M>
InputBreakage Rewrite(std::function<void(M&)> change) {
  return [change](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    if (const auto f = WholeFrame(bytes)) {
      const auto m = dmc::DecodeHostMessage(*f);
      if (const auto* msg = m.ok() ? std::get_if<M>(&m.value()) : nullptr) {
        M changed = *msg;
        change(changed);
        out = dmc::Encode(f->id, dmc::HostMessage{changed});
      }
    }
    return out;
  };
}

TEST(DmcLinkProofs, AValidSpeedRefusedIsCaughtByCfg001) {
  const RunReport r =
      RunBroken(Recode([](const dmc::FrameRef& f,
                          uint32_t code) { return IsOkFor(f, code, MsgType::kMotorSetSpeed); },
                       ToWire(AckCode::kErrRange)),
                Only("motor/configure-jog"));
  ExpectCaught(r, "DMC-CFG-001");
  ExpectMustsFailed(r, {"DMC-CFG-001"});
}

TEST(DmcLinkProofs, UnknownConfigureFlagsRefusedAreCaughtByCfg002) {
  // The device refuses MOTOR_CONFIGURE flag bits it does not know (above 0x20).
  auto unknown_flags = std::make_shared<std::set<uint32_t>>();
  const InputBreakage in = [unknown_flags](wire::ByteView bytes) {
    if (const auto f = WholeFrame(bytes)) {
      const auto m = dmc::DecodeHostMessage(*f);
      const auto* cfg = m.ok() ? std::get_if<dmc::MotorConfigure>(&m.value()) : nullptr;
      if (cfg != nullptr && (cfg->flags & ~0x3f) != 0) unknown_flags->insert(f->id);
    }
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r =
      RunBroken(Recode([unknown_flags](const dmc::FrameRef& f,
                                       uint32_t) { return unknown_flags->count(f.id) != 0; },
                       ToWire(AckCode::kErrRange)),
                Only("motor/configure-jog"), "", in);
  ExpectCaught(r, "DMC-CFG-002");
  ExpectMustsFailed(r, {"DMC-CFG-002"});
}

TEST(DmcLinkProofs, AJogAcknowledgedButIgnoredIsCaughtByCfg003) {
  // A jog within the speed range reaches the device as a MOTOR_STOP of its
  // motor under the same ID, whose ACK goes out as the jog's.
  auto jogs = std::make_shared<std::set<uint32_t>>();
  const InputBreakage in = [jogs](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    if (const auto f = WholeFrame(bytes)) {
      const auto m = dmc::DecodeHostMessage(*f);
      const auto* jog = m.ok() ? std::get_if<dmc::MotorJog>(&m.value()) : nullptr;
      if (jog != nullptr && jog->speed >= dmc::kJogSpeedInch && jog->speed <= dmc::kJogSpeedMax) {
        jogs->insert(f->id);
        out = dmc::Encode(f->id, dmc::HostMessage{dmc::MotorStop{jog->motor}});
      }
    }
    return out;
  };
  const RunReport r = RunBroken(
      [jogs](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (jogs->count(f.id) != 0 && IsAckOf(f, MsgType::kMotorStop)) {
          if (const auto c = CodeOf(f)) raw = AckFrame(f.id, ToWire(MsgType::kMotorJog), *c);
        }
        out.Write(raw);
      },
      Only("motor/configure-jog"), "", in);
  ExpectCaught(r, "DMC-CFG-003");
  ExpectMustsFailed(r, {"DMC-CFG-003"});
}

TEST(DmcLinkProofs, AJogSpeedOutOfRangeClampedInsteadOfRefusedIsCaughtByCfg004) {
  // The device reads SPEED 0 as 1 and anything above 10000 as 10000, and jogs.
  const InputBreakage in = [](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    if (const auto f = WholeFrame(bytes)) {
      const auto m = dmc::DecodeHostMessage(*f);
      if (const auto* jog = m.ok() ? std::get_if<dmc::MotorJog>(&m.value()) : nullptr) {
        dmc::MotorJog clamped = *jog;
        clamped.speed = std::clamp(jog->speed, dmc::kJogSpeedInch, dmc::kJogSpeedMax);
        out = dmc::Encode(f->id, dmc::HostMessage{clamped});
      }
    }
    return out;
  };
  const RunReport r = RunBroken(PassThrough, Only("motor/configure-jog"), "", in);
  ExpectCaught(r, "DMC-CFG-004");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, LimitsRefusedAreCaughtByCfg005) {
  const RunReport r =
      RunBroken(Recode([](const dmc::FrameRef& f,
                          uint32_t code) { return IsOkFor(f, code, MsgType::kMotorSetLimits); },
                       ToWire(AckCode::kErrRange)),
                Only("motor/configure-jog"));
  ExpectCaught(r, "DMC-CFG-005");
  ExpectMustsFailed(r, {"DMC-CFG-005"});
}

// ------------------------------------------------------------------ DMC-ERR

// The device reads motor number `from` as `to` in every motor command
// (MOTOR BYTE is the first data byte of each).
InputBreakage ReadMotorAs(uint8_t from, uint8_t to) {
  return [from, to](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    const auto f = WholeFrame(bytes);
    if (!f || f->data.empty() || f->data[0] != from) return out;
    switch (static_cast<MsgType>(f->type)) {
      case MsgType::kMotorMove:
      case MsgType::kMotorStop:
      case MsgType::kMotorResetPosition:
      case MsgType::kMotorJog:
      case MsgType::kMotorConfigure:
      case MsgType::kMotorSetSpeed:
      case MsgType::kMotorSetLimits: {
        wire::Bytes data(f->data.begin(), f->data.end());
        data[0] = to;
        out.clear();
        dmc::EncodeFrame(f->id, f->type, data, out);
        break;
      }
      default:
        break;
    }
    return out;
  };
}

TEST(DmcLinkProofs, MotorZeroReadAsMotorOneIsCaughtByErr001) {
  const RunReport r = RunBroken(PassThrough, Only("errors/bad-motor"), "", ReadMotorAs(0, 1));
  ExpectCaught(r, "DMC-ERR-001");
  EXPECT_EQ(r.rules.at("DMC-ERR-002").status, Status::kPass);
  ExpectMustsFailed(r, {"DMC-ERR-001"});
}

TEST(DmcLinkProofs, AMotorAboveTheCountReadAsTheLastIsCaughtByErr002) {
  const RunReport r = RunBroken(PassThrough, Only("errors/bad-motor"), "", ReadMotorAs(17, 16));
  ExpectCaught(r, "DMC-ERR-002");
  EXPECT_EQ(r.rules.at("DMC-ERR-001").status, Status::kPass);
  ExpectMustsFailed(r, {"DMC-ERR-002"});
}

bool IsUnsupported(uint32_t code) { return code == ToWire(AckCode::kErrUnsupported); }

TEST(DmcLinkProofs, AnUnknownTypeAcknowledgedOkIsCaughtByErr003) {
  const RunReport r = RunBroken(Recode(
                                    [](const dmc::FrameRef& f, uint32_t code) {
                                      return IsUnsupported(code) &&
                                             !dmc::IsKnownType(Plain(f.type)) &&
                                             Plain(f.type) != dmc::kLegacyVirtJogOnLineType;
                                    },
                                    ToWire(AckCode::kOk)),
                                Only("errors/unknown-type"));
  ExpectCaught(r, "DMC-ERR-003");
  EXPECT_EQ(r.rules.at("DMC-ERR-004").status, Status::kPass);
  ExpectMustsFailed(r, {"DMC-ERR-003"});
}

TEST(DmcLinkProofs, TheRetiredVirtJogOnLineTypeAcknowledgedOkIsCaughtByErr004) {
  const RunReport r =
      RunBroken(Recode(
                    [](const dmc::FrameRef& f, uint32_t code) {
                      return IsUnsupported(code) && Plain(f.type) == dmc::kLegacyVirtJogOnLineType;
                    },
                    ToWire(AckCode::kOk)),
                Only("errors/unknown-type"));
  ExpectCaught(r, "DMC-ERR-004");
  EXPECT_EQ(r.rules.at("DMC-ERR-003").status, Status::kPass);
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ARequestShorterThanItsLayoutCarriedOutIsCaughtByErr005) {
  // The device acts on requests too short for their layout (reading past
  // their data) and answers them as done: ACK OK, or MOTOR_MOVE's own response.
  auto short_ids = std::make_shared<std::set<uint32_t>>();
  const InputBreakage in = [short_ids](wire::ByteView bytes) {
    if (const auto f = WholeFrame(bytes)) {
      if (!dmc::DecodeHostMessage(*f, dmc::TrailingBytes::kIgnore).ok()) short_ids->insert(f->id);
    }
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r = RunBroken(
      [short_ids](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&,
                  devices::ByteSink& out) {
        const auto code = CodeOf(f);
        if (short_ids->count(f.id) != 0 && code && *code != ToWire(AckCode::kOk)) {
          raw = Plain(f.type) == ToWire(MsgType::kMotorMove)
                    ? dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorMoveResponse{0}})
                    : AckFrame(f.id, Plain(f.type), ToWire(AckCode::kOk));
        }
        out.Write(raw);
      },
      Only("errors/bad-length"), "", in);
  ExpectCaught(r, "DMC-ERR-005");
  ExpectMustsFailed(r, {"DMC-ERR-005"});
}

TEST(DmcLinkProofs, NoiseThatCostsTheNextFrameIsCaughtByErr007) {
  // After the first bytes that are no frame, the device's parser drops the
  // next frame as well.
  auto noise_seen = std::make_shared<int>(0);
  auto lose_next = std::make_shared<bool>(false);
  const InputBreakage in = [noise_seen, lose_next](wire::ByteView bytes) {
    if (*lose_next) {
      *lose_next = false;
      return wire::Bytes{};
    }
    if (!WholeFrame(bytes) && ++*noise_seen == 1) *lose_next = true;
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r = RunBroken(PassThrough, Only("errors/noise"), "", in);
  ExpectCaught(r, "DMC-ERR-007");
  EXPECT_EQ(r.rules.at("DMC-ERR-008").status, Status::kPass);
  // The lost HI goes unanswered.
  ExpectMustsFailed(r, {"DMC-ERR-007", "DMC-ACK-001"});
}

TEST(DmcLinkProofs, ADeviceWaitingOutALength65535HeaderIsCaughtByErr008) {
  // After a header declaring Length 65535 the device reads every later byte
  // as that frame's data.
  auto waiting = std::make_shared<bool>(false);
  const InputBreakage in = [waiting](wire::ByteView bytes) {
    if (*waiting) return wire::Bytes{};
    const auto header = dmc::PeekHeader(bytes);
    if (header && header->length == 0xffff) *waiting = true;
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r = RunBroken(PassThrough, Only("errors/noise"), "", in);
  ExpectCaught(r, "DMC-ERR-008");
  EXPECT_EQ(r.rules.at("DMC-ERR-007").status, Status::kPass);
  ExpectMustsFailed(r, {"DMC-ACK-001"});
}

TEST(DmcLinkProofs, ADeviceThatDropsSingleBytesIsCaughtByErr009) {
  // A device that takes a frame only when it arrives in one read.
  const InputBreakage in = [](wire::ByteView bytes) {
    if (bytes.size() == 1) return wire::Bytes{};
    return wire::Bytes(bytes.begin(), bytes.end());
  };
  const RunReport r = RunBroken(PassThrough, Only("connect/bytewise"), "", in);
  ExpectCaught(r, "DMC-ERR-009");
  ExpectMustsFailed(r, {"DMC-ERR-009", "DMC-ACK-001"});
}

TEST(DmcLinkProofs, VirtualMessagesCarriedOutWithoutTheCapabilityAreCaughtByErr010) {
  // A DMC-16 with virtual axes whose HI leaves out the virtual capability
  // bits: it answers the virtual messages it does not advertise.
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string profile =
      std::string(root != nullptr ? root : ".") + "/fixtures/profiles/dmc16-virtual.json";
  static constexpr uint32_t kVirtualCaps = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                                           dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz |
                                           dmc::kCapAimPoint;
  const RunReport r =
      RunBroken(RewriteHi([](dmc::HiResponse& h) { h.capabilities &= ~kVirtualCaps; }),
                Only("errors/unadvertised"), profile);
  ExpectCaught(r, "DMC-ERR-010");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, DmxStartChannelZeroReadAsOneIsCaughtByErr011) {
  const InputBreakage in = [](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    if (const auto f = WholeFrame(bytes)) {
      const auto m = dmc::DecodeHostMessage(*f);
      if (const auto* d = m.ok() ? std::get_if<dmc::Dmx>(&m.value()) : nullptr) {
        dmc::Dmx one = *d;
        if (one.start_channel == 0) one.start_channel = 1;
        out = dmc::Encode(f->id, dmc::HostMessage{one});
      }
    }
    return out;
  };
  const RunReport r = RunBroken(PassThrough, Only("io/dmx"), "", in);
  ExpectCaught(r, "DMC-ERR-011");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ DMC-UNS

TEST(DmcLinkProofs, AnUnpromptedMotorStatusIsCaughtByUns001) {
  // After each HI it answers, the device sends a MOTOR_STATUS nobody asked
  // for under an ID of its own.
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        out.Write(raw);
        if (FromHost(f) && f.type == ToWire(MsgType::kHi)) {
          out.Write(dmc::Encode(900, dmc::DeviceMessage{dmc::MotorStatusResponse{}}));
        }
      },
      Only("connect/boot-hi"));
  ExpectCaught(r, "DMC-UNS-001");
  // Its ID answers no request either.
  ExpectMustsFailed(r, {"DMC-UNS-001", "DMC-ACK-003"});
}

TEST(DmcLinkProofs, AHardStopWithAnUnknownReasonIsCaughtByUns003) {
  const RunReport r = RunBroken(
      [](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
        if (f.type == ToWire(MsgType::kMotorHardStop)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorHardStop{7, std::nullopt}});
        }
        out.Write(raw);
      },
      Only("motor/estop"));
  ExpectCaught(r, "DMC-UNS-003");
  ExpectMustsFailed(r, {"DMC-UNS-003"});
}

TEST(DmcLinkProofs, AJogThatIgnoresItsSpeedIsCaughtByCfg006) {
  // Every jog runs at full speed, whatever SPEED says: a SPEED 1 inch races.
  const RunReport r =
      RunBroken(PassThrough, Only("motor/jog-speeds"), "",
                Rewrite<dmc::MotorJog>([](dmc::MotorJog& j) { j.speed = dmc::kJogSpeedMax; }));
  ExpectCaught(r, "DMC-CFG-006");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ACorrectJogPassesCfg006) {
  const RunReport r = RunBroken(PassThrough, Only("motor/jog-speeds"));
  EXPECT_EQ(r.rules.at("DMC-CFG-006").status, Status::kPass) << ConsoleReport(r, false);
}

TEST(DmcLinkProofs, CouplingRefusedIsCaughtByCfg007) {
  // The device takes a coupling flag as a motor out of range.
  const RunReport r =
      RunBroken(PassThrough, Only("motor/couple"), "",
                Rewrite<dmc::MotorConfigure>([](dmc::MotorConfigure& m) {
                  if ((m.flags & (dmc::kMotorCoupled | dmc::kMotorCoupledReversed)) != 0) {
                    m.motor = 0;
                  }
                }));
  ExpectCaught(r, "DMC-CFG-007");
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, CouplingAcknowledgedButNotDoneIsNotedByCfg008) {
  // The flags are taken and dropped: motor 2 never follows motor 1.
  const RunReport r = RunBroken(PassThrough, Only("motor/couple"), "",
                                Rewrite<dmc::MotorConfigure>([](dmc::MotorConfigure& m) {
                                  m.flags = static_cast<uint8_t>(
                                      m.flags & ~(dmc::kMotorCoupled | dmc::kMotorCoupledReversed));
                                }));
  EXPECT_EQ(r.rules.at("DMC-CFG-007").status, Status::kPass) << ConsoleReport(r, false);
  ExpectCaught(r, "DMC-CFG-008", Status::kNoted);
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ACorrectCouplingPassesCfg007And008) {
  const RunReport r = RunBroken(PassThrough, Only("motor/couple"));
  EXPECT_EQ(r.rules.at("DMC-CFG-007").status, Status::kPass) << ConsoleReport(r, false);
  EXPECT_EQ(r.rules.at("DMC-CFG-008").status, Status::kPass) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ DMC-DMX

TEST(DmcLinkProofs, DmxWithinTheChannelsRefusedIsCaughtByDmx001) {
  const RunReport r = RunBroken(
      Recode([](const dmc::FrameRef& f, uint32_t code) { return IsOkFor(f, code, MsgType::kDmx); },
             ToWire(AckCode::kErrRange)),
      Only("io/dmx"));
  ExpectCaught(r, "DMC-DMX-001");
  ExpectMustsFailed(r, {"DMC-DMX-001"});
}

TEST(DmcLinkProofs, ARampThatSwitchesAtOnceIsCaughtByDmx002) {
  const RunReport r = RunBroken(PassThrough, Only("io/dmx"), "",
                                Rewrite<dmc::Dmx>([](dmc::Dmx& d) { d.ramp = 0; }));
  ExpectCaught(r, "DMC-DMX-002");
  ExpectMustsFailed(r, {});
}

// MOTOR_STATUS with DMX STATUS 1 from the first that showed a ramp on.
Breakage DmxStatusStuck() {
  auto stuck = std::make_shared<bool>(false);
  return [stuck](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&, devices::ByteSink& out) {
    const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
    if (const auto* st = m.ok() ? std::get_if<dmc::MotorStatusResponse>(&m.value()) : nullptr) {
      *stuck = *stuck || st->dmx_adjusting == 1;
      if (*stuck) {
        dmc::MotorStatusResponse changed = *st;
        changed.dmx_adjusting = 1;
        raw = dmc::Encode(f.id, dmc::DeviceMessage{changed});
      }
    }
    out.Write(raw);
  };
}

TEST(DmcLinkProofs, ADmxStatusThatNeverSettlesIsCaughtByDmx003) {
  const RunReport r = RunBroken(DmxStatusStuck(), Only("io/dmx"));
  ExpectCaught(r, "DMC-DMX-003");
  // The immediate set after it still reads adjusting: DMC-DMX-004, a SHOULD.
  ExpectMustsFailed(r, {"DMC-DMX-003"});
}

TEST(DmcLinkProofs, AnImmediateSetThatRampsIsCaughtByDmx004) {
  const RunReport r = RunBroken(PassThrough, Only("io/dmx"), "",
                                Rewrite<dmc::Dmx>([](dmc::Dmx& d) { d.ramp = 1; }));
  ExpectCaught(r, "DMC-DMX-004");
  EXPECT_EQ(r.rules.at("DMC-DMX-002").status, Status::kPass) << ConsoleReport(r, false);
  ExpectMustsFailed(r, {});
}

TEST(DmcLinkProofs, ACorrectDmxPassesDmx002To004) {
  const RunReport r = RunBroken(PassThrough, Only("io/dmx"));
  for (const char* rule : {"DMC-DMX-002", "DMC-DMX-003", "DMC-DMX-004"}) {
    EXPECT_EQ(r.rules.at(rule).status, Status::kPass) << rule << "\n" << ConsoleReport(r, false);
  }
}

}  // namespace
}  // namespace moco::conformance
