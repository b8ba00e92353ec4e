// DFMoco motor cases (dfmoco-protocol.txt "Move Motor (mm)", "Motor Status (ms)",
// "Motor Position (mp)", "Stop Motor (sm)", "Stop All (sa)", "Pulse Rate (pr)", "New
// Position (np)", "Zero Motor (zm)", "Jog Motor (jm)", "Inch Motor (im)"; FACTS "DFMoco"):
// moves with the unprompted `mp` reports judged along them, pulse rates, stops, new
// positions, jogs and inches, a fast reversal for the pin rules and a shoot of frames,
// each judged against the named rules. Listed by the table in dfmoco_cases.cpp.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_cases_internal.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "conformance/rules/dfmoco_needs.h"

namespace moco::conformance::dfmoco_cases {

namespace {

struct Report {
  TimeNs t_ns;
  int32_t position_steps;
};

// Unprompted `mp` lines for `motor` from line `from` on.
std::vector<Report> ReportsSince(const DfmHost& h, size_t from, int32_t motor) {
  std::vector<Report> out;
  for (size_t i = from; i < h.lines().size(); ++i) {
    const DfmLine& l = h.lines()[i];
    if (l.command >= 0) continue;
    if (const auto* p = As<dfmoco::PositionReply>(&l); p != nullptr && p->motor == motor) {
      out.push_back(Report{l.t_ns, p->position_steps});
    }
  }
  return out;
}

// A motion of one motor, started at line `mark` / time `t0_ns`, judged once
// every motor rests: the unprompted `mp` reports (DFM-MP-002..006).
struct Motion {
  int32_t motor = 1;
  int32_t from_steps = 0;
  int32_t to_steps = 0;  // the target commanded
  size_t mark = 0;
  TimeNs t0_ns = 0;
};

// Judges `m` after `rest`; `rest_steps` is where the motor rests (from `mp m`).
void JudgeReports(DfmCaseContext& c, const Motion& m, const DfmRest& rest, int32_t rest_steps) {
  DfmHost& h = c.host;
  const size_t mi = static_cast<size_t>(m.motor - 1);
  const TimeNs last_moving = mi < rest.last_moving_ns.size() ? rest.last_moving_ns[mi] : -1;
  if (last_moving < 0) return;  // never seen moving
  // No `ms` showed the motors at rest (unanswered, or moving to the end):
  // when the motion ended, and so which reports came after it, is unknown.
  if (!rest.rested) return;
  // The report after the stop can lag it by up to a second (FACTS).
  const TimeNs stop_report_by = last_moving + kPollNs + kReportPeriodNs + Tolerance(c);
  if (h.Now() < stop_report_by) h.Idle(stop_report_by - h.Now());
  const std::vector<Report> reports = ReportsSince(h, m.mark, m.motor);
  const int32_t lo = std::min(m.from_steps, m.to_steps);
  const int32_t hi = std::max(m.from_steps, m.to_steps);
  for (const Report& r : reports) {
    Expect(c, "DFM-MP-006", r.position_steps >= lo && r.position_steps <= hi,
           "mp " + Str(m.motor) + " within " + Str(lo) + ".." + Str(hi),
           "mp " + Str(m.motor) + " " + Str(r.position_steps) + " at " + Str(r.t_ns / kMs) + " ms");
  }
  std::vector<TimeNs> times = {m.t0_ns};
  for (const Report& r : reports) {
    if (r.t_ns <= last_moving) times.push_back(r.t_ns);
  }
  const bool long_move = last_moving - m.t0_ns > kLongMoveNs;
  if (long_move) {
    Expect(c, "DFM-MP-002", times.size() > 1,
           "mp " + Str(m.motor) + " reports during a move of " +
               Str((last_moving - m.t0_ns) / kMs) + " ms",
           "none");
  }
  if (last_moving - m.t0_ns > kReportPeriodNs) {
    times.push_back(last_moving);
    TimeNs gap = 0;
    TimeNs at = 0;
    for (size_t i = 1; i < times.size(); ++i) {
      if (times[i] - times[i - 1] > gap) {
        gap = times[i] - times[i - 1];
        at = times[i - 1];
      }
    }
    Expect(c, "DFM-MP-003", gap <= kReportPeriodNs + Tolerance(c),
           "mp " + Str(m.motor) + " at most " + Str((kReportPeriodNs + Tolerance(c)) / kMs) +
               " ms apart while moving",
           "a gap of " + Str(gap / kMs) + " ms from " + Str(at / kMs) + " ms");
  }
  const Report* after = nullptr;
  for (const Report& r : reports) {
    if (r.t_ns > last_moving) after = &r;
  }
  const Report* first_after = nullptr;
  for (const Report& r : reports) {
    if (r.t_ns > last_moving) {
      first_after = &r;
      break;
    }
  }
  Expect(
      c, "DFM-MP-004", first_after != nullptr && first_after->t_ns <= stop_report_by,
      "an mp " + Str(m.motor) + " within 1 s of the stop (by " + Str(stop_report_by / kMs) + " ms)",
      first_after == nullptr ? "none" : "the first at " + Str(first_after->t_ns / kMs) + " ms");
  if (after != nullptr) {
    Expect(c, "DFM-MP-005", after->position_steps == rest_steps,
           "mp " + Str(m.motor) + " " + Str(rest_steps) + " (where it rests)",
           "mp " + Str(m.motor) + " " + Str(after->position_steps) + " at " +
               Str(after->t_ns / kMs) + " ms");
  }
}

}  // namespace

// ---------------------------------------------------------------- motor

// Moves motor 1 far, watching ms, the reports and where it rests.
void Move(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 5000");
  const auto before = Positions(h, c.device.motor_count);
  if (!before) return;
  const int32_t from = (*before)[0];
  const int32_t to = from + 6000;
  Motion m{1, from, to, h.lines().size(), h.Now()};
  h.Call(Cmd("mm", {1, to}));
  const DfmLine* ms = h.Call("ms");
  Expect(c, "DFM-MS-003", ShowsMoving(ms, 1), "ms with motor 1 moving right after mm 1 " + Str(to),
         Show(ms));
  const DfmRest rest = Rest(c);
  const auto after = Positions(h, c.device.motor_count);
  if (!after) return;
  Expect(c, "DFM-MM-003", (*after)[0] == to, "motor 1 rests on " + Str(to), Str((*after)[0]));
  Expect(c, "DFM-MP-001", (*after)[0] == to, "mp 1 " + Str(to), "mp 1 " + Str((*after)[0]));
  for (size_t i = 1; i < after->size(); ++i) {
    Expect(c, "DFM-MOTOR-002", (*after)[i] == (*before)[i],
           "motor " + Str(static_cast<int64_t>(i + 1)) + " stays on " + Str((*before)[i]),
           Str((*after)[i]));
  }
  JudgeReports(c, m, rest, (*after)[0]);
  // Already there: `mp m p`.
  const DfmLine* again = h.Call(Cmd("mm", {1, to}));
  Expect(c, "DFM-MM-002", As<dfmoco::PositionReply>(again) != nullptr, "mp 1 " + Str(to),
         Show(again));
  // Back, so that the case leaves the motor where it found it.
  h.Call(Cmd("mm", {1, from}));
  Rest(c);
}

void PulseRate(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 20000");
  h.Call("pr 1 100");
  h.Call("pr 1 50");     // clamped to 100 (FACTS)
  h.Call("pr 1 25000");  // clamped to 20000
  h.Call("pr 1 1000");
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  const int32_t to = *from + 1500;
  const TimeNs t0 = h.Now();
  h.Call(Cmd("mm", {1, to}));
  const DfmRest rest = Rest(c);
  // 1500 steps at 1000 steps/s take 1.5 s at least; the rest is seen one poll late at most.
  const TimeNs took = rest.rest_ns - t0;
  Expect(c, "DFM-PR-003", took >= kPulseRateMoveMinNs, "at least 1500 ms for 1500 steps at pr 1000",
         Str(took / kMs) + " ms");
  h.Call("pr 1 5000");
  h.Call(Cmd("mm", {1, *from}));
  Rest(c);
}

void Stop(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 5000");
  const bool two = c.device.motor_count >= 2;
  if (two) h.Call("pr 2 5000");
  const auto from = Positions(h, two ? 2 : 1);
  if (!from) return;
  const int32_t to = (*from)[0] + 40000;
  Motion m{1, (*from)[0], to, h.lines().size(), h.Now()};
  h.Call(Cmd("mm", {1, to}));
  if (two) h.Call(Cmd("mm", {2, (*from)[1] + 40000}));
  h.Idle(kMoveBeforeStopNs);
  const TimeNs t_stop = h.Now();
  h.Call("sm 1");
  h.Idle(kAfterStopCheckNs);
  if (two) {
    const DfmLine* ms = h.Call("ms");
    Expect(c, "DFM-SM-003", ShowsMoving(ms, 2), "motor 2 still moving after sm 1", Show(ms));
  }
  // Motor 1 rests within 5 s, short of its target.
  TimeNs rested_at = -1;
  TimeNs last_moving = t_stop;
  while (h.Now() - t_stop <= kStopWithinNs + kPollNs && !h.link_lost()) {
    const DfmLine* ms = h.Call("ms");
    if (ms == nullptr) break;
    if (!ShowsMoving(ms, 1)) {
      rested_at = h.Now();
      break;
    }
    last_moving = h.Now();
    h.Idle(kPollNs);
  }
  Expect(
      c, "DFM-SM-002", rested_at >= 0 && rested_at - t_stop <= kStopWithinNs + kPollNs,
      "motor 1 at rest within 5 s of sm 1",
      rested_at < 0 ? "still moving" : "at rest after " + Str((rested_at - t_stop) / kMs) + " ms");
  if (two) h.Call("sa");
  DfmRest rest = Rest(c);
  if (!rest.last_moving_ns.empty()) {
    rest.last_moving_ns[0] = std::max(rest.last_moving_ns[0], last_moving);
  }
  const auto p = DfmPosition(h, 1);
  if (!p) return;
  Expect(c, "DFM-SM-002", *p < to, "motor 1 short of " + Str(to), "rests on " + Str(*p));
  JudgeReports(c, m, rest, *p);
  h.Call(Cmd("mm", {1, (*from)[0]}));
  if (two) h.Call(Cmd("mm", {2, (*from)[1]}));
  Rest(c);
}

void StopAll(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = std::min<int32_t>(c.device.motor_count, 4);
  const auto from = Positions(h, n);
  if (!from) return;
  std::vector<Motion> motions;
  for (int32_t m = 1; m <= n; ++m) {
    h.Call(Cmd("pr", {m, 5000}));
    const int32_t to = (*from)[static_cast<size_t>(m - 1)] - 40000;
    motions.push_back(
        Motion{m, (*from)[static_cast<size_t>(m - 1)], to, h.lines().size(), h.Now()});
    h.Call(Cmd("mm", {m, to}));
  }
  h.Idle(kMoveBeforeStopAllNs);
  const TimeNs t_stop = h.Now();
  h.Call("sa");
  const DfmRest rest = Rest(c);
  Expect(
      c, "DFM-SA-002", rest.rested && rest.rest_ns - t_stop <= kStopWithinNs + kPollNs,
      "every motor at rest within 5 s of sa",
      rest.rested ? "at rest after " + Str((rest.rest_ns - t_stop) / kMs) + " ms" : "still moving");
  const auto p = Positions(h, n);
  if (!p) return;
  for (const Motion& m : motions) {
    const int32_t at = (*p)[static_cast<size_t>(m.motor - 1)];
    Expect(c, "DFM-SA-002", at > m.to_steps,
           "motor " + Str(m.motor) + " short of " + Str(m.to_steps), "rests on " + Str(at));
    JudgeReports(c, m, rest, at);
  }
  for (int32_t m = 1; m <= n; ++m) h.Call(Cmd("mm", {m, (*from)[static_cast<size_t>(m - 1)]}));
  Rest(c);
}

// Motor 1 at the top rate, sent back while at full speed: the pin rules see the
// highest step rate, the steepest ramps and a reversal (pins only; nothing is
// judged on the serial line here).
void FastReversal(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 20000");
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  h.Call(Cmd("mm", {1, *from + 60000}));
  h.Idle(kReachTopRateNs);
  h.Call(Cmd("mm", {1, *from}));
  Rest(c);
  h.Call("pr 1 5000");
}

void NewPositionZero(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const auto before = Positions(h, c.device.motor_count);
  if (!before) return;
  const int32_t p = (*before)[0] + 1234;
  h.Call(Cmd("np", {1, p}));
  const DfmLine* ms = h.Call("ms");
  Expect(c, "DFM-NP-002", !ShowsMoving(ms, 1), "no motion after np", Show(ms));
  const auto at = DfmPosition(h, 1);
  Expect(c, "DFM-NP-002", at == p, "mp 1 " + Str(p), at ? "mp 1 " + Str(*at) : "no answer");
  h.Call("zm 1");
  ms = h.Call("ms");
  Expect(c, "DFM-ZM-002", !ShowsMoving(ms, 1), "no motion after zm", Show(ms));
  const auto zero = DfmPosition(h, 1);
  Expect(c, "DFM-ZM-002", zero == 0, "mp 1 0", zero ? "mp 1 " + Str(*zero) : "no answer");
  const auto after = Positions(h, c.device.motor_count);
  if (!after) return;
  for (size_t i = 1; i < after->size(); ++i) {
    Expect(c, "DFM-MOTOR-002", (*after)[i] == (*before)[i],
           "motor " + Str(static_cast<int64_t>(i + 1)) + " stays on " + Str((*before)[i]),
           Str((*after)[i]));
  }
  h.Call(Cmd("np", {1, (*before)[0]}));  // as it was
}

void Jog(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 5000");
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  // A far destination, repeated as a host does while the jog button is held.
  const int32_t far = *from + 100000;
  int32_t last = *from;
  bool towards = true;
  for (int i = 0; i < 6; ++i) {
    h.Call(Cmd("jm", {1, far}));
    h.Idle(kJogRepeatNs);
    const auto p = DfmPosition(h, 1);
    if (!p) return;
    towards = towards && *p >= last && *p <= far;
    last = *p;
  }
  Rest(c);
  const auto end = DfmPosition(h, 1);
  if (!end) return;
  Expect(c, "DFM-JM-002", towards && *end > *from && *end <= far,
         "motor 1 moving from " + Str(*from) + " towards " + Str(far),
         "rests on " + Str(*end) + (towards ? "" : " (went backwards or past on the way)"));
  // A near destination: reached, never passed.
  const int32_t near = *end + 40;
  h.Call(Cmd("jm", {1, near}));
  Rest(c);
  const auto at = DfmPosition(h, 1);
  if (at) {
    Expect(c, "DFM-JM-002", *at > *end && *at <= near,
           "motor 1 towards " + Str(near) + ", not past it", "rests on " + Str(*at));
  }
  if (DfmocoApplies(DfmocoNeeds::kJogVelocity, c.device) && at) {
    const int32_t back = *at - 100000;
    h.Call(Cmd("jm", {1, back, 5000}));
    h.Idle(kMotorStartNs);
    Rest(c);
    const auto v = DfmPosition(h, 1);
    if (v) {
      Expect(c, "DFM-JM-003", *v < *at && *v >= back, "motor 1 towards " + Str(back) + " at 50 %",
             "rests on " + Str(*v));
    }
  }
  h.Call(Cmd("mm", {1, *from}));
  Rest(c);
}

void Inch(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  h.Call(Cmd("im", {1, *from + 1000}));
  Rest(c);
  const auto p = DfmPosition(h, 1);
  if (!p) return;
  const int32_t moved = *p - *from;
  Expect(c, "DFM-IM-002", moved >= 1, "motor 1 a step or more towards " + Str(*from + 1000),
         "moved " + Str(moved));
  Expect(c, "DFM-IM-003", moved <= 16, "at most 16 steps", "moved " + Str(moved));
  // One step away: the sketch's inch is two steps from the position with only
  // the destination clamped (inchMotor, FACTS DFMoco), so it ends on the
  // target or one step past it, never further.
  h.Call(Cmd("im", {1, *p - 1}));
  Rest(c);
  const auto q = DfmPosition(h, 1);
  if (q) {
    Expect(c, "DFM-IM-002", *q == *p - 1 || *q == *p - 2,
           "motor 1 on " + Str(*p - 1) + " or one step past it", Str(*q));
  }
  h.Call(Cmd("mm", {1, *from}));
  Rest(c);
}

// ---------------------------------------------------------------- shoot

// A shoot: N frames, each a move of up to two motors, `ms` polled until rest,
// then a position check (as Dragonframe does before each exposure).
void Shoot(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = std::min<int32_t>(c.device.motor_count, 2);
  const auto from = Positions(h, n);
  if (!from) return;
  for (int32_t m = 1; m <= n; ++m) h.Call(Cmd("pr", {m, 8000}));
  for (int frame = 1; frame <= 6; ++frame) {
    std::vector<int32_t> want;
    for (int32_t m = 1; m <= n; ++m) {
      want.push_back((*from)[static_cast<size_t>(m - 1)] + frame * 500 * m);
      h.Call(Cmd("mm", {m, want.back()}));
    }
    Rest(c);
    for (int32_t m = 1; m <= n; ++m) {
      const auto p = DfmPosition(h, m);
      if (!p) return;
      Expect(c, "DFM-MM-003", *p == want[static_cast<size_t>(m - 1)],
             "frame " + Str(frame) + ": motor " + Str(m) + " on " +
                 Str(want[static_cast<size_t>(m - 1)]),
             Str(*p));
    }
  }
  for (int32_t m = 1; m <= n; ++m) {
    h.Call(Cmd("pr", {m, 5000}));
    h.Call(Cmd("mm", {m, (*from)[static_cast<size_t>(m - 1)]}));
  }
  Rest(c);
}

}  // namespace moco::conformance::dfmoco_cases
