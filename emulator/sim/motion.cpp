// The step model (ARCHITECTURE "Motion", docs/sim-model.md): contiguous
// monotonic constant-acceleration segments, step edges at the exact roots.
#include "sim/motion.h"

#include <algorithm>
#include <cmath>
#include <utility>

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
  std::vector<int32_t> run_of;  // per laid-out segment: its index in runs_, or -1
  auto push = [&](Segment s) {
    plan.segs_.push_back(s);
    run_of.push_back(-1);
    t = s.EndTime();
    x = s.EndPosition();
  };
  auto piece_velocity = [](const Segment& run, int64_t j, double x_steps) {
    return run.chunk_velocities ? run.chunk_velocities->Velocity(j, x_steps) : run.v0_steps_per_s;
  };
  // Lays out a chunked run kept whole; false (nothing laid out) if it cannot
  // be: a non-finite piece, or pieces of both directions.
  auto add_run = [&](const Segment& in) {
    if (!(in.duration_s > 0) || !std::isfinite(in.duration_s)) return false;
    RunInfo run;
    run.marks.reserve(static_cast<size_t>((in.chunks + kRunMarkStride - 1) / kRunMarkStride));
    int dir = 0;
    double pt = t;
    double px = x;
    for (int64_t j = 0; j < in.chunks; ++j) {
      const double v = piece_velocity(in, j, px);
      if (!std::isfinite(v)) return false;
      const int d = v > 0 ? 1 : (v < 0 ? -1 : 0);
      if (d != 0 && dir != 0 && d != dir) return false;
      if (d != 0) dir = d;
      if (j % kRunMarkStride == 0) run.marks.push_back(PieceMark{j, pt, px, 0});
      Segment piece;
      piece.t0_s = pt;
      piece.x0_steps = px;
      piece.v0_steps_per_s = v;
      piece.duration_s = in.duration_s;
      pt = piece.EndTime();
      px = piece.EndPosition();
    }
    run.end_t_s = pt;
    run.end_x_steps = px;
    Segment s = in;
    s.t0_s = t;
    s.x0_steps = x;
    s.v0_steps_per_s = piece_velocity(in, 0, x);
    s.a_steps_per_s2 = 0;
    plan.segs_.push_back(s);
    run_of.push_back(static_cast<int32_t>(plan.runs_.size()));
    plan.runs_.push_back(std::move(run));
    t = pt;
    x = px;
    return true;
  };
  auto add = [&](const Segment& in) {
    if (!(in.duration_s > 0) || !std::isfinite(in.duration_s) ||
        !std::isfinite(in.v0_steps_per_s) || !std::isfinite(in.a_steps_per_s2)) {
      return;
    }
    Segment s = in;
    s.chunks = 1;
    s.chunk_velocities = nullptr;
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
        return;
      }
    }
    push(s);
  };
  for (const Segment& in : segments) {
    if (!in.IsRun()) {
      add(in);
    } else if (!add_run(in)) {
      // Not a valid run: its expansion, piece by piece.
      for (int64_t j = 0; j < in.chunks; ++j) {
        Segment piece;
        piece.duration_s = in.duration_s;
        piece.v0_steps_per_s = piece_velocity(in, j, x);
        add(piece);
      }
    }
  }
  plan.info_.reserve(plan.segs_.size());
  int64_t p = 0;
  int64_t total_edges = 0;
  for (size_t i = 0; i < plan.segs_.size(); ++i) {
    const Segment& s = plan.segs_[i];
    if (run_of[i] < 0) {
      const int dir = s.Direction();
      const int64_t n = EdgesReached(dir, p, s.EndPosition());
      plan.info_.push_back(SegInfo{p, n, static_cast<int8_t>(dir)});
      p += dir * n;
      total_edges += n;
      continue;
    }
    // A run: count its edges piece by piece, as its expansion would.
    RunInfo& run = plan.runs_[static_cast<size_t>(run_of[i])];
    int dir = 0;
    int64_t n = 0;
    const int64_t p_start = p;
    Segment piece;
    piece.t0_s = s.t0_s;
    piece.x0_steps = s.x0_steps;
    piece.duration_s = s.duration_s;
    for (int64_t j = 0; j < s.chunks; ++j) {
      if (j % kRunMarkStride == 0)
        run.marks[static_cast<size_t>(j / kRunMarkStride)].edges_before = n;
      piece.v0_steps_per_s = piece_velocity(s, j, piece.x0_steps);
      const int d = piece.Direction();
      if (d != 0) dir = d;
      const int64_t e = EdgesReached(d, p, piece.EndPosition());
      p += d * e;
      n += e;
      const double next_t = piece.EndTime();
      piece.x0_steps = piece.EndPosition();
      piece.t0_s = next_t;
    }
    plan.info_.push_back(SegInfo{p_start, n, static_cast<int8_t>(dir), run_of[i]});
    total_edges += n;
  }
  if (!plan.segs_.empty()) {
    const double last_end =
        plan.info_.back().run >= 0 ? plan.runs_.back().end_t_s : plan.segs_.back().EndTime();
    const double end_rel_ns = std::ceil(last_end * kNsPerSecondF);
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

Segment Plan::PieceSegment(size_t i, const PieceCursor& c) const {
  Segment piece;
  piece.t0_s = c.at.t_s;
  piece.x0_steps = c.at.x_steps;
  piece.v0_steps_per_s = c.v_steps_per_s;
  piece.duration_s = segs_[i].duration_s;
  return piece;
}

Plan::PieceCursor Plan::MakeCursor(size_t i, const PieceMark& m) const {
  const Segment& run = segs_[i];
  const SegInfo& info = info_[i];
  PieceCursor c;
  c.at = m;
  c.v_steps_per_s =
      run.chunk_velocities ? run.chunk_velocities->Velocity(m.j, m.x_steps) : run.v0_steps_per_s;
  const Segment piece = PieceSegment(i, c);
  c.edges = EdgesReached(piece.Direction(), info.p_start + info.dir * m.edges_before,
                         piece.EndPosition());
  return c;
}

void Plan::NextPiece(size_t i, PieceCursor& c) const {
  const Segment piece = PieceSegment(i, c);
  c = MakeCursor(
      i, PieceMark{c.at.j + 1, piece.EndTime(), piece.EndPosition(), c.at.edges_before + c.edges});
}

Plan::PieceCursor Plan::PieceOfEdge(size_t i, int64_t k) const {
  const std::vector<PieceMark>& marks = runs_[static_cast<size_t>(info_[i].run)].marks;
  auto it = std::upper_bound(marks.begin(), marks.end(), k,
                             [](int64_t kk, const PieceMark& m) { return kk < m.edges_before; });
  PieceCursor c = MakeCursor(i, it == marks.begin() ? marks.front() : *(it - 1));
  while (k >= c.at.edges_before + c.edges && c.at.j + 1 < segs_[i].chunks) NextPiece(i, c);
  return c;
}

Plan::PieceCursor Plan::PieceAt(size_t i, double rel_ns) const {
  const std::vector<PieceMark>& marks = runs_[static_cast<size_t>(info_[i].run)].marks;
  // The same rule as SegmentAt, piece by piece.
  auto it = std::upper_bound(marks.begin(), marks.end(), rel_ns, [](double r, const PieceMark& m) {
    return !(m.t_s * kNsPerSecondF <= r);
  });
  PieceCursor c = MakeCursor(i, it == marks.begin() ? marks.front() : *(it - 1));
  while (c.at.j + 1 < segs_[i].chunks && PieceSegment(i, c).EndTime() * kNsPerSecondF <= rel_ns) {
    NextPiece(i, c);
  }
  return c;
}

TimeNs Plan::PieceEdgeTime(size_t i, const PieceCursor& c, int64_t k_local) const {
  const SegInfo& info = info_[i];
  const int64_t p_start = info.p_start + info.dir * c.at.edges_before;
  const double threshold =
      static_cast<double>(p_start) + info.dir * (static_cast<double>(k_local) + 0.5);
  const Segment piece = PieceSegment(i, c);
  const double tau = CrossingTime(piece, info.dir, threshold);
  const auto rel = static_cast<TimeNs>(std::ceil((piece.t0_s + tau) * kNsPerSecondF));
  return RoundUp(origin_ns_ + std::max<TimeNs>(1, rel), quantum_ns_);
}

TimeNs Plan::EdgeTime(size_t i, int64_t k) const {
  if (info_[i].run >= 0) {
    const PieceCursor c = PieceOfEdge(i, k);
    return PieceEdgeTime(i, c, k - c.at.edges_before);
  }
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
  int64_t k = 0;
  if (info.run >= 0) {
    const PieceCursor c = PieceAt(i, static_cast<double>(t - origin_ns_));
    const Segment piece = PieceSegment(i, c);
    const double tau = std::clamp(static_cast<double>(t - origin_ns_) / kNsPerSecondF - piece.t0_s,
                                  0.0, piece.duration_s);
    const int64_t p_piece = info.p_start + info.dir * c.at.edges_before;
    k = c.at.edges_before +
        std::min(EdgesReached(info.dir, p_piece, piece.PositionAt(tau)), c.edges);
    // Settle on the edge times, from the located piece when the edge is in it.
    auto time_of = [&](int64_t kk) {
      const int64_t local = kk - c.at.edges_before;
      return local >= 0 && local < c.edges ? PieceEdgeTime(i, c, local) : EdgeTime(i, kk);
    };
    while (k > 0 && time_of(k - 1) > t) --k;
    while (k < info.edges && time_of(k) <= t) ++k;
    return k;
  } else {
    const Segment& s = segs_[i];
    const double tau =
        std::clamp(static_cast<double>(t - origin_ns_) / kNsPerSecondF - s.t0_s, 0.0, s.duration_s);
    // Estimate from x(t), then settle on the edge times themselves so that
    // StepsAt agrees with ForEachEdge to the nanosecond.
    k = std::min(EdgesReached(info.dir, info.p_start, s.PositionAt(tau)), info.edges);
  }
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
  const Segment s = info_[i].run >= 0
                        ? PieceSegment(i, PieceAt(i, static_cast<double>(t - origin_ns_)))
                        : segs_[i];
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
  size_t bytes = segs_.capacity() * sizeof(Segment) + info_.capacity() * sizeof(SegInfo) +
                 runs_.capacity() * sizeof(RunInfo);
  for (const RunInfo& run : runs_) bytes += run.marks.capacity() * sizeof(PieceMark);
  for (const Segment& s : segs_) {
    if (s.chunk_velocities) bytes += s.chunk_velocities->HeapBytes();
  }
  return bytes;
}

}  // namespace moco::sim
