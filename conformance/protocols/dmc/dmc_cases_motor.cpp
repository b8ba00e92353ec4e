// DMC v2 motor and limit cases (dmc-v2-protocol.txt "MSG_MOTOR_*", "MSG_MOTOR_SET_LIMITS",
// "MSG_MOTOR_HARD_STOP", "Capabilities"; ERRATA 1.2-1.11): moves with their position
// updates and status, stops, STOP_ALL and its hard stop, RESET_POSITION, CONFIGURE and
// JOG, coupled motors, un-ACKed updates, the e-stop, soft limits and hardware limit
// switches, each judged against the named rules. Listed by the table in dmc_cases.cpp.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "conformance/protocols/dmc/dmc_cases_internal.h"

namespace moco::conformance::dmc_cases {

using dmc::AckCode;
using dmc::MsgType;

// ---------------------------------------------------------------- motor

namespace {

void SetSpeed(DmcCaseContext& c, uint8_t motor, uint32_t v, uint32_t a) {
  ExpectOk(c, "DMC-CFG-001", c.host.Call(dmc::MotorSetSpeed{motor, v, a}));
}

}  // namespace

void Move(DmcCaseContext& c) {
  DmcHost& h = c.host;
  SetSpeed(c, 1, 2000, 4000);
  const auto p0 = GetPositions(h);
  if (!p0) return;
  const int32_t start = At(*p0, 0), target = start + 2000;
  const size_t mark = h.records().size();
  const DmcRecord* r = h.Call(dmc::MotorMove{1, target});
  const TimeNs t0 = r != nullptr ? r->t_ns : h.Now();
  const auto* mv = As<dmc::MotorMoveResponse>(r);
  // An ACK OK has no MOVING byte: the clause fails; the motion itself is
  // judged below all the same.
  c.v.Check("DMC-MOVE-002", mv != nullptr && mv->moving == 1,
            [&] { return EvOf(h, r, "MOTOR_MOVE moving=1", Show(r)); });
  h.Idle(kMoveUnderWayNs);
  r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-STAT-004", st != nullptr && (st->moving_bits & 1u) != 0,
            [&] { return EvOf(h, r, "bit 0 set while motor 1 moves", Show(r)); });
  const bool rested = WaitRest(c, kRestWaitNs);
  Expect(c, "DMC-STAT-004", rested, "status at rest after the move", "still moving");
  h.Idle(kMoveLastUpdateNs);
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
    c.v.Check("DMC-POS-003", mean >= kUpdateMeanFloorNs, [&] {
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
  h.Idle(kRunBeforeStopNs);
  ExpectOk(c, "DMC-STOP-001", h.Call(dmc::MotorStop{1}));
  const bool rested = WaitRest(c, kStopRestWaitNs);
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
    h.Idle(kRunBeforeStopAllNs);
    dmc::MotorStopAll stop;
    if (pass == 0) stop.flags = dmc::kStopAllSilent;
    const DmcRecord* r = h.Call(stop);
    ExpectOk(c, "DMC-STOP-002", r);
    ExpectOk(c, "DMC-STOP-003", r);
    // Motor 1 was at about 1600 steps/s: decelerating at 4000 steps/s^2 it
    // travels about 300 steps after the STOP_ALL; a halt travels none.
    const auto at_stop = GetPositions(h);
    Expect(c, "DMC-STOP-002", WaitRest(c, kStopRestWaitNs), "every motor at rest after STOP_ALL",
           "still moving");
    const auto at_rest = GetPositions(h);
    if (at_stop && at_rest) {
      const int64_t travel = static_cast<int64_t>(At(*at_rest, 0)) - At(*at_stop, 0);
      Expect(c, "DMC-STOP-005", travel > 0,
             "motor 1 decelerating on after STOP_ALL (about 300 steps at 4000 steps/s^2)",
             std::to_string(travel) + " steps after the STOP_ALL was answered");
    }
    h.Idle(kPastHardStopWindowNs);
  }
  for (uint8_t m = 1; m <= motors; ++m) h.Call(dmc::MotorMove{m, At(*p0, m - 1u)});
  WaitRest(c, kRestWaitNs);
}

namespace {

// Distance travelled by motor 1 after STOP_ALL (twice when `twice`).
std::optional<int64_t> StopDistance(DmcCaseContext& c, bool twice) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return std::nullopt;
  h.Call(dmc::MotorMove{1, At(*p0, 0) + 100000});
  h.Idle(kRunBeforeHardStopNs);
  h.Call(dmc::MotorStopAll{});
  if (twice) h.Call(dmc::MotorStopAll{});
  WaitRest(c, kStopRestWaitNs);
  const auto p1 = GetPositions(h);
  MoveAndRest(c, 1, At(*p0, 0));
  h.Idle(kPastHardStopWindowNs);
  if (!p1) return std::nullopt;
  return static_cast<int64_t>(At(*p1, 0)) - At(*p0, 0);
}

}  // namespace

