#include "physics/bullet/rig_dynamics.h"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>

namespace moco::physics {
namespace {
RigProfile Load() {
  auto r = ReadRigProfile("fixtures/rigs/boom-jib.json");
  if (!r.ok()) {
    std::printf("%s\n", r.error().message.c_str());
  }
  EXPECT_TRUE(r.ok());
  return r.value();
}
TEST(Explore, Basics) {
  RigProfile p = Load();
  BoomRigDynamics d(p);
  JointVector cmd{0, 0.3, 0.2, 0.1, 0.1, 0.05};
  d.Reset(cmd);
  for (int i = 0; i < 3000; ++i) {
    d.Step(cmd);
    if (i % 300 == 0) {
      auto e = d.FollowingError();
      auto pose = d.Pose();
      auto ideal = IdealNodal(p, d.PhysicalJoints());
      std::printf("t=%d fe=%g %g %g %g %g %g nodal=%g %g %g ideal=%g %g %g\n", i, e[0], e[1], e[2],
                  e[3], e[4], e[5], pose.nodal_m[0], pose.nodal_m[1], pose.nodal_m[2], ideal[0],
                  ideal[1], ideal[2]);
    }
  }
  std::printf("sag predicted %g\n", BoomSagRad(p, 0.2));
}
}  // namespace
}  // namespace moco::physics
