// DMC v2 scenario suites (dmc-v2-protocol.txt "Capabilities", "MSG_HI",
// "MSG_MOTOR_*", "MSG_RT_*", "Computing and Validating the Checksum"; ERRATA
// 1.2-1.11): each case drives Dragonframe-style traffic and judges what the
// device did against the named rules. Cases work relative to the positions
// they find, so they also run against a device that is not fresh.
#include "conformance/protocols/dmc/dmc_suites.h"

#include "conformance/protocols/dmc/dmc_cases_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>

namespace moco::conformance {
namespace dmc_cases {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;

Evidence EvOf(const DmcHost& h, const DeviceRecord* r, std::string expected, std::string observed) {
  return Evidence{std::move(expected), std::move(observed), r != nullptr ? wire::ToHex(r->raw) : "",
                  r != nullptr ? r->t_ns : h.Now()};
}

std::string CodeText(const DeviceRecord* r) {
  if (auto code = AckCodeOf(r)) return "ACK " + dmc::AckCodeName(*code);
  return Show(r);
}

// `rule` passes when `r` is an ACK with `want`.
bool ExpectCode(DmcCaseContext& c, std::string_view rule, const DeviceRecord* r, AckCode want) {
  const std::optional<uint32_t> code = AckCodeOf(r);
  return c.v.Check(rule, code && *code == ToWire(want), [&] {
    return EvOf(c.host, r, "ACK " + dmc::AckCodeName(ToWire(want)), CodeText(r));
  });
}

// `rule` and DMC-ACK-011 pass when `r` is ACK OK.
bool ExpectOk(DmcCaseContext& c, std::string_view rule, const DeviceRecord* r) {
  ExpectCode(c, "DMC-ACK-011", r, AckCode::kOk);
  return ExpectCode(c, rule, r, AckCode::kOk);
}

// `rule` passes when `r` is an ACK other than OK.
bool ExpectRefused(DmcCaseContext& c, std::string_view rule, const DeviceRecord* r) {
  const std::optional<uint32_t> code = AckCodeOf(r);
  return c.v.Check(rule, code && *code != ToWire(AckCode::kOk),
                   [&] { return EvOf(c.host, r, "an ACK with an error code", CodeText(r)); });
}

bool Expect(DmcCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed) {
  return c.v.Check(rule, ok, [&] { return EvOf(c.host, nullptr, expected, observed); });
}

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

bool ReportsAt(const DmcHost& h, size_t from, const std::optional<std::vector<int32_t>>& answer,
               size_t motor, const std::function<bool(int32_t)>& ok) {
  if (answer && ok(At(*answer, motor))) return true;
  const std::vector<Update> ups = UpdatesSince(h, from);
  return !ups.empty() && ok(At(ups.back().positions, motor));
}

bool MoveAccepted(const DeviceRecord* r) {
  return As<dmc::MotorMoveResponse>(r) != nullptr || AckCodeOf(r) == ToWire(AckCode::kOk);
}

const DeviceRecord* Go(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const TimeNs t0 = h.Now();
  const DeviceRecord* r = h.Call(dmc::RtGo{});
  int refusals = 0;
  while (AckCodeOf(r) == ToWire(AckCode::kErrNotInPosition) && h.Now() - t0 < kArmingLimit &&
         !h.link_lost()) {
    ++refusals;
    h.Idle(10 * kMs);
    r = h.Call(dmc::RtGo{});
  }
  if (AckCodeOf(r) == ToWire(AckCode::kOk)) {
    const TimeNs waited = h.Now() - t0;
    c.v.Check("DMC-RT-015", refusals == 0, [&] {
      return EvOf(h, r, "RT_GO accepted once the motors rest",
                  "ERR_NOT_IN_POSITION " + std::to_string(refusals) + " time(s) over " +
                      std::to_string(waited / kMs) + " ms after the motors rested, then OK");
    });
  }
  return r;
}

void MoveAndRest(DmcCaseContext& c, uint8_t motor, int32_t to) {
  c.host.Call(dmc::MotorMove{motor, to});
  WaitRest(c, kRestTimeout);
}

}  // namespace dmc_cases

namespace {

using namespace dmc_cases;  // NOLINT: the shared checks of every DMC case

// ---------------------------------------------------------------- connect

void BootHi(DmcCaseContext& c) {
  if (!c.target.CanRestart()) {
    // The start-up of an external device is not observed.
    c.v.NotExercised("DMC-HI-011",
                     "the runner cannot restart this target, so it never sees the device start "
                     "(simavr and in-process targets restart it)");
    return;
  }
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

void HiAgain(DmcCaseContext& c) {
  const DeviceRecord* r = c.host.Call(dmc::HiRequest{});
  Expect(c, "DMC-HI-001", As<dmc::HiResponse>(r) != nullptr, "HI response", Show(r));
}

void Bytewise(DmcCaseContext& c) {
  const DeviceRecord* r = c.host.Await(c.host.SendBytewise(dmc::HiRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::HiResponse>(r) != nullptr, "HI response to a byte-wise HI",
         Show(r));
  r = c.host.Await(c.host.SendBytewise(dmc::MotorStatusRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS response to a byte-wise MOTOR_STATUS", Show(r));
}

void Queries(DmcCaseContext& c) {
  const DeviceRecord* r = c.host.Call(dmc::MotorStatusRequest{});
  if (const auto* st = As<dmc::MotorStatusResponse>(r); st != nullptr && c.device.motor_count > 0) {
    c.v.Check("DMC-STAT-004", st->moving_bits == 0,
              [&] { return EvOf(c.host, r, "no motor moving at rest", Show(r)); });
  }
  // The positions' layout is judged by the host on whichever message carries
  // them (the response, or a message under ID 0 before an ACK OK, whose form
  // DMC-ACK-008 judges); here, that they came at all.
  const auto p = GetPositions(c.host);
  Expect(c, "DMC-POS-001", p.has_value(), "positions from MOTOR_GET_POSITION", "none");
  c.host.Call(dmc::GioInRequest{});
}

// ---------------------------------------------------------------- motor

void SetSpeed(DmcCaseContext& c, uint8_t motor, uint32_t v, uint32_t a) {
  ExpectOk(c, "DMC-CFG-001", c.host.Call(dmc::MotorSetSpeed{motor, v, a}));
}

void Move(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0), target = start + 2000;
  const size_t mark = h.records().size();
  const DeviceRecord* r = h.Call(dmc::MotorMove{1, target});
  const TimeNs t0 = r != nullptr ? r->t_ns : h.Now();
  const auto* mv = As<dmc::MotorMoveResponse>(r);
  // An ACK OK has no MOVING byte: the clause fails; the motion itself is
  // judged below all the same.
  c.v.Check("DMC-MOVE-002", mv != nullptr && mv->moving == 1,
            [&] { return EvOf(h, r, "MOTOR_MOVE moving=1", Show(r)); });
  h.Idle(250 * kMs);
  r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-STAT-004", st != nullptr && (st->moving_bits & 1u) != 0,
            [&] { return EvOf(h, r, "bit 0 set while motor 1 moves", Show(r)); });
  const bool rested = WaitRest(c, kRestTimeout);
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
  const auto p1 = GetPositions(h);
  if (!p1) {
    Expect(c, "DMC-POS-004", !ups.empty() && At(ups.back().positions, 0) == target,
           "a last update with motor 1 on " + std::to_string(target),
           ups.empty() ? "no update" : "last update " + Vec(ups.back().positions));
    return;
  }
  // The device tells where motor 1 rests twice: in its last update and in its
  // answer to MOTOR_GET_POSITION. When the two disagree, the one on the target
  // is taken for the motor and the other for the report at fault, so a motor
  // that stops short fails DMC-MOVE-003 alone, an answer off the motor fails
  // DMC-POS-006 alone and a last update off it DMC-POS-004 alone.
  const int32_t got = At(*p1, 0);
  const bool updated = !ups.empty();
  const int32_t rests = updated ? At(ups.back().positions, 0) : got;
  const std::string seen = updated ? ", last update " + std::to_string(rests) : std::string();
  Expect(c, "DMC-POS-004", updated && (rests == got || rests == target),
         "a last update with motor 1 where it rests (" + std::to_string(target) + ")",
         updated ? "last update " + Vec(ups.back().positions) + ", MOTOR_GET_POSITION " +
                       std::to_string(got)
                 : "no update");
  Expect(c, "DMC-MOVE-003", got == target || (updated && rests == target),
         "motor 1 at " + std::to_string(target),
         "MOTOR_GET_POSITION " + std::to_string(got) + seen);
  Expect(c, "DMC-POS-006", got == target || (updated && got == rests),
         "MOTOR_GET_POSITION motor 1 = " + std::to_string(target) + ", where it rests",
         Vec(*p1) + seen);
  bool others = p1->size() == p0->size();
  for (size_t i = 1; others && i < p1->size(); ++i) others = (*p1)[i] == (*p0)[i];
  Expect(c, "DMC-MOVE-004", others, "other motors as before " + Vec(*p0), Vec(*p1));
  r = h.Call(dmc::MotorMove{1, target});
  mv = As<dmc::MotorMoveResponse>(r);
  c.v.Check("DMC-MOVE-002", mv != nullptr && mv->moving == 0,
            [&] { return EvOf(h, r, "MOTOR_MOVE moving=0 for the current position", Show(r)); });
  MoveAndRest(c, 1, start);
}

void Stop(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0), far = start + 100000;
  h.Call(dmc::MotorMove{1, far});
  h.Idle(500 * kMs);
  ExpectOk(c, "DMC-STOP-001", h.Call(dmc::MotorStop{1}));
  const bool rested = WaitRest(c, 10'000 * kMs);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-STOP-001", rested && p1 && At(*p1, 0) > start && At(*p1, 0) < far,
         "motor 1 at rest between " + std::to_string(start) + " and " + std::to_string(far),
         p1 ? (rested ? "" : "still moving at ") + std::to_string(At(*p1, 0)) : "no position");
  MoveAndRest(c, 1, start);
}

void StopAll(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const uint8_t motors = std::min<uint8_t>(c.device.motor_count, 2);
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
    // Motor 1 was at about 1600 steps/s: decelerating at 4000 steps/s^2 it
    // travels about 300 steps after the STOP_ALL; a halt travels none.
    const auto at_stop = GetPositions(h);
    Expect(c, "DMC-STOP-002", WaitRest(c, 10'000 * kMs), "every motor at rest after STOP_ALL",
           "still moving");
    const auto at_rest = GetPositions(h);
    if (at_stop && at_rest) {
      const int64_t travel = static_cast<int64_t>(At(*at_rest, 0)) - At(*at_stop, 0);
      Expect(c, "DMC-STOP-005", travel > 0,
             "motor 1 decelerating on after STOP_ALL (about 300 steps at 4000 steps/s^2)",
             std::to_string(travel) + " steps after the STOP_ALL was answered");
    }
    h.Idle(1500 * kMs);  // past any "soon after" window
  }
  for (uint8_t m = 1; m <= motors; ++m) h.Call(dmc::MotorMove{m, At(*p0, m - 1u)});
  WaitRest(c, kRestTimeout);
}

// Distance travelled by motor 1 after STOP_ALL (twice when `twice`).
std::optional<int64_t> StopDistance(DmcCaseContext& c, bool twice) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return std::nullopt;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 100000});
  h.Idle(600 * kMs);
  h.Call(dmc::MotorStopAll{});
  if (twice) h.Call(dmc::MotorStopAll{});
  WaitRest(c, 10'000 * kMs);
  const auto p1 = GetPositions(h);
  MoveAndRest(c, 1, At(*p0, 0));
  h.Idle(1500 * kMs);
  if (!p1) return std::nullopt;
  return static_cast<int64_t>(At(*p1, 0)) - At(*p0, 0);
}

void HardStop(DmcCaseContext& c) {
  SetSpeed(c, 1, 2000, 4000);
  c.host.Idle(1500 * kMs);
  const auto single = StopDistance(c, false);
  const auto twice = StopDistance(c, true);
  if (!single || !twice) return;
  // "it should HARD STOP. Meaning it should decelerate faster than normal":
  // strictly shorter, so a device ignoring the second STOP_ALL fails.
  Expect(c, "DMC-STOP-004", *twice < *single,
         "shorter than after a single STOP_ALL (" + std::to_string(*single) + " steps)",
         std::to_string(*twice) + " steps after two");
}

void Reset(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t value = At(*p0, 0) + 12345;
  const size_t mark = h.records().size();
  const DeviceRecord* ack = h.Call(dmc::MotorResetPosition{1, value});
  ExpectOk(c, "DMC-RST-001", ack);
  // "After changing the internal position and responding to this message":
  // the update follows the answer, so only records after the ACK count.
  size_t after = mark;
  for (size_t k = mark; ack != nullptr && k < h.records().size(); ++k) {
    if (&h.records()[k] == ack) after = k + 1;
  }
  const int i = h.WaitFor(after, 500 * kMs, [](const DeviceRecord& r) {
    return IsUnsolicited(r, MsgType::kMotorGetPosition);
  });
  const DeviceRecord* u = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
  const auto* rep = As<dmc::MotorPositionReport>(u);
  c.v.Check("DMC-RST-002", rep != nullptr && At(rep->positions_steps, 0) == value, [&] {
    const std::string want = "MOTOR_GET_POSITION with motor 1 = " + std::to_string(value) +
                             " after the ACK, within 500 ms";
    if (u == nullptr) {
      // A confirming message sent before the answer is not "after ...
      // responding": say so, rather than "no answer".
      for (size_t k = mark; k < after && k < h.records().size(); ++k) {
        const DeviceRecord& before = h.records()[k];
        const auto* early = As<dmc::MotorPositionReport>(&before);
        if (IsUnsolicited(before, MsgType::kMotorGetPosition) && early != nullptr &&
            At(early->positions_steps, 0) == value) {
          return EvOf(h, &before, want,
                      "sent " + std::to_string((ack->t_ns - before.t_ns) / 1000) +
                          " us before the ACK, none after it: " + Show(&before));
        }
      }
    }
    return EvOf(h, u, want, Show(u));
  });
  const auto p1 = GetPositions(h);
  const DeviceRecord* r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  const bool at_value = ReportsAt(h, mark, p1, 0, [&](int32_t v) { return v == value; });
  Expect(c, "DMC-RST-003", at_value && st != nullptr && (st->moving_bits & 1u) == 0,
         "motor 1 at rest reporting " + std::to_string(value),
         (p1 ? Vec(*p1) : "no position") + ", " + Show(r));
  h.Call(dmc::MotorResetPosition{1, At(*p0, 0)});
}

void Configure(DmcCaseContext& c) {
  DmcHost& h = c.host;
  ExpectOk(c, "DMC-CFG-002", h.Call(dmc::MotorConfigure{1, dmc::kMotorEnabled | 0x40}));
  ExpectOk(c, "DMC-CFG-002", h.Call(dmc::MotorConfigure{1, dmc::kMotorEnabled}));
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0}));
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0);
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-CFG-003", h.Call(dmc::MotorJog{1, dmc::kJogSpeedMax, start + 300}));
  WaitRest(c, kRestTimeout);
  const auto p1 = GetPositions(h);
  Expect(c, "DMC-CFG-003",
         ReportsAt(h, mark, p1, 0, [&](int32_t v) { return v > start && v <= start + 300; }),
         "motor 1 moved towards " + std::to_string(start + 300), p1 ? Vec(*p1) : "no position");
  ExpectCode(c, "DMC-CFG-004", h.Call(dmc::MotorJog{1, 0, start}), AckCode::kErrRange);
  ExpectCode(c, "DMC-CFG-004", h.Call(dmc::MotorJog{1, 10001, start}), AckCode::kErrRange);
  MoveAndRest(c, 1, start);
}

