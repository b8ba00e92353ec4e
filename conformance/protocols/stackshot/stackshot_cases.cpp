// StackShot 3X scenario suites (stackshot-protocol.txt 1.1.3-1.1.20 and the
// section 2 tables; ERRATA stackshot 2-5, 10; FACTS "StackShot"): each case
// drives host traffic and judges what the device did against the named
// rules. Cases work relative to what they find (positions, settings, NVM)
// and put back what they change, so they also run against a device that is
// not fresh; the serial number is only burnt on a restartable target.
#include "conformance/protocols/stackshot/stackshot_suites.h"

#include "conformance/protocols/stackshot/stackshot_cases_internal.h"
#include "conformance/protocols/stackshot/stackshot_timing.h"

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>

#include "devices/stackshot3x/stackshot3x.h"

namespace moco::conformance {
namespace ss_cases {

using stackshot::Action;
using stackshot::Command;
using stackshot::Units;

Evidence EvOf(const SsHost& h, const SsRecord* r, std::string expected, std::string observed) {
  return Evidence{std::move(expected), std::move(observed), r != nullptr ? wire::ToHex(r->raw) : "",
                  r != nullptr ? r->t_ns : h.Now()};
}

bool Expect(SsCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed) {
  return c.v.Check(rule, ok, [&] { return EvOf(c.host, nullptr, expected, observed); });
}

// `rule` passes when `r` has status `want`.
bool ExpectStatus(SsCaseContext& c, std::string_view rule, const SsRecord* r, Action want) {
  return c.v.Check(rule, StatusOf(r) == want, [&] {
    return EvOf(c.host, r, std::string(stackshot::ActionName(want)), Show(r));
  });
}

// `rule` and SS-CODE-003 pass when `r` is RSP_OK.
bool ExpectOk(SsCaseContext& c, std::string_view rule, const SsRecord* r) {
  ExpectStatus(c, "SS-CODE-003", r, Action::kRspOk);
  return ExpectStatus(c, rule, r, Action::kRspOk);
}

// `rule` passes when `r` is answered with anything but RSP_OK.
bool ExpectRefused(SsCaseContext& c, std::string_view rule, const SsRecord* r) {
  const auto s = StatusOf(r);
  return c.v.Check(rule, s && *s != Action::kRspOk,
                   [&] { return EvOf(c.host, r, "a refusal (an error status)", Show(r)); });
}

stackshot::HostCommand Move(uint8_t axis, int64_t delta_steps, bool backlash) {
  stackshot::RailMove m;
  m.direction = delta_steps < 0 ? stackshot::Direction::kBack : stackshot::Direction::kForward;
  m.units = Units::kSteps;
  m.backlash = backlash;
  m.distance = static_cast<float>(delta_steps < 0 ? -delta_steps : delta_steps);
  return SsWrite(Command::kRailMove, m, axis);
}

stackshot::HostCommand MoveAtSpeed(uint8_t axis, int64_t delta_steps, float fraction) {
  stackshot::RailMoveAtSpeed m;
  m.direction = delta_steps < 0 ? stackshot::Direction::kBack : stackshot::Direction::kForward;
  m.units = Units::kSteps;
  m.distance = static_cast<float>(delta_steps < 0 ? -delta_steps : delta_steps);
  m.speed_fraction = fraction;
  return SsWrite(Command::kRailMoveAtSpeed, m, axis);
}

// Moves `axis` back to `steps` (relative move from where it rests).
void ReturnTo(SsCaseContext& c, uint8_t axis, int64_t steps) {
  SsWaitRest(c.host, {axis}, kRestWaitNs);
  const auto p = SsPositionSteps(c.host, axis);
  if (!p || *p == steps) return;
  c.host.Call(Move(axis, steps - *p));
  SsWaitRest(c.host, {axis}, kRestWaitNs);
}

std::string Steps(std::optional<int64_t> p) { return p ? std::to_string(*p) : "no position"; }

std::vector<uint8_t> Axes(const SsCaseContext& c) {
  return c.device.three_axes ? std::vector<uint8_t>{0, 1, 2} : std::vector<uint8_t>{0};
}

}  // namespace ss_cases

namespace {

using namespace ss_cases;  // NOLINT: the shared checks of every StackShot case
using stackshot::Action;
using stackshot::Command;
using stackshot::Units;

// ---------------------------------------------------------------- connect

void PingCase(SsCaseContext& c) {
  for (uint8_t v : std::initializer_list<uint8_t>{0x00, 0x5a, 0xa5, 0xff}) {
    ExpectOk(c, "SS-PING-001", c.host.Call(SsRead(Command::kPing, stackshot::PingRequest{v})));
  }
  // CC_PING's table id (0x110A; the enum count gives 0x110B).
  stackshot::HostCommand at_table = SsRead(Command::kPing, stackshot::PingRequest{0x3c});
  at_table.command = stackshot::kPingTableId;
  const SsRecord* r = c.host.Call(at_table);
  const auto* pong = PayloadOf<stackshot::PingReply>(r);
  c.v.Check("SS-PING-002", pong != nullptr && *pong == stackshot::PingAnswer(0x3c),
            [&] { return EvOf(c.host, r, "a ping reply c3 00 at 0x110A", Show(r)); });
}

void IdentityCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const SsRecord* r = h.Call(SsRead(Command::kSoftwareString));
  const auto* text = PayloadOf<stackshot::Text>(r);
  Expect(c, "SS-ID-001", text != nullptr && text->terminated, "NUL-terminated software string",
         Show(r));
  if (text != nullptr && c.device.software_string) {
    Expect(c, "SS-ID-002", text->text == *c.device.software_string,
           "\"" + *c.device.software_string + "\" as before", "\"" + text->text + "\"");
  }
  const std::pair<Command, std::optional<uint32_t>> ids[] = {
      {Command::kSoftwareId, c.device.software_id},
      {Command::kHardwareId, c.device.hardware_id},
      {Command::kBootloaderId, c.device.bootloader_id}};
  for (const auto& [cmd, before] : ids) {
    r = h.Call(SsRead(cmd));
    const auto* v = PayloadOf<stackshot::U32Value>(r);
    ExpectOk(c, "SS-LAYOUT-001", r);
    if (v != nullptr && before) {
      Expect(
          c, "SS-ID-002", v->value == *before,
          stackshot::CommandName(stackshot::Id(cmd)) + " " + std::to_string(*before) + " as before",
          std::to_string(v->value));
    }
  }
  ExpectOk(c, "SS-LAYOUT-001", h.Call(SsRead(Command::kSoftwareChecksum)));
  ExpectOk(c, "SS-LAYOUT-001", h.Call(SsRead(Command::kSerialNumber)));
}

void BytewiseCase(SsCaseContext& c) {
  if (!c.target.VirtualClock()) {
    // Byte-sized writes on a real link may leave 2 ms between bytes, which
    // rightly makes the device drop the partial packet (section 2).
    c.log.push_back(
        "a real link cannot promise byte-sized writes arrive within the 2 ms "
        "inter-frame gap: SS-PKT-005 not exercised");
    return;
  }
  const SsRecord* r =
      c.host.Await(c.host.SendBytewise(SsRead(Command::kPing, stackshot::PingRequest{0x11})));
  ExpectOk(c, "SS-PKT-005", r);
  r = c.host.Await(c.host.SendBytewise(SsRead(Command::kRailStatus)));
  Expect(c, "SS-PKT-005", PayloadOf<stackshot::RailStatus>(r) != nullptr,
         "CC_RAIL_STATUS answered to a byte-wise request", Show(r));
}

void ChecksumCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const stackshot::ChecksumAlgorithm before = h.checksum();
  for (stackshot::ChecksumAlgorithm a :
       {stackshot::ChecksumAlgorithm::kConstant69, stackshot::ChecksumAlgorithm::kConstant00}) {
    h.set_checksum(a);
    ExpectOk(c, "SS-CSUM-003", h.Call(SsRead(Command::kRailStatus)));
  }
  h.set_checksum(before);
  // A checksum byte that fits no algorithm.
  stackshot::Packet p = stackshot::ToPacket(SsRead(Command::kPing, stackshot::PingRequest{7}));
  p.checksum = static_cast<uint8_t>(p.checksum ^ 0x5a);
  if (p.checksum == 0x69 || p.checksum == 0x00) p.checksum = 0x42;
  ExpectOk(c, "SS-CSUM-003", h.Await(h.SendPacket(p)));
}

