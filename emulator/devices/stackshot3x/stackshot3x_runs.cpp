// The StackShot 3X's stack runs and motion runs (stackshot-protocol.txt
// CC_RAIL_STACK_*, CC_RAIL_MOTION_*; FACTS.md "StackShot"): planned from the
// host's settings, stepped on the device's clock.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

#include "devices/stackshot3x/stackshot3x.h"

namespace moco::devices {

// ---------------------------------------------------------------------------
// Stack run

bool Stackshot3x::StackAxesAtRest() const {
  for (int a = 0; a < kAxes; ++a) {
    if ((stack_.used[Index(a)] || stack_.pano_axis == a) && Motor(a).IsMoving()) return false;
  }
  return true;
}

int64_t Stackshot3x::StackFramePosition(int axis, uint32_t frame) const {
  const size_t a = Index(axis);
  const int64_t span = stack_.end[a] - stack_.start[a];
  if (stack_.fixed_step) {
    const int64_t along =
        std::min<int64_t>(std::abs(stack_.step[a]) * static_cast<int64_t>(frame), std::abs(span));
    return stack_.start[a] + (span < 0 ? -along : along);
  }
  if (stack_.frames <= 1) return stack_.start[a];
  return stack_.start[a] + std::llround(static_cast<double>(span) * frame / (stack_.frames - 1));
}

std::optional<Stackshot3x::StackRun> Stackshot3x::PlanStack(const stackshot::RailStack& s,
                                                            int axis) const {
  using stackshot::RailMode;
  StackRun run;
  run.active = true;
  run.phase = StackPhase::kToStart;
  run.request = s;
  // Positions, distances and pano frames are signed motor steps in u32 fields.
  auto steps = [](uint32_t v) { return static_cast<int64_t>(static_cast<int32_t>(v)); };
  const std::array<std::pair<uint32_t, uint32_t>, 3> ends = {
      {{s.x_start, s.x_end}, {s.y_start, s.y_end}, {s.z_start, s.z_end}}};
  const int64_t distance = steps(s.distance);
  switch (static_cast<RailMode>(s.mode)) {
    case RailMode::kAutoStep:
      // Start and end per axis, "Number of steps" frames between them.
      if (s.num_steps == 0) return std::nullopt;
      run.frames = s.num_steps;
      for (size_t a = 0; a < 3; ++a) {
        run.start[a] = steps(ends[a].first);
        run.end[a] = steps(ends[a].second);
        run.used[a] = run.start[a] != run.end[a];
      }
      break;
    case RailMode::kAutoDist: {
      // Start and end per axis, a frame every `distance` steps along the
      // longest span (the other axes in proportion), the last on the end.
      if (distance <= 0) return std::nullopt;
      int64_t longest = 0;
      for (size_t a = 0; a < 3; ++a) {
        run.start[a] = steps(ends[a].first);
        run.end[a] = steps(ends[a].second);
        run.used[a] = run.start[a] != run.end[a];
        longest = std::max(longest, std::abs(run.end[a] - run.start[a]));
      }
      const int64_t intervals = (longest + distance - 1) / distance;
      if (intervals + 1 > int64_t{UINT32_MAX}) return std::nullopt;
      run.frames = static_cast<uint32_t>(intervals + 1);
      run.fixed_step = true;
      for (size_t a = 0; a < 3; ++a) {
        const int64_t span = std::abs(run.end[a] - run.start[a]);
        run.step[a] = longest == 0
                          ? 0
                          : std::llround(static_cast<double>(span) * static_cast<double>(distance) /
                                         static_cast<double>(longest));
      }
      break;
    }
    case RailMode::kTotalDistance:
    case RailMode::kDistancePerStep:
    case RailMode::kRotary: {
      // The addressed axis from where it stands: TOTAL_DISTANCE covers
      // `distance` in "Number of steps" frames (both ends shot); DISTANCE_PER_STEP
      // (and ROTARY, steps of the table) moves `distance` between frames.
      if (s.num_steps == 0 || distance == 0 || axis >= kAxes) return std::nullopt;
      const auto a = Index(axis);
      // In double first: distance x (num_steps - 1) can pass int64.
      const double total = static_cast<RailMode>(s.mode) == RailMode::kTotalDistance
                               ? static_cast<double>(distance)
                               : static_cast<double>(distance) * (s.num_steps - 1.0);
      run.frames = s.num_steps;
      run.start[a] = axes_[a].target_rail_steps;
      const double end = static_cast<double>(run.start[a]) + total;
      if (!(std::fabs(end) <= kMaxTravelSteps)) return std::nullopt;
      run.end[a] = static_cast<int64_t>(end);
      run.used[a] = run.start[a] != run.end[a];
      break;
    }
    case RailMode::kManual:
    case RailMode::kContinuous:
    case RailMode::kManualDistance:
    default:
      // Manual modes step on the panel's buttons; continuous mode runs on
      // the panel's timing: no stack a host describes by frames.
      return std::nullopt;
  }
  if (s.pano_start_steps != 0 || s.pano_stop_steps != 0) {
    // The pano frame: the first axis the stack leaves alone stands at
    // pano_start for the stack and goes on to pano_stop after it.
    for (int a = 0; a < kAxes; ++a) {
      if (!run.used[Index(a)]) {
        run.pano_axis = a;
        break;
      }
    }
    if (run.pano_axis < 0) return std::nullopt;  // every axis is stacking
    run.pano_start = steps(s.pano_start_steps);
    run.pano_stop = steps(s.pano_stop_steps);
  }
  return run;
}

void Stackshot3x::StackMoveTo(uint32_t frame) {
  if (stack_.phase == StackPhase::kToStart && stack_.pano_axis >= 0) {
    const int a = stack_.pano_axis;
    if (MoveAxisTo(a, stack_.pano_start,
                   SpeedStepsPerS(a, config_.axes[Index(a)].move_speed_mm_per_s),
                   /*backlash=*/true) != sim::MoveStatus::kOk) {
      AbortStack("stack aborted: pano axis refused to move");
      return;
    }
  }
  for (int a = 0; a < kAxes; ++a) {
    if (!stack_.used[Index(a)]) continue;
    const int64_t target = StackFramePosition(a, frame);
    const double v = stack_.phase == StackPhase::kMoving
                         ? SpeedStepsPerS(a, config_.axes[Index(a)].speed_mm_per_s)
                         : SpeedStepsPerS(a, config_.axes[Index(a)].move_speed_mm_per_s);
    if (MoveAxisTo(a, target, v, /*backlash=*/true) != sim::MoveStatus::kOk) {
      AbortStack("stack aborted: axis " + stackshot::AxisName(static_cast<uint8_t>(a)) +
                 " refused to move");
      return;
    }
  }
  if (StackAxesAtRest()) {
    // Nothing to move: continue once the current event is done.
    stack_.timer = scheduler_.After(0, [this] {
      stack_.timer = sim::Scheduler::kNoTimer;
      StackAdvance();
    });
  }
}

void Stackshot3x::StackShoot() {
  stack_.phase = StackPhase::kShooting;
  std::array<bool, 2> outputs{};
  bool any_axis = false;
  for (int a = 0; a < kAxes; ++a) {
    if (!stack_.used[Index(a)]) continue;
    any_axis = true;
    const auto s = static_cast<uint8_t>(config_.axes[Index(a)].shutter);
    outputs[0] = outputs[0] || (s & 1) != 0;
    outputs[1] = outputs[1] || (s & 2) != 0;
  }
  if (!any_axis) {
    const auto s = static_cast<uint8_t>(config_.axes[0].shutter);
    outputs = {(s & 1) != 0, (s & 2) != 0};
  }
  bool fired = false;
  for (int o = 0; o < kShutters; ++o) {
    if (!outputs[Index(o)]) continue;
    const Stackshot3xConfig::Shutter& sh = config_.shutters[Index(o)];
    fired |= FireShutter(o, sh.num_pulses, sh.pulse_time_s, sh.off_time_s,
                         config_.toff_final && sh.num_pulses > 1);
  }
  if (!fired) {
    stack_.timer = scheduler_.After(0, [this] {
      stack_.timer = sim::Scheduler::kNoTimer;
      StackAdvance();
    });
  }
}

// Moves the stack on once the step in progress (move, settle, shots) ends.
void Stackshot3x::StackAdvance() {
  if (!stack_.active) return;
  switch (stack_.phase) {
    case StackPhase::kToStart:
    case StackPhase::kMoving:
      stack_.phase = StackPhase::kSettling;
      stack_.timer = scheduler_.After(SecondsToNs(config_.settle_time_s), [this] {
        stack_.timer = sim::Scheduler::kNoTimer;
        StackShoot();
      });
      return;
    case StackPhase::kSettling:
      return;
    case StackPhase::kShooting:
      ++stack_.frames_shot;
      if (stack_.frames_shot < stack_.frames) {
        stack_.phase = StackPhase::kMoving;
        StackMoveTo(stack_.frames_shot);
        return;
      }
      if (config_.auto_return &&
          std::any_of(stack_.used.begin(), stack_.used.end(), [](bool u) { return u; })) {
        stack_.phase = StackPhase::kReturning;
        StackMoveTo(0);
        return;
      }
      break;
    case StackPhase::kReturning:
      break;
    case StackPhase::kPanoNext:
      stack_.pano_axis = -1;
      break;
  }
  if (stack_.pano_axis >= 0 && stack_.pano_stop != stack_.pano_start) {
    // On to the next pano frame.
    stack_.phase = StackPhase::kPanoNext;
    const int a = stack_.pano_axis;
    if (MoveAxisTo(a, stack_.pano_stop,
                   SpeedStepsPerS(a, config_.axes[Index(a)].move_speed_mm_per_s),
                   /*backlash=*/true) == sim::MoveStatus::kOk &&
        Motor(a).IsMoving()) {
      return;
    }
  }
  stack_.active = false;
  AddLog("stack done, " + std::to_string(stack_.frames_shot) + " frames");
}

void Stackshot3x::AbortStack(std::string_view why) {
  if (!stack_.active) return;
  scheduler_.Cancel(stack_.timer);
  stack_.timer = sim::Scheduler::kNoTimer;
  stack_.active = false;
  AbortShutters();
  AddLog(std::string(why));
}

// ---------------------------------------------------------------------------
// CC_MOTION_START

void Stackshot3x::MotionAdvance() {
  for (int a = 0; a < kAxes; ++a) {
    if (motion_.axes[Index(a)] && Motor(a).IsMoving()) return;
  }
  motion_.pending = false;
  for (int a = 0; a < kAxes; ++a) {
    if (!motion_.axes[Index(a)]) continue;
    sim::StepperMotor& m = Motor(a);
    m.SetProfile(sim::RampProfile(profile_.axes[Index(a)].max_speed_steps_per_s,
                                  config_.axes[Index(a)].ramp_time_s));
    motion_.stage[Index(a)] = 0;
    motion_.playing[Index(a)] = true;
    const AxisState& s = axes_[Index(a)];
    const sim::MoveStatus st = sim::PlaySpline(m, *planners_[Index(a)], s.runs.front());
    if (st != sim::MoveStatus::kOk) {
      motion_.playing[Index(a)] = false;
      AddLog("motion start refused on axis " + stackshot::AxisName(static_cast<uint8_t>(a)) + ": " +
             std::string(sim::MoveStatusName(st)));
      continue;
    }
    axes_[Index(a)].target_rail_steps = s.runs.back().FinalStep();
    if (!m.IsMoving()) MotionAxisNext(a);  // a run shorter than a step
  }
}

void Stackshot3x::MotionAxisNext(int axis) {
  const size_t ax = Index(axis);
  const std::vector<sim::BezierSpline>& runs = axes_[ax].runs;
  sim::StepperMotor& m = Motor(axis);
  // Each stage either starts a motion (and waits for OnMotionFinished) or,
  // when there is nothing to move, goes straight on to the next one.
  while (motion_.playing[ax] && !m.IsMoving()) {
    const size_t stage = ++motion_.stage[ax];
    const size_t run = (stage + 1) / 2;  // the run played or travelled to
    if (run >= runs.size()) {
      motion_.playing[ax] = false;
      axes_[ax].target_rail_steps = RailPosition(axis);
      return;
    }
    sim::MoveStatus st = sim::MoveStatus::kOk;
    if (stage % 2 == 1) {
      // A position jump between curves: the rail cannot jump, so it travels
      // to the next curve's start at the axis's maximum speed.
      m.SetProfile(
          sim::RampProfile(profile_.axes[ax].max_speed_steps_per_s, config_.axes[ax].ramp_time_s));
      planners_[ax]->SetRampTime(config_.axes[ax].ramp_time_s);
      if (m.Position() != runs[run].StartStep()) st = m.MoveTo(runs[run].StartStep());
    } else {
      st = sim::PlaySpline(m, *planners_[ax], runs[run]);
    }
    if (st != sim::MoveStatus::kOk) {
      motion_.playing[ax] = false;
      axes_[ax].target_rail_steps = RailPosition(axis);
      AddLog("motion on axis " + stackshot::AxisName(static_cast<uint8_t>(axis)) +
             " ended early: " + std::string(sim::MoveStatusName(st)));
      return;
    }
  }
}

std::optional<std::vector<sim::BezierSpline>> Stackshot3x::MakeRuns(const sim::MotionCurves& curves,
                                                                    double steps_per_unit,
                                                                    int axis) const {
  const double vmax = profile_.axes[Index(axis)].max_speed_steps_per_s;
  int used = 1;
  while (used < sim::kMotionCurves && curves[static_cast<size_t>(used)].p[0].t_s != 0) ++used;
  std::vector<sim::BezierSpline> runs;
  int first = 0;
  while (first < used) {
    // A run: curves whose positions join (P0.y = previous P3.y).
    int last = first;
    while (last + 1 < used && curves[static_cast<size_t>(last + 1)].p[0].position ==
                                  curves[static_cast<size_t>(last)].p[3].position) {
      ++last;
    }
    const double t0 = curves[static_cast<size_t>(first)].p[0].t_s;
    // "Limits should be applied to prevent sudden velocity changes which may
    // result in loss of steps": a run asking for more than the axis's
    // maximum speed is played slowed down as a whole (every time stretched by
    // one factor, the fewest that brings its fastest point to the maximum),
    // so it keeps its shape and keyframes. Found by bisection on the factor.
    auto run_at = [&](double scale) {
      sim::MotionCurves run{};
      for (int c = first; c <= last; ++c) {
        sim::BezierCurve k = curves[static_cast<size_t>(c)];
        for (sim::BezierPoint& pt : k.p) pt.t_s = (pt.t_s - t0) * scale;
        run[static_cast<size_t>(c - first)] = k;
      }
      return sim::MakeSpline(run, steps_per_unit, vmax);
    };
    sim::SplineOrFault made = run_at(1.0);
    if (!made.ok()) {
      if (made.fault.error != sim::SplineError::kTooFast) return std::nullopt;
      double lo = 1.0;
      double hi = 2.0;
      constexpr double kMaxScale = 1e9;  // beyond: the speed is unbounded (a vertical tangent)
      while (!run_at(hi).ok()) {
        lo = hi;
        hi *= 2;
        if (hi > kMaxScale) return std::nullopt;
      }
      for (int i = 0; i < 40 && hi - lo > 1e-9 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (run_at(mid).ok() ? hi : lo) = mid;
      }
      made = run_at(hi);
      if (!made.ok()) return std::nullopt;
    }
    runs.push_back(std::move(*made.spline));
    first = last + 1;
  }
  return runs;
}

}  // namespace moco::devices
