// DFMoco go-motion maths and chunked execution (dfmoco-protocol.txt "Go-Motion
// (Blur)", FACTS.md "DFMoco ... Go-motion"); see go_motion.h.
#include "devices/dfmoco_arduino/go_motion.h"

#include <algorithm>
#include <cmath>

namespace moco::devices {
namespace {

constexpr double kChunkS = static_cast<double>(sim::kDfmocoChunkNs) / 1e9;
// More chunks than any move can need: a go-motion of 24 days.
constexpr int64_t kMaxChunks = 40'000'000;

}  // namespace

double BlurMove::PositionAt(double t_s) const {
  const double ramp = kGoMotionRampS;
  const double half = exposure_s / 2;
  if (t_s <= 0) return start_steps;
  if (t_s < ramp) return start_steps + 0.5 * (v1_steps_per_s / ramp) * t_s * t_s;
  if (t_s < ramp + half) return exposure_start_steps + v1_steps_per_s * (t_s - ramp);
  if (t_s < ramp + exposure_s) return p1_steps + v2_steps_per_s * (t_s - ramp - half);
  if (t_s < 2 * ramp + exposure_s) {
    const double tau = t_s - ramp - exposure_s;
    return exposure_end_steps + v2_steps_per_s * tau - 0.5 * (v2_steps_per_s / ramp) * tau * tau;
  }
  return end_steps;
}

double BlurMove::MaxSpeed() const {
  return std::max(std::fabs(v1_steps_per_s), std::fabs(v2_steps_per_s));
}

BlurMove PlanBlur(int32_t exposure_ms, int32_t blur, int32_t p0_steps, int32_t p1_steps,
                  int32_t p2_steps) {
  BlurMove m;
  const double b = static_cast<double>(blur) / 1000.0;
  const double p0 = p0_steps;
  const double p1 = p1_steps;
  const double p2 = p2_steps;
  m.exposure_s = static_cast<double>(exposure_ms) / 1000.0;
  m.p1_steps = p1;
  m.exposure_start_steps = p1 - (p1 - p0) * b;
  m.exposure_end_steps = p1 + (p2 - p1) * b;
  const double half = m.exposure_s / 2;
  m.v1_steps_per_s = (p1 - m.exposure_start_steps) / half;
  m.v2_steps_per_s = (m.exposure_end_steps - p1) / half;
  // A ramp from rest to v over the ramp time covers v * ramp / 2.
  m.start_steps = m.exposure_start_steps - 0.5 * m.v1_steps_per_s * kGoMotionRampS;
  m.end_steps = m.exposure_end_steps + 0.5 * m.v2_steps_per_s * kGoMotionRampS;
  return m;
}

std::vector<sim::Segment> GoMotionPlanner::Plan(const sim::PlanRequest& req) {
  if (req.kind != sim::PlanRequest::Kind::kMoveTo) return fallback_.Plan(req);
  std::vector<sim::Segment> out;
  // Positions below are relative to the plan origin, the motor's step then.
  const double origin_steps = static_cast<double>(end_target_steps_ - req.target_steps);
  const double target = static_cast<double>(req.target_steps);
  double x = req.start.x_steps;
  const double wait_s = static_cast<double>(std::max<sim::TimeNs>(start_ns_ - req.now_ns, 0)) / 1e9;
  if (wait_s > 0) {
    sim::Segment s;
    s.v0_steps_per_s = req.start.v_steps_per_s;
    s.duration_s = wait_s;
    out.push_back(s);
    x += req.start.v_steps_per_s * wait_s;
  }
  auto chunk = [&](double v) {
    sim::Segment s;
    s.v0_steps_per_s = v;
    s.duration_s = kChunkS;
    out.push_back(s);
    x += v * kChunkS;
  };
  const double cap = sim::kDfmocoMaxStepsPerS;
  const double total_s = move_.DurationS();
  double tau_s = 0;
  int last_dir = 0;
  for (int64_t n = 0; n < kMaxChunks; ++n) {
    const bool last = tau_s + kChunkS >= total_s - 1e-9;
    const double x_end = last ? target : move_.PositionAt(tau_s + kChunkS) - origin_steps;
    const double v = std::clamp((x_end - x) / kChunkS, -cap, cap);
    const int dir = v > 0 ? 1 : (v < 0 ? -1 : 0);
    if (dir != 0 && last_dir != 0 && dir != last_dir) {
      chunk(0);  // the direction pin changes; the move's clock stands still
      last_dir = dir;
      continue;
    }
    if (dir != 0) last_dir = dir;
    chunk(v);
    tau_s += kChunkS;
    if (last) break;
  }
  // Held back by the 20 kHz cap: the remaining distance at the cap.
  for (int64_t n = 0; n < kMaxChunks && std::fabs(target - x) > 0.5; ++n) {
    chunk(std::clamp((target - x) / kChunkS, -cap, cap));
  }
  return out;
}

}  // namespace moco::devices