void ResyncCase(SsCaseContext& c) {
  SsHost& h = c.host;
  // Noise without a sync byte, then a request.
  const uint8_t noise[] = {0x00, 0x13, 0xaa, 0xfe, 0x10};
  h.SendNoise(noise);
  h.Idle(kResyncPauseNs);
  ExpectOk(c, "SS-PKT-006", h.Call(SsRead(Command::kPing, stackshot::PingRequest{1})));
  // A packet cut short (its header promises 10 data bytes), the gap, a request.
  const uint8_t partial[] = {stackshot::kSyncHost, 0x10, 0x07, 0x01, 0x0a, 0x00, 0x01};
  h.SendNoise(partial);
  h.Idle(kResyncPauseNs);
  const SsRecord* r = h.Call(SsRead(Command::kPing, stackshot::PingRequest{2}));
  const auto* pong = PayloadOf<stackshot::PingReply>(r);
  Expect(c, "SS-PKT-006", pong != nullptr && *pong == stackshot::PingAnswer(2),
         "a ping reply fd 00 after a partial packet and 10 ms", Show(r));
}

// ---------------------------------------------------------------- errors

void UnknownCommandCase(SsCaseContext& c) {
  stackshot::Packet p;
  for (uint16_t id : std::initializer_list<uint16_t>{0x1234, 0x10ff, 0x2000}) {
    p.command = id;
    p.action = static_cast<uint8_t>(Action::kRead);
    stackshot::Seal(p, c.host.checksum());
    c.host.Await(c.host.SendPacket(p));  // SS-ERR-001 is judged by the host
  }
}