// MSG_MOTOR_JOG: "A speed of 1 means the device should move very slowly ...
// A value in between 1 and 10,000 should provide an appropriate speed between
// 1% and 100% of the jog speed." Each jog heads for a far destination for the
// same time; what it covers in that time orders the speeds. At 3000 steps/s
// and 6000 steps/s^2, 600 ms of a full-speed jog cover about 1000 steps and 1%
// of it under 20.
void JogSpeeds(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0);
  struct Leg {
    uint16_t speed;
    std::optional<int64_t> travel;
  };
  std::vector<Leg> legs = {{dmc::kJogSpeedMax, {}}, {2500, {}}, {dmc::kJogSpeedInch, {}}};
  for (Leg& leg : legs) {
    if (!ExpectOk(c, "DMC-CFG-003", h.Call(dmc::MotorJog{1, leg.speed, start + 100000}))) break;
    h.Idle(600 * kMs);
    const auto p = GetPositions(h);
    h.Call(dmc::MotorStop{1});
    WaitRest(c, 10'000 * kMs);
    if (p) leg.travel = static_cast<int64_t>(At(*p, 0)) - start;
    MoveAndRest(c, 1, start);
  }
  std::string seen;
  for (const Leg& leg : legs) {
    seen += (seen.empty() ? "" : ", ") + std::string("SPEED ") + std::to_string(leg.speed) + ": " +
            (leg.travel ? std::to_string(*leg.travel) + " steps" : "not measured");
  }
  if (!legs[0].travel || !legs[1].travel || !legs[2].travel) return;
  const int64_t full = *legs[0].travel, part = *legs[1].travel, inch = *legs[2].travel;
  Expect(c, "DMC-CFG-006", full > 0 && part < full && inch < part && inch * 10 <= full,
         "in 600 ms: SPEED 10000 > SPEED 2500 > SPEED 1 steps, SPEED 1 at most a tenth of "
         "SPEED 10000",
         seen);
}