void HardStop(DmcCaseContext& c) {
  SetSpeed(c, 1, 2000, 4000);
  c.host.Idle(kPastHardStopWindowNs);
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
  const DmcRecord* ack = h.Call(dmc::MotorResetPosition{1, value});
  ExpectOk(c, "DMC-RST-001", ack);
  // "After changing the internal position and responding to this message":
  // the update follows the answer, so only records after the ACK count.
  size_t after = mark;
  for (size_t k = mark; ack != nullptr && k < h.records().size(); ++k) {
    if (&h.records()[k] == ack) after = k + 1;
  }
  const int i = h.WaitFor(after, kResetUpdateWithinNs, [](const DmcRecord& r) {
    return IsUnsolicited(r, MsgType::kMotorGetPosition);
  });
  const DmcRecord* u = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
  const auto* rep = As<dmc::MotorPositionReport>(u);
  c.v.Check("DMC-RST-002", rep != nullptr && At(rep->positions_steps, 0) == value, [&] {
    const std::string want = "MOTOR_GET_POSITION with motor 1 = " + std::to_string(value) +
                             " after the ACK, within 500 ms";
    if (u == nullptr) {
      // A confirming message sent before the answer is not "after ...
      // responding": say so, rather than "no answer".
      for (size_t k = mark; k < after && k < h.records().size(); ++k) {
        const DmcRecord& before = h.records()[k];
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
  const DmcRecord* r = h.Call(dmc::MotorStatusRequest{});
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
  WaitRest(c, kRestWaitNs);
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
    h.Idle(kJogLegNs);
    const auto p = GetPositions(h);
    h.Call(dmc::MotorStop{1});
    WaitRest(c, kStopRestWaitNs);
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
    const DmcRecord* r = h.Call(dmc::MotorConfigure{2, uint8_t(dmc::kMotorEnabled | k.flag)});
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
    h.Idle(kNoAckPollNs);
    const DmcRecord* r = h.Call(dmc::MotorStatusRequest{});
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
  h.Idle(kRunBeforeSwitchNs);
  const size_t mark = h.records().size();
  if (!c.target.SetEStop(true)) {
    c.log.push_back("the target has no e-stop the runner can press: MOTOR_HARD_STOP not exercised");
    c.v.NotExercised("DMC-UNS-003",
                     "the target has no e-stop the runner can press (an external device: press it "
                     "by hand, or certify the emulation in-process)");
    h.Call(dmc::MotorStopAll{});
    WaitRest(c, kRestWaitNs);
    MoveAndRest(c, 1, At(*p0, 0));
    return;
  }
  const int i = h.WaitFor(mark, kHardStopReportWithinNs, [](const DmcRecord& r) {
    return IsUnsolicited(r, MsgType::kMotorHardStop);
  });
  const DmcRecord* hs = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
  const auto* m = As<dmc::MotorHardStop>(hs);
  Expect(c, "DMC-UNS-003", m != nullptr && m->reason == 0 && !m->motor,
         "MOTOR_HARD_STOP reason=0 (E-Stop) without MOTOR within 500 ms", Show(hs));
  c.target.SetEStop(false);
  WaitRest(c, kRestWaitNs);
  MoveAndRest(c, 1, At(*p0, 0));
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
  WaitRest(c, kRestWaitNs);
  const bool low =
      ExpectCode(c, "DMC-LIM-002", h.Call(dmc::MotorMove{1, s - 2000}), AckCode::kErrSoftLow);
  h.Idle(kRefusedMoveShowNs);
  WaitRest(c, kRestWaitNs);
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
  const DmcRecord* r = h.Call(dmc::MotorMove{1, s + 500});
  Expect(c, "DMC-LIM-004", MoveAccepted(r), "MOTOR_MOVE accepted", Show(r));
  WaitRest(c, kRestWaitNs);
  p = GetPositions(h);
  Expect(c, "DMC-LIM-004", ReportsAt(h, mark, p, 0, near(s + 500)),
         "motor 1 at " + std::to_string(s + 500) + " (within a step)", p ? Vec(*p) : "no position");
  mark = h.records().size();
  h.Call(dmc::MotorJog{1, dmc::kJogSpeedMax, s + 5000});
  WaitRest(c, kRestWaitNs);
  p = GetPositions(h);
  int32_t highest = p ? At(*p, 0) : 0;
  for (const Update& u : UpdatesSince(h, mark)) highest = std::max(highest, At(u.positions, 0));
  Expect(c, "DMC-LIM-006", highest <= s + 1000, "never above " + std::to_string(s + 1000),
         "reached " + std::to_string(highest));
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, s - 1000, 0, s + 1000, 0}));
  mark = h.records().size();
  r = h.Call(dmc::MotorMove{1, s + 2000});
  Expect(c, "DMC-LIM-005", MoveAccepted(r), "MOTOR_MOVE beyond a disabled limit accepted", Show(r));
  WaitRest(c, kRestWaitNs);
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
    h.Idle(kRunBeforeSwitchNs);
    const size_t mark = h.records().size();
    if (!c.target.SetLimitInput(1, e.high, true)) {
      // Reached a moment ago: the link went meanwhile.
      h.Call(dmc::MotorStopAll{});
      WaitRest(c, kRestWaitNs);
      break;
    }
    const int i = h.WaitFor(mark, kHardStopReportWithinNs, [](const DmcRecord& r) {
      return IsUnsolicited(r, MsgType::kMotorHardStop);
    });
    const DmcRecord* hs = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
    const auto* m = As<dmc::MotorHardStop>(hs);
    Expect(c, "DMC-LIM-007", m != nullptr && m->reason == e.reason && m->motor == uint8_t{1},
           std::string("MOTOR_HARD_STOP reason=") + std::to_string(e.reason) + " motor=1 within " +
               "500 ms of the " + e.name + " switch closing",
           Show(hs));
    const bool halted = WaitRest(c, kLimitHaltWithinNs);
    Expect(c, "DMC-LIM-007", halted,
           std::string("motor 1 at rest within 200 ms of the ") + e.name + " switch closing",
           "still moving");
    c.target.SetLimitInput(1, e.high, false);
    if (!halted) {
      h.Call(dmc::MotorStopAll{});
      WaitRest(c, kRestWaitNs);
    }
  }
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0}));
  MoveAndRest(c, 1, s);
}

}  // namespace moco::conformance::dmc_cases