void BadActionCase(SsCaseContext& c) {
  auto send = [&](Command cmd, Action a, wire::Bytes data) {
    stackshot::Packet p;
    p.command = stackshot::Id(cmd);
    p.action = static_cast<uint8_t>(a);
    p.data = std::move(data);
    stackshot::Seal(p, c.host.checksum());
    return c.host.Await(c.host.SendPacket(p));
  };
  ExpectStatus(c, "SS-ERR-002", send(Command::kSoftwareId, Action::kWrite, {1, 2, 3, 4}),
               Action::kUnsupportedAction);
  ExpectStatus(c, "SS-ERR-002", send(Command::kRailMove, Action::kRead, {}),
               Action::kUnsupportedAction);
  ExpectStatus(c, "SS-ERR-002", send(Command::kRailStatus, Action::kRspOk, {}),
               Action::kUnsupportedAction);
}

void BadLengthCase(SsCaseContext& c) {
  auto send = [&](Command cmd, Action a, size_t len) {
    stackshot::Packet p;
    p.command = stackshot::Id(cmd);
    p.action = static_cast<uint8_t>(a);
    p.data.assign(len, 0x01);
    stackshot::Seal(p, c.host.checksum());
    return c.host.Await(c.host.SendPacket(p));
  };
  ExpectRefused(c, "SS-ERR-003", send(Command::kRailMove, Action::kWrite, 3));
  ExpectRefused(c, "SS-ERR-003", send(Command::kRailStatus, Action::kRead, 2));
  ExpectRefused(c, "SS-ERR-003", send(Command::kRailConfigBacklight, Action::kWrite, 2));
  ExpectRefused(c, "SS-ERR-003", send(Command::kMotionConfig, Action::kWrite, 131));
  const auto p = SsPositionSteps(c.host, 0);
  c.host.Idle(kBadLengthStillNs);
  const auto q = SsPositionSteps(c.host, 0);
  Expect(c, "SS-ERR-003", p == q, "a refused short CC_RAIL_MOVE moves nothing: " + Steps(p),
         Steps(q));
}

void WadCase(SsCaseContext& c) {
  const uint8_t some[] = {0x55, 0x10, 0x05, 0x00, 0x00};
  c.host.Call(
      SsWrite(Command::kWad, stackshot::Raw{wire::Bytes(std::begin(some), std::end(some))}));
}

void AxisThreeCase(SsCaseContext& c) {
  ExpectStatus(c, "SS-ERR-005", c.host.Call(SsRead(Command::kRailStatus, stackshot::Empty{}, 3)),
               Action::kBadParam);
  ExpectStatus(
      c, "SS-ERR-005",
      c.host.Call(SsRead(Command::kRailPositionCurrent, stackshot::UnitsQuery{Units::kSteps}, 3)),
      Action::kBadParam);
  ExpectStatus(c, "SS-ERR-005", c.host.Call(Move(3, 100)), Action::kBadParam);
}

