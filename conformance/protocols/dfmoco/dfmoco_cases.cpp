// DFMoco scenario suites (dfmoco-protocol.txt "Hello (hi)", "Motor Status
// (ms)", "Move Motor (mm)" ... "Go-Motion (Blur)", "Notes"; ERRATA dfmoco
// 1-5; FACTS "DFMoco"): each case drives Dragonframe-style traffic and judges
// what the device did against the named rules, and RunDfmoco runs them.
// Cases work relative to the positions they find, so they also run against a
// device that is not fresh. This file holds the checks every case makes, the
// connect and error cases, the table of every case in run order (the others
// are in dfmoco_cases_motor.cpp, _gomotion.cpp and _stackshot.cpp), and the
// position query and the wait for rest that the cases and the random suite
// share.
#include "conformance/protocols/dfmoco/dfmoco_suites.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "conformance/core/run.h"
#include "conformance/core/run_report.h"
#include "conformance/protocols/dfmoco/dfmoco_cases_internal.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "conformance/rules/dfmoco_needs.h"

namespace moco::conformance {
namespace dfmoco_cases {

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

TimeNs Tolerance(const DfmCaseContext& c) { return c.host_options.deadline_ns; }

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
DfmRest Rest(DfmCaseContext& c, const std::function<void()>& while_moving) {
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

}  // namespace dfmoco_cases

namespace {

using namespace dfmoco_cases;  // NOLINT: the shared checks of every DFMoco case

// ---------------------------------------------------------------- connect

void BootHi(DfmCaseContext& c) {
  if (!c.target.CanRestart()) return;  // the start-up of an external device is not observed
  bool seen = false;
  for (const DfmLine& l : c.host.lines()) {
    seen = seen ||
           (l.command < 0 && As<dfmoco::HelloReply>(&l) != nullptr && l.t_ns <= kBootHiWithinNs);
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
  h.Idle(kQuietAtRestNs);
  const size_t extra = h.lines().size() - mark;
  Expect(c, "DFM-MP-007", extra == 0, "no line for 2.5 s at rest",
         Str(static_cast<int64_t>(extra)) + " line(s), the first " +
             (extra > 0 ? Show(&h.lines()[mark]) : ""));
}

void LineEnd(DfmCaseContext& c) {
  DfmHost& h = c.host;
  const int k = h.Send("ms", {}, "\n");
  h.Idle(kListenForReplyNs);
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
  if (!DfmocoApplies(DfmocoNeeds::kGoMotion, c.device)) {
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
    h.Idle(kListenForReplyNs);
    std::string seen;
    for (size_t i = mark; i < h.lines().size(); ++i) {
      if (As<dfmoco::PositionReply>(&h.lines()[i]) == nullptr) seen = Show(&h.lines()[i]);
    }
    Expect(c, "DFM-REPLY-003", seen.empty(), "no reply to \"" + std::string(line) + "\"", seen);
  }
  const DfmLine* l = h.Call("ms");
  Expect(c, "DFM-ERR-005", As<dfmoco::MotorStatusReply>(l) != nullptr, "ms answered", Show(l));
}

std::vector<DfmCase> MakeCases() {
  using N = DfmocoNeeds;
  return {
      {"connect", "boot-hi", N::kNothing, "unprompted hi at power-on", BootHi},
      {"connect", "hi", N::kNothing, "hi twice: fields, stable answer", HiAgain},
      {"connect", "queries", N::kNothing, "ms and mp at rest, then quiet", Queries},
      {"connect", "line-end", N::kNothing, "a command ended by a bare \\n", LineEnd},
      {"connect", "pipelined", N::kNothing, "12 commands in one write: all answered, in order",
       Pipelined},
      {"motor", "move", N::kMotors, "mm with ms, mp reports, rest and the already-there answer",
       Move},
      {"motor", "pulse-rate", N::kMotors, "pr echo, clamps and the speed limit", PulseRate},
      {"motor", "stop", N::kMotors, "sm during a long move (other motor keeps going)", Stop},
      {"motor", "stop-all", N::kMotors, "sa during moves of every motor (up to 4)", StopAll},
      {"motor", "np-zm", N::kMotors, "np and zm: answers, no motion, new positions",
       NewPositionZero},
      {"motor", "jog", N::kMotors, "jm repeated towards a far and a near destination", Jog},
      {"motor", "inch", N::kMotors, "im from rest: a few steps, at most one past", Inch},
      {"pins", "fast-reversal", N::kPins,
       "pr 20000, a long move sent back at full speed (for the pin rules)", FastReversal},
      {"errors", "arguments", N::kNothing, "wrong argument counts and malformed numbers",
       BadArguments},
      {"errors", "bad-motor", N::kMotors, "motor 0 and axes + 1 for every motor command", BadMotor},
      {"errors", "too-many-args", N::kNothing, "40 and more arguments", TooMany},
      {"errors", "unknown", N::kNothing, "unknown words get no reply", Unknown},
      {"gomotion", "blur", N::kGoMotion, "bf, pre-position, go, exposure timing, bf while moving",
       Blur},
      {"gomotion", "go-at-once", N::kGoMotion,
       "bf, ms polled back to back, go the moment it shows rest", GoAtOnce},
      {"gomotion", "too-fast", N::kBlurRefusal, "bf faster than 20000 steps/s: bf -1", BlurTooFast},
      {"shoot", "frames", N::kMotors, "a shoot of 6 frames on up to 2 motors", Shoot},
      {"stackshot", "mp-all", N::kMotors, "hi axes 1-3; mp * answers every motor's position",
       SsPositionsAll},
      {"stackshot", "move-reports", N::kMotors,
       "mm answered and reported periodically as mm <motor> <current position>", SsMoveReports},
      {"stackshot", "np-zm", N::kMotors, "zm and np answer mp; np to a moving motor retargets it",
       SsNewPosition},
      {"stackshot", "stop-all-motor", N::kMotors, "sa <motor> answered sa, every motor stops",
       SsStopAllMotor},
      {"stackshot", "pulse-rate", N::kMotors, "pr echoed up to the maximum, else the maximum",
       SsPulseRate},
      {"stackshot", "no-go-motion", N::kMotors, "bf and go: no go-motion answer, no motion",
       SsNoGoMotion},
      {"random", "sequence", N::kMotors, "a seeded sequence of valid commands (--seed)",
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
