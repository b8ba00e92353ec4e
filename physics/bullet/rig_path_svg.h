// A plot of the camera head's path, commanded against physical, as SVG: top
// view (x east-west, y along the track) and side view (y, z up) in the world
// frame of docs/rig-dynamics.md "Frames". Pure text, no I/O.
#ifndef MOCO_PHYSICS_BULLET_RIG_PATH_SVG_H_
#define MOCO_PHYSICS_BULLET_RIG_PATH_SVG_H_

#include <string>
#include <string_view>
#include <vector>

#include "physics/bullet/rig_dynamics.h"

namespace moco::physics {

// One sample of the nodal point: where the command puts it (ideal kinematics)
// and where the simulated rig has it.
struct RigPathSample {
  double time_s = 0;
  Point3 commanded_m = {0, 0, 0};
  Point3 physical_m = {0, 0, 0};
};

// A standalone SVG document with two panels (top view, side view), each with
// axes, tick labels in metres, axis titles, and two paths: commanded (dashed)
// and physical (solid), with ids "top-commanded", "top-physical",
// "side-commanded", "side-physical". Equal scale on both axes of a panel.
// Long paths are thinned to at most 2000 points each; non-finite points and
// points beyond 1e6 are left out. Any `samples`
// (including none) give a well-formed document; `title` is escaped.
std::string RigPathSvg(const std::vector<RigPathSample>& samples,
                       std::string_view title = "camera head path");

}  // namespace moco::physics

#endif  // MOCO_PHYSICS_BULLET_RIG_PATH_SVG_H_