// Capabilities "0x0100 Couple motors" through the MOTOR_CONFIGURE flags of
// the reference firmware (FACTS "DMC v2": 0x10 coupled, 0x20 coupled
// reversed). Motor 2 is coupled, both ways, then uncoupled; motor 1 moves.
void Couple(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t s1 = At(*p0, 0), s2 = At(*p0, 1);
  constexpr int32_t kTravel = 400;
  // Motor 1 moves out and back; `want2` is where motor 2 must be at the far end.
  const auto follow = [&](int32_t want2, const std::string& how) {
    const size_t mark = h.records().size();
    MoveAndRest(c, 1, s1 + kTravel);
    const auto p = GetPositions(h);
    Expect(c, "DMC-CFG-008",
           ReportsAt(h, mark, p, 1, [&](int32_t v) { return v == want2; }) &&
               ReportsAt(h, mark, p, 0, [&](int32_t v) { return v == s1 + kTravel; }),
           "motor 1 at " + std::to_string(s1 + kTravel) + ", motor 2 (" + how + ") at " +
               std::to_string(want2),
           p ? Vec(*p) : "no position");
    MoveAndRest(c, 1, s1);
  };
  const struct {
    uint8_t flag;
    int32_t sign;
    const char* how;
  } kinds[] = {{dmc::kMotorCoupled, 1, "coupled"},
               {dmc::kMotorCoupledReversed, -1, "coupled reversed"}};
  for (const auto& k : kinds) {
    const auto at = GetPositions(h);
    if (!at) return;
    const DeviceRecord* r = h.Call(dmc::MotorConfigure{2, uint8_t(dmc::kMotorEnabled | k.flag)});
    if (!ExpectOk(c, "DMC-CFG-007", r)) continue;
    follow(At(*at, 1) + k.sign * kTravel, k.how);
  }
  ExpectOk(c, "DMC-CFG-007", h.Call(dmc::MotorConfigure{2, dmc::kMotorEnabled}));
  const auto at = GetPositions(h);
  if (!at) return;
  follow(At(*at, 1), "uncoupled, standing");
  MoveAndRest(c, 2, s2);
}

