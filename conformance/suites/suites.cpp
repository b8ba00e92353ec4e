// DMC v2 scenario suites (dmc-v2-protocol.txt "Capabilities", "MSG_HI",
// "MSG_MOTOR_*", "MSG_RT_*", "Computing and Validating the Checksum"; ERRATA
// 1.2-1.11): each case drives Dragonframe-style traffic and judges what the
// device did against the named rules. Cases work relative to the positions
// they find, so they also run against a device that is not fresh.
#include "conformance/suites/suites.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace moco::conformance {
namespace {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;
constexpr TimeNs kMs = sim::kNsPerMs;

Evidence EvOf(const DmcHost& h, const DeviceRecord* r, std::string expected, std::string observed) {
  return Evidence{std::move(expected), std::move(observed), r != nullptr ? wire::ToHex(r->raw) : "",
                  r != nullptr ? r->t_ns : h.Now()};
}

std::string CodeText(const DeviceRecord* r) {
  if (auto code = AckCodeOf(r)) return "ACK " + dmc::AckCodeName(*code);
  return Show(r);
}

// `rule` passes when `r` is an ACK with `want`.
bool ExpectCode(CaseContext& c, std::string_view rule, const DeviceRecord* r, AckCode want) {
  const std::optional<uint32_t> code = AckCodeOf(r);
  return c.v.Check(rule, code && *code == ToWire(want), [&] {
    return EvOf(c.host, r, "ACK " + dmc::AckCodeName(ToWire(want)), CodeText(r));
  });
}

// `rule` and DMC-ACK-011 pass when `r` is ACK OK.
bool ExpectOk(CaseContext& c, std::string_view rule, const DeviceRecord* r) {
  ExpectCode(c, "DMC-ACK-011", r, AckCode::kOk);
  return ExpectCode(c, rule, r, AckCode::kOk);
}

// `rule` passes when `r` is an ACK other than OK.
bool ExpectRefused(CaseContext& c, std::string_view rule, const DeviceRecord* r) {
  const std::optional<uint32_t> code = AckCodeOf(r);
  return c.v.Check(rule, code && *code != ToWire(AckCode::kOk),
                   [&] { return EvOf(c.host, r, "an ACK with an error code", CodeText(r)); });
}

bool Expect(CaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed) {
  return c.v.Check(rule, ok, [&] { return EvOf(c.host, nullptr, expected, observed); });
}

struct Update {
  TimeNs t_ns;
  uint32_t move_time;
  std::vector<int32_t> positions;
  const DeviceRecord* rec;
};

// Unsolicited MOTOR_GET_POSITION messages from record `from` on.
std::vector<Update> UpdatesSince(const DmcHost& h, size_t from) {
  std::vector<Update> out;
  for (size_t i = from; i < h.records().size(); ++i) {
    const DeviceRecord& r = h.records()[i];
    if (r.request >= 0) continue;
    if (const auto* p = As<dmc::MotorPositionReport>(&r)) {
      out.push_back(Update{r.t_ns, p->move_time_x1000, p->positions_steps, &r});
    }
  }
  return out;
}

int CountSince(const DmcHost& h, size_t from, MsgType type) {
  int n = 0;
  for (size_t i = from; i < h.records().size(); ++i) {
    if (h.records()[i].request < 0 && h.records()[i].type == ToWire(type)) ++n;
  }
  return n;
}

bool IsUnsolicited(const DeviceRecord& r, MsgType type) {
  return r.request < 0 && r.type == ToWire(type);
}

std::string Vec(const std::vector<int32_t>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

int32_t At(const std::vector<int32_t>& v, size_t i) { return i < v.size() ? v[i] : 0; }

const TimeNs kRestTimeout = 60'000 * kMs;

void MoveAndRest(CaseContext& c, uint8_t motor, int32_t to) {
  c.host.Call(dmc::MotorMove{motor, to});
  WaitRest(c.host, kRestTimeout);
}

// ---------------------------------------------------------------- connect

void BootHi(CaseContext& c) {
  if (!c.target.CanRestart()) return;  // the start-up of an external device is not observed
  bool seen = false;
  for (const DeviceRecord& r : c.host.records()) {
    seen = seen || (IsUnsolicited(r, MsgType::kHi) && r.t_ns <= 1000 * kMs);
  }
  if (!seen) {
    c.host.WaitFor(0, 1000 * kMs,
                   [](const DeviceRecord& r) { return IsUnsolicited(r, MsgType::kHi); });
    for (const DeviceRecord& r : c.host.records()) seen = seen || IsUnsolicited(r, MsgType::kHi);
  }
  Expect(c, "DMC-HI-011", seen, "an unsolicited HI within 1 s of power-on", "none");
}

void HiAgain(CaseContext& c) {
  const DeviceRecord* r = c.host.Call(dmc::HiRequest{});
  Expect(c, "DMC-HI-001", As<dmc::HiResponse>(r) != nullptr, "HI response", Show(r));
}

void Bytewise(CaseContext& c) {
  const DeviceRecord* r = c.host.Await(c.host.SendBytewise(dmc::HiRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::HiResponse>(r) != nullptr, "HI response to a byte-wise HI",
         Show(r));
  r = c.host.Await(c.host.SendBytewise(dmc::MotorStatusRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS response to a byte-wise MOTOR_STATUS", Show(r));
}

void Queries(CaseContext& c) {
  const DeviceRecord* r = c.host.Call(dmc::MotorStatusRequest{});
  if (const auto* st = As<dmc::MotorStatusResponse>(r); st != nullptr && c.hi.motor_count > 0) {
    c.v.Check("DMC-STAT-004", st->moving_bits == 0,
              [&] { return EvOf(c.host, r, "no motor moving at rest", Show(r)); });
  }
  r = c.host.Call(dmc::MotorGetPositionRequest{});
  Expect(c, "DMC-POS-001", As<dmc::MotorPositionReport>(r) != nullptr,
         "MOTOR_GET_POSITION response", Show(r));
  c.host.Call(dmc::GioInRequest{});
}

// ---------------------------------------------------------------- motor

void SetSpeed(CaseContext& c, uint8_t motor, uint32_t v, uint32_t a) {
  ExpectOk(c, "DMC-CFG-001", c.host.Call(dmc::MotorSetSpeed{motor, v, a}));
}

void Move(CaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0), target = start + 2000;
  const size_t mark = h.records().size();
  const DeviceRecord* r = h.Call(dmc::MotorMove{1, target});
  const TimeNs t0 = r != nullptr ? r->t_ns : h.Now();
  const auto* mv = As<dmc::MotorMoveResponse>(r);
  c.v.Check("DMC-MOVE-002", mv != nullptr && mv->moving == 1,
            [&] { return EvOf(h, r, "MOTOR_MOVE moving=1", Show(r)); });
  h.Idle(250 * kMs);
  r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-STAT-004", st != nullptr && (st->moving_bits & 1u) != 0,
            [&] { return EvOf(h, r, "bit 0 set while motor 1 moves", Show(r)); });
  const bool rested = WaitRest(h, kRestTimeout);
  Expect(c, "DMC-STAT-004", rested, "status at rest after the move", "still moving");
  h.Idle(300 * kMs);
  const std::vector<Update> ups = UpdatesSince(h, mark);
  // Updates while moving: from the move until the first one on the target.
  TimeNs last = t0, worst = 0, sum = 0;
  size_t n = 0;
  bool reached = false;
  for (const Update& u : ups) {
    if (reached) break;
    worst = std::max(worst, u.t_ns - last);
    sum += u.t_ns - last;
    ++n;
    last = u.t_ns;
    reached = At(u.positions, 0) == target;
  }
  c.v.Check("DMC-POS-002", n > 0 && worst <= c.host_options.position_gap_ns, [&] {
    return EvOf(
        h, nullptr,
        "updates at most " + std::to_string(c.host_options.position_gap_ns / kMs) + " ms apart",
        n == 0 ? "no update" : "a gap of " + std::to_string(worst / kMs) + " ms");
  });
  if (n > 1) {
    const TimeNs mean = sum / static_cast<TimeNs>(n);
    c.v.Check("DMC-POS-003", mean >= 75 * kMs, [&] {
      return EvOf(h, nullptr, "about 100 ms between updates",
                  std::to_string(mean / kMs) + " ms mean");
    });
  }
  for (const Update& u : ups) {
    const int32_t p = At(u.positions, 0);
    if (!c.v.Check("DMC-POS-005", p >= start && p <= target, [&] {
          return EvOf(
              h, u.rec,
              "motor 1 within [" + std::to_string(start) + ", " + std::to_string(target) + "]",
              std::to_string(p));
        }))
      break;
  }
  Expect(c, "DMC-POS-004", !ups.empty() && At(ups.back().positions, 0) == target,
         "a last update with motor 1 on " + std::to_string(target),
         ups.empty() ? "no update" : "last update " + Vec(ups.back().positions));
  const auto p1 = GetPositions(h);
  if (!p1) return;
  Expect(c, "DMC-MOVE-003", At(*p1, 0) == target, "motor 1 at " + std::to_string(target),
         std::to_string(At(*p1, 0)));
  Expect(c, "DMC-POS-006", At(*p1, 0) == target,
         "MOTOR_GET_POSITION motor 1 = " + std::to_string(target), Vec(*p1));
  bool others = p1->size() == p0->size();
  for (size_t i = 1; others && i < p1->size(); ++i) others = (*p1)[i] == (*p0)[i];
  Expect(c, "DMC-MOVE-004", others, "other motors as before " + Vec(*p0), Vec(*p1));
  r = h.Call(dmc::MotorMove{1, target});
  mv = As<dmc::MotorMoveResponse>(r);
  c.v.Check("DMC-MOVE-002", mv != nullptr && mv->moving == 0,
            [&] { return EvOf(h, r, "MOTOR_MOVE moving=0 for the current position", Show(r)); });
  MoveAndRest(c, 1, start);
}

void Stop(CaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0), far = start + 100000;
  h.Call(dmc::MotorMove{1, far});
  h.Idle(500 * kMs);
  ExpectOk(c, "DMC-STOP-001", h.Call(dmc::MotorStop{1}));
  const bool rested = WaitRest(h, 10'000 * kMs);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-STOP-001", rested && p1 && At(*p1, 0) > start && At(*p1, 0) < far,
         "motor 1 at rest between " + std::to_string(start) + " and " + std::to_string(far),
         p1 ? (rested ? "" : "still moving at ") + std::to_string(At(*p1, 0)) : "no position");
  MoveAndRest(c, 1, start);
}

void StopAll(CaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t motors = std::min<uint8_t>(c.hi.motor_count, 2);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  for (int pass = 0; pass < 2; ++pass) {
    for (uint8_t m = 1; m <= motors; ++m) {
      SetSpeed(c, m, 2000, 4000);
      h.Call(dmc::MotorMove{m, At(*p0, m - 1u) + 100000});
    }
    h.Idle(400 * kMs);
    dmc::MotorStopAll stop;
    if (pass == 0) stop.flags = dmc::kStopAllSilent;
    const DeviceRecord* r = h.Call(stop);
    ExpectOk(c, "DMC-STOP-002", r);
    ExpectOk(c, "DMC-STOP-003", r);
    Expect(c, "DMC-STOP-002", WaitRest(h, 10'000 * kMs), "every motor at rest after STOP_ALL",
           "still moving");
    h.Idle(1500 * kMs);  // past any "soon after" window
  }
  for (uint8_t m = 1; m <= motors; ++m) h.Call(dmc::MotorMove{m, At(*p0, m - 1u)});
  WaitRest(h, kRestTimeout);
}

// Distance travelled by motor 1 after STOP_ALL (twice when `twice`).
std::optional<int64_t> StopDistance(CaseContext& c, bool twice) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return std::nullopt;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 100000});
  h.Idle(600 * kMs);
  h.Call(dmc::MotorStopAll{});
  if (twice) h.Call(dmc::MotorStopAll{});
  WaitRest(h, 10'000 * kMs);
  const auto p1 = GetPositions(h);
  MoveAndRest(c, 1, At(*p0, 0));
  h.Idle(1500 * kMs);
  if (!p1) return std::nullopt;
  return static_cast<int64_t>(At(*p1, 0)) - At(*p0, 0);
}

void HardStop(CaseContext& c) {
  SetSpeed(c, 1, 2000, 4000);
  c.host.Idle(1500 * kMs);
  const auto single = StopDistance(c, false);
  const auto twice = StopDistance(c, true);
  if (!single || !twice) return;
  Expect(c, "DMC-STOP-004", *twice <= *single,
         "no further than a single STOP_ALL (" + std::to_string(*single) + " steps)",
         std::to_string(*twice) + " steps after two");
}

void Reset(CaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t value = At(*p0, 0) + 12345;
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-RST-001", h.Call(dmc::MotorResetPosition{1, value}));
  const int i = h.WaitFor(mark, 500 * kMs, [](const DeviceRecord& r) {
    return IsUnsolicited(r, MsgType::kMotorGetPosition);
  });
  const DeviceRecord* u = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
  const auto* rep = As<dmc::MotorPositionReport>(u);
  c.v.Check("DMC-RST-002", rep != nullptr && At(rep->positions_steps, 0) == value, [&] {
    return EvOf(h, u,
                "MOTOR_GET_POSITION with motor 1 = " + std::to_string(value) + " within 500 ms",
                Show(u));
  });
  const auto p1 = GetPositions(h);
  const DeviceRecord* r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  Expect(c, "DMC-RST-003",
         p1 && At(*p1, 0) == value && st != nullptr && (st->moving_bits & 1u) == 0,
         "motor 1 at rest reporting " + std::to_string(value),
         (p1 ? Vec(*p1) : "no position") + ", " + Show(r));
  h.Call(dmc::MotorResetPosition{1, At(*p0, 0)});
}

void Configure(CaseContext& c) {
  DmcHost& h = c.host;
  ExpectOk(c, "DMC-CFG-002", h.Call(dmc::MotorConfigure{1, dmc::kMotorEnabled | 0x40}));
  ExpectOk(c, "DMC-CFG-002", h.Call(dmc::MotorConfigure{1, dmc::kMotorEnabled}));
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0}));
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0);
  ExpectOk(c, "DMC-CFG-003", h.Call(dmc::MotorJog{1, dmc::kJogSpeedMax, start + 300}));
  WaitRest(h, kRestTimeout);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-CFG-003", p1 && At(*p1, 0) > start && At(*p1, 0) <= start + 300,
         "motor 1 moved towards " + std::to_string(start + 300), p1 ? Vec(*p1) : "no position");
  ExpectCode(c, "DMC-CFG-004", h.Call(dmc::MotorJog{1, 0, start}), AckCode::kErrRange);
  ExpectCode(c, "DMC-CFG-004", h.Call(dmc::MotorJog{1, 10001, start}), AckCode::kErrRange);
  MoveAndRest(c, 1, start);
}

