// The pin rules judged (conformance/rules/pin_rules.cpp; FACTS "Step drivers",
// "DFMoco"): step counts against reported positions, driver timing, rate,
// acceleration and reversals, from a case's pin trace and traffic.
#include "conformance/core/pin_judge.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace moco::conformance {
namespace {

using sim::TimeNs;

constexpr TimeNs kMs = sim::kNsPerMs;
// A motor with no rising STEP edge for this long after (or before) a report is at rest; its
// position was taken at most this long before the report was complete (a full
// 192-byte output queue at 57600 baud takes 33 ms).
constexpr TimeNs kRestWindowNs = kPinRestWindowNs;
// The window the step rate is counted over for PIN-006 (the sketch's chunk).
constexpr TimeNs kRateWindowNs = 50 * kMs;
constexpr double kAccelTolerance = 1.5;  // the planner's acceleration plus 50 %
constexpr double kQuantumPulses = 3;     // plus 3 pulses per window
// PIN-005 counts the pulses in every window of these lengths, anchored at a
// pulse (a rate sustained over a burst and over a stretch: what a driver, a
// motor and the protocol's maximum speed are about): a step entered late
// after a long interrupt shortens the next interval but adds no step, so
// interrupt latency never reads as a rate. One pulse of slack for where the
// window's end falls between pulses.
constexpr TimeNs kRateWindowsNs[] = {1 * kMs, 10 * kMs};

std::string Seconds(TimeNs t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f s", static_cast<double>(t) / 1e9);
  return text;
}

// One motor's STEP and DIR as the rules read them.
struct MotorView {
  int motor = 1;
  const PinSignal* step = nullptr;
  const PinSignal* dir = nullptr;
  std::vector<TimeNs> rises;        // rising STEP edges
  std::vector<int64_t> cumulative;  // signed count after each rise
  TimeNs until = 0;                 // edges after this are not judged