void NoHostAck(DmcCaseContext& c) {
  DmcHost& h = c.host;
  h.set_ack_unsolicited(false);
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const size_t mark = h.records().size();
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 1500});
  for (int i = 0; i < 4; ++i) {
    h.Idle(150 * kMs);
    const DeviceRecord* r = h.Call(dmc::MotorStatusRequest{});
    Expect(c, "DMC-UNS-002", As<dmc::MotorStatusResponse>(r) != nullptr,
           "MOTOR_STATUS answered while updates go un-ACKed", Show(r));
  }
  // Nor do its updates stall: the move lasts well over 600 ms, so a device
  // reporting about every 0.10 s has sent several while none was ACKed.
  const size_t updates = UpdatesSince(h, mark).size();
  Expect(c, "DMC-UNS-002", updates >= 3, "position updates going on while none is ACKed",
         std::to_string(updates) + " update(s) in 600 ms of motion");
  MoveAndRest(c, 1, At(*p0, 0));
  h.set_ack_unsolicited(true);
}

void EStop(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 50000});
  h.Idle(300 * kMs);
  const size_t mark = h.records().size();
  if (!c.target.SetEStop(true)) {
    c.log.push_back("the target has no e-stop the runner can press: MOTOR_HARD_STOP not exercised");
    c.v.NotExercised("DMC-UNS-003",
                     "the target has no e-stop the runner can press (an external device: press it "
                     "by hand, or certify the emulation in-process)");
    h.Call(dmc::MotorStopAll{});
    WaitRest(c, kRestTimeout);
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
  WaitRest(c, kRestTimeout);
  MoveAndRest(c, 1, At(*p0, 0));
}

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
  const DeviceRecord* r = h.Await(id);
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
  h.Idle(200 * kMs);
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
    const DeviceRecord* r = h.Await(h.SendFrame(ToWire(b.type), wire::ByteView(junk, b.len)));
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
    const DeviceRecord* r = h.Await(h.SendFrame(ToWire(b.type), wire::ByteView(junk, b.len)));
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
  const DeviceRecord* r = h.Call(dmc::HiRequest{});
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
  const DeviceRecord* r = h.Await(h.SendFrame(0x0077, data));
  // ERR_UNSUPPORTED proves the frame was read whole and its checksum found
  // good; ERR_CHECKSUM or silence means the buffer did not hold it.
  ExpectCode(c, "DMC-ERR-012", r, AckCode::kErrUnsupported);
}