void NoHostAck(CaseContext& c) {
  DmcHost& h = c.host;
  h.set_ack_unsolicited(false);
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 1500});
  for (int i = 0; i < 4; ++i) {
    h.Idle(150 * kMs);
    const DeviceRecord* r = h.Call(dmc::MotorStatusRequest{});
    Expect(c, "DMC-UNS-002", As<dmc::MotorStatusResponse>(r) != nullptr,
           "MOTOR_STATUS answered while updates go un-ACKed", Show(r));
  }
  MoveAndRest(c, 1, At(*p0, 0));
  h.set_ack_unsolicited(true);
}

void EStop(CaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 50000});
  h.Idle(300 * kMs);
  const size_t mark = h.records().size();
  if (!c.target.SetEStop(true)) {
    c.log.push_back("the target has no e-stop the runner can press: MOTOR_HARD_STOP not exercised");
    h.Call(dmc::MotorStopAll{});
    WaitRest(h, kRestTimeout);
    MoveAndRest(c, 1, At(*p0, 0));
    return;
  }
  const int i = h.WaitFor(mark, 500 * kMs, [](const DeviceRecord& r) {
    return IsUnsolicited(r, MsgType::kMotorHardStop);
  });
  const DeviceRecord* hs = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
  const auto* m = As<dmc::MotorHardStop>(hs);
  Expect(c, "DMC-UNS-003", m != nullptr && m->reason == 0 && !m->motor,
         "MOTOR_HARD_STOP reason=0 (E-Stop) without MOTOR within 500 ms", Show(hs));
  c.target.SetEStop(false);
  WaitRest(h, kRestTimeout);
  MoveAndRest(c, 1, At(*p0, 0));
}

