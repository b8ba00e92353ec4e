// Writes docs/rig-path-example.svg (docs/rig-dynamics.md "Plots"): the
// boom-jib fixture running a combined track, swing, boom and pan move, the
// nodal point commanded (ideal kinematics) against simulated.
// Usage: rig_path_example <profile.json> <output.svg>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <vector>

#include "physics/bullet/rig_dynamics.h"
#include "physics/bullet/rig_path_svg.h"

namespace {

// Smooth rest-to-rest blend over [0, 1] (cosine ramp).
double Blend(double u) {
  if (u <= 0) return 0;
  if (u >= 1) return 1;
  return 0.5 - 0.5 * std::cos(3.14159265358979323846 * u);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace moco::physics;
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s <profile.json> <output.svg>\n", argv[0]);
    return 2;
  }
  const RigProfileResult profile = ReadRigProfile(argv[1]);
  if (!profile.ok()) {
    std::fprintf(stderr, "%s\n", profile.error().message.c_str());
    return 1;
  }
  const RigProfile& p = profile.value();
  BoomRigDynamics rig(p);
  constexpr double kDeg = 3.14159265358979323846 / 180;
  const JointVector from = {0.2, -20 * kDeg, -10 * kDeg, 20 * kDeg, 0, 0};
  const JointVector to = {1.8, 35 * kDeg, 30 * kDeg, -35 * kDeg, 10 * kDeg, 0};
  rig.Reset(from);
  std::vector<RigPathSample> samples;
  constexpr double kSettleS = 0.5, kMoveS = 4.0, kEndS = 5.5;
  for (int i = 0; i * kStepS <= kEndS; ++i) {
    const double t = i * kStepS;
    const double u = Blend((t - kSettleS) / kMoveS);
    JointVector cmd{};
    for (size_t j = 0; j < kJointCount; ++j) cmd[j] = from[j] + u * (to[j] - from[j]);
    rig.Step(cmd);
    if (i % 5 == 0) samples.push_back({t, IdealNodal(p, cmd), rig.Pose().nodal_m});
  }
  std::ofstream out(argv[2]);
  out << RigPathSvg(samples, p.name + ": track, swing, boom, pan, tilt in 4 s");
  return out ? 0 : 1;
}