// ---------------------------------------------------------------- rail

void AtRestCase(SsCaseContext& c) {
  SsHost& h = c.host;
  SsWaitRest(h, Axes(c), kRestWaitNs);
  for (uint8_t axis : Axes(c)) {
    const auto st = SsRailStatus(h, axis);
    Expect(c, "SS-STATUS-003", st && (*st & stackshot::kRailStatusMoving) == 0,
           "no MOVING bit at rest", st ? "status " + std::to_string(*st) : "no status");
    const auto cur = SsPositionSteps(h, axis);
    const auto tgt = SsPositionSteps(h, axis, true);
    Expect(c, "SS-POS-004", cur && tgt && *cur == *tgt, "target = current " + Steps(cur),
           "target " + Steps(tgt));
    const auto* mm = PayloadOf<stackshot::UnitsF32>(
        h.Call(SsRead(Command::kRailPositionCurrent, stackshot::UnitsQuery{Units::kMm}, axis)));
    const auto* mils = PayloadOf<stackshot::UnitsF32>(
        h.Call(SsRead(Command::kRailPositionCurrent, stackshot::UnitsQuery{Units::kMils}, axis)));
    if (mm == nullptr || mils == nullptr) {
      Expect(c, "SS-POS-003", false, "the position in mm and in mils", "no answer");
      continue;
    }
    const double a = mm->value.value(), b = mils->value.value() * 0.0254;
    Expect(c, "SS-POS-003", std::fabs(a - b) <= 1e-4 + 1e-5 * std::fabs(a),
           std::to_string(a) + " mm",
           std::to_string(mils->value.value()) + " mils = " + std::to_string(b) + " mm");
  }
}

void MoveCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  ExpectOk(c, "SS-MOVE-001", h.Call(Move(0, 1600)));
  auto st = SsRailStatus(h, 0);
  Expect(c, "SS-STATUS-002", st && (*st & stackshot::kRailStatusMoving) != 0,
         "MOVING right after a 1600-step move started", st ? std::to_string(*st) : "no status");
  // 1.1.3 reads both ways on a move during a move: "relative from the target
  // position ... two move commands of 10.0 mm ... back to back, the rail will
  // move 20.0 mm total", and "COMM_STATUS_BUSY StackShot is currently moving.
  // The move request was rejected." Either is taken; the rail then rests on
  // the first move's end (refused) or on both moves' sum (accepted).
  std::optional<Action> second;
  const SsRecord* during = nullptr;
  if (st && (*st & stackshot::kRailStatusMoving) != 0) {
    during = h.Call(Move(0, 500));
    second = StatusOf(during);
    c.v.Check("SS-MOVE-002", second == Action::kBusy || second == Action::kRspOk, [&] {
      return EvOf(h, during, "BUSY (refused) or RSP_OK (added to the target)", Show(during));
    });
    ExpectStatus(c, "SS-MOVE-007", during, Action::kBusy);
    ExpectStatus(c, "SS-POS-002", h.Call(SsWrite(Command::kRailPositionZero)), Action::kBusy);
  }
  const bool rested = SsWaitRest(h, {0}, kRestWaitNs);
  Expect(c, "SS-STATUS-002", rested, "MOVING clear once the move ends", "still moving");
  auto p1 = SsPositionSteps(h, 0);
  const int64_t added = second == Action::kRspOk ? 500 : 0;
  if (second != Action::kRspOk) {
    Expect(c, "SS-MOVE-001", p1 && *p1 == *p0 + 1600, "at rest on " + std::to_string(*p0 + 1600),
           Steps(p1));
  }
  if (second == Action::kBusy || second == Action::kRspOk) {
    Expect(c, "SS-MOVE-002", p1 && *p1 == *p0 + 1600 + added,
           second == Action::kBusy
               ? "the refused move changed nothing: " + std::to_string(*p0 + 1600)
               : "the accepted move added to the target: " + std::to_string(*p0 + 2100),
           Steps(p1));
  }
  // Back to back: a second move adds up. Judged from where the rail rests,
  // so a fault above is not counted again.
  const int64_t at = p1 ? *p1 : *p0 + 1600 + added;
  ExpectOk(c, "SS-MOVE-001", h.Call(Move(0, 1600)));
  SsWaitRest(h, {0}, kRestWaitNs);
  p1 = SsPositionSteps(h, 0);
  Expect(c, "SS-MOVE-001", p1 && *p1 == at + 1600,
         "the next 1600-step move ends on " + std::to_string(at + 1600), Steps(p1));
  // Backwards with backlash compensation: the rail still ends on its target.
  ExpectOk(c, "SS-MOVE-001", h.Call(Move(0, -3200, true)));
  SsWaitRest(h, {0}, kRestWaitNs);
  p1 = SsPositionSteps(h, 0);
  Expect(c, "SS-MOVE-001", p1 && *p1 == at - 1600,
         "back on " + std::to_string(at - 1600) + " (backlash on)", Steps(p1));
  // Other axes did not move.
  if (c.device.three_axes) {
    for (uint8_t axis : std::initializer_list<uint8_t>{1, 2}) {
      const auto st2 = SsRailStatus(h, axis);
      Expect(c, "SS-STATUS-003", st2 && (*st2 & stackshot::kRailStatusMoving) == 0,
             "axis " + std::to_string(axis) + " at rest", st2 ? std::to_string(*st2) : "none");
    }
  }
}

void MoveAtSpeedCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  ExpectOk(c, "SS-MOVE-003", h.Call(MoveAtSpeed(0, 800, 0.5f)));
  SsWaitRest(h, {0}, kRestWaitNs);
  auto p = SsPositionSteps(h, 0);
  Expect(c, "SS-MOVE-003", p && *p == *p0 + 800, "at rest on " + std::to_string(*p0 + 800),
         Steps(p));
  // During a long move: relative to the position when it arrives.
  ExpectOk(c, "SS-MOVE-001", h.Call(Move(0, 16000)));
  h.Idle(kMotorStartNs);
  const auto before = SsPositionSteps(h, 0);
  const SsRecord* r = h.Call(MoveAtSpeed(0, -400, 1.0f));
  const auto after = SsPositionSteps(h, 0);
  ExpectStatus(c, "SS-MOVE-004", r, Action::kRspOk);
  if (StatusOf(r) == Action::kRspOk && before && after) {
    SsWaitRest(h, {0}, kRestWaitNs);
    p = SsPositionSteps(h, 0);
    const int64_t lo = std::min(*before, *after) - 400, hi = std::max(*before, *after) - 400;
    Expect(c, "SS-MOVE-003", p && *p >= lo && *p <= hi,
           "at rest 400 steps behind where the move arrived: [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "]",
           Steps(p));
  } else {
    h.Call(SsWrite(Command::kRailStop));
  }
  ReturnTo(c, 0, *p0);
}

void BadMoveCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  stackshot::RailMove m;
  m.units = Units::kSteps;
  m.distance = 100.0f;
  m.direction = static_cast<stackshot::Direction>(2);
  ExpectStatus(c, "SS-MOVE-005", h.Call(SsWrite(Command::kRailMove, m)), Action::kBadParam);
  m.direction = stackshot::Direction::kForward;
  for (uint8_t u : std::initializer_list<uint8_t>{3, 7}) {
    m.units = static_cast<Units>(u);
    ExpectStatus(c, "SS-MOVE-005", h.Call(SsWrite(Command::kRailMove, m)), Action::kBadParam);
  }
  for (float f : {0.0f, 1.5f, -0.5f, std::numeric_limits<float>::quiet_NaN()}) {
    ExpectStatus(c, "SS-MOVE-005", h.Call(MoveAtSpeed(0, 100, f)), Action::kBadParam);
  }
  h.Idle(kNoMotionWatchNs);
  const auto p1 = SsPositionSteps(h, 0);
  Expect(c, "SS-MOVE-005", p1 == p0, "the rail still on " + Steps(p0), Steps(p1));
  // A negative distance (the direction byte carries the sign).
  stackshot::RailMove neg;
  neg.units = Units::kSteps;
  neg.distance = -100.0f;
  const SsRecord* r = h.Call(SsWrite(Command::kRailMove, neg));
  c.v.Check("SS-MOVE-006", StatusOf(r) != Action::kRspOk,
            [&] { return EvOf(h, r, "bad-param for distance -100", Show(r)); });
  ReturnTo(c, 0, *p0);
}

void StopCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  const int64_t far = *p0 + 200000;
  h.Call(Move(0, 200000));
  h.Idle(kRunBeforeStopNs);
  ExpectOk(c, "SS-STOP-001", h.Call(SsWrite(Command::kRailStop)));
  const bool rested = SsWaitRest(h, {0}, kStopRestWaitNs);
  const auto p1 = SsPositionSteps(h, 0);
  Expect(c, "SS-STOP-001", rested && p1 && *p1 > *p0 && *p1 < far,
         "at rest between " + std::to_string(*p0) + " and " + std::to_string(far),
         (rested ? "" : "still moving at ") + Steps(p1));
  ExpectOk(c, "SS-STOP-002", h.Call(SsWrite(Command::kRailStop)));
  h.Idle(kNoMotionWatchNs);
  const auto p2 = SsPositionSteps(h, 0);
  Expect(c, "SS-STOP-002", p1 == p2, "STOP at rest moves nothing: " + Steps(p1), Steps(p2));
  ReturnTo(c, 0, *p0);
}

void ZeroCase(SsCaseContext& c) {
  SsHost& h = c.host;
  SsWaitRest(h, {0}, kRestWaitNs);
  ExpectOk(c, "SS-POS-001", h.Call(SsWrite(Command::kRailPositionZero)));
  const auto cur = SsPositionSteps(h, 0);
  const auto tgt = SsPositionSteps(h, 0, true);
  Expect(c, "SS-POS-001", cur == 0 && tgt == 0, "current 0 and target 0",
         "current " + Steps(cur) + ", target " + Steps(tgt));
  const auto st = SsRailStatus(h, 0);
  Expect(c, "SS-POS-001", st && (*st & stackshot::kRailStatusMoving) == 0, "the rail not moving",
         st ? std::to_string(*st) : "no status");
}

// Polls status until SHUTTER clears; the time it took, or nullopt. Without a
// status to go by (its answer missing, already judged), waits out
// `pulses_ns`, how long the pulses fired last, so that the case goes on
// after them whether the host waited out the answer timeout or not.
std::optional<TimeNs> WaitShutter(SsHost& h, TimeNs timeout_ns, TimeNs pulses_ns = 0) {
  const TimeNs t0 = h.Now();
  for (;;) {
    const auto st = SsRailStatus(h, 0);
    if (!st) {
      if (const TimeNs left = t0 + pulses_ns - h.Now(); left > 0) h.Idle(left);
      return std::nullopt;
    }
    if ((*st & stackshot::kRailStatusShutter) == 0) return h.Now() - t0;
    if (h.Now() - t0 >= timeout_ns || h.link_lost()) return std::nullopt;
    h.Idle(kShutterPollNs);
  }
}

void ShutterCase(SsCaseContext& c) {
  SsHost& h = c.host;
  WaitShutter(h, kShutterClearWaitNs);
  ExpectOk(c, "SS-SHUT-001",
           h.Call(SsWrite(Command::kRailShutterFire, stackshot::ShutterFire{2, 0.2f, 0.2f})));
  const auto st = SsRailStatus(h, 0);
  Expect(c, "SS-STATUS-004", st && (*st & stackshot::kRailStatusShutter) != 0,
         "SHUTTER while 2 pulses of 0.2 s fire", st ? std::to_string(*st) : "no status");
  const auto took = WaitShutter(h, kShutterClearWaitNs, kTwoPulsesNs);
  Expect(c, "SS-STATUS-004", took.has_value(), "SHUTTER clear after the pulses",
         "still set after 10 s");
  // Out-of-range values are bounded, not refused.
  ExpectOk(c, "SS-SHUT-001",
           h.Call(SsWrite(Command::kRailShutterFire, stackshot::ShutterFire{0, -1.0f, 0.0f})));
  WaitShutter(h, kShutterClearWaitNs, kBoundedPulsesNs);
}