// ---------------------------------------------------------------- errors

void BadMotor(CaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t bad[2] = {0, static_cast<uint8_t>(c.hi.motor_count + 1)};
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

void Checksum(CaseContext& c) {
  DmcHost& h = c.host;
  const uint32_t id = h.SendFrame(ToWire(MsgType::kHi), {}, true);
  const DeviceRecord* r = h.Await(id);
  ExpectCode(c, "DMC-CSUM-002", r, AckCode::kErrChecksum);
  c.v.Check("DMC-CSUM-003",
            r != nullptr && r->id == id && r->type == (ToWire(MsgType::kHi) | dmc::kFlagAck),
            [&] { return EvOf(h, r, "ACK HI with id=" + std::to_string(id), Show(r)); });
  r = h.Call(dmc::MotorStatusRequest{});
  Expect(c, "DMC-CSUM-005", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS answered after a corrupted frame", Show(r));
  if (c.hi.motor_count == 0) return;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  wire::Bytes data;
  dmc::EncodeData(dmc::HostMessage{dmc::MotorMove{1, At(*p0, 0) + 1000}}, data);
  r = h.Await(h.SendFrame(ToWire(MsgType::kMotorMove), data, true));
  ExpectCode(c, "DMC-CSUM-002", r, AckCode::kErrChecksum);
  h.Idle(200 * kMs);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-CSUM-005", p1 && *p1 == *p0, "a corrupted MOTOR_MOVE does not move: " + Vec(*p0),
         p1 ? Vec(*p1) : "no position");
}

void UnknownType(CaseContext& c) {
  DmcHost& h = c.host;
  ExpectCode(c, "DMC-ERR-003", h.Await(h.SendFrame(0x0077, {})), AckCode::kErrUnsupported);
  const uint8_t some[3] = {1, 2, 3};
  ExpectCode(c, "DMC-ERR-003", h.Await(h.SendFrame(0x0301, some)), AckCode::kErrUnsupported);
  ExpectCode(c, "DMC-ERR-004", h.Await(h.SendFrame(dmc::kLegacyVirtJogOnLineType, some)),
             AckCode::kErrUnsupported);
}

void BadLength(CaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t junk[8] = {1, 0, 0, 0, 0, 0, 0, 0};
  struct Bad {
    MsgType type;
    size_t len;
  };
  std::vector<Bad> bad = {{MsgType::kMotorStatus, 1}, {MsgType::kHi, 2}};
  if (c.hi.motor_count > 0) {
    bad.insert(bad.end(), {{MsgType::kMotorMove, 3},
                           {MsgType::kMotorSetSpeed, 5},
                           {MsgType::kMotorResetPosition, 6},
                           {MsgType::kMotorStop, 0}});
  }
  for (const Bad& b : bad) {
    const DeviceRecord* r = h.Await(h.SendFrame(ToWire(b.type), wire::ByteView(junk, b.len)));
    ExpectRefused(c, "DMC-ERR-005", r);
    const std::optional<uint32_t> code = AckCodeOf(r);
    if (code && *code != ToWire(AckCode::kOk)) {
      c.v.Check("DMC-ERR-006", *code == ToWire(AckCode::kErrGeneral),
                [&] { return EvOf(h, r, "ERR_GENERAL", CodeText(r)); });
    }
  }
}

void Noise(CaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t noise[] = {'x', 'y', 0x00, 0xff, 'D', 0x01, 'F', 'D'};
  h.SendNoise(noise);
  const DeviceRecord* r = h.Call(dmc::HiRequest{});
  Expect(c, "DMC-ERR-007", As<dmc::HiResponse>(r) != nullptr, "HI answered after noise", Show(r));
  // A header declaring Length 2000 and nothing after it.
  wire::Bytes over = {'D', 'F', 0x99, 0x99, 0, 0, 0x30, 0, 0xd0, 0x07};
  h.SendNoise(over);
  r = h.Call(dmc::MotorStatusRequest{});
  Expect(c, "DMC-ERR-008", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS answered after an oversize header", Show(r));
}

void MaxFrame(CaseContext& c) {
  DmcHost& h = c.host;
  const wire::Bytes data(dmc::kMaxDataLength, 0x11);
  const DeviceRecord* r = h.Await(h.SendFrame(0x0077, data));
  Expect(c, "DMC-ERR-012", AckCodeOf(r).has_value(), "an ACK to a 1048-byte frame", Show(r));
}

void Unadvertised(CaseContext& c) {
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtGetPositionRequest{}),
             AckCode::kErrUnsupported);
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtStop{1}), AckCode::kErrUnsupported);
}