  // Signed count of rises at or before t.
  int64_t CountAt(TimeNs t) const {
    const auto it = std::upper_bound(rises.begin(), rises.end(), t);
    return it == rises.begin() ? 0 : cumulative[static_cast<size_t>(it - rises.begin()) - 1];
  }
  // Smallest and largest signed count over [a, b].
  std::pair<int64_t, int64_t> RangeOver(TimeNs a, TimeNs b) const {
    int64_t lo = CountAt(a), hi = lo;
    auto it = std::upper_bound(rises.begin(), rises.end(), a);
    for (; it != rises.end() && *it <= b; ++it) {
      const int64_t c = cumulative[static_cast<size_t>(it - rises.begin())];
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    return {lo, hi};
  }
  bool RiseWithin(TimeNs a, TimeNs b) const {
    auto it = std::lower_bound(rises.begin(), rises.end(), a);
    return it != rises.end() && *it <= b;
  }
};

MotorView ViewOf(const PinTrace& trace, size_t i) {
  MotorView m;
  m.motor = static_cast<int>(i + 1);
  m.step = &trace.signals[static_cast<size_t>(trace.motors[i].step)];
  m.dir = &trace.signals[static_cast<size_t>(trace.motors[i].dir)];
  m.until = trace.complete_until_ns;
  int64_t count = 0;
  for (const PinEdge& e : m.step->edges) {
    if (e.t_ns > m.until) break;
    if (!e.level) continue;
    count += m.dir->LevelAt(e.t_ns) ? 1 : -1;
    m.rises.push_back(e.t_ns);
    m.cumulative.push_back(count);
  }
  return m;
}

std::string Id(std::string_view prefix, const char* n) { return std::string(prefix) + n; }

// What the checks of one motor work with.
struct MotorJudge {
  const MotorView& m;
  std::string mn;  // "motor 1"
  std::string_view prefix;
  const PinJudgeOptions& o;
  TimeNs end;  // the end of the trace judged
  Verdicts& v;
};

// The highest pulse rate the host set for motor `motor` by `end` (pr), or the
// rate a motor starts with.
double MaxPulseRate(const std::vector<PinPositionEvent>& events, int motor, TimeNs end,
                    double default_rate) {
  double max_rate = default_rate;
  for (const PinPositionEvent& e : events) {
    if (e.motor != motor || e.t_ns > end) continue;
    if (e.kind == PinPositionEvent::Kind::kPulseRate) {
      max_rate = std::max(max_rate, static_cast<double>(e.position));
    }
  }
  return max_rate;
}

// PIN-001 / PIN-002: reported positions against the signed STEP count.
void JudgePositions(const MotorJudge& judge, const std::vector<PinPositionEvent>& events,
                    TimeNs period_ns) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const TimeNs end = judge.end;
  const std::string p001 = Id(judge.prefix, "PIN-001"), p002 = Id(judge.prefix, "PIN-002");
  int64_t base_value = 0, base_count = 0;
  for (const PinPositionEvent& e : events) {
    if (e.motor != m.motor || e.t_ns > end) continue;
    if (e.kind == PinPositionEvent::Kind::kPulseRate) continue;
    if (e.kind == PinPositionEvent::Kind::kReset) {
      base_value = e.position;
      base_count = m.CountAt(e.t_ns);
      continue;
    }
    const int64_t offset = base_value - base_count;
    // Moving: still pulsing within kRestWindowNs after the report, whatever
    // came before. A sketch reports the planned end of the chunk its timer
    // is still stepping out (FACTS DFMoco), at a start, a stop or a turn as
    // well as mid-move, and PIN-002 judges such a report; PIN-001 judges
    // the reports after which the motor makes no step.
    //
    // Each needs the pins after the report, which a run or a case cut short
    // while a motor moves does not hold: whether the motor steps within the
    // rest window (a report with no step after it up to the end, sooner than
    // the window, is not judged), and the steps of a reporting period after
    // it (fewer steps only narrow PIN-002's allowance, so a report that
    // passes within the steps the trace holds passes; one that does not is
    // not judged).
    const int64_t now = m.CountAt(e.t_ns);
    const bool moving = m.RiseWithin(e.t_ns + 1, std::min(end, e.t_ns + kRestWindowNs));
    if (!moving && e.t_ns + kRestWindowNs > end) continue;
    if (!moving) {
      // Not stepping on both sides: the position was taken at most a queued line before t.
      const auto [lo_rest, hi_rest] = m.RangeOver(e.t_ns - kRestWindowNs, e.t_ns);
      v.Check(p001, e.position >= offset + lo_rest && e.position <= offset + hi_rest, [&] {
        const int64_t expected = offset + m.CountAt(e.t_ns);
        return Evidence{mn + " reported at rest as " + std::to_string(expected) +
                            " (the STEP pulses counted since the last zero)",
                        "reported " + std::to_string(e.position) + " at " + Seconds(e.t_ns) + " (" +
                            std::to_string(e.position - expected) + " steps off)",
                        "", e.t_ns};
      });
    } else {
      // Within the steps taken one reporting period either side of the report.
      const auto first = std::lower_bound(m.rises.begin(), m.rises.end(), e.t_ns - period_ns);
      const auto last =
          std::upper_bound(m.rises.begin(), m.rises.end(), std::min(end, e.t_ns + period_ns));
      const int64_t steps = last - first;
      const int64_t off = e.position - (offset + now);
      const bool within = off >= -steps && off <= steps;
      if (!within && e.t_ns + period_ns > end) continue;
      v.Check(p002, within, [&] {
        return Evidence{mn + " reported while moving within " + std::to_string(steps) +
                            " steps (those one reporting period either side) of " +
                            std::to_string(offset + now),
                        "reported " + std::to_string(e.position) + " at " + Seconds(e.t_ns) + " (" +
                            std::to_string(off) + " steps off)",
                        "", e.t_ns};
      });
    }
  }
}

// PIN-003: pulse widths.
void JudgePulseWidths(const MotorJudge& judge) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const DriverProfile& d = judge.o.driver;
  const TimeNs end = judge.end;
  const std::string p003 = Id(judge.prefix, "PIN-003");
  const std::vector<PinEdge>& se = m.step->edges;
  for (size_t k = 0; k < se.size() && se[k].t_ns <= end; ++k) {
    if (k + 1 >= se.size() || se[k + 1].t_ns > end) break;
    const TimeNs width = se[k + 1].t_ns - se[k].t_ns;
    const bool high = se[k].level;
    const int64_t min_ns = high ? d.step_high_min_ns : d.step_low_min_ns;
    v.Check(p003, width >= min_ns, [&] {
      return Evidence{mn + " STEP " + (high ? "high" : "low") + " for at least " +
                          std::to_string(min_ns) + " ns (" + d.name + ")",
                      std::string(high ? "high" : "low") + " for " + std::to_string(width) +
                          " ns from " + Seconds(se[k].t_ns),
                      "", se[k].t_ns};
    });
  }
}