void UserAbortCase(SsCaseContext& c) {
  SsHost& h = c.host;
  constexpr std::string_view kButton = devices::Stackshot3x::kAbortButton;
  auto st = SsRailStatus(h, 0);
  Expect(c, "SS-STATUS-005", st && (*st & stackshot::kRailStatusUserAborted) == 0,
         "no USER_ABORTED without an abort", st ? std::to_string(*st) : "no status");
  if (!c.target.CanPressButton(kButton)) {
    c.log.push_back(
        "the runner cannot press this device's buttons: USER_ABORTED after an abort "
        "not exercised");
    return;
  }
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  h.Call(Move(0, 100000));
  h.Idle(kMotorStartNs);
  c.target.PressButton(kButton);
  h.Idle(kAfterAbortNs);
  st = SsRailStatus(h, 0);
  Expect(c, "SS-STATUS-005", st && (*st & stackshot::kRailStatusUserAborted) != 0,
         "USER_ABORTED after a button abort", st ? std::to_string(*st) : "no status");
  st = SsRailStatus(h, 0);
  Expect(c, "SS-STATUS-005", st && (*st & stackshot::kRailStatusUserAborted) == 0,
         "USER_ABORTED cleared by the read before", st ? std::to_string(*st) : "no status");
  ReturnTo(c, 0, *p0);
}

std::vector<SsCase> MakeCases() {
  using N = StackshotNeeds;
  return {
      {"connect", "ping", N::kNothing, "CC_PING values, and at its table id 0x110A", PingCase},
      {"connect", "identity", N::kNothing, "software string and ids twice, checksum, serial",
       IdentityCase},
      {"connect", "bytewise", N::kNothing, "requests delivered one byte at a time", BytewiseCase},
      {"connect", "checksums", N::kNothing, "requests ending in 0x69, 0x00 and a wrong checksum",
       ChecksumCase},
      {"connect", "resync", N::kNothing, "noise and a partial packet, the 2 ms gap, a request",
       ResyncCase},
      {"errors", "unknown-command", N::kNothing, "command ids the protocol does not have",
       UnknownCommandCase},
      {"errors", "bad-action", N::kNothing, "write of a read-only, read of a write-only command",
       BadActionCase},
      {"errors", "bad-length", N::kNothing, "known commands with a wrong data length",
       BadLengthCase},
      {"errors", "wad", N::kNothing, "CC_WAD (no documented layout)", WadCase},
      {"errors", "axis-3", N::kNothing, "axis-addressed commands for axis 3", AxisThreeCase},
      {"rail", "at-rest", N::kNothing, "status and positions of every axis at rest", AtRestCase},
      {"rail", "move", N::kNothing, "moves, BUSY while moving, back-to-back, backlash", MoveCase},
      {"rail", "move-at-speed", N::kNothing, "MOVE_AT_SPEED at rest and during a move",
       MoveAtSpeedCase},
      {"rail", "bad-move", N::kNothing, "bad direction, units, speed and a negative distance",
       BadMoveCase},
      {"rail", "stop", N::kNothing, "CC_RAIL_STOP during a long move and at rest", StopCase},
      {"rail", "zero", N::kNothing, "CC_RAIL_POSITION_ZERO at rest", ZeroCase},
      {"rail", "shutter", N::kNothing, "CC_RAIL_SHUTTER_FIRE and the SHUTTER bit", ShutterCase},
      {"rail", "user-abort", N::kNothing, "USER_ABORTED after a button abort (in-process)",
       UserAbortCase},
      {"config", "values", N::kNothing, "every setting group written and read back",
       ConfigValuesCase},
      {"config", "ranges", N::kNothing, "out-of-range and non-finite settings refused",
       ConfigRangesCase},
      {"config", "units", N::kNothing, "units + f32 settings in mm and mils", ConfigUnitsCase},
      {"config", "name", N::kNothing, "CC_RAIL_CONFIG_NAME", NameCase},
      {"config", "slots", N::kNothing, "SAVE and LOAD of user slots, empty slots", SlotsCase},
      {"config", "power-on", N::kNothing, "slot 0 after CC_RESET, unsaved settings lost",
       PowerOnConfigCase},
      {"nvm", "registers", N::kNothing, "NVM registers, range, register 0 = axis",
       NvmRegistersCase},
      {"nvm", "serial", N::kNothing, "the write-once serial number", SerialCase},
      {"nvm", "persist", N::kNothing, "NVM and serial across CC_RESET and a power cycle",
       NvmPersistCase},
      {"stack", "run", N::kThreeAxes, "a three-frame CC_RAIL_STACK, BUSY while moving", StackCase},
      {"curve", "play", N::kThreeAxes, "CC_MOTION_CONFIG and CC_MOTION_START", CurveCase},
      {"curve", "invalid", N::kThreeAxes, "curves breaking each listed requirement", BadCurveCase},
      {"random", "sequence", N::kNothing, "a seeded sequence of valid rail requests (--seed)",
       SsRandomSequence},
  };
}

}  // namespace

