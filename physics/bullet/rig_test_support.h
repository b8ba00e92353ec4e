// Test support for the boom rig dynamics: the fixture profile and smooth
// commanded moves (constant-acceleration trapezoids, as a DMC-16 plans them).
#ifndef MOCO_PHYSICS_BULLET_RIG_TEST_SUPPORT_H_
#define MOCO_PHYSICS_BULLET_RIG_TEST_SUPPORT_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "physics/bullet/rig_dynamics.h"

namespace moco::physics::test_support {

inline std::string SourcePath(const std::string& relative) {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  return dir != nullptr ? std::string(dir) + "/" + relative : relative;
}

inline RigProfile BoomJib() {
  const RigProfileResult r = ReadRigProfile(SourcePath("fixtures/rigs/boom-jib.json"));
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? r.value() : RigProfile{};
}

// Position at time t_s of a rest-to-rest move from x0 to x1 with peak speed
// v and acceleration a (triangular when the distance is short).
struct Trapezoid {
  double x0, x1, v, a;
  double Duration() const {
    const double d = std::abs(x1 - x0);
    const double t_acc = v / a;
    if (d <= v * t_acc) return 2 * std::sqrt(d / a);
    return 2 * t_acc + (d - v * t_acc) / v;
  }
  double At(double t_s) const {
    const double d = std::abs(x1 - x0);
    const double sign = x1 >= x0 ? 1.0 : -1.0;
    const double total = Duration();
    const double t = std::clamp(t_s, 0.0, total);
    const double peak = std::min(v, std::sqrt(d * a));
    const double t_acc = peak / a;
    double s;
    if (t < t_acc) {
      s = 0.5 * a * t * t;
    } else if (t > total - t_acc) {
      const double r = total - t;
      s = d - 0.5 * a * r * r;
    } else {
      s = 0.5 * a * t_acc * t_acc + peak * (t - t_acc);
    }
    return x0 + sign * s;
  }
};

inline constexpr double kDeg = 3.14159265358979323846 / 180.0;

}  // namespace moco::physics::test_support

#endif  // MOCO_PHYSICS_BULLET_RIG_TEST_SUPPORT_H_
