// DMC v2 scenario suites (dmc-v2-protocol.txt "Capabilities", "MSG_HI",
// "MSG_MOTOR_*", "MSG_RT_*", "Computing and Validating the Checksum"; ERRATA
// 1.2-1.11): each case drives Dragonframe-style traffic and judges what the
// device did against the named rules. Cases work relative to the positions
// they find, so they also run against a device that is not fresh. This file
// holds the checks every case makes, the connect cases, the table of every
// case in run order (the others are in dmc_cases_motor.cpp, _errors.cpp,
// _io.cpp, _rt.cpp and _rt_io.cpp), and the position query and the wait for
// rest that the cases and the random suite share.
#include "conformance/protocols/dmc/dmc_suites.h"

#include "conformance/protocols/dmc/dmc_cases_internal.h"
#include "conformance/rules/dmc_needs.h"

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

Evidence EvOf(const DmcHost& h, const DmcRecord* r, std::string expected, std::string observed) {
  return Evidence{std::move(expected), std::move(observed), r != nullptr ? wire::ToHex(r->raw) : "",
                  r != nullptr ? r->t_ns : h.Now()};
}

std::string CodeText(const DmcRecord* r) {
  if (auto code = AckCodeOf(r)) return "ACK " + dmc::AckCodeName(*code);
  return Show(r);
}

// `rule` passes when `r` is an ACK with `want`.
bool ExpectCode(DmcCaseContext& c, std::string_view rule, const DmcRecord* r, AckCode want) {
  const std::optional<uint32_t> code = AckCodeOf(r);
  return c.v.Check(rule, code && *code == ToWire(want), [&] {
    return EvOf(c.host, r, "ACK " + dmc::AckCodeName(ToWire(want)), CodeText(r));
  });
}

// `rule` and DMC-ACK-011 pass when `r` is ACK OK.
bool ExpectOk(DmcCaseContext& c, std::string_view rule, const DmcRecord* r) {
  ExpectCode(c, "DMC-ACK-011", r, AckCode::kOk);
  return ExpectCode(c, rule, r, AckCode::kOk);
}

