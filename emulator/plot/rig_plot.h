// The camera head's path during a recorded DMC v2 session (docs/sessions.md,
// docs/rig-dynamics.md "Plots"): the session's host bytes replayed at their
// recorded times into a DMC-16 that drives the Bullet boom rig of its profile
// (docs/profiles.md `physical_rig`), the nodal point sampled commanded
// (ideal kinematics) against physical, in virtual time.
#ifndef MOCO_PLOT_RIG_PLOT_H_
#define MOCO_PLOT_RIG_PLOT_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/result.h"
#include "physics/bullet/rig_dynamics.h"
#include "physics/bullet/rig_path_svg.h"
#include "session/session.h"
#include "sim/scheduler.h"

namespace moco::plot {

struct RigPlotOptions {
  // One sample every period_ns of simulated time, at 0, period, 2 period, ...
  sim::TimeNs period_ns = 10 * sim::kNsPerMs;
  // Only samples with from_s <= time <= to_s are kept (seconds since power-on,
  // the session's t_ns / 1e9). The replay always starts at 0.
  std::optional<double> from_s;
  std::optional<double> to_s;
  // How long to keep sampling after the last entry of the session while the
  // rig settles. The plot ends earlier once, after the last entry, the rig is
  // asleep (PhysicalRig::awake() false: at rest, command unchanged) and no
  // motor moves.
  double tail_s = 2.0;
};

// What happened over the plotted samples.
struct RigPlotSummary {
  std::string rig_name;     // the rig profile's "name"
  size_t sample_count = 0;  // == samples.size()
  double start_s = 0;       // time of the first sample
  double duration_s = 0;    // last sample time - first sample time
  // |physical - commanded| nodal point, millimetres.
  double peak_deviation_mm = 0;
  double peak_time_s = 0;  // time of the (first) peak
  double final_deviation_mm = 0;
  // Whole motor steps lost per joint (physics::Joint order) and head
  // collisions counted by the device, between the first and the last sample.
  std::array<int64_t, physics::kJointCount> lost_steps{};
  int64_t collisions = 0;
  // Replayed into the device up to the last sample: host frames it decoded
  // (requests and ACKs) and host chunks fed.
  uint64_t host_messages = 0;
  size_t host_chunks = 0;
  size_t device_bytes = 0;  // what the device sent (discarded)
  // Control events re-applied to the device (source "control" or
  // "scenario" with ok true), and those that could not be applied here.
  size_t control_events_applied = 0;
  std::vector<std::string> warnings;  // one line per event that could not be applied
  // Device events ("stall", "collision"; docs/control.md "events") by kind,
  // from power-on to the last sample: those the session recorded (event
  // lines with "source":"device") and those this replay produced. They
  // differ when the session was recorded with another profile or rig.
  std::map<std::string, size_t> recorded_device_events;
  std::map<std::string, size_t> replayed_device_events;
};

struct RigPlot {
  std::vector<physics::RigPathSample> samples;  // in time order, period apart
  RigPlotSummary summary;
};

// Why there is no plot. Every message names the problem and the fix.
struct RigPlotError {
  enum class Kind {
    kNotDmc,         // the session's protocol is not "dmc"
    kBadProfile,     // the device profile cannot be read or is invalid (ProfileError text)
    kNoPhysicalRig,  // the profile has no physical_rig
    kBadOptions,     // period <= 0, negative or non-finite times, over 10^7 samples
    kEmptyWindow,    // from_s >= to_s, or no sample falls in the window
  };
  Kind kind = Kind::kBadOptions;
  std::string message;
};

// A plot, or why there is none.
using RigPlotResult = base::Result<RigPlot, RigPlotError>;

// Replays `session` into a fresh DMC-16 built from the profile file at
// `profile_path` (which must have a `physical_rig`): the device is powered on
// at t = 0, each host traffic entry is fed at its t_ns, and each event line
// whose "source" is "control" or "scenario" with "ok" true is executed again
// at its t_ns through a control::ControlChannel on the device (so a recorded
// e-stop stops the plotted rig too). Device lines are not compared, other
// events (device, link) are skipped. Deterministic: the same inputs give
// bit-identical samples. Never throws for bad input; errors are values.
RigPlotResult PlotSession(const session::Session& session, const std::string& profile_path,
                          const RigPlotOptions& options = {});

}  // namespace moco::plot

#endif  // MOCO_PLOT_RIG_PLOT_H_
