// DFMoco scenario suites (dfmoco-protocol.txt "Hello (hi)", "Motor Status
// (ms)", "Move Motor (mm)" ... "Go-Motion (Blur)", "Notes"; ERRATA dfmoco
// 1-5; FACTS "DFMoco"): each case drives Dragonframe-style traffic and judges
// what the device did against the named rules, and RunDfmoco runs them.
// Cases work relative to the positions they find, so they also run against a
// device that is not fresh.
#include "conformance/protocols/dfmoco/dfmoco_suites.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "conformance/core/run.h"
#include "conformance/core/run_report.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"

namespace moco::conformance {
namespace {

constexpr TimeNs kMs = sim::kNsPerMs;
constexpr TimeNs kRestTimeout = 120'000 * kMs;
constexpr TimeNs kPollNs = 50 * kMs;            // DfmWaitRest's `ms` polling period
constexpr TimeNs kReportPeriodNs = 1000 * kMs;  // FACTS: `mp` once a second
constexpr TimeNs kStopWithinNs = 5000 * kMs;    // DFM-SM-002 / SA-002 "fairly quickly"

std::string Str(int64_t v) { return std::to_string(v); }

Evidence EvOf(const DfmHost& h, const DfmLine* l, std::string expected, std::string observed) {
  return Evidence{std::move(expected), std::move(observed), l != nullptr ? wire::ToHex(l->raw) : "",
                  l != nullptr ? l->t_ns : h.Now()};
}

bool Expect(DfmCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed) {
  return c.v.Check(rule, ok, [&] { return EvOf(c.host, nullptr, expected, observed); });
}

std::string Cmd(std::string_view word, std::initializer_list<int64_t> args) {
  std::string s(word);
  for (const int64_t a : args) s += " " + Str(a);
  return s;
}

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

TimeNs Tolerance(const DfmCaseContext& c) { return c.host_options.deadline_ns; }

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
  const bool long_move = last_moving - m.t0_ns > 1500 * kMs;
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

// Positions of motors 1..n, or nullopt when one is missing.
std::optional<std::vector<int32_t>> Positions(DfmHost& h, int32_t n) {
  std::vector<int32_t> out;
  for (int32_t m = 1; m <= n; ++m) {
    const auto p = DfmPosition(h, m);
    if (!p) return std::nullopt;
    out.push_back(*p);
  }
  return out;
}

std::string Vec(const std::vector<int32_t>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + Str(v[i]);
  return s + "]";
}

// Rest, judged by DFM-MS-004; `while_moving` as DfmWaitRest's.
DfmRest Rest(DfmCaseContext& c, const std::function<void()>& while_moving = {}) {
  const DfmRest r = DfmWaitRest(c.host, kRestTimeout, while_moving);
  Expect(c, "DFM-MS-004", r.rested, "every ms digit 0 once the motors rest",
         "still moving after " + Str(kRestTimeout / kMs) + " ms");
  return r;
}

// Whether the `ms` answer `l` shows motor `motor` moving.
bool ShowsMoving(const DfmLine* l, int32_t motor) {
  const auto* ms = As<dfmoco::MotorStatusReply>(l);
  return ms != nullptr && motor >= 1 && static_cast<size_t>(motor) <= ms->moving.size() &&
         ms->moving[static_cast<size_t>(motor - 1)];
}

// ---------------------------------------------------------------- connect

void BootHi(DfmCaseContext& c) {
  if (!c.target.CanRestart()) return;  // the start-up of an external device is not observed
  bool seen = false;
  for (const DfmLine& l : c.host.lines()) {
    seen = seen || (l.command < 0 && As<dfmoco::HelloReply>(&l) != nullptr && l.t_ns <= 1000 * kMs);
  }
  Expect(c, "DFM-HI-001", seen, "an unprompted hi within 1 s of power-on", "none");
}

void HiAgain(DfmCaseContext& c) {
  for (int i = 0; i < 2; ++i) {
    const DfmLine* l = c.host.Call("hi");
    Expect(c, "DFM-HI-002", As<dfmoco::HelloReply>(l) != nullptr, "hi <major> <axes> <version>",
           Show(l));
  }
}

void Queries(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const DfmLine* ms = h.Call("ms");
  if (const auto* st = As<dfmoco::MotorStatusReply>(ms)) {
    const bool none = std::none_of(st->moving.begin(), st->moving.end(), [](bool b) { return b; });
    Expect(c, "DFM-MS-004", none, "ms all 0 at rest", Show(ms));
  }
  for (int32_t m = 1; m <= c.device.motor_count; ++m) {
    const DfmLine* l = h.Call(Cmd("mp", {m}));
    Expect(c, "DFM-MP-001", As<dfmoco::PositionReply>(l) != nullptr, "mp " + Str(m) + " <pos>",
           Show(l));
  }
  // Quiet at rest: after any report still owed (up to a second), nothing comes.
  h.Idle(kReportPeriodNs + Tolerance(c));
  const size_t mark = h.lines().size();
  h.Idle(2500 * kMs);
  const size_t extra = h.lines().size() - mark;
  Expect(c, "DFM-MP-007", extra == 0, "no line for 2.5 s at rest",
         Str(static_cast<int64_t>(extra)) + " line(s), the first " +
             (extra > 0 ? Show(&h.lines()[mark]) : ""));
}

void LineEnd(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int k = h.Send("ms", {}, "\n");
  h.Idle(300 * kMs);
  const bool taken = h.commands()[static_cast<size_t>(k)].answers > 0;
  Expect(c, "DFM-LINE-007", taken, "a command ended by a bare \\n is taken (ERRATA 2.1)",
         "no answer to \"ms\\n\" (the sketch's framing, docs/device-facts.md)");
  if (!taken) {
    h.SendRaw("\r\n");  // completes the "ms" the sketch kept
    h.Await(k);
  }
  const DfmLine* l = h.Call("ms");
  Expect(c, "DFM-ERR-005", As<dfmoco::MotorStatusReply>(l) != nullptr, "ms answered", Show(l));
}

void Pipelined(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = std::max<int32_t>(c.device.motor_count, 1);
  std::vector<std::string> batch;
  for (int i = 0; i < 12; ++i) {
    const int32_t m = 1 + i % n;
    switch (i % 3) {
      case 0:
        batch.push_back("ms");
        break;
      case 1:
        batch.push_back(c.device.motor_count >= 1 ? Cmd("pr", {m, 5000}) : "ms");
        break;
      default:
        batch.push_back(c.device.motor_count >= 1 ? Cmd("mp", {m}) : "ms");
        break;
    }
  }
  const int first = h.SendBatch(batch);
  TimeNs prev = -1;
  int prev_line = -1;
  bool all = true;
  bool ordered = true;
  std::string order_note;
  for (int i = 0; i < static_cast<int>(batch.size()); ++i) {
    const DfmLine* l = h.Await(first + i);
    if (l == nullptr) {
      all = false;
      continue;
    }
    const int li = h.commands()[static_cast<size_t>(first + i)].answer;
    if (li < prev_line || l->t_ns < prev) {
      ordered = false;
      order_note =
          "the answer to \"" + batch[static_cast<size_t>(i)] + "\" came before earlier ones";
    }
    prev = l->t_ns;
    prev_line = li;
  }
  Expect(c, "DFM-QUEUE-001", all, "12 answers to 12 commands in one write", "some missing");
  Expect(c, "DFM-REPLY-004", ordered, "answers in the order of the commands", order_note);
}

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
  Expect(c, "DFM-PR-003", took >= 1500 * kMs, "at least 1500 ms for 1500 steps at pr 1000",
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
  h.Idle(1200 * kMs);
  const TimeNs t_stop = h.Now();
  h.Call("sm 1");
  h.Idle(200 * kMs);
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
  h.Idle(1500 * kMs);
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
  h.Idle(2300 * kMs);  // 20000 steps/s after 2 s at 10000 steps/s^2
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
    h.Idle(200 * kMs);
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
  if (DfmocoApplies(Needs::kDfmJogVelocity, c.device) && at) {
    const int32_t back = *at - 100000;
    h.Call(Cmd("jm", {1, back, 5000}));
    h.Idle(300 * kMs);
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

// ---------------------------------------------------------------- errors

// Sends each refused line and requires every position unchanged and no motion.
void Refused(DfmCaseContext& c, const std::vector<std::string>& lines) {
  DfmHost& h = c.host;
  Rest(c);
  const int32_t n = c.device.motor_count;
  const auto before = n >= 1 ? Positions(h, n) : std::optional<std::vector<int32_t>>{};
  for (const std::string& l : lines) h.Call(l);
  if (n < 1 || !before) return;
  const DfmLine* ms = h.Call("ms");
  bool any = false;
  for (int32_t m = 1; m <= n; ++m) any = any || ShowsMoving(ms, m);
  Expect(c, "DFM-ERR-004", !any, "no motion after refused commands", Show(ms));
  const auto after = Positions(h, n);
  if (after) {
    Expect(c, "DFM-ERR-004", *after == *before, "positions " + Vec(*before), Vec(*after));
  }
  Expect(c, "DFM-ERR-005", after.has_value(), "mp answered after the refused commands",
         "no answer");
}

// Lines a real sketch refuses. Its byte-at-a-time reader (FACTS DFMoco) takes
// "mm 1 --5" as -5 and wraps "mm 1 99999999999", so those move a real sketch
// and are not asked here; "x" starts no argument, so "mm 1 x" has one.
void BadArguments(DfmCaseContext& c) {
  Refused(c,
          {"mm 1", "mm 1 x", "mm 1 2 3", "pr", "np 1", "np 1 x", "mp", "sm", "jm 1", "im 1 1 1"});
}

void BadMotor(DfmCaseContext& c) {
  const int32_t over = c.device.motor_count + 1;
  std::vector<std::string> lines;
  for (const int32_t m : {0, over}) {
    for (const char* w : {"mp", "sm", "zm"}) lines.push_back(Cmd(w, {m}));
    for (const char* w : {"mm", "np", "jm", "im"}) lines.push_back(Cmd(w, {m, 500}));
    lines.push_back(Cmd("pr", {m, 5000}));
  }
  Refused(c, lines);
}

void TooMany(DfmCaseContext& c) {
  std::string forty = "mm";
  for (int i = 0; i < 40; ++i) forty += " 1";
  // `bf` is a command word only where the sketch has go-motion; elsewhere it
  // is unknown, and unknown words are never answered (their arguments are
  // not counted), so the second line is sent only to a go-motion sketch.
  if (!DfmocoApplies(Needs::kDfmGoMotion, c.device)) {
    Refused(c, {forty});
    return;
  }
  std::string many = "bf";
  for (int i = 0; i < 45; ++i) many += " 1";
  Refused(c, {forty, many});
}

void Unknown(DfmCaseContext& c) {
  DfmHost& h = c.host;
  for (const char* line : {"xx 1 2", "hello", "MM 1 100", "zz"}) {
    const size_t mark = h.lines().size();
    h.Send(line);
    h.Idle(300 * kMs);
    std::string seen;
    for (size_t i = mark; i < h.lines().size(); ++i) {
      if (As<dfmoco::PositionReply>(&h.lines()[i]) == nullptr) seen = Show(&h.lines()[i]);
    }
    Expect(c, "DFM-REPLY-003", seen.empty(), "no reply to \"" + std::string(line) + "\"", seen);
  }
  const DfmLine* l = h.Call("ms");
  Expect(c, "DFM-ERR-005", As<dfmoco::MotorStatusReply>(l) != nullptr, "ms answered", Show(l));
}

// ---------------------------------------------------------------- go-motion

// One channel's go-motion move (dfmoco-protocol.txt "Go-Motion (Blur)"; ERRATA
// 2.5; FACTS DFMoco). With b = blur / 1000 "the exposure happens between
// these positions: [p1 - (p1 - p0) * blurPercent] -> [p1] -> [p1 + (p2 - p1) *
// blurPercent]", taking "1/2 of the exposure time" for each half (at v1, then
// v2); "a ramp up to speed before the exposure starts" that "should take
// exactly 1 second" from rest to v1, and "a slow-down after it", a fixed 1 s
// from v2 to rest (FACTS). The move starts at `go` ("immediately").
struct BlurPlan {
  double exposure_s = 0;
  double exposure_start_steps = 0;
  double p1_steps = 0;
  double exposure_end_steps = 0;
  double v1_steps_per_s = 0;
  double v2_steps_per_s = 0;
  double start_steps = 0;  // where the ramp starts: the motor pre-positions there
  double end_steps = 0;    // where the slow-down ends

  // Where the motor is `t_s` seconds after the move starts.
  double At(double t_s) const {
    const double half = exposure_s / 2;
    if (t_s <= 0) return start_steps;
    if (t_s < 1) return start_steps + v1_steps_per_s * t_s * t_s / 2;
    if (t_s < 1 + half) return exposure_start_steps + v1_steps_per_s * (t_s - 1);
    if (t_s < 1 + exposure_s) return p1_steps + v2_steps_per_s * (t_s - 1 - half);
    if (t_s < 2 + exposure_s) {
      const double tau = t_s - 1 - exposure_s;
      return exposure_end_steps + v2_steps_per_s * tau - v2_steps_per_s * tau * tau / 2;
    }
    return end_steps;
  }
  // The lowest and the highest position between `from_s` and `to_s`.
  std::pair<double, double> Span(double from_s, double to_s) const {
    double lo = At(from_s);
    double hi = lo;
    for (double t = from_s; t < to_s; t += 0.001) {
      lo = std::min(lo, At(t));
      hi = std::max(hi, At(t));
    }
    lo = std::min(lo, At(to_s));
    hi = std::max(hi, At(to_s));
    return {lo, hi};
  }
};
BlurPlan PlanOf(int32_t exposure_ms, int32_t blur, int32_t p0, int32_t p1, int32_t p2) {
  BlurPlan plan;
  const double b = blur / 1000.0;
  plan.exposure_s = exposure_ms / 1000.0;
  plan.p1_steps = p1;
  plan.exposure_start_steps = p1 - (p1 - p0) * b;
  plan.exposure_end_steps = p1 + (p2 - p1) * b;
  plan.v1_steps_per_s = (p1 - plan.exposure_start_steps) / (plan.exposure_s / 2);
  plan.v2_steps_per_s = (plan.exposure_end_steps - p1) / (plan.exposure_s / 2);
  // From rest to v over 1 s covers v / 2, and from v to rest as much.
  plan.start_steps = plan.exposure_start_steps - plan.v1_steps_per_s / 2;
  plan.end_steps = plan.exposure_end_steps + plan.v2_steps_per_s / 2;
  return plan;
}

// A motor's position sampled during the go-motion move: `mp m` sent at
// `asked_ns`, answered at `answered_ns`.
struct GoSample {
  int32_t motor;
  TimeNs asked_ns;
  TimeNs answered_ns;
  int32_t steps;
};

constexpr TimeNs kGoWithinNs = 150 * kMs;  // DFM-GO-006's tolerance
constexpr TimeNs kChunkNs = 50 * kMs;      // FACTS: the sketch's velocity chunks

double Seconds(TimeNs t) { return static_cast<double>(t) / 1e9; }

// DFM-GO-006 along the move, not only its length: Dragonframe triggers the
// camera by the clock ("so that Dragonframe knows when to trigger the
// camera"), so each sample must lie where the plan puts the motor within
// 150 ms of when it was taken, measured from `go` sent at `t_go`. A
// position answered is the planned end of the 50 ms chunk running (FACTS),
// so it may lead the clock by a chunk on top of that (the emulated sketch's
// answers trail the plan by about 40 ms, well inside the 150 ms); motors
// land on whole steps (2 steps, as DFM-GO-003/005).
void JudgeGoShape(DfmCaseContext& c, const std::vector<std::pair<int32_t, BlurPlan>>& plans,
                  const std::vector<GoSample>& samples, TimeNs t_go) {
  // Plain names, not structured bindings: the lambda below captures them
  // (clang 14 cannot capture a structured binding).
  for (const auto& motor_plan : plans) {
    const int32_t m = motor_plan.first;
    const BlurPlan& plan = motor_plan.second;
    for (const GoSample& s : samples) {
      if (s.motor != m) continue;
      const auto span = plan.Span(Seconds(s.asked_ns - t_go - kGoWithinNs),
                                  Seconds(s.answered_ns - t_go + kChunkNs + kGoWithinNs));
      const double lo = span.first, hi = span.second;
      const bool ok = s.steps >= lo - 2.0 && s.steps <= hi + 2.0;
      c.v.Check("DFM-GO-006", ok, [&] {
        const auto exposure_ms = std::llround(plan.exposure_s * 1000);
        return Evidence{"motor " + Str(m) + " on " + Str(std::llround(lo)) + ".." +
                            Str(std::llround(hi)) + " " + Str((s.asked_ns - t_go) / kMs) + ".." +
                            Str((s.answered_ns - t_go) / kMs) + " ms after go (a 1 s ramp, " +
                            Str(exposure_ms / 2) + " ms on each half of the exposure, a 1 s " +
                            "slow-down; within " + Str(kGoWithinNs / kMs) + " ms)",
                        "mp " + Str(m) + " " + Str(s.steps), "", s.answered_ns};
      });
      if (!ok) break;  // the first sample off the plan explains it
    }
  }
}

void Blur(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const bool two = c.device.motor_count >= 2;
  const auto from = Positions(h, two ? 2 : 1);
  if (!from) return;
  const int32_t exposure_ms = 800;
  const int32_t p1 = (*from)[0];
  std::string bf = Cmd("bf", {exposure_ms, 500, 1, p1 - 400, p1, p1 + 400});
  std::vector<std::pair<int32_t, BlurPlan>> plans = {
      {1, PlanOf(exposure_ms, 500, p1 - 400, p1, p1 + 400)}};
  if (two) {
    const int32_t q1 = (*from)[1];
    bf += " " + Cmd("2", {q1 + 300, q1, q1 - 100});
    plans.push_back({2, PlanOf(exposure_ms, 500, q1 + 300, q1, q1 - 100)});
  }
  const DfmLine* r = h.Call(bf);
  if (As<dfmoco::BlurReply>(r) == nullptr || As<dfmoco::BlurReply>(r)->value < 0) return;
  Rest(c);
  for (const auto& [m, plan] : plans) {
    const auto p = DfmPosition(h, m);
    if (!p) return;
    Expect(c, "DFM-GO-003", std::fabs(*p - plan.start_steps) <= 2.0,
           "motor " + Str(m) + " on the ramp start " + Str(std::llround(plan.start_steps)),
           "rests on " + Str(*p));
  }
  const TimeNs t_go = h.Now();
  h.Call("go");
  // Each `ms` showing motion is followed by `mp` of every blur motor.
  std::vector<GoSample> samples;
  const DfmRest rest = Rest(c, [&] {
    for (const auto& [m, plan] : plans) {
      const TimeNs asked = h.Now();
      const DfmLine* l = h.Call(Cmd("mp", {m}));
      if (const auto* p = As<dfmoco::PositionReply>(l)) {
        samples.push_back(GoSample{m, asked, l->t_ns, p->position_steps});
      }
    }
  });
  const TimeNs took = rest.rest_ns - t_go;
  const TimeNs want = 2000 * kMs + exposure_ms * kMs;
  Expect(c, "DFM-GO-006", std::llabs(took - want) <= kGoWithinNs,
         "motion for 1 s + " + Str(exposure_ms) + " ms + 1 s after go", Str(took / kMs) + " ms");
  JudgeGoShape(c, plans, samples, t_go);
  for (const auto& [m, plan] : plans) {
    const auto p = DfmPosition(h, m);
    if (!p) return;
    Expect(c, "DFM-GO-005", std::fabs(*p - plan.end_steps) <= 2.0,
           "motor " + Str(m) + " at the end of the slow-down " + Str(std::llround(plan.end_steps)),
           "rests on " + Str(*p));
  }
  // `bf` while a motor moves is refused.
  h.Call(Cmd("mm", {1, p1 + 20000}));
  h.Call(Cmd("bf", {exposure_ms, 500, 1, p1 - 400, p1, p1 + 400}), "DFM-GO-007");
  h.Call("sa");
  Rest(c);
  for (size_t i = 0; i < from->size(); ++i) {
    h.Call(Cmd("mm", {static_cast<int64_t>(i + 1), (*from)[i]}));
  }
  Rest(c);
}

// A host in a hurry: after `bf` it polls `ms` back to back and sends `go` the
// moment every digit is 0, with no position query in between. The sketch's
// `ms` shows rest once the last chunk of the pre-position is loaded, while
// that chunk may still have a step to make (FACTS DFMoco); a `go` at that
// moment must not lose it. The motor ends at the end of its slow-down
// (DFM-GO-005), and with --board its pulses add up to what it reports
// (DFM-PIN-001).
void GoAtOnce(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  const int32_t p1 = *from;
  const BlurPlan plan = PlanOf(800, 500, p1 - 450, p1, p1 + 450);
  const DfmLine* r = h.Call(Cmd("bf", {800, 500, 1, p1 - 450, p1, p1 + 450}));
  if (As<dfmoco::BlurReply>(r) == nullptr || As<dfmoco::BlurReply>(r)->value < 0) return;
  const TimeNs until = h.Now() + kRestTimeout;
  for (;;) {
    const DfmLine* l = h.Call("ms");
    const auto* st = As<dfmoco::MotorStatusReply>(l);
    if (st == nullptr || h.Now() >= until || h.link_lost()) return;
    if (std::none_of(st->moving.begin(), st->moving.end(), [](bool m) { return m; })) break;
  }
  h.Call("go");
  Rest(c);
  const auto p = DfmPosition(h, 1);
  if (!p) return;
  Expect(c, "DFM-GO-005", std::fabs(*p - plan.end_steps) <= 2.0,
         "motor 1 at the end of the slow-down " + Str(std::llround(plan.end_steps)) +
             " after a go sent the moment ms showed rest",
         "rests on " + Str(*p));
  h.Call(Cmd("mm", {1, p1}));
  Rest(c);
}

void BlurTooFast(DfmCaseContext& c) {
  DfmHost& h = c.host;
  Rest(c);
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  const int32_t p1 = *from;
  const DfmLine* r = h.Call(Cmd("bf", {100, 1000, 1, p1 - 100000, p1, p1 + 100000}));
  const auto* b = As<dfmoco::BlurReply>(r);
  Expect(c, "DFM-GO-008", b != nullptr && b->value == dfmoco::kBlurRefused,
         "bf -1 for 2,000,000 steps/s", Show(r));
  h.Idle(200 * kMs);
  const DfmLine* ms = h.Call("ms");
  Expect(c, "DFM-GO-008", !ShowsMoving(ms, 1), "nothing moves after bf -1", Show(ms));
  const auto p = DfmPosition(h, 1);
  Expect(c, "DFM-GO-008", p == *from, "motor 1 stays on " + Str(*from), p ? Str(*p) : "no answer");
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

// --- The StackShot 3X DfMoco dialect (stackshot-protocol.txt section 3; ERRATA 3.9) ---

// Lines from index `from` on that answer no command, of type T, for `motor`.
template <typename T>
std::vector<const DfmLine*> Unprompted(const DfmHost& h, size_t from, int32_t motor) {
  std::vector<const DfmLine*> out;
  for (size_t i = from; i < h.lines().size(); ++i) {
    const DfmLine& l = h.lines()[i];
    if (l.command >= 0) continue;
    if (const auto* r = As<T>(&l); r != nullptr && r->motor == motor) out.push_back(&l);
  }
  return out;
}

// `mp *`: one `mp m pos` per motor, 1 to the axes, each at the motor's
// position; and the `hi` axes are 1 to 3.
void SsPositionsAll(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = c.device.motor_count;
  Expect(c, "DFM-SS-001", n >= 1 && n <= 3, "hi with 1 to 3 axes", "hi with " + Str(n) + " axes");
  const auto each = Positions(h, n);
  if (!each) return;
  const size_t mark = h.lines().size();
  const int k = h.Send("mp *");
  h.Await(k);
  h.Idle(300 * kMs);
  std::vector<std::pair<int32_t, int32_t>> got;
  std::string seen;
  for (size_t i = mark; i < h.lines().size(); ++i) {
    const DfmLine& l = h.lines()[i];
    if (const auto* p = As<dfmoco::PositionReply>(&l)) {
      got.emplace_back(p->motor, p->position_steps);
      seen += (seen.empty() ? "" : ", ") + Show(&l);
    }
  }
  std::string want;
  bool ok = got.size() == static_cast<size_t>(n);
  for (int32_t m = 1; m <= n; ++m) {
    const int32_t pos = (*each)[static_cast<size_t>(m - 1)];
    want += (m == 1 ? "" : ", ") + Cmd("mp", {m, pos});
    const size_t i = static_cast<size_t>(m - 1);
    ok = ok && i < got.size() && got[i].first == m && got[i].second == pos;
  }
  Expect(c, "DFM-SS-004", ok, want, seen.empty() ? "no mp line" : seen);
}

// `mm` to a new position: `mm m <current position>` at once, then the same
// line periodically while the motor moves; it comes to rest on the target.
void SsMoveReports(DfmCaseContext& c) {
  DfmHost& h = c.host;
  h.Call("pr 1 2000");
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  const int32_t to = *from + 6000;
  const size_t mark = h.lines().size();
  const DfmLine* answer = h.Call(Cmd("mm", {1, to}));
  const auto* mm = As<dfmoco::MoveReply>(answer);
  Expect(c, "DFM-SS-002",
         mm != nullptr && mm->motor == 1 && mm->position_steps >= *from && mm->position_steps < to,
         "mm 1 <current position> (" + Str(*from) + ".." + Str(to - 1) + ", not the target)",
         Show(answer));
  const TimeNs t0 = h.Now();
  const DfmRest rest = Rest(c);
  const TimeNs last_moving = rest.last_moving_ns.empty() ? -1 : rest.last_moving_ns[0];
  const std::vector<const DfmLine*> reports = Unprompted<dfmoco::MoveReply>(h, mark, 1);
  if (last_moving - t0 > 1500 * kMs) {
    bool within = !reports.empty();
    std::string seen;
    for (const DfmLine* l : reports) {
      const int32_t p = As<dfmoco::MoveReply>(l)->position_steps;
      within = within && p >= *from && p <= to;
      seen += (seen.empty() ? "" : ", ") + Show(l);
    }
    Expect(c, "DFM-SS-003", within,
           "mm 1 <current position> lines within " + Str(*from) + ".." + Str(to) +
               " during a move of " + Str((last_moving - t0) / kMs) + " ms",
           seen.empty() ? "none" : seen);
  }
  const auto after = DfmPosition(h, 1);
  if (after) {
    Expect(c, "DFM-MM-003", *after == to, "motor 1 rests on " + Str(to), Str(*after));
  }
  h.Call("pr 1 5000");
  h.Call(Cmd("mm", {1, *from}));
  Rest(c);
}

// `zm` and `np` answer `mp <motor> <current position>`; `np` to a moving
// motor sends it to the new position.
void SsNewPosition(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const auto from = DfmPosition(h, 1);
  if (!from) return;
  const DfmLine* zm = h.Call("zm 1");
  const auto* zp = As<dfmoco::PositionReply>(zm);
  Expect(c, "DFM-SS-005", zp != nullptr && zp->motor == 1 && zp->position_steps == 0, "mp 1 0",
         Show(zm));
  const DfmLine* np = h.Call("np 1 500");
  const auto* npp = As<dfmoco::PositionReply>(np);
  Expect(c, "DFM-SS-005", npp != nullptr && npp->motor == 1 && npp->position_steps == 500,
         "mp 1 500", Show(np));
  h.Call("pr 1 2000");
  h.Call("mm 1 8500");
  h.Idle(300 * kMs);
  const DfmLine* moving = h.Call("np 1 3500");
  const auto* mp = As<dfmoco::PositionReply>(moving);
  Expect(c, "DFM-SS-005",
         mp != nullptr && mp->motor == 1 && mp->position_steps >= 500 && mp->position_steps <= 8500,
         "mp 1 <current position> (500..8500) to np 1 3500 while moving", Show(moving));
  Rest(c);
  const auto rest = DfmPosition(h, 1);
  if (rest) {
    Expect(c, "DFM-SS-006", *rest == 3500, "motor 1 rests on 3500 after np 1 3500 while moving",
           Str(*rest));
  }
  h.Call("pr 1 5000");
  h.Call(Cmd("np", {1, *from}));
  Rest(c);
}

// `sa <motor>` is answered `sa` and stops every motor short of its target.
void SsStopAllMotor(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = std::min<int32_t>(c.device.motor_count, 3);
  const auto from = Positions(h, n);
  if (!from) return;
  std::vector<int32_t> to;
  for (int32_t m = 1; m <= n; ++m) {
    h.Call(Cmd("pr", {m, 2000}));
    to.push_back((*from)[static_cast<size_t>(m - 1)] + 20000);
    h.Call(Cmd("mm", {m, to.back()}));
  }
  h.Idle(500 * kMs);
  const DfmLine* sa = h.Call("sa 1");
  Expect(c, "DFM-SS-007", As<dfmoco::StopAllReply>(sa) != nullptr, "sa", Show(sa));
  const TimeNs t0 = h.Now();
  const DfmRest rest = DfmWaitRest(h, kStopWithinNs);
  const auto after = Positions(h, n);
  bool short_of = rest.rested && after.has_value();
  std::string seen = rest.rested ? "" : "still moving after 5 s";
  for (int32_t m = 1; after && m <= n; ++m) {
    const int32_t p = (*after)[static_cast<size_t>(m - 1)];
    short_of = short_of && p < to[static_cast<size_t>(m - 1)];
    seen += (seen.empty() ? "" : ", ") + Cmd("mp", {m, p});
  }
  Expect(c, "DFM-SS-007", short_of,
         "every motor at rest short of its target within 5 s of sa 1 (at " + Str(t0 / kMs) + " ms)",
         seen);
  for (int32_t m = 1; m <= n; ++m) {
    h.Call(Cmd("pr", {m, 5000}));
    h.Call(Cmd("mm", {m, (*from)[static_cast<size_t>(m - 1)]}));
  }
  Rest(c);
}

// `pr` up to the controller's maximum is echoed; above it the answer is the
// maximum, which is then echoed in turn.
void SsPulseRate(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const DfmLine* low = h.Call("pr 1 1000");
  const auto* lp = As<dfmoco::PulseRateReply>(low);
  Expect(c, "DFM-SS-008", lp != nullptr && lp->motor == 1 && lp->rate_steps_per_s == 1000,
         "pr 1 1000", Show(low));
  constexpr int32_t kHuge = 100'000'000;
  const DfmLine* high = h.Call(Cmd("pr", {1, kHuge}));
  const auto* hp = As<dfmoco::PulseRateReply>(high);
  const bool capped =
      hp != nullptr && hp->motor == 1 && hp->rate_steps_per_s > 0 && hp->rate_steps_per_s < kHuge;
  Expect(c, "DFM-SS-008", capped, "pr 1 <the controller's maximum, below " + Str(kHuge) + ">",
         Show(high));
  if (capped) {
    const int32_t max = hp->rate_steps_per_s;
    const DfmLine* again = h.Call(Cmd("pr", {1, max}));
    const auto* ap = As<dfmoco::PulseRateReply>(again);
    Expect(c, "DFM-SS-008", ap != nullptr && ap->rate_steps_per_s == max,
           "pr 1 " + Str(max) + " (the maximum, echoed)", Show(again));
  }
  h.Call("pr 1 5000");
}

// `bf` and `go` (go-motion, real-time): no go-motion answer, no motion.
void SsNoGoMotion(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int32_t n = c.device.motor_count;
  const auto before = Positions(h, n);
  if (!before) return;
  const int32_t p = (*before)[0];
  const size_t mark = h.lines().size();
  h.Send(Cmd("bf", {1000, 500, 1, p, p + 1000, p + 2000}));
  h.Idle(1500 * kMs);
  h.Send("go");
  h.Idle(1500 * kMs);
  std::string seen;
  for (size_t i = mark; i < h.lines().size(); ++i) {
    const DfmLine& l = h.lines()[i];
    if (As<dfmoco::BlurReply>(&l) != nullptr || As<dfmoco::GoReply>(&l) != nullptr) {
      seen += (seen.empty() ? "" : ", ") + Show(&l);
    }
  }
  const auto after = Positions(h, n);
  if (!after) return;
  for (size_t i = 0; i < after->size(); ++i) {
    if ((*after)[i] != (*before)[i]) {
      seen += (seen.empty() ? "" : ", ") + Cmd("mp", {static_cast<int64_t>(i + 1), (*after)[i]});
    }
  }
  Expect(c, "DFM-SS-009", seen.empty(), "no bf or go answer and no motion", seen);
}

std::vector<DfmCase> MakeCases() {
  using N = Needs;
  return {
      {"connect", "boot-hi", N::kNothing, "unprompted hi at power-on", BootHi},
      {"connect", "hi", N::kNothing, "hi twice: fields, stable answer", HiAgain},
      {"connect", "queries", N::kNothing, "ms and mp at rest, then quiet", Queries},
      {"connect", "line-end", N::kNothing, "a command ended by a bare \\n", LineEnd},
      {"connect", "pipelined", N::kNothing, "12 commands in one write: all answered, in order",
       Pipelined},
      {"motor", "move", N::kDfmMotors, "mm with ms, mp reports, rest and the already-there answer",
       Move},
      {"motor", "pulse-rate", N::kDfmMotors, "pr echo, clamps and the speed limit", PulseRate},
      {"motor", "stop", N::kDfmMotors, "sm during a long move (other motor keeps going)", Stop},
      {"motor", "stop-all", N::kDfmMotors, "sa during moves of every motor (up to 4)", StopAll},
      {"motor", "np-zm", N::kDfmMotors, "np and zm: answers, no motion, new positions",
       NewPositionZero},
      {"motor", "jog", N::kDfmMotors, "jm repeated towards a far and a near destination", Jog},
      {"motor", "inch", N::kDfmMotors, "im from rest: a few steps, at most one past", Inch},
      {"pins", "fast-reversal", N::kPins,
       "pr 20000, a long move sent back at full speed (for the pin rules)", FastReversal},
      {"errors", "arguments", N::kNothing, "wrong argument counts and malformed numbers",
       BadArguments},
      {"errors", "bad-motor", N::kDfmMotors, "motor 0 and axes + 1 for every motor command",
       BadMotor},
      {"errors", "too-many-args", N::kNothing, "40 and more arguments", TooMany},
      {"errors", "unknown", N::kNothing, "unknown words get no reply", Unknown},
      {"gomotion", "blur", N::kDfmGoMotion,
       "bf, pre-position, go, exposure timing, bf while moving", Blur},
      {"gomotion", "go-at-once", N::kDfmGoMotion,
       "bf, ms polled back to back, go the moment it shows rest", GoAtOnce},
      {"gomotion", "too-fast", N::kDfmBlurRefusal, "bf faster than 20000 steps/s: bf -1",
       BlurTooFast},
      {"shoot", "frames", N::kDfmMotors, "a shoot of 6 frames on up to 2 motors", Shoot},
      {"stackshot", "mp-all", N::kDfmMotors, "hi axes 1-3; mp * answers every motor's position",
       SsPositionsAll},
      {"stackshot", "move-reports", N::kDfmMotors,
       "mm answered and reported periodically as mm <motor> <current position>", SsMoveReports},
      {"stackshot", "np-zm", N::kDfmMotors,
       "zm and np answer mp; np to a moving motor retargets it", SsNewPosition},
      {"stackshot", "stop-all-motor", N::kDfmMotors, "sa <motor> answered sa, every motor stops",
       SsStopAllMotor},
      {"stackshot", "pulse-rate", N::kDfmMotors, "pr echoed up to the maximum, else the maximum",
       SsPulseRate},
      {"stackshot", "no-go-motion", N::kDfmMotors, "bf and go: no go-motion answer, no motion",
       SsNoGoMotion},
      {"random", "sequence", N::kDfmMotors, "a seeded sequence of valid commands (--seed)",
       DfmRandomSequence},
  };
}

}  // namespace

const std::vector<DfmCase>& DfmocoCases() {
  static const std::vector<DfmCase> cases = MakeCases();
  return cases;
}

std::optional<int32_t> DfmPosition(DfmHost& host, int32_t motor) {
  const auto* p = As<dfmoco::PositionReply>(host.Call(Cmd("mp", {motor})));
  if (p == nullptr) return std::nullopt;
  return p->position_steps;
}

namespace {

// Polls every motor's position until none has changed for kStillForRest, or
// until `until`.
void WaitPositionsStill(DfmHost& host, TimeNs until) {
  constexpr TimeNs kStillForRest = 150 * kMs;
  std::vector<std::optional<int32_t>> last;
  TimeNs still_since = host.Now();
  while (host.Now() < until && !host.link_lost()) {
    std::vector<std::optional<int32_t>> now;
    for (int32_t m = 1; m <= host.axes(); ++m) now.push_back(DfmPosition(host, m));
    if (now != last) {
      last = std::move(now);
      still_since = host.Now();
    } else if (host.Now() - still_since >= kStillForRest) {
      return;
    }
    host.Idle(std::min(kPollNs, until - host.Now()));
  }
}

}  // namespace

DfmRest DfmWaitRest(DfmHost& host, TimeNs timeout_ns, const std::function<void()>& while_moving) {
  DfmRest r;
  r.last_moving_ns.assign(static_cast<size_t>(std::max(host.axes(), 0)), -1);
  const TimeNs until = host.Now() + timeout_ns;
  for (;;) {
    const auto* st = As<dfmoco::MotorStatusReply>(host.Call("ms"));
    if (st == nullptr) {
      // No status to go by (its answer is missing, already judged): the
      // positions tell when the motion ended, so that what the case checks
      // next is judged on a motion that ended whether the host waited out
      // the answer timeout or not (HostOptions::give_up_after_unanswered).
      WaitPositionsStill(host, until);
      return r;
    }
    bool any = false;
    for (size_t i = 0; i < st->moving.size(); ++i) {
      if (!st->moving[i]) continue;
      any = true;
      if (i < r.last_moving_ns.size()) r.last_moving_ns[i] = host.Now();
    }
    if (!any) {
      r.rested = true;
      r.rest_ns = host.Now();
      return r;
    }
    if (host.Now() >= until || host.link_lost()) return r;
    if (while_moving) while_moving();
    host.Idle(kPollNs);
  }
}

}  // namespace moco::conformance