// PIN-005: the step rate.
void JudgeStepRate(const MotorJudge& judge) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const PinJudgeOptions& o = judge.o;
  const std::string p005 = Id(judge.prefix, "PIN-005");
  // The most pulses any window of kRateWindowsNs holds; judged once per
  // motor, with the worst window (the most pulses over its allowance) as the
  // evidence, not the first.
  if (!m.rises.empty()) {
    struct Worst {
      TimeNs window_ns = 0;
      int64_t pulses = 0, allowed = 1, windows_over = 0;
      size_t last = 0;  // index of the window's last rise
    } worst;
    for (const TimeNs w : kRateWindowsNs) {
      const int64_t allowed = static_cast<int64_t>(std::floor(
                                  o.board.max_step_rate_hz * static_cast<double>(w) / 1e9 + 1e-9)) +
                              1;
      int64_t over = 0;
      size_t j = 0;
      for (size_t k = 0; k < m.rises.size(); ++k) {
        while (m.rises[k] - m.rises[j] >= w) ++j;
        const auto n = static_cast<int64_t>(k - j + 1);
        over += n > allowed;
        // n / allowed > worst.pulses / worst.allowed, in integers.
        if (n * worst.allowed > worst.pulses * allowed) {
          worst = Worst{w, n, allowed, 0, k};
        }
      }
      if (worst.window_ns == w) worst.windows_over = over;
    }
    v.Check(p005, worst.pulses <= worst.allowed, [&] {
      const TimeNs from = m.rises[worst.last + 1 - static_cast<size_t>(worst.pulses)];
      const TimeNs to = m.rises[worst.last];
      char text[260];
      std::snprintf(
          text, sizeof text,
          "%lld STEP pulses within %.0f ms (%.0f steps/s) from %s to %s; %lld "
          "pulses ended a %.0f ms window over the rate",
          static_cast<long long>(worst.pulses), static_cast<double>(worst.window_ns) / 1e6,
          static_cast<double>(worst.pulses - 1) * 1e9 /
              static_cast<double>(std::max<TimeNs>(1, to - from)),
          Seconds(from).c_str(), Seconds(to).c_str(), static_cast<long long>(worst.windows_over),
          static_cast<double>(worst.window_ns) / 1e6);
      char want[200];
      std::snprintf(want, sizeof want,
                    "%s at most %lld steps/s (board %s): at most %lld pulses in any %.0f ms",
                    mn.c_str(), static_cast<long long>(o.board.max_step_rate_hz),
                    o.board.name.c_str(), static_cast<long long>(worst.allowed),
                    static_cast<double>(worst.window_ns) / 1e6);
      return Evidence{want, text, "", to};
    });
  }
}

// PIN-004: DIR setup and hold around every rising STEP edge.
void JudgeDirTiming(const MotorJudge& judge) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const DriverProfile& d = judge.o.driver;
  const std::string p004 = Id(judge.prefix, "PIN-004");
  const std::vector<PinEdge>& de = m.dir->edges;
  for (const TimeNs r : m.rises) {
    auto next = std::upper_bound(de.begin(), de.end(), r,
                                 [](TimeNs t, const PinEdge& e) { return t < e.t_ns; });
    const TimeNs setup = next == de.begin() ? INT64_MAX : r - std::prev(next)->t_ns;
    const TimeNs hold = next == de.end() ? INT64_MAX : next->t_ns - r;
    v.Check(p004, setup >= d.dir_setup_min_ns && hold >= d.dir_hold_min_ns, [&] {
      const bool bad_setup = setup < d.dir_setup_min_ns;
      return Evidence{
          mn + " DIR stable " + std::to_string(d.dir_setup_min_ns) + " ns before and " +
              std::to_string(d.dir_hold_min_ns) + " ns after each rising STEP edge (" + d.name +
              ")",
          bad_setup
              ? "DIR changed " + std::to_string(setup) + " ns before the STEP edge at " + Seconds(r)
              : "DIR changed " + std::to_string(hold) + " ns after the STEP edge at " + Seconds(r),
          "", r};
    });
  }
}

