// DFMoco cases of the StackShot 3X dialect (stackshot-protocol.txt section 3; ERRATA
// 3.9): a StackShot 3X in DfMoco mode answers `mp *` for every motor, reports moves as
// `mm <motor> <position>`, answers `zm` and `np` with `mp`, stops every motor on `sa
// <motor>`, caps `pr` at its maximum and has no go-motion; each case is judged against
// the named rules. Listed by the table in dfmoco_cases.cpp.
#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_cases_internal.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"

namespace moco::conformance::dfmoco_cases {

// --- The StackShot 3X DfMoco dialect (stackshot-protocol.txt section 3; ERRATA 3.9) ---

namespace {

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

}  // namespace

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
  h.Idle(kMpAllLinesNs);
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
  if (last_moving - t0 > kLongMoveNs) {
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
  h.Idle(kMotorStartNs);
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
  h.Idle(kSsMoveBeforeStopAllNs);
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
  h.Idle(kSsGoMotionListenNs);
  h.Send("go");
  h.Idle(kSsGoMotionListenNs);
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

}  // namespace moco::conformance::dfmoco_cases
