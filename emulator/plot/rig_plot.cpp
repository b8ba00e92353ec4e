// Replays a DMC v2 session into a DMC-16 driving the Bullet boom rig and
// samples the nodal point (see rig_plot.h).
#include "plot/rig_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <variant>

#include <nlohmann/json.hpp>

#include "control/control_channel.h"
#include "devices/device.h"
#include "devices/dmc16/dmc16.h"
#include "devices/dmc16/dmc16_profile.h"
#include "devices/profile.h"
#include "physics/bullet/physical_rig.h"

namespace moco::plot {
namespace {

using Kind = RigPlotError::Kind;
using nlohmann::json;

constexpr double kNsPerS = 1e9;
// Samples are taken (and the rig simulated) from t = 0 to the plot's end:
// beyond this many the period is too short for the session's length.
constexpr int64_t kMaxSamples = 10'000'000;

// Device output is not compared (a replay's business); only counted.
class CountingSink final : public devices::ByteSink {
 public:
  void Write(wire::ByteView bytes) override { bytes_ += bytes.size(); }
  size_t bytes() const { return bytes_; }

 private:
  size_t bytes_ = 0;
};

std::string Seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f s", s);
  return buf;
}

double Distance(const physics::Point3& a, const physics::Point3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Whether an event line is a control command that took effect when recorded
// (docs/sessions.md; ControlEvent::SessionLine): source "control" or
// "scenario" and ok true. Device and link events are not commands.
bool IsReplayedEvent(const json& line) {
  const auto source = line.find("source");
  if (source == line.end() || !source->is_string()) return false;
  const std::string& s = source->get_ref<const std::string&>();
  if (s != "control" && s != "scenario") return false;
  const auto ok = line.find("ok");
  return ok != line.end() && ok->is_boolean() && ok->get<bool>();
}

// The command of a replayed event line, or why it does not parse. The
// device name is dropped: here the one device answers every command.
std::variant<control::Command, std::string> EventCommand(const json& line) {
  json request = line;
  request["cmd"] = line["event"];
  for (const char* key : {"event", "device", "id"}) request.erase(key);
  return control::ParseCommand(request, {"t_ns", "source", "index", "ok", "error"});
}

// Lost steps summed over every physical rig the device had (a power cycle
// builds a new one, starting from none lost).
class LostStepCounter {
 public:
  std::array<int64_t, physics::kJointCount> Total(const physics::PhysicalRig& rig) {
    if (&rig != rig_ || rig.steps_taken() < steps_taken_) {
      for (size_t j = 0; j < physics::kJointCount; ++j) base_[j] += last_[j];
      last_ = {};
      rig_ = &rig;
    }
    steps_taken_ = rig.steps_taken();
    last_ = rig.dynamics().LostSteps();
    std::array<int64_t, physics::kJointCount> total{};
    for (size_t j = 0; j < physics::kJointCount; ++j) total[j] = base_[j] + last_[j];
    return total;
  }

 private:
  const physics::PhysicalRig* rig_ = nullptr;
  int64_t steps_taken_ = 0;
  std::array<int64_t, physics::kJointCount> base_{};
  std::array<int64_t, physics::kJointCount> last_{};
};

std::optional<RigPlotError> CheckOptions(const RigPlotOptions& o) {
  if (o.period_ns <= 0) {
    return RigPlotError{Kind::kBadOptions, "the sample period must be positive (e.g. 10 ms), not " +
                                               std::to_string(o.period_ns) + " ns"};
  }
  if (!std::isfinite(o.tail_s) || o.tail_s < 0 || o.tail_s > 3600) {
    return RigPlotError{Kind::kBadOptions, "the settle tail must be 0..3600 s (default 2 s), not " +
                                               std::to_string(o.tail_s)};
  }
  for (const auto& [name, v] : {std::pair{"from", o.from_s}, std::pair{"to", o.to_s}}) {
    if (v && (!std::isfinite(*v) || *v < 0 || *v > 1e6)) {
      return RigPlotError{Kind::kBadOptions, std::string("the window's ") + name +
                                                 " time must be 0..1e6 s, not " +
                                                 std::to_string(*v)};
    }
  }
  if (o.from_s && o.to_s && *o.from_s >= *o.to_s) {
    return RigPlotError{Kind::kEmptyWindow, "the window " + Seconds(*o.from_s) + " .. " +
                                                Seconds(*o.to_s) +
                                                " is empty: give a from time before the to time"};
  }
  return std::nullopt;
}

// Replays one session entry into `device`: host bytes are fed to it, a
// recorded control event (e-stop, limits) is applied again through `channel`,
// the device's own recorded events are counted; what could not be applied is
// a warning in `sum`.
void ApplyEntry(const session::SessionEntry& e, devices::Dmc16& device,
                control::ControlChannel& channel, RigPlotSummary& sum) {
  if (!e.is_event) {
    if (e.from != session::Origin::kHost) return;
    ++sum.host_chunks;
    device.OnHostBytes(e.bytes);
    return;
  }
  if (e.event.value("source", std::string()) == "device") {
    ++sum.recorded_device_events[e.event.value("event", std::string("?"))];
    return;
  }
  if (!IsReplayedEvent(e.event)) return;
  const std::string at = "event at " + Seconds(static_cast<double>(e.t_ns) / kNsPerS);
  auto parsed = EventCommand(e.event);
  if (const auto* why = std::get_if<std::string>(&parsed)) {
    sum.warnings.push_back(at + " not applied: " + *why);
    return;
  }
  const control::Command& command = std::get<control::Command>(parsed);
  if (!control::IsAction(command.body)) return;
  if (auto why = channel.Check(command)) {
    sum.warnings.push_back(at + " (" + std::string(control::CommandName(command.body)) +
                           ") not applied: " + *why);
    return;
  }
  const json reply = channel.Execute(command, "replay");
  if (reply.value("ok", false)) {
    ++sum.control_events_applied;
  } else {
    sum.warnings.push_back(at + " (" + std::string(control::CommandName(command.body)) +
                           ") failed: " + reply.value("error", std::string("no reason given")));
  }
}

}  // namespace

RigPlotResult PlotSession(const session::Session& session, const std::string& profile_path,
                          const RigPlotOptions& options) {
  if (session.header.protocol != wire::Protocol::kDmc) {
    return RigPlotError{Kind::kNotDmc,
                        "the session is " + std::string(ProtocolName(session.header.protocol)) +
                            " traffic; a rig plot replays DMC v2 sessions (header \"protocol\": "
                            "\"dmc\") into a DMC-16 with a physical rig"};
  }
  if (auto error = CheckOptions(options)) return *error;

  devices::Dmc16Profile profile;
  try {
    profile = devices::LoadDmc16Profile(profile_path);
  } catch (const std::exception& e) {
    return RigPlotError{Kind::kBadProfile, e.what()};
  }
  if (!profile.physical_rig.enabled) {
    return RigPlotError{
        Kind::kNoPhysicalRig,
        "profile " + profile_path +
            " has no physical_rig: a rig plot needs the Bullet-modelled rig the motors drive; "
            "add a \"physical_rig\" field naming a rig profile and the motor of each joint "
            "(docs/profiles.md \"physical_rig\"; example: fixtures/profiles/dmc16-boom.json)"};
  }

  sim::Scheduler scheduler;
  CountingSink sink;
  devices::Dmc16 device(scheduler, sink, std::move(profile));
  control::ControlChannel channel(scheduler);
  channel.AddDevice("dmc16", device);
  std::map<std::string, size_t> replayed_events;
  channel.SetDeviceEventListener([&](const control::DeviceEvent& e) {
    ++replayed_events[e.event.value("event", std::string("?"))];
  });
  device.PowerOn();

  const std::vector<session::SessionEntry>& entries = session.entries;
  const sim::TimeNs last_entry_ns = entries.empty() ? 0 : entries.back().t_ns;
  const sim::TimeNs tail_ns = static_cast<sim::TimeNs>(options.tail_s * kNsPerS);
  sim::TimeNs end_ns =
      last_entry_ns > sim::kTimeNever - tail_ns ? sim::kTimeNever : last_entry_ns + tail_ns;
  if (options.to_s) end_ns = std::min(end_ns, static_cast<sim::TimeNs>(*options.to_s * kNsPerS));
  const sim::TimeNs from_ns =
      options.from_s ? static_cast<sim::TimeNs>(std::ceil(*options.from_s * kNsPerS)) : 0;
  if (end_ns / options.period_ns > kMaxSamples) {
    return RigPlotError{Kind::kBadOptions,
                        "the plot would take more than " + std::to_string(kMaxSamples) +
                            " samples (up to " + Seconds(static_cast<double>(end_ns) / kNsPerS) +
                            " every " + std::to_string(options.period_ns) +
                            " ns); give a longer sample period or an earlier end time"};
  }

  RigPlot plot;
  RigPlotSummary& sum = plot.summary;
  LostStepCounter lost;
  std::array<int64_t, physics::kJointCount> lost_at_start{};
  uint64_t collisions_at_start = 0;
  size_t next = 0;

  for (int64_t k = 0;; ++k) {
    const sim::TimeNs t_ns = k * options.period_ns;
    if (t_ns > end_ns) break;
    while (next < entries.size() && entries[next].t_ns <= t_ns) {
      scheduler.RunUntil(entries[next].t_ns);
      ApplyEntry(entries[next], device, channel, sum);
      ++next;
    }
    scheduler.RunUntil(t_ns);
    const physics::PhysicalRig* rig = device.physical_rig();
    if (rig == nullptr) break;  // not reached: the profile enables it
    const auto lost_now = lost.Total(*rig);
    if (t_ns >= from_ns) {
      const physics::BoomRigDynamics& dyn = rig->dynamics();
      physics::RigPathSample s;
      s.time_s = static_cast<double>(t_ns) / kNsPerS;
      s.commanded_m = physics::IdealNodal(dyn.profile(), dyn.CommandedJoints());
      s.physical_m = dyn.Pose().nodal_m;
      if (plot.samples.empty()) {
        lost_at_start = lost_now;
        collisions_at_start = device.stats().collisions;
        sum.rig_name = dyn.profile().name;
      }
      const double dev_mm = Distance(s.commanded_m, s.physical_m) * 1e3;
      if (plot.samples.empty() || dev_mm > sum.peak_deviation_mm) {
        sum.peak_deviation_mm = dev_mm;
        sum.peak_time_s = s.time_s;
      }
      sum.final_deviation_mm = dev_mm;
      for (size_t j = 0; j < physics::kJointCount; ++j) {
        sum.lost_steps[j] = lost_now[j] - lost_at_start[j];
      }
      sum.collisions = static_cast<int64_t>(device.stats().collisions - collisions_at_start);
      sum.replayed_device_events = replayed_events;
      plot.samples.push_back(s);
    }
    if (next == entries.size() && !rig->awake()) {
      bool moving = false;
      const sim::Rig& motors = device.rig_ref();
      for (int m = 1; m <= motors.motor_count(); ++m) moving = moving || motors.motor(m).IsMoving();
      if (!moving) break;  // at rest and nothing left to replay
    }
  }

  if (plot.samples.empty()) {
    const double end_s = static_cast<double>(scheduler.Now()) / kNsPerS;
    return RigPlotError{Kind::kEmptyWindow,
                        "no sample falls in the window from " +
                            Seconds(options.from_s.value_or(0)) +
                            ": the plot of this session ends at " + Seconds(end_s) +
                            " (the last entry plus the settle tail, or earlier once the rig is "
                            "at rest); give an earlier from time or a longer settle tail"};
  }
  sum.sample_count = plot.samples.size();
  sum.start_s = plot.samples.front().time_s;
  sum.duration_s = plot.samples.back().time_s - sum.start_s;
  sum.host_messages = device.stats().requests + device.stats().host_acks;
  sum.device_bytes = sink.bytes();
  return plot;
}

}  // namespace moco::plot