void Unadvertised(DmcCaseContext& c) {
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtGetPositionRequest{}),
             AckCode::kErrUnsupported);
  ExpectCode(c, "DMC-ERR-010", c.host.Call(dmc::VirtStop{1}), AckCode::kErrUnsupported);
}

void Io(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (As<dmc::GioInReport>(h.Call(dmc::GioInRequest{})) == nullptr) {
    c.v.NotExercised("DMC-GIO-002",
                     "the device answered GIO_IN without its inputs (DMC-GIO-001), so no TRIGGERS "
                     "bits could be judged");
  }
  if (c.device.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{1}));
  if (c.device.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{0}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{dmc::kGioCamShutter}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{0}));
}

void Dmx(DmcCaseContext& c) {
  DmcHost& h = c.host;
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {10, 20, 30}}));
  ExpectCode(c, "DMC-ERR-011", h.Call(dmc::Dmx{0, 0, {10}}), AckCode::kErrRange);
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {0, 0, 0}}));
  // MSG_DMX "If RAMP is set to 1, the device should ramp the light value ...
  // rather than switching to it immediately"; MSG_MOTOR_STATUS "DMX STATUS
  // BYTE 1=DMX adjusting, 0=Not adjusting". Channel 1 ramps over its full range.
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{1, 1, {255}}));
  const DeviceRecord* r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-DMX-002", st != nullptr && st->dmx_adjusting == 1, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 1 right after a ramp to 255 began", Show(r));
  });
  // The ramp ends: polled as a host waiting for the rig to settle would.
  const TimeNs until = h.Now() + 30'000 * kMs;
  for (;;) {
    r = h.Call(dmc::MotorStatusRequest{});
    st = As<dmc::MotorStatusResponse>(r);
    if (st == nullptr || st->dmx_adjusting == 0 || h.Now() >= until) break;
    h.Idle(100 * kMs);
  }
  c.v.Check("DMC-DMX-003", st != nullptr && st->dmx_adjusting == 0, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 0 within 30 s of the ramp", Show(r));
  });
  // "RAMP BYTE 1=ramp, 0=immediate": back to 0 at once.
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {0}}));
  r = h.Call(dmc::MotorStatusRequest{});
  st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-DMX-004", st != nullptr && st->dmx_adjusting == 0, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 0 right after an immediate set", Show(r));
  });
}

// ---------------------------------------------------------------- limits

void SoftLimits(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 3000, 6000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t s = At(*p0, 0);
  ExpectOk(c, "DMC-CFG-005",
           h.Call(dmc::MotorSetLimits{1, dmc::kLimitEnabled, s - 1000, dmc::kLimitEnabled, s + 1000,
                                      0}));
  const bool up =
      ExpectCode(c, "DMC-LIM-001", h.Call(dmc::MotorMove{1, s + 2000}), AckCode::kErrSoftUp);
  WaitRest(c, kRestTimeout);
  const bool low =
      ExpectCode(c, "DMC-LIM-002", h.Call(dmc::MotorMove{1, s - 2000}), AckCode::kErrSoftLow);
  h.Idle(200 * kMs);
  WaitRest(c, kRestTimeout);
  auto p = GetPositions(h);
  // Judged when both moves were refused: a device that leaves soft limits to
  // the host (LIM-001/002, SHOULD) has carried them out, rightly moving.
  if (up && low) {
    Expect(c, "DMC-LIM-003", p && At(*p, 0) == s, "motor 1 still at " + std::to_string(s),
           p ? Vec(*p) : "no position");
  } else {
    c.v.NotExercised("DMC-LIM-003",
                     "the device refused neither move past its soft limits (DMC-LIM-001/002), so "
                     "no refused move could leave the motor in place");
  }
  if (p && At(*p, 0) != s) MoveAndRest(c, 1, s);
  // Carried out: on the target within a step, by either of the device's
  // reports (landing exactly is DMC-MOVE-003's, each report's accuracy
  // DMC-POS-004's and DMC-POS-006's).
  const auto near = [](int32_t want) {
    return [want](int32_t v) { return v >= want - 1 && v <= want + 1; };
  };
  size_t mark = h.records().size();
  const DeviceRecord* r = h.Call(dmc::MotorMove{1, s + 500});
  Expect(c, "DMC-LIM-004", MoveAccepted(r), "MOTOR_MOVE accepted", Show(r));
  WaitRest(c, kRestTimeout);
  p = GetPositions(h);
  Expect(c, "DMC-LIM-004", ReportsAt(h, mark, p, 0, near(s + 500)),
         "motor 1 at " + std::to_string(s + 500) + " (within a step)", p ? Vec(*p) : "no position");
  mark = h.records().size();
  h.Call(dmc::MotorJog{1, dmc::kJogSpeedMax, s + 5000});
  WaitRest(c, kRestTimeout);
  p = GetPositions(h);
  int32_t highest = p ? At(*p, 0) : 0;
  for (const Update& u : UpdatesSince(h, mark)) highest = std::max(highest, At(u.positions, 0));
  Expect(c, "DMC-LIM-006", highest <= s + 1000, "never above " + std::to_string(s + 1000),
         "reached " + std::to_string(highest));
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, s - 1000, 0, s + 1000, 0}));
  mark = h.records().size();
  r = h.Call(dmc::MotorMove{1, s + 2000});
  Expect(c, "DMC-LIM-005", MoveAccepted(r), "MOTOR_MOVE beyond a disabled limit accepted", Show(r));
  WaitRest(c, kRestTimeout);
  p = GetPositions(h);
  Expect(c, "DMC-LIM-005", ReportsAt(h, mark, p, 0, near(s + 2000)),
         "motor 1 at " + std::to_string(s + 2000) + " (within a step)",
         p ? Vec(*p) : "no position");
  MoveAndRest(c, 1, s);
}

