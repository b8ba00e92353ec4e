// The step model (ARCHITECTURE "Motion", docs/sim-model.md): contiguous
// monotonic constant-acceleration segments, step edges at the exact roots.
#include "sim/motion.h"

#include <algorithm>
#include <cmath>

namespace moco::sim {
namespace {

constexpr double kNsPerSecondF = 1e9;

// Smallest multiple of q at or after t (t >= 0 in practice; exact for t < 0 too).
TimeNs RoundUp(TimeNs t, TimeNs q) {
  if (q <= 1) return t;
  const TimeNs r = t % q;
  if (r == 0) return t;
  return r > 0 ? t + (q - r) : t - r;
}

// Number of thresholds p +- (k + 1/2), k >= 0, that x_end reaches from p.
int64_t EdgesReached(int dir, int64_t p, double x_end) {
  double n = 0;
  if (dir > 0) {
    n = std::floor(x_end - (static_cast<double>(p) + 0.5)) + 1;
  } else if (dir < 0) {
    n = std::floor((static_cast<double>(p) - 0.5) - x_end) + 1;
  }
  return n > 0 ? static_cast<int64_t>(n) : 0;
}

}  // namespace

int Segment::Direction() const {
  if (v0_steps_per_s > 0) return 1;
  if (v0_steps_per_s < 0) return -1;
  if (a_steps_per_s2 > 0) return 1;
  if (a_steps_per_s2 < 0) return -1;
  return 0;
}

double CrossingTime(const Segment& s, int dir, double threshold_steps) {
  const double d = threshold_steps - s.x0_steps;
  if (dir * d <= 0) return 0;
  const double v0 = s.v0_steps_per_s;
  const double disc = v0 * v0 + 2 * s.a_steps_per_s2 * d;
  if (disc < 0) return s.duration_s;  // not reached (the peak is short of it)
  // Root of a/2 tau^2 + v0 tau - d = 0 nearest 0, in the form without
  // cancellation: tau = 2d / (v0 + dir sqrt(disc)).
  const double denom = v0 + dir * std::sqrt(disc);
  if (denom == 0) return s.duration_s;
  const double tau = 2 * d / denom;
  if (!(tau > 0)) return 0;
  return std::min(tau, s.duration_s);
}

Plan Plan::Build(TimeNs origin_ns, int64_t origin_steps, double start_x_steps,
                 const std::vector<Segment>& segments, TimeNs step_quantum_ns) {
  Plan plan;
  plan.quantum_ns_ = step_quantum_ns > 1 ? step_quantum_ns : 1;
  plan.origin_ns_ = origin_ns;
  plan.origin_steps_ = origin_steps;
  plan.end_ns_ = origin_ns;
  double t = 0;
  double x = start_x_steps;
  auto push = [&](Segment s) {
    plan.segs_.push_back(s);
    t = s.EndTime();
    x = s.EndPosition();
  };
  for (const Segment& in : segments) {
    if (!(in.duration_s > 0) || !std::isfinite(in.duration_s) ||
        !std::isfinite(in.v0_steps_per_s) || !std::isfinite(in.a_steps_per_s2)) {
      continue;
    }
    Segment s = in;
    s.t0_s = t;
    s.x0_steps = x;
    const double v0 = s.v0_steps_per_s;
    const double a = s.a_steps_per_s2;
    if (v0 != 0 && a != 0 && (v0 > 0) != (a > 0)) {
      const double t_zero = -v0 / a;
      if (t_zero < s.duration_s) {
        Segment first = s;
        first.duration_s = t_zero;
        push(first);
        Segment second = s;
        second.t0_s = t;
        second.x0_steps = x;
        second.v0_steps_per_s = 0;
        second.duration_s = s.duration_s - t_zero;
        if (second.duration_s > 0) push(second);
        continue;
      }
    }
    push(s);
  }
  plan.info_.reserve(plan.segs_.size());
  int64_t p = 0;
  int64_t total_edges = 0;
  for (const Segment& s : plan.segs_) {
    const int dir = s.Direction();
    const int64_t n = EdgesReached(dir, p, s.EndPosition());
    plan.info_.push_back(SegInfo{p, n, static_cast<int8_t>(dir)});
    p += dir * n;
    total_edges += n;
  }
  if (!plan.segs_.empty()) {
    const double end_rel_ns = std::ceil(plan.segs_.back().EndTime() * kNsPerSecondF);
    TimeNs end_rel = static_cast<TimeNs>(end_rel_ns);
    if (total_edges > 0 && end_rel < 1) end_rel = 1;
    plan.end_ns_ = RoundUp(origin_ns + end_rel, plan.quantum_ns_);
  }
  return plan;
}

int64_t Plan::EndSteps() const {
  if (info_.empty()) return origin_steps_;
  const SegInfo& last = info_.back();
  return origin_steps_ + last.p_start + last.dir * last.edges;
}

int64_t Plan::EdgeCount() const {
  int64_t n = 0;
  for (const SegInfo& i : info_) n += i.edges;
  return n;
}

TimeNs Plan::EdgeTime(size_t i, int64_t k) const {
  const Segment& s = segs_[i];
  const SegInfo& info = info_[i];
  const double threshold =
      static_cast<double>(info.p_start) + info.dir * (static_cast<double>(k) + 0.5);
  const double tau = CrossingTime(s, info.dir, threshold);
  const auto rel = static_cast<TimeNs>(std::ceil((s.t0_s + tau) * kNsPerSecondF));
  return RoundUp(origin_ns_ + std::max<TimeNs>(1, rel), quantum_ns_);
}

size_t Plan::SegmentAt(TimeNs t) const {
  const double rel_ns = static_cast<double>(t - origin_ns_);
  // First segment starting after t, minus one.
  size_t lo = 0;
  size_t hi = segs_.size();
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (segs_[mid].t0_s * kNsPerSecondF <= rel_ns) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo == 0 ? 0 : lo - 1;
}

int64_t Plan::EdgesUpTo(size_t i, TimeNs t) const {
  const SegInfo& info = info_[i];
  if (info.edges == 0 || t <= origin_ns_) return 0;
  const Segment& s = segs_[i];
  const double tau =
      std::clamp(static_cast<double>(t - origin_ns_) / kNsPerSecondF - s.t0_s, 0.0, s.duration_s);
  // Estimate from x(t), then settle on the edge times themselves so that
  // StepsAt agrees with ForEachEdge to the nanosecond.
  int64_t k = std::min(EdgesReached(info.dir, info.p_start, s.PositionAt(tau)), info.edges);
  while (k > 0 && EdgeTime(i, k - 1) > t) --k;
  while (k < info.edges && EdgeTime(i, k) <= t) ++k;
  return k;
}

std::pair<size_t, int64_t> Plan::Locate(TimeNs t) const {
  size_t i = SegmentAt(t);
  int64_t k = EdgesUpTo(i, t);
  // With a step quantum, the last edges of earlier segments may fall after
  // the start of this one: walk back to the segment of the last edge <= t.
  while (k == 0 && i > 0) {
    const SegInfo& prev = info_[i - 1];
    if (prev.edges > 0 && EdgeTime(i - 1, prev.edges - 1) <= t) break;
    --i;
    k = EdgesUpTo(i, t);
  }
  return {i, k};
}

int64_t Plan::StepsAt(TimeNs t) const {
  if (segs_.empty() || t <= origin_ns_) return origin_steps_;
  const auto [i, k] = Locate(t);
  return origin_steps_ + info_[i].p_start + info_[i].dir * k;
}

KinematicState Plan::StateAt(TimeNs t) const {
  if (segs_.empty()) return {};
  if (t <= origin_ns_) return {segs_.front().x0_steps, segs_.front().v0_steps_per_s};
  const size_t i = SegmentAt(t);
  const Segment& s = segs_[i];
  const double tau =
      std::clamp(static_cast<double>(t - origin_ns_) / kNsPerSecondF - s.t0_s, 0.0, s.duration_s);
  return {s.PositionAt(tau), s.VelocityAt(tau)};
}

std::optional<TimeNs> Plan::TimeOfStep(int64_t steps, int direction, TimeNs after_ns) const {
  const int64_t p_rel = steps - origin_steps_;
  for (size_t i = 0; i < segs_.size(); ++i) {
    const SegInfo& info = info_[i];
    if (info.dir != direction || info.edges == 0) continue;
    const int64_t k = info.dir * (p_rel - info.p_start) - 1;
    if (k < 0 || k >= info.edges) continue;
    const TimeNs t = EdgeTime(i, k);
    if (t > after_ns) return t;
  }
  return std::nullopt;
}

size_t Plan::HeapBytes() const {
  return segs_.capacity() * sizeof(Segment) + info_.capacity() * sizeof(SegInfo);
}

}  // namespace moco::sim