// `rule` passes when `r` is an ACK other than OK.
bool ExpectRefused(DmcCaseContext& c, std::string_view rule, const DmcRecord* r) {
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
    const DmcRecord& r = h.records()[i];
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

bool IsUnsolicited(const DmcRecord& r, MsgType type) {
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

bool MoveAccepted(const DmcRecord* r) {
  return As<dmc::MotorMoveResponse>(r) != nullptr || AckCodeOf(r) == ToWire(AckCode::kOk);
}

const DmcRecord* Go(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const TimeNs t0 = h.Now();
  const DmcRecord* r = h.Call(dmc::RtGo{});
  int refusals = 0;
  while (AckCodeOf(r) == ToWire(AckCode::kErrNotInPosition) && h.Now() - t0 < kArmingLimitNs &&
         !h.link_lost()) {
    ++refusals;
    h.Idle(kArmingRetryNs);
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
  WaitRest(c, kRestWaitNs);
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
  for (const DmcRecord& r : c.host.records()) {
    seen = seen || (IsUnsolicited(r, MsgType::kHi) && r.t_ns <= kBootHiWithinNs);
  }
  if (!seen) {
    c.host.WaitFor(0, kBootHiWithinNs,
                   [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kHi); });
    for (const DmcRecord& r : c.host.records()) seen = seen || IsUnsolicited(r, MsgType::kHi);
  }
  // The spec sets no time ("whenever it starts up"): a HI that comes while the
  // case waits counts, however long the device's start-up took.
  Expect(c, "DMC-HI-011", seen,
         "an unsolicited HI at start-up (looked for until 1 s into the case)", "none");
}

void HiAgain(DmcCaseContext& c) {
  const DmcRecord* r = c.host.Call(dmc::HiRequest{});
  Expect(c, "DMC-HI-001", As<dmc::HiResponse>(r) != nullptr, "HI response", Show(r));
}

void Bytewise(DmcCaseContext& c) {
  const DmcRecord* r = c.host.Await(c.host.SendBytewise(dmc::HiRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::HiResponse>(r) != nullptr, "HI response to a byte-wise HI",
         Show(r));
  r = c.host.Await(c.host.SendBytewise(dmc::MotorStatusRequest{}));
  Expect(c, "DMC-ERR-009", As<dmc::MotorStatusResponse>(r) != nullptr,
         "MOTOR_STATUS response to a byte-wise MOTOR_STATUS", Show(r));
}

void Queries(DmcCaseContext& c) {
  const DmcRecord* r = c.host.Call(dmc::MotorStatusRequest{});
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

std::vector<DmcCase> MakeCases() {
  using N = DmcNeeds;
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
  const DmcRecord* r = host.Call(dmc::MotorGetPositionRequest{});
  if (const auto* p = As<dmc::MotorPositionReport>(r)) return p->positions_steps;
  // A device that sends the positions as a message of its own (ID 0, as the
  // reference firmware does) and then ACKs the request OK: DMC-ACK-008 has
  // judged that form; the positions are the last such message before the ACK.
  if (r == nullptr || AckCodeOf(r) != ToWire(AckCode::kOk)) return std::nullopt;
  std::optional<std::vector<int32_t>> found;
  for (size_t i = mark; i < host.records().size() && &host.records()[i] != r; ++i) {
    const DmcRecord& u = host.records()[i];
    if (u.request >= 0) continue;
    if (const auto* p = As<dmc::MotorPositionReport>(&u)) found = p->positions_steps;
  }
  return found;
}

namespace {

bool IsQuery(uint16_t type) {
  return type == ToWire(MsgType::kMotorStatus) || type == ToWire(MsgType::kMotorGetPosition) ||
         type == ToWire(MsgType::kHi) || (type & dmc::kFlagAck) != 0;
}

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
    const DmcRecord& r = h.records()[i];
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
    const DmcRecord& r = h.records()[i];
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
    const DmcRecord* r = host.Call(dmc::MotorStatusRequest{});
    const auto* st = As<dmc::MotorStatusResponse>(r);
    if (st == nullptr) {
      // No status to go by (its answer is missing, already judged): the
      // position updates tell when the motion ended. What the case checks
      // next is then judged on a motion that ended, whether the host waited
      // out the answer timeout or not (HostOptions::give_up_after_unanswered).
      for (;;) {
        const TimeNs quiet_at = LastActivity(host, host.records().size()) + kRestQuietNs;
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
      const TimeNs quiet_at = LastActivity(host, mark) + kRestQuietNs;
      if (r->t_ns >= quiet_at) return w.rested = true, w;
      host.Idle(quiet_at - host.Now());
      const std::optional<size_t> moved_at = MovedSince(host, mark, LastPositions(host, mark));
      if (!moved_at) return w.rested = true, w;
      // A deque's records stay where they are as more arrive.
      const DmcRecord* moved = &host.records()[*moved_at];
      // The status was stale only if the motor went on moving after it: the
      // updates after it change from one to the next. One last update that
      // carries the rest position is the end of the motion reported on the
      // device's own update tick, up to a period after it stopped (dmc-lite:
      // 15-113 ms after a correct status, calibration). A status asked
      // within kStartLatencyNs of a command that starts motion may rightly be
      // 0: nothing moves before the device's next motion tick (dmc-lite: 20
      // ms). Either way the host asks again.
      // Whether another update follows within the quiet period after it.
      if (const TimeNs wait = moved->t_ns + kRestQuietNs - host.Now(); wait > 0) host.Idle(wait);
      const bool went_on =
          MovedSince(host, *moved_at + 1, As<dmc::MotorPositionReport>(moved)).has_value();
      const bool just_commanded = r->t_ns - LastCommandSent(host) < kStartLatencyNs;
      if (!went_on && !just_commanded) return w.rested = true, w;
      if (went_on && !just_commanded && w.stale_status == nullptr) {
        w.stale_status = r;
        w.moved_after = moved;
      }
    }
    if (host.Now() >= until || host.link_lost()) return w;
    host.Idle(kRestPollNs);
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