// A hardware limit switch closing under a moving motor (in-process: the
// runner closes the switch): MSG_MOTOR_HARD_STOP "can send this when a limit
// has been hit", REASON 1 = upper, 2 = lower, with the MOTOR; the motor halts.
void HardLimit(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t s = At(*p0, 0);
  // Motor 1 bound to hardware set 1, soft limits off (MSG_MOTOR_SET_LIMITS HW SET).
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 1}));
  struct End {
    bool high;
    int32_t towards;
    uint8_t reason;
    const char* name;
  };
  const End ends[] = {{true, s + 50000, 1, "upper"}, {false, s - 50000, 2, "lower"}};
  // Whether the runner can reach the switches is asked before anything moves
  // (opening an open switch changes nothing): a motor sent off and stopped
  // with STOP_ALL instead would put a device with a STOP_ALL lockout (the
  // reference firmware's 2 s) into it, and the case's own SET_LIMITS after
  // would be refused for the runner's doing.
  const bool reachable =
      c.target.SetLimitInput(1, true, false) && c.target.SetLimitInput(1, false, false);
  if (!reachable) {
    c.log.push_back(
        "the target has no limit switch the runner can close: hardware limits not exercised");
  }
  for (const End& e : ends) {
    if (!reachable) break;
    h.Call(dmc::MotorMove{1, e.towards});
    h.Idle(300 * kMs);
    const size_t mark = h.records().size();
    if (!c.target.SetLimitInput(1, e.high, true)) {
      // Reached a moment ago: the link went meanwhile.
      h.Call(dmc::MotorStopAll{});
      WaitRest(c, kRestTimeout);
      break;
    }
    const int i = h.WaitFor(mark, 500 * kMs, [](const DeviceRecord& r) {
      return IsUnsolicited(r, MsgType::kMotorHardStop);
    });
    const DeviceRecord* hs = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
    const auto* m = As<dmc::MotorHardStop>(hs);
    Expect(c, "DMC-LIM-007", m != nullptr && m->reason == e.reason && m->motor == uint8_t{1},
           std::string("MOTOR_HARD_STOP reason=") + std::to_string(e.reason) + " motor=1 within " +
               "500 ms of the " + e.name + " switch closing",
           Show(hs));
    const bool halted = WaitRest(c, 200 * kMs);
    Expect(c, "DMC-LIM-007", halted,
           std::string("motor 1 at rest within 200 ms of the ") + e.name + " switch closing",
           "still moving");
    c.target.SetLimitInput(1, e.high, false);
    if (!halted) {
      h.Call(dmc::MotorStopAll{});
      WaitRest(c, kRestTimeout);
    }
  }
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0}));
  MoveAndRest(c, 1, s);
}

// A general I/O input changing (in-process: the runner drives it): "The
// device should also send this message, unsolicited, any time the inputs
// change" (MSG_GIO_IN), after its debounce.
void GioInputChange(DmcCaseContext& c) {
  DmcHost& h = c.host;
  for (const bool level : {true, false}) {
    const size_t mark = h.records().size();
    if (!c.target.SetGioInput(0, level)) {
      c.log.push_back(
          "the target has no input the runner can drive: GIO_IN on change not exercised");
      c.v.NotExercised("DMC-GIO-005",
                       "the target has no input the runner can drive (in-process targets do)");
      return;
    }
    const int i = h.WaitFor(
        mark, 1000 * kMs, [](const DeviceRecord& r) { return IsUnsolicited(r, MsgType::kGioIn); });
    const DeviceRecord* g = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
    const auto* in = As<dmc::GioInReport>(g);
    Expect(c, "DMC-GIO-005", in != nullptr && ((in->triggers & 1u) != 0) == level,
           std::string("an unsolicited GIO_IN with input 1 ") + (level ? "set" : "clear") +
               " within 1 s of the change",
           Show(g));
  }
}