void Io(CaseContext& c) {
  DmcHost& h = c.host;
  h.Call(dmc::GioInRequest{});
  if (c.hi.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{1}));
  if (c.hi.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{0}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{dmc::kGioCamShutter}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{0}));
}

void Dmx(CaseContext& c) {
  DmcHost& h = c.host;
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {10, 20, 30}}));
  ExpectCode(c, "DMC-ERR-011", h.Call(dmc::Dmx{0, 0, {10}}), AckCode::kErrRange);
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {0, 0, 0}}));
}

// ---------------------------------------------------------------- limits

void SoftLimits(CaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t s = At(*p0, 0);
  ExpectOk(c, "DMC-CFG-005",
           h.Call(dmc::MotorSetLimits{1, dmc::kLimitEnabled, s - 1000, dmc::kLimitEnabled, s + 1000,
                                      0}));
  ExpectCode(c, "DMC-LIM-001", h.Call(dmc::MotorMove{1, s + 2000}), AckCode::kErrSoftUp);
  ExpectCode(c, "DMC-LIM-002", h.Call(dmc::MotorMove{1, s - 2000}), AckCode::kErrSoftLow);
  h.Idle(200 * kMs);
  auto p = GetPositions(h);
  Expect(c, "DMC-LIM-003", p && At(*p, 0) == s, "motor 1 still at " + std::to_string(s),
         p ? Vec(*p) : "no position");
  const DeviceRecord* r = h.Call(dmc::MotorMove{1, s + 500});
  Expect(c, "DMC-LIM-004", As<dmc::MotorMoveResponse>(r) != nullptr, "MOTOR_MOVE response",
         Show(r));
  WaitRest(h, kRestTimeout);
  p = GetPositions(h);
  Expect(c, "DMC-LIM-004", p && At(*p, 0) == s + 500, "motor 1 at " + std::to_string(s + 500),
         p ? Vec(*p) : "no position");
  const size_t mark = h.records().size();
  h.Call(dmc::MotorJog{1, dmc::kJogSpeedMax, s + 5000});
  WaitRest(h, kRestTimeout);
  p = GetPositions(h);
  int32_t highest = p ? At(*p, 0) : 0;
  for (const Update& u : UpdatesSince(h, mark)) highest = std::max(highest, At(u.positions, 0));
  Expect(c, "DMC-LIM-006", highest <= s + 1000, "never above " + std::to_string(s + 1000),
         "reached " + std::to_string(highest));
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, s - 1000, 0, s + 1000, 0}));
  r = h.Call(dmc::MotorMove{1, s + 2000});
  Expect(c, "DMC-LIM-005", As<dmc::MotorMoveResponse>(r) != nullptr,
         "MOTOR_MOVE beyond a disabled limit accepted", Show(r));
  WaitRest(h, kRestTimeout);
  p = GetPositions(h);
  Expect(c, "DMC-LIM-005", p && At(*p, 0) == s + 2000, "motor 1 at " + std::to_string(s + 2000),
         p ? Vec(*p) : "no position");
  MoveAndRest(c, 1, s);
}

