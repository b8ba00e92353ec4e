// DFMoco go-motion cases (dfmoco-protocol.txt "Go-Motion (Blur)"; ERRATA 2.5; FACTS
// "DFMoco"): the plan of a blurred move (ramp, exposure, slow-down) a device must
// follow, and the cases that pre-position with `bf`, run it with `go` and sample the
// motion against that plan, send `go` the moment `ms` shows rest, and ask for a blur
// too fast to make, each judged against the named rules. Listed by the table in
// dfmoco_cases.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_cases_internal.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "sim/planner_dfmoco.h"
#include "wire/dfmoco_timing.h"

namespace moco::conformance::dfmoco_cases {

// ---------------------------------------------------------------- go-motion

namespace {

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
      const auto span =
          plan.Span(Seconds(s.asked_ns - t_go - kGoWithinNs),
                    Seconds(s.answered_ns - t_go + sim::kDfmocoChunkNs + kGoWithinNs));
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

}  // namespace

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
  const TimeNs want = 2 * dfmoco::kGoMotionRampNs + exposure_ms * kMs;
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
  h.Idle(kAfterBlurRefusedNs);
  const DfmLine* ms = h.Call("ms");
  Expect(c, "DFM-GO-008", !ShowsMoving(ms, 1), "nothing moves after bf -1", Show(ms));
  const auto p = DfmPosition(h, 1);
  Expect(c, "DFM-GO-008", p == *from, "motor 1 stays on " + Str(*from), p ? Str(*p) : "no answer");
}

}  // namespace moco::conformance::dfmoco_cases
