// Solves per second of the rig kinematics (physics/kinematics.h): forward and
// inverse for a boom-swing-track rig with a nodal offset, with and without the
// boom compensation table and the aim point.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "physics/kinematics.h"

namespace moco::physics {
namespace {

constexpr int kPoses = 1024;

RigGeometry Geometry(bool table) {
  RigGeometry g;
  g.type = RigType::kBoomSwingTrack;
  g.boom_length = 2.5;
  g.boom_ext = 0.4;
  g.nodal_offset = {0.02, 0.12, 0.08};
  if (table) {
    std::array<double, CompensationTable::kEntries> t{};
    for (size_t i = 0; i < t.size(); ++i) {
      const double deg = static_cast<double>(i) - 60;
      t[i] = (deg + deg * deg * deg / 14400.0) * std::numbers::pi / 180;
    }
    g.compensation = *CompensationTable::Make(t);
  }
  return g;
}

// Joint poses spread over the workspace (deterministic).
std::vector<JointPose> Poses() {
  std::vector<JointPose> out;
  for (int i = 0; i < kPoses; ++i) {
    const double u = i / static_cast<double>(kPoses);
    out.push_back({4 * u - 2, 1.2 * std::sin(7 * u), 0.9 * std::cos(5 * u), 2 * u - 1,
                   0.5 * std::sin(3 * u), 0.1 * u});
  }
  return out;
}

void Run(benchmark::State& state, bool inverse, bool table, bool aim) {
  const RigGeometry g = Geometry(table);
  const std::optional<Vec3> aim_point = aim ? std::optional<Vec3>(Vec3{0.5, 6, 0.2}) : std::nullopt;
  const std::vector<JointPose> joints = Poses();
  std::vector<VirtualPose> targets;
  for (const JointPose& q : joints) targets.push_back(*Forward(g, q, aim_point));
  size_t i = 0;
  for (auto _ : state) {
    if (inverse) {
      benchmark::DoNotOptimize(Inverse(g, targets[i], aim_point));
    } else {
      benchmark::DoNotOptimize(Forward(g, joints[i], aim_point));
    }
    i = (i + 1) % joints.size();
  }
  state.counters["solves_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Forward(benchmark::State& s) { Run(s, false, false, false); }
void BM_Inverse(benchmark::State& s) { Run(s, true, false, false); }
void BM_ForwardTable(benchmark::State& s) { Run(s, false, true, false); }
void BM_InverseTable(benchmark::State& s) { Run(s, true, true, false); }
void BM_ForwardAim(benchmark::State& s) { Run(s, false, false, true); }
void BM_InverseAim(benchmark::State& s) { Run(s, true, false, true); }
BENCHMARK(BM_Forward);
BENCHMARK(BM_Inverse);
BENCHMARK(BM_ForwardTable);
BENCHMARK(BM_InverseTable);
BENCHMARK(BM_ForwardAim);
BENCHMARK(BM_InverseAim);

}  // namespace
}  // namespace moco::physics