// PIN-006: the rate over 50 ms windows changes no faster than the planner
// allows for the highest pulse rate set, `max_rate`.
void JudgeAcceleration(const MotorJudge& judge, double max_rate) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const PinJudgeOptions& o = judge.o;
  const TimeNs end = judge.end;
  const std::string p006 = Id(judge.prefix, "PIN-006");
  if (!m.rises.empty()) {
    const double w_s = static_cast<double>(kRateWindowNs) / 1e9;
    const double limit = kAccelTolerance * o.accel_per_rate * max_rate + kQuantumPulses / w_s / w_s;
    const TimeNs last = std::min(end, m.rises.back() + kRateWindowNs);
    size_t k = 0;
    double prev_rate = 0;
    for (TimeNs w0 = 0; w0 < last; w0 += kRateWindowNs) {
      size_t n = 0;
      while (k < m.rises.size() && m.rises[k] < w0 + kRateWindowNs) ++k, ++n;
      const double rate = static_cast<double>(n) / w_s;
      const double accel = std::fabs(rate - prev_rate) / w_s;
      if (n > 0 || prev_rate > 0) {
        v.Check(p006, accel <= limit, [&] {
          char text[200];
          std::snprintf(text, sizeof text,
                        "%.0f steps/s then %.0f steps/s in the 50 ms windows from %s: %.0f "
                        "steps/s^2",
                        prev_rate, rate, Seconds(w0 - kRateWindowNs).c_str(), accel);
          char want[160];
          std::snprintf(want, sizeof want, "%s accelerating at most %.0f steps/s^2", mn.c_str(),
                        limit);
          return Evidence{want, text, "", w0};
        });
      }
      prev_rate = rate;
    }
  }
}

// PIN-007: DIR changes only after the motor has slowed down.
void JudgeReversals(const MotorJudge& judge) {
  const MotorView& m = judge.m;
  const std::string& mn = judge.mn;
  Verdicts& v = judge.v;
  const PinJudgeOptions& o = judge.o;
  const TimeNs end = judge.end;
  const std::string p007 = Id(judge.prefix, "PIN-007");
  const std::vector<PinEdge>& de = m.dir->edges;
  const double slow_ns = 1e9 / o.board.reversal_max_rate_hz;
  for (const PinEdge& e : de) {
    if (e.t_ns > end) break;
    auto it = std::upper_bound(m.rises.begin(), m.rises.end(), e.t_ns);
    if (it == m.rises.begin() || std::prev(it) == m.rises.begin()) continue;  // from rest
    const TimeNs r2 = *std::prev(it), r1 = *std::prev(it, 2);
    // A motor whose last pulse is longer ago than a slow interval had stopped.
    const bool fast =
        static_cast<double>(r2 - r1) < slow_ns && static_cast<double>(e.t_ns - r2) < slow_ns;
    v.Check(p007, !fast, [&] {
      char text[200];
      std::snprintf(text, sizeof text,
                    "DIR changed at %s, %lld ns after a STEP pulse, pulses %lld ns apart "
                    "(%.0f steps/s)",
                    Seconds(e.t_ns).c_str(), static_cast<long long>(e.t_ns - r2),
                    static_cast<long long>(r2 - r1), 1e9 / static_cast<double>(r2 - r1));
      return Evidence{mn + " reverses only below " +
                          std::to_string(static_cast<int64_t>(o.board.reversal_max_rate_hz)) +
                          " steps/s",
                      text, "", e.t_ns};
    });
  }
}

}  // namespace

void JudgePins(std::string_view prefix, const PinTrace& trace,
               const std::vector<PinPositionEvent>& events, const PinJudgeOptions& o, TimeNs end_ns,
               Verdicts& v) {
  const TimeNs period_ns = o.board.report_period_ms * kMs;
  const TimeNs end = std::min(end_ns, trace.complete_until_ns);
  for (size_t i = 0; i < trace.motors.size(); ++i) {
    const MotorView m = ViewOf(trace, i);
    const MotorJudge judge{m, "motor " + std::to_string(m.motor), prefix, o, end, v};
    JudgePositions(judge, events, period_ns);
    JudgePulseWidths(judge);
    JudgeStepRate(judge);
    JudgeDirTiming(judge);
    JudgeAcceleration(judge, MaxPulseRate(events, m.motor, end, o.default_pulse_rate));
    JudgeReversals(judge);
  }
}

}  // namespace moco::conformance