// ---------------------------------------------------------------- real-time

struct Uploaded {
  std::vector<std::vector<int32_t>> path;  // [motor-1][frame]: positions at frames 0..end
  uint32_t end = 0;
};

// Uploads frames 0..20: motor 1 climbs 40 steps a frame and motor 2 falls 25
// a frame over frames 0..10 (last set), then both hold.
std::optional<Uploaded> Upload(CaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return std::nullopt;
  Uploaded u;
  u.end = 20;
  const uint8_t motors = std::min<uint8_t>(c.hi.motor_count, 2);
  ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveBegin{0, u.end}));
  for (uint8_t m = 1; m <= motors; ++m) {
    const int32_t step = m == 1 ? 40 : -25;
    std::vector<int32_t> section;
    for (int k = 0; k <= 10; ++k) section.push_back(At(*p0, m - 1u) + step * k);
    ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveAxis{m, 0, true, section}));
    std::vector<int32_t> path = section;
    while (path.size() <= u.end) path.push_back(section.back());
    u.path.push_back(path);
  }
  ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveEnd{}));
  return u;
}

bool AtFrame(CaseContext& c, const Uploaded& u, uint32_t frame, std::string_view rule) {
  ExpectOk(c, rule, c.host.Call(dmc::RtPositionFrame{frame}));
  WaitRest(c.host, kRestTimeout);
  const auto p = GetPositions(c.host);
  std::vector<int32_t> want;
  for (const auto& path : u.path) want.push_back(path[frame]);
  bool ok = p.has_value();
  for (size_t i = 0; ok && i < want.size(); ++i) ok = (*p)[i] == want[i];
  return Expect(c, rule, ok, "frame " + std::to_string(frame) + " positions " + Vec(want),
                p ? Vec(*p) : "no position");
}

void UploadPosition(CaseContext& c) {
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 5, "DMC-RT-002");
  AtFrame(c, *u, 15, "DMC-RT-003");
  ExpectRefused(c, "DMC-RT-010", c.host.Call(dmc::RtPositionFrame{u->end + 1}));
  AtFrame(c, *u, 0, "DMC-RT-002");
}

dmc::RtRunMove ShortRun(uint32_t end) {
  dmc::RtRunMove run;
  run.fps_x1000 = 24000;
  run.start_frame = 0;
  run.end_frame = end;
  run.preroll_ms = 500;
  run.postroll_ms = 500;
  return run;  // FLAGS and the camera angles left out: 29 data bytes
}