const std::vector<SsCase>& StackshotCases() {
  static const std::vector<SsCase> cases = MakeCases();
  return cases;
}

bool SsApplies(const Need& needs, const SsDeviceInfo& device) {
  if (needs == StackshotNeeds::kThreeAxes) return device.three_axes;
  return needs == StackshotNeeds::kNothing;  // of the others, only kNothing applies
}

SsDeviceInfo DiscoverStackshot(SsHost& host) {
  SsDeviceInfo d;
  d.answered =
      StatusOf(host.Call(SsRead(Command::kPing, stackshot::PingRequest{0x5a}))) == Action::kRspOk;
  if (!d.answered) return d;
  if (const auto* t = PayloadOf<stackshot::Text>(host.Call(SsRead(Command::kSoftwareString)))) {
    d.software_string = t->text;
  }
  auto u32 = [&](Command cmd) -> std::optional<uint32_t> {
    if (const auto* v = PayloadOf<stackshot::U32Value>(host.Call(SsRead(cmd)))) return v->value;
    return std::nullopt;
  };
  d.software_id = u32(Command::kSoftwareId);
  d.hardware_id = u32(Command::kHardwareId);
  d.bootloader_id = u32(Command::kBootloaderId);
  d.serial_number = u32(Command::kSerialNumber);
  d.three_axes =
      StatusOf(host.Call(SsRead(Command::kRailStatus, stackshot::Empty{}, 1))) == Action::kRspOk &&
      StatusOf(host.Call(SsRead(Command::kRailStatus, stackshot::Empty{}, 2))) == Action::kRspOk;
  return d;
}

std::optional<int64_t> SsPositionSteps(SsHost& host, uint8_t axis, bool target) {
  const auto* v = PayloadOf<stackshot::UnitsF32>(
      host.Call(SsRead(target ? Command::kRailPositionTarget : Command::kRailPositionCurrent,
                       stackshot::UnitsQuery{Units::kSteps}, axis)));
  if (v == nullptr || !std::isfinite(v->value.value())) return std::nullopt;
  return std::llround(static_cast<double>(v->value.value()));
}

std::optional<uint32_t> SsRailStatus(SsHost& host, uint8_t axis) {
  const auto* v = PayloadOf<stackshot::RailStatus>(
      host.Call(SsRead(Command::kRailStatus, stackshot::Empty{}, axis)));
  if (v == nullptr) return std::nullopt;
  return v->bits;
}

namespace {

// Polls the axes' positions until none has changed for kSsStillForRestNs, or
// until `until`.
void WaitPositionsStill(SsHost& host, const std::vector<uint8_t>& axes, TimeNs until) {
  std::vector<std::optional<int64_t>> last;
  TimeNs still_since = host.Now();
  while (host.Now() < until && !host.link_lost()) {
    std::vector<std::optional<int64_t>> now;
    for (uint8_t a : axes) now.push_back(SsPositionSteps(host, a));
    if (now != last) {
      last = std::move(now);
      still_since = host.Now();
    } else if (host.Now() - still_since >= kSsStillForRestNs) {
      return;
    }
    host.Idle(std::min<TimeNs>(kSsStatusPollNs, until - host.Now()));
  }
}

}  // namespace

bool SsWaitRest(SsHost& host, const std::vector<uint8_t>& axes, TimeNs timeout_ns) {
  const TimeNs until = host.Now() + timeout_ns;
  for (;;) {
    bool moving = false;
    for (uint8_t a : axes) {
      const auto st = SsRailStatus(host, a);
      if (!st) {
        // No status to go by (its answer is missing, already judged): the
        // positions tell when the motion ended, so that what the case checks
        // next is judged on a motion that ended whether the host waited out
        // the answer timeout or not (HostOptions::give_up_after_unanswered).
        WaitPositionsStill(host, axes, until);
        return false;
      }
      moving = moving || (*st & stackshot::kRailStatusMoving) != 0;
    }
    if (!moving) return true;
    if (host.Now() >= until || host.link_lost()) return false;
    host.Idle(kSsStatusPollNs);
  }
}

}  // namespace moco::conformance
