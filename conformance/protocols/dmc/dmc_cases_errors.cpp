// DMC v2 error cases (dmc-v2-protocol.txt "Computing and Validating the Checksum",
// "MSG_ACK", "Capabilities"; ERRATA 1.2-1.4): a bad motor number for every motor
// command, corrupted check bytes, unknown and retired types, wrong data lengths, noise
// and an oversize header between frames, a frame filling the buffer and virtual
// messages to a device without virtual axes, each judged against the named rules.
// Listed by the table in dmc_cases.cpp.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/protocols/dmc/dmc_cases_internal.h"

namespace moco::conformance::dmc_cases {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;

// ---------------------------------------------------------------- errors

void BadMotor(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t bad[2] = {0, static_cast<uint8_t>(c.device.motor_count + 1)};
  for (uint8_t m : bad) {
    const std::string_view rule = m == 0 ? "DMC-ERR-001" : "DMC-ERR-002";
    const std::vector<dmc::HostMessage> msgs = {
        dmc::MotorMove{m, 100},
        dmc::MotorStop{m},
        dmc::MotorResetPosition{m, 5},
        dmc::MotorJog{m, 100, 100},
        dmc::MotorConfigure{m, 1},
        dmc::MotorSetSpeed{m, 1000, 1000},
        dmc::MotorSetLimits{m, 0, 0, 0, 0, 0},
    };
    for (const auto& msg : msgs) ExpectCode(c, rule, h.Call(msg), AckCode::kErrRange);
  }
}

void Checksum(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const uint32_t id = h.SendFrame(ToWire(MsgType::kHi), {}, true);
  const DmcRecord* r = h.Await(id);
  ExpectCode(c, "DMC-CSUM-002", r, AckCode::kErrChecksum);
  c.v.Check("DMC-CSUM-003",
            r != nullptr && r->id == id && r->type == (ToWire(MsgType::kHi) | dmc::kFlagAck),
            [&] { return EvOf(h, r, "ACK HI with id=" + std::to_string(id), Show(r)); });
  r = h.Call(dmc::MotorStatusRequest{});
  Expect(c, "DMC-CSUM-005", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS answered after a corrupted frame", Show(r));
  if (c.device.motor_count == 0) return;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  wire::Bytes data;
  dmc::EncodeData(dmc::HostMessage{dmc::MotorMove{1, At(*p0, 0) + 1000}}, data);
  r = h.Await(h.SendFrame(ToWire(MsgType::kMotorMove), data, true));
  ExpectCode(c, "DMC-CSUM-002", r, AckCode::kErrChecksum);
  h.Idle(kRefusedMoveShowNs);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-CSUM-005", p1 && *p1 == *p0, "a corrupted MOTOR_MOVE does not move: " + Vec(*p0),
         p1 ? Vec(*p1) : "no position");
}

void UnknownType(DmcCaseContext& c) {
  DmcHost& h = c.host;
  ExpectCode(c, "DMC-ERR-003", h.Await(h.SendFrame(0x0077, {})), AckCode::kErrUnsupported);
  const uint8_t some[3] = {1, 2, 3};
  ExpectCode(c, "DMC-ERR-003", h.Await(h.SendFrame(0x0301, some)), AckCode::kErrUnsupported);
  ExpectCode(c, "DMC-ERR-004", h.Await(h.SendFrame(dmc::kLegacyVirtJogOnLineType, some)),
             AckCode::kErrUnsupported);
}

void BadLength(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t junk[8] = {1, 0, 0, 0, 0, 0, 0, 0};
  struct Bad {
    MsgType type;
    size_t len;
  };
  // Shorter than the layout.
  std::vector<Bad> bad = {{MsgType::kGioOut, 2}};
  if (c.device.motor_count > 0) {
    bad.insert(bad.end(),
               {{MsgType::kMotorMove, 3}, {MsgType::kMotorSetSpeed, 5}, {MsgType::kMotorStop, 0}});
  }
  for (const Bad& b : bad) {
    const DmcRecord* r = h.Await(h.SendFrame(ToWire(b.type), wire::ByteView(junk, b.len)));
    ExpectRefused(c, "DMC-ERR-005", r);
    const std::optional<uint32_t> code = AckCodeOf(r);
    if (code && *code != ToWire(AckCode::kOk)) {
      c.v.Check("DMC-ERR-006", *code == ToWire(AckCode::kErrGeneral),
                [&] { return EvOf(h, r, "ERR_GENERAL", CodeText(r)); });
    }
  }
  // Longer than the layout: the protocol grows by appending fields, so a
  // device may ignore what follows the fields it knows (DMC-ERR-013 notes a
  // device that refuses them instead). Answered either way (DMC-ACK-001).
  std::vector<Bad> longer = {{MsgType::kMotorStatus, 1}, {MsgType::kHi, 2}};
  if (c.device.motor_count > 0) longer.push_back({MsgType::kMotorResetPosition, 6});
  for (const Bad& b : longer) {
    const DmcRecord* r = h.Await(h.SendFrame(ToWire(b.type), wire::ByteView(junk, b.len)));
    if (r == nullptr) continue;
    const std::optional<uint32_t> code = AckCodeOf(r);
    c.v.Check("DMC-ERR-013", !code || *code == ToWire(AckCode::kOk), [&] {
      return EvOf(h, r, "the message carried out, its extra bytes ignored", CodeText(r));
    });
  }
}

void Noise(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t noise[] = {'x', 'y', 0x00, 0xff, 'D', 0x01, 'F', 'D'};
  h.SendNoise(noise);
  const DmcRecord* r = h.Call(dmc::HiRequest{});
  Expect(c, "DMC-ERR-007", As<dmc::HiResponse>(r) != nullptr, "HI answered after noise", Show(r));
  // A header declaring Length 65535, which no device buffer holds, and
  // nothing after it (a Length within a larger buffer than the spec's 1048
  // is rightly waited for: ERRATA 1.2 names a minimum).
  wire::Bytes over = {'D', 'F', 0x99, 0x99, 0, 0, 0x30, 0, 0xff, 0xff};
  h.SendNoise(over);
  r = h.Call(dmc::MotorStatusRequest{});
  Expect(c, "DMC-ERR-008", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS answered after an oversize header", Show(r));
}

void MaxFrame(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const wire::Bytes data(dmc::kMaxDataLength, 0x11);
  const DmcRecord* r = h.Await(h.SendFrame(0x0077, data));
  // ERR_UNSUPPORTED proves the frame was read whole and its checksum found
  // good; ERR_CHECKSUM or silence means the buffer did not hold it.
  ExpectCode(c, "DMC-ERR-012", r, AckCode::kErrUnsupported);
}

void Unadvertised(DmcCaseContext& c) {
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtGetPositionRequest{}),
             AckCode::kErrUnsupported);
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtStop{1}), AckCode::kErrUnsupported);
}

}  // namespace moco::conformance::dmc_cases