void LiveRun(CaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  const uint32_t end = 10;
  ExpectOk(c, "DMC-RT-009", h.Call(ShortRun(end)));
  WaitRest(h, kRestTimeout);
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-RT-009", h.Call(dmc::RtGo{}));
  const int e = h.WaitFor(mark, 20'000 * kMs,
                          [](const DeviceRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, "DMC-RT-005", e >= 0, "RT_END after the run", "none within 20 s");
  h.Idle(500 * kMs);
  const int ends = CountSince(h, mark, MsgType::kRtEnd);
  Expect(c, "DMC-RT-006", ends <= 1, "one RT_END", std::to_string(ends) + " RT_END messages");
  const std::vector<Update> ups = UpdatesSince(h, mark);
  const double interval_ns = 1e9 / 24.0;
  const TimeNs slack = c.target.VirtualClock() ? 0 : 30 * kMs;
  TimeNs prev_t = -1;  // none yet
  for (uint32_t k = 0; k <= end; ++k) {
    const Update* first = nullptr;
    for (const Update& up : ups) {
      if (up.move_time / 1000 == k) {
        first = &up;
        break;
      }
    }
    if (!Expect(c, "DMC-RT-004", first != nullptr,
                "a report with MOVE TIME " + std::to_string(k * 1000),
                "none for frame " + std::to_string(k))) {
      prev_t = -1;
      continue;
    }
    if (prev_t >= 0) {
      const TimeNs dt = first->t_ns - prev_t;
      c.v.Check("DMC-RT-007",
                dt >= static_cast<TimeNs>(interval_ns * 0.5) - slack &&
                    dt <= static_cast<TimeNs>(interval_ns * 1.5) + slack,
                [&] {
                  return EvOf(h, first->rec, "about 41.7 ms after the previous frame's report",
                              std::to_string(dt / kMs) + " ms");
                });
    }
    prev_t = first->t_ns;
    for (size_t m = 0; m < u->path.size(); ++m) {
      const int32_t a = u->path[m][k], b = u->path[m][std::min(k + 1, u->end)];
      const int32_t p = At(first->positions, m);
      c.v.Check("DMC-RT-008", p >= std::min(a, b) && p <= std::max(a, b), [&] {
        return EvOf(h, first->rec,
                    "motor " + std::to_string(m + 1) + " within [" +
                        std::to_string(std::min(a, b)) + ", " + std::to_string(std::max(a, b)) +
                        "] at frame " + std::to_string(k),
                    std::to_string(p));
      });
    }
  }
  WaitRest(h, kRestTimeout);
}

void StopRun(CaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  h.Call(ShortRun(10));
  WaitRest(h, kRestTimeout);
  const size_t mark = h.records().size();
  h.Call(dmc::RtGo{});
  h.WaitFor(mark, 10'000 * kMs, [](const DeviceRecord& r) {
    const auto* p = As<dmc::MotorPositionReport>(&r);
    return r.request < 0 && p != nullptr && p->move_time_x1000 >= 3000;
  });
  const size_t stop_mark = h.records().size();
  ExpectOk(c, "DMC-STOP-002", h.Call(dmc::MotorStopAll{}));
  const int e = h.WaitFor(stop_mark, 5000 * kMs,
                          [](const DeviceRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, "DMC-RT-012", e >= 0, "RT_END after STOP_ALL ends the run", "none within 5 s");
  WaitRest(h, kRestTimeout);
}

void GoUnarmed(CaseContext& c) { ExpectRefused(c, "DMC-RT-011", c.host.Call(dmc::RtGo{})); }

void JogAll(CaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-RT-013", h.Call(dmc::RtJogAll{24000, 5}));
  WaitRest(h, kRestTimeout);
  h.Idle(200 * kMs);
  const std::vector<Update> ups = UpdatesSince(h, mark);
  for (uint32_t k = 1; k <= 5; ++k) {
    bool seen = false;
    for (const Update& up : ups) seen = seen || up.move_time / 1000 == k;
    Expect(c, "DMC-RT-013", seen, "a report with MOVE TIME " + std::to_string(k * 1000),
           "none for frame " + std::to_string(k));
  }
  const auto p = GetPositions(h);
  if (!p) return;
  MoveAndRest(c, 1, At(*p, 0) + 37);
  ExpectCode(c, "DMC-RT-014", h.Call(dmc::RtJogAll{24000, 0}), AckCode::kErrNotInPosition);
  MoveAndRest(c, 1, u->path[0][0]);
}

void Shoot(CaseContext& c, bool second) {
  DmcHost& h = c.host;
  const std::string_view rule = second ? "DMC-GM-002" : "DMC-GM-001";
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 3, "DMC-RT-002");
  const int32_t at = u->path[0][3];
  const std::vector<dmc::BlurMotor> blur = {{1, at - 20, at + 20}};
  if (second) {
    ExpectOk(c, rule, h.Call(dmc::RtShootFrame2{3, 200, 90, 270, blur}));
  } else {
    ExpectOk(c, rule, h.Call(dmc::RtShootFrame{3, dmc::kDirectionForward, 200, 500, blur}));
  }
  WaitRest(h, kRestTimeout);
  const size_t mark = h.records().size();
  ExpectOk(c, rule, h.Call(dmc::RtGo{}));
  const int e = h.WaitFor(mark, 10'000 * kMs,
                          [](const DeviceRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, rule, e >= 0, "RT_END after the exposure", "none within 10 s");
  WaitRest(h, kRestTimeout);
}

void StopLoop(CaseContext& c) { ExpectOk(c, "DMC-LOOP-001", c.host.Call(dmc::RtStopLoop{})); }

void VirtPosition(CaseContext& c) {
  const DeviceRecord* r = c.host.Call(dmc::VirtGetPositionRequest{});
  Expect(c, "DMC-VIRT-001", As<dmc::VirtPositionReport>(r) != nullptr, "VIRT_GET_POSITION response",
         Show(r));
}

// A boom-swing-track rig on motors 1..6 (boom 2.0 + level extension 0.5,
// angles 1000 steps per degree, track 10000 steps per unit), every POSITION 0.
constexpr int32_t kVirtAngleSpu = 1000;
constexpr int32_t kVirtTrackSpu = 10000;
constexpr int32_t kVirtTolerance = 200;  // 0.002 units or degrees, x100000

dmc::VirtRigBoomSwingTrack TestBoomRig() {
  dmc::VirtRigBoomSwingTrack b;
  b.boom = {1, kVirtAngleSpu, 0};
  b.swing = {2, kVirtAngleSpu, 0};
  b.track = {3, kVirtTrackSpu, 0};
  b.pan = {4, kVirtAngleSpu, 0};
  b.tilt = {5, kVirtAngleSpu, 0};
  b.roll = {6, kVirtAngleSpu, 0};
  b.boom_length_x1000 = 2000;
  b.boom_ext_x1000 = 500;
  return b;
}

bool ConfigureBoomRig(CaseContext& c) {
  return ExpectOk(c, "DMC-VIRT-002", c.host.Call(dmc::VirtConfig{TestBoomRig()}));
}

void Unconfigure(CaseContext& c) { c.host.Call(dmc::VirtConfig{dmc::VirtRigNone{}}); }

std::optional<dmc::VirtPositionReport> VirtPositions(DmcHost& h) {
  const auto* p = As<dmc::VirtPositionReport>(h.Call(dmc::VirtGetPositionRequest{}));
  if (p == nullptr) return std::nullopt;
  return *p;
}

void ExpectVirtAt(CaseContext& c, std::string_view rule, const char* axis, int32_t got,
                  int32_t want) {
  c.v.Check(rule, std::abs(int64_t{got} - want) <= kVirtTolerance, [&] {
    return EvOf(c.host, nullptr, std::string(axis) + " " + std::to_string(want) + " (x100000)",
                std::to_string(got));
  });
}

void VirtConfigForms(CaseContext& c) {
  DmcHost& h = c.host;
  constexpr uint32_t kModes = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                              dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz;
  char caps[16];
  std::snprintf(caps, sizeof caps, "0x%04x", c.hi.capabilities);
  Expect(c, "DMC-VIRT-011", (c.hi.capabilities & kModes) == kModes,
         "capabilities with 0x003c all set", caps);
  if ((c.hi.capabilities & dmc::kCapVirtBoomSwingTrack) != 0 && c.hi.motor_count >= 6) {
    // ERRATA 1.7: the table and SAFE DISTANCE are each optional.
    dmc::VirtRigBoomSwingTrack b = TestBoomRig();
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 93 bytes
    b.safe_distance_x1000 = 500;
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 97
    // A table in which the boom's present position is geometric 0 degrees,
    // one degree of axis per degree of angle.
    const auto p = GetPositions(h);
    const double boom_deg =
        static_cast<double>(At(p.value_or(std::vector<int32_t>{}), 0)) / kVirtAngleSpu;
    b.compensation.emplace();
    for (size_t i = 0; i < b.compensation->size(); ++i) {
      (*b.compensation)[i] = static_cast<int32_t>(
          std::lround((boom_deg + static_cast<double>(i) - 60.0) * dmc::kVirtPositionScale));
    }
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 581
    b.safe_distance_x1000.reset();
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 577
  }
  if ((c.hi.capabilities & dmc::kCapVirtXyz) != 0 && c.hi.motor_count >= 6) {
    // TYPE 8 with TYPE 1's layout: x-y-z in the bit-flag numbering.
    wire::Bytes data;
    dmc::EncodeData(dmc::HostMessage{dmc::VirtConfig{TestBoomRig()}}, data);
    dmc::VirtRigRaw raw;
    raw.type = static_cast<uint8_t>(dmc::RigType::kXyzFlag);
    raw.data.assign(data.begin() + 1, data.end());
    const DeviceRecord* r = h.Call(dmc::VirtConfig{raw});
    const std::optional<uint32_t> code = AckCodeOf(r);
    c.v.Check("DMC-VIRT-012", code && *code != ToWire(AckCode::kOk), [&] {
      return EvOf(h, r, "TYPE 8 refused (the spec numbers the rigs 0..4)",
                  CodeText(r) + ": TYPE 8 taken as x-y-z (bit-flag numbering)");
    });
  }
  Unconfigure(c);
}

void VirtMoveReadBack(CaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  // 0.1 units along the track, then 0.1 units up.
  ExpectOk(c, "DMC-VIRT-003", h.Call(dmc::VirtMove{1, p0->track_x100000 + 10000}));
  WaitRest(h, kRestTimeout);
  const auto p1 = VirtPositions(h);
  if (!p1) return;
  ExpectVirtAt(c, "DMC-VIRT-003", "vTrack", p1->track_x100000, p0->track_x100000 + 10000);
  ExpectOk(c, "DMC-VIRT-003", h.Call(dmc::VirtMove{3, p1->ns_x100000 + 10000}));
  WaitRest(h, kRestTimeout);
  const auto p2 = VirtPositions(h);
  if (!p2) return;
  ExpectVirtAt(c, "DMC-VIRT-003", "vNS", p2->ns_x100000, p1->ns_x100000 + 10000);
  ExpectVirtAt(c, "DMC-VIRT-003", "vTrack", p2->track_x100000, p1->track_x100000);
  // 6 units above a boom of 2: out of reach.
  const auto steps = GetPositions(h);
  const DeviceRecord* r = h.Call(dmc::VirtMove{3, p2->ns_x100000 + 600000});
  ExpectRefused(c, "DMC-VIRT-004", r);
  ExpectCode(c, "DMC-VIRT-005", r, AckCode::kErrRange);
  h.Idle(100 * kMs);
  const auto after = GetPositions(h);
  Expect(c, "DMC-VIRT-004", steps && after && *steps == *after,
         "motor positions unchanged: " + (steps ? Vec(*steps) : std::string("?")),
         after ? Vec(*after) : std::string("no MOTOR_GET_POSITION answer"));
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtMove{0, 0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtMove{7, 0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtStop{0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtStop{7}), AckCode::kErrRange);
  Unconfigure(c);
}

void VirtStopShort(CaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  const int32_t far = p0->track_x100000 + 2'000'000;  // 20 units: far enough to stop short of
  ExpectOk(c, "DMC-VIRT-007", h.Call(dmc::VirtMove{1, far}));
  h.Idle(200 * kMs);
  ExpectOk(c, "DMC-VIRT-007", h.Call(dmc::VirtStop{1}));
  Expect(c, "DMC-VIRT-007", WaitRest(h, 10'000 * kMs), "the rig at rest within 10 s of VIRT_STOP",
         "still moving");
  const auto p1 = VirtPositions(h);
  if (!p1) return;
  Expect(c, "DMC-VIRT-007", p1->track_x100000 < far - kVirtTolerance,
         "vTrack short of " + std::to_string(far), std::to_string(p1->track_x100000));
  h.Call(dmc::VirtMove{1, p0->track_x100000});
  WaitRest(h, kRestTimeout);
  Unconfigure(c);
}

void VirtJogs(CaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJog{1, dmc::kJogSpeedMax, p0->track_x100000 + 5000}));
  WaitRest(h, kRestTimeout);
  if (const auto p1 = VirtPositions(h)) {
    ExpectVirtAt(c, "DMC-VIRT-008", "vTrack", p1->track_x100000, p0->track_x100000 + 5000);
  }
  // Along the camera line, then speed 0; the pan, then VIRT_STOP.
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{2, 5000}));
  h.Idle(300 * kMs);
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{2, 0}));
  Expect(c, "DMC-VIRT-008", WaitRest(h, 10'000 * kMs), "at rest within 10 s of speed 0",
         "still moving");
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{3, -3000}));
  h.Idle(300 * kMs);
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtStop{4}));
  Expect(c, "DMC-VIRT-008", WaitRest(h, 10'000 * kMs), "at rest within 10 s of VIRT_STOP",
         "still moving");
  Unconfigure(c);
}