std::vector<DmcCase> MakeCases() {
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
      {"motor", "jog-speeds", N::kMotors, "JOG at SPEED 10000, 2500 and 1: the pace follows SPEED",
       JogSpeeds},
      {"motor", "couple", N::kCoupleMotors, "motor 2 coupled, coupled reversed, uncoupled", Couple},
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
      {"io", "dmx", N::kDmx, "DMX set, channel 0, a ramp and its DMX STATUS", Dmx},
      {"io", "gio-in-change", N::kGioIn, "an input changing (in-process): GIO_IN sent unsolicited",
       GioInputChange},
      {"limits", "soft", N::kMotors, "moves and a jog against enabled and disabled soft limits",
       SoftLimits},
      {"limits", "hard", N::kHwLimits,
       "hardware limit switches closing under a moving motor (in-process): MOTOR_HARD_STOP",
       HardLimit},
      {"rt", "upload-position", N::kRealTime, "upload, POSITION_FRAME, last-set repeat, range",
       UploadPosition},
      {"rt", "live-run", N::kRealTime, "RUN_MOVE (short form), GO, frame reports, RT_END", LiveRun},
      {"rt", "stop-run", N::kRealTime, "STOP_ALL during a live run", StopRun},
      {"rt", "go-unarmed", N::kRealTime, "GO with nothing armed", GoUnarmed},
      {"rt", "jog-all", N::kRealTime, "JOG_ALL from a frame position and off it", JogAll},
      {"rt", "stop-loop", N::kLooping, "STOP_LOOP", StopLoop},
      {"rt", "upload-dmx", N::kRtDmx,
       "UPLOAD_MOVE_DMX sections and refusals; POSITION_FRAME sets the uploaded levels", UploadDmx},
      {"rt", "sync-run", N::kRtDmx,
       "RUN_MOVE with SYNC DMX 1 plays the levels per frame, with 0 leaves them; DMX bloop",
       SyncRun},
      {"rt", "triggers", N::kRtTriggers,
       "UPLOAD_MOVE_TRIGGERS; the GIO outputs follow them per frame; GIO bloop", Triggers},
      {"rt", "camera-stills", N::kRtCamera,
       "RUN_MOVE FLAGS 0x20: one exposure per frame between the camera angles; bad angles",
       CameraStills},
      {"rt", "camera-video", N::kRtCamera,
       "RUN_MOVE FLAGS 0x10: a shutter press at the start and at the end of the run", CameraVideo},
      {"rt", "roll-limits", N::kRealTime,
       "pre-roll and post-roll past soft limits: ERR_PREROLL, ERR_POSTROLL; within: accepted",
       RollLimits},
      {"gomotion", "shoot", N::kGoMotion, "SHOOT_FRAME, GO, RT_END",
       [](DmcCaseContext& c) { Shoot(c, false); }},
      {"gomotion", "shoot2", N::kGoMotion2, "SHOOT_FRAME2, GO, RT_END",
       [](DmcCaseContext& c) { Shoot(c, true); }},
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

const std::vector<DmcCase>& DmcCases() {
  static const std::vector<DmcCase> cases = MakeCases();
  return cases;
}

std::optional<std::vector<int32_t>> GetPositions(DmcHost& host) {
  const size_t mark = host.records().size();
  const DeviceRecord* r = host.Call(dmc::MotorGetPositionRequest{});
  if (const auto* p = As<dmc::MotorPositionReport>(r)) return p->positions_steps;
  // A device that sends the positions as a message of its own (ID 0, as the
  // reference firmware does) and then ACKs the request OK: DMC-ACK-008 has
  // judged that form; the positions are the last such message before the ACK.
  if (r == nullptr || AckCodeOf(r) != ToWire(AckCode::kOk)) return std::nullopt;
  std::optional<std::vector<int32_t>> found;
  for (size_t i = mark; i < host.records().size() && &host.records()[i] != r; ++i) {
    const DeviceRecord& u = host.records()[i];
    if (u.request >= 0) continue;
    if (const auto* p = As<dmc::MotorPositionReport>(&u)) found = p->positions_steps;
  }
  return found;
}

namespace {

// A device "should send [position updates] about every 0.10 seconds, if any of
// the motors are moving": a rest the updates have not contradicted for this
// long (from the last update or the last command) is believed.
constexpr TimeNs kQuietForRest = 150 * kMs;

bool IsQuery(uint16_t type) {
  return type == ToWire(MsgType::kMotorStatus) || type == ToWire(MsgType::kMotorGetPosition) ||
         type == ToWire(MsgType::kHi) || (type & dmc::kFlagAck) != 0;
}

// How long after a command a device may take to start its motion (two of
// dmc-lite's 20 ms motion ticks, and a margin): a MOTOR_STATUS of 0 asked
// before then is not stale.
constexpr TimeNs kStartLatency = 50 * kMs;

// When the host last sent a request other than a query; 0 when none.
TimeNs LastCommandSent(const DmcHost& h) {
  for (auto it = h.requests().rbegin(); it != h.requests().rend(); ++it) {
    if (!IsQuery(it->type)) return it->sent_ns;
  }
  return 0;
}

// When the device last showed or was told of motion before record `end`:
// its last position update, or the host's last request other than a query.
TimeNs LastActivity(const DmcHost& h, size_t end) {
  TimeNs t = 0;
  for (size_t i = end; i-- > 0;) {
    const DeviceRecord& r = h.records()[i];
    if (r.request < 0 && As<dmc::MotorPositionReport>(&r) != nullptr) {
      t = r.t_ns;
      break;
    }
  }
  for (auto it = h.requests().rbegin(); it != h.requests().rend(); ++it) {
    if (!IsQuery(it->type)) {
      t = std::max(t, it->sent_ns);
      break;
    }
  }
  return t;
}

// The positions the device last reported before record `end` (an update or
// an answer), or nullptr.
const dmc::MotorPositionReport* LastPositions(const DmcHost& h, size_t end) {
  for (size_t i = end; i-- > 0;) {
    if (const auto* p = As<dmc::MotorPositionReport>(&h.records()[i])) return p;
  }
  return nullptr;
}

// The index of the first unsolicited update from record `from` on whose
// positions differ from `base`, or nullopt.
std::optional<size_t> MovedSince(const DmcHost& h, size_t from,
                                 const dmc::MotorPositionReport* base) {
  for (size_t i = from; i < h.records().size(); ++i) {
    const DeviceRecord& r = h.records()[i];
    if (r.request >= 0) continue;
    const auto* p = As<dmc::MotorPositionReport>(&r);
    if (p != nullptr && (base == nullptr || p->positions_steps != base->positions_steps)) return i;
  }
  return std::nullopt;
}

}  // namespace

RestWait WaitRestSeen(DmcHost& host, TimeNs timeout_ns) {
  const TimeNs until = host.Now() + timeout_ns;
  RestWait w;
  for (;;) {
    const DeviceRecord* r = host.Call(dmc::MotorStatusRequest{});
    const auto* st = As<dmc::MotorStatusResponse>(r);
    if (st == nullptr) {
      // No status to go by (its answer is missing, already judged): the
      // position updates tell when the motion ended. What the case checks
      // next is then judged on a motion that ended, whether the host waited
      // out the answer timeout or not (HostOptions::give_up_after_unanswered).
      for (;;) {
        const TimeNs quiet_at = LastActivity(host, host.records().size()) + kQuietForRest;
        if (host.Now() >= quiet_at || host.Now() >= until || host.link_lost()) return w;
        host.Idle(std::min(quiet_at, until) - host.Now());
      }
    }
    if (st->moving_bits == 0) {
      // "MOTOR STATUS ... bit set = motor moving" at rest; believed once the
      // position updates have been quiet for an update period: a move's last
      // update, or a command just sent, may precede it, and a status gone stale
      // shows as an update that still moves.
      const size_t mark = host.records().size();
      const TimeNs quiet_at = LastActivity(host, mark) + kQuietForRest;
      if (r->t_ns >= quiet_at) return w.rested = true, w;
      host.Idle(quiet_at - host.Now());
      const std::optional<size_t> moved_at = MovedSince(host, mark, LastPositions(host, mark));
      if (!moved_at) return w.rested = true, w;
      // A deque's records stay where they are as more arrive.
      const DeviceRecord* moved = &host.records()[*moved_at];
      // The status was stale only if the motor went on moving after it: the
      // updates after it change from one to the next. One last update that
      // carries the rest position is the end of the motion reported on the
      // device's own update tick, up to a period after it stopped (dmc-lite:
      // 15-113 ms after a correct status, calibration). A status asked
      // within kStartLatency of a command that starts motion may rightly be
      // 0: nothing moves before the device's next motion tick (dmc-lite: 20
      // ms). Either way the host asks again.
      // Whether another update follows within the quiet period after it.
      if (const TimeNs wait = moved->t_ns + kQuietForRest - host.Now(); wait > 0) host.Idle(wait);
      const bool went_on =
          MovedSince(host, *moved_at + 1, As<dmc::MotorPositionReport>(moved)).has_value();
      const bool just_commanded = r->t_ns - LastCommandSent(host) < kStartLatency;
      if (!went_on && !just_commanded) return w.rested = true, w;
      if (went_on && !just_commanded && w.stale_status == nullptr) {
        w.stale_status = r;
        w.moved_after = moved;
      }
    }
    if (host.Now() >= until || host.link_lost()) return w;
    host.Idle(50 * kMs);
  }
}

bool WaitRest(DmcHost& host, TimeNs timeout_ns) { return WaitRestSeen(host, timeout_ns).rested; }

bool WaitRest(DmcCaseContext& c, TimeNs timeout_ns) {
  const RestWait w = WaitRestSeen(c.host, timeout_ns);
  if (w.stale_status != nullptr) {
    // "MOTOR STATUS: bit set = motor moving": the status said nothing moved
    // while the position updates still changed. Judged here once; the case's
    // own rules are judged on the rest the host waited for.
    Expect(c, "DMC-STAT-004", false, "MOTOR_STATUS showing motion while the positions change",
           "status 0 at " + std::to_string(w.stale_status->t_ns / kMs) +
               " ms, then an update moving to " +
               Vec(As<dmc::MotorPositionReport>(w.moved_after)->positions_steps) + " at " +
               std::to_string(w.moved_after->t_ns / kMs) + " ms");
  }
  return w.rested;
}

}  // namespace moco::conformance