void VirtAim(CaseContext& c) {
  DmcHost& h = c.host;
  for (const dmc::VirtAimPoint& a :
       {dmc::VirtAimPoint{1, 1500, -250, 9000}, dmc::VirtAimPoint{0, 1500, -250, 9000}}) {
    const DeviceRecord* r = h.Call(a);
    const auto* echo = As<dmc::VirtAimPoint>(r);
    c.v.Check("DMC-VIRT-009", echo != nullptr && *echo == a, [&] {
      return EvOf(h, r, "VIRT_AIM_POINT enable=" + std::to_string(a.enable) + " 1500,-250,9000",
                  Show(r));
    });
    const auto p = VirtPositions(h);
    const bool same = p && p->aim && p->aim->enabled == a.enable && p->aim->x_x1000 == a.x_x1000 &&
                      p->aim->y_x1000 == a.y_x1000 && p->aim->z_x1000 == a.z_x1000;
    Expect(c, "DMC-VIRT-010", same,
           "aim fields enabled=" + std::to_string(a.enable) + " 1500,-250,9000",
           p && p->aim ? "enabled=" + std::to_string(p->aim->enabled) + " " +
                             std::to_string(p->aim->x_x1000) + "," +
                             std::to_string(p->aim->y_x1000) + "," + std::to_string(p->aim->z_x1000)
                       : std::string("no aim fields"));
  }
}

std::vector<Case> MakeCases() {
  using N = Needs;
  return {
      {"connect", "boot-hi", N::kNothing, "unsolicited HI at power-on", BootHi},
      {"connect", "hi", N::kNothing, "HI twice: layout, ranges, stable answer", HiAgain},
      {"connect", "bytewise", N::kNothing, "requests delivered one byte at a time", Bytewise},
      {"connect", "queries", N::kNothing, "MOTOR_STATUS, MOTOR_GET_POSITION, GIO_IN at rest",
       Queries},
      {"motor", "move", N::kMotors, "move with position updates, status and final position", Move},
      {"motor", "stop", N::kMotors, "MOTOR_STOP during a long move", Stop},
      {"motor", "stop-all", N::kMotors, "STOP_ALL with and without FLAGS", StopAll},
      {"motor", "hard-stop", N::kMotors, "a second STOP_ALL stops no later than one", HardStop},
      {"motor", "reset-position", N::kMotors, "RESET_POSITION and its position update", Reset},
      {"motor", "configure-jog", N::kMotors, "CONFIGURE, SET_LIMITS, SET_SPEED, JOG", Configure},
      {"motor", "no-host-ack", N::kMotors, "updates left un-ACKed do not stall the device",
       NoHostAck},
      {"motor", "estop", N::kMotors, "the e-stop button (in-process): MOTOR_HARD_STOP", EStop},
      {"errors", "bad-motor", N::kMotors, "motor 0 and MOTOR COUNT + 1 for every motor command",
       BadMotor},
      {"errors", "checksum", N::kNothing, "corrupted check bytes, then a valid request", Checksum},
      {"errors", "unknown-type", N::kNothing, "unknown and retired types", UnknownType},
      {"errors", "bad-length", N::kNothing, "known types with a wrong data length", BadLength},
      {"errors", "noise", N::kNothing, "noise and an oversize header between frames", Noise},
      {"errors", "max-frame", N::kNothing, "a frame filling the 1048-byte buffer", MaxFrame},
      {"errors", "unadvertised", N::kNoVirtual, "virtual messages to a device without virtuals",
       Unadvertised},
      {"io", "gio", N::kNothing, "GIO_IN, GIO_OUT, GIO_CAM", Io},
      {"io", "dmx", N::kDmx, "DMX set and channel 0", Dmx},
      {"limits", "soft", N::kMotors, "moves and a jog against enabled and disabled soft limits",
       SoftLimits},
      {"rt", "upload-position", N::kRealTime, "upload, POSITION_FRAME, last-set repeat, range",
       UploadPosition},
      {"rt", "live-run", N::kRealTime, "RUN_MOVE (short form), GO, frame reports, RT_END", LiveRun},
      {"rt", "stop-run", N::kRealTime, "STOP_ALL during a live run", StopRun},
      {"rt", "go-unarmed", N::kRealTime, "GO with nothing armed", GoUnarmed},
      {"rt", "jog-all", N::kRealTime, "JOG_ALL from a frame position and off it", JogAll},
      {"rt", "stop-loop", N::kLooping, "STOP_LOOP", StopLoop},
      {"gomotion", "shoot", N::kGoMotion, "SHOOT_FRAME, GO, RT_END",
       [](CaseContext& c) { Shoot(c, false); }},
      {"gomotion", "shoot2", N::kGoMotion2, "SHOOT_FRAME2, GO, RT_END",
       [](CaseContext& c) { Shoot(c, true); }},
      {"virtual", "get-position", N::kVirtual, "VIRT_GET_POSITION layout", VirtPosition},
      {"virtual", "config", N::kVirtual,
       "VIRT_CONFIG forms, the capability bits together, the TYPE 8 reading", VirtConfigForms},
      {"virtual", "move", N::kVirtualBoomRig,
       "VIRT_MOVE reached and read back, unreachable, virtual motor 0 and 7", VirtMoveReadBack},
      {"virtual", "stop", N::kVirtualBoomRig, "VIRT_STOP during a long virtual move",
       VirtStopShort},
      {"virtual", "jog", N::kVirtualBoomRig, "VIRT_JOG, VIRT_JOG_ON_LINE and their stops",
       VirtJogs},
      {"virtual", "aim-point", N::kAimPoint, "VIRT_AIM_POINT echo and the position's aim fields",
       VirtAim},
      {"random", "sequence", N::kMotors, "a seeded sequence of valid motor requests (--seed)",
       RandomSequence},
  };
}

}  // namespace

const std::vector<Case>& DmcCases() {
  static const std::vector<Case> cases = MakeCases();
  return cases;
}

std::optional<std::vector<int32_t>> GetPositions(DmcHost& host) {
  const auto* p = As<dmc::MotorPositionReport>(host.Call(dmc::MotorGetPositionRequest{}));
  if (p == nullptr) return std::nullopt;
  return p->positions_steps;
}

bool WaitRest(DmcHost& host, TimeNs timeout_ns) {
  const TimeNs until = host.Now() + timeout_ns;
  for (;;) {
    const auto* st = As<dmc::MotorStatusResponse>(host.Call(dmc::MotorStatusRequest{}));
    if (st == nullptr) return false;
    if (st->moving_bits == 0) return true;
    if (host.Now() >= until || host.link_lost()) return false;
    host.Idle(50 * kMs);
  }
}

std::string Transcript(const DmcHost& host) {
  struct Line {
    TimeNs t;
    size_t order;
    std::string text;
  };
  std::vector<Line> lines;
  size_t order = 0;
  for (const Request& r : host.requests()) {
    std::string text;
    auto f = dmc::DecodeFrame(r.raw);
    if (f.ok()) {
      auto m = dmc::DecodeHostMessage(f.value());
      text = m.ok() ? dmc::Describe(m.value()) : dmc::TypeName(r.type) + " (malformed)";
    } else {
      text = dmc::TypeName(r.type) + (r.bad_checksum ? " (bad checksum)" : " (not a frame)");
    }
    lines.push_back({r.sent_ns, order++, "host   > id=" + std::to_string(r.id) + " " + text});
  }
  for (const DeviceRecord& r : host.records()) {
    lines.push_back({r.t_ns, order++, "device < id=" + std::to_string(r.id) + " " + Show(&r)});
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.t < b.t; });
  std::string out;
  for (const Line& l : lines) {
    char t[32];
    std::snprintf(t, sizeof t, "%10.3f ms  ", static_cast<double>(l.t) / 1e6);
    out += t + l.text + "\n";
  }
  return out;
}

}  // namespace moco::conformance
