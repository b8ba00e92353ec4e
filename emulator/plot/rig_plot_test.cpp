// Tests for the rig path plot of a session (rig_plot.h): the fixture
// fixtures/sessions/dmc16-boom-move.jsonl replayed into the DMC-16 of
// fixtures/profiles/dmc16-boom.json driving the boom-jib rig
// (docs/rig-dynamics.md), sampled at the asked period and window; control
// events replayed; errors as values.
#include "plot/rig_plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <variant>

#include "control/control_channel.h"
#include "devices/dmc16/dmc16.h"
#include "devices/dmc16/dmc16_profile.h"
#include "physics/bullet/rig_path_svg.h"
#include "wire/dmc.h"

namespace moco::plot {
namespace {

using physics::Joint;
using physics::Point3;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

std::string Source(const std::string& rel) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + rel;
}

const std::string kBoomProfile = Source("fixtures/profiles/dmc16-boom.json");

session::Session LoadFixture(const std::string& name) {
  auto loaded = session::LoadSession(Source("fixtures/sessions/" + name));
  if (const auto* e = std::get_if<session::SessionError>(&loaded)) {
    ADD_FAILURE() << name << ":" << e->line << ": " << e->message;
    return {};
  }
  return std::get<session::Session>(loaded);
}

physics::RigProfile BoomJib() {
  const physics::RigProfileResult r =
      physics::ReadRigProfile(Source("fixtures/rigs/boom-jib.json"));
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.value();
}

double Distance(const Point3& a, const Point3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// The joints the fixture's moves end on (boom_session_gen.cpp): steps over
// steps per unit of boom-jib.json (3200 microsteps x gear ratio per metre or
// per revolution).
physics::JointVector FixtureTargets() {
  const double track_steps_per_m = 3200.0 * 50;
  const double swing_steps_per_deg = 3200.0 * 90 / 360;
  const double head_steps_per_deg = 3200.0 * 100 / 360;  // boom, pan, tilt
  return {64000 / track_steps_per_m,         -24000 / swing_steps_per_deg * kDeg,
          13333 / head_steps_per_deg * kDeg, -35556 / head_steps_per_deg * kDeg,
          8889 / head_steps_per_deg * kDeg,  0};
}

RigPlot PlotOk(const session::Session& s, const RigPlotOptions& o = {}) {
  const RigPlotResult r = PlotSession(s, kBoomProfile, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? r.value() : RigPlot{};
}

TEST(RigPlot, SamplesComeAtTheAskedPeriodFromPowerOnUntilTheRigRests) {
  const session::Session s = LoadFixture("dmc16-boom-move.jsonl");
  RigPlotOptions o;
  o.period_ns = 20 * sim::kNsPerMs;
  const RigPlot plot = PlotOk(s, o);
  ASSERT_GT(plot.samples.size(), 10u);
  for (size_t k = 0; k < plot.samples.size(); ++k) {
    ASSERT_NEAR(plot.samples[k].time_s, 0.02 * static_cast<double>(k), 1e-9) << k;
  }
  EXPECT_EQ(plot.summary.sample_count, plot.samples.size());
  EXPECT_DOUBLE_EQ(plot.summary.start_s, 0);
  // Past the last entry (6.0 s status reply), at most the 2 s settle tail.
  const double last_entry_s = static_cast<double>(s.entries.back().t_ns) / 1e9;
  EXPECT_GE(plot.summary.duration_s, last_entry_s - 0.02);
  EXPECT_LE(plot.summary.duration_s, last_entry_s + 2.0 + 1e-9);
  // Every host frame of the session was fed (one frame per chunk here).
  size_t host_chunks = 0;
  for (const auto& e : s.entries) host_chunks += !e.is_event && e.from == session::Origin::kHost;
  EXPECT_EQ(plot.summary.host_chunks, host_chunks);
  EXPECT_EQ(plot.summary.host_messages, host_chunks);
  EXPECT_GT(plot.summary.device_bytes, 0u);
  EXPECT_TRUE(plot.summary.warnings.empty());
}

TEST(RigPlot, TheCommandedPathMovesToTheIdealNodalPointOfTheTargets) {
  const physics::RigProfile rig = BoomJib();
  const RigPlot plot = PlotOk(LoadFixture("dmc16-boom-move.jsonl"));
  ASSERT_FALSE(plot.samples.empty());
  const Point3 home = physics::IdealNodal(rig, {0, 0, 0, 0, 0, 0});
  const Point3 end = physics::IdealNodal(rig, FixtureTargets());
  EXPECT_LT(Distance(plot.samples.front().commanded_m, home), 1e-9);
  // The track alone moves 0.4 m; swing and boom add to it.
  EXPECT_GT(Distance(home, end), 0.4);
  EXPECT_LT(Distance(plot.samples.back().commanded_m, end), 1e-3);
  // Before the move starts (0.5 s) the command is at home; half way it is
  // neither at home nor at the end.
  const physics::RigPathSample& mid = plot.samples[300];  // 3.0 s
  EXPECT_NEAR(mid.time_s, 3.0, 1e-9);
  EXPECT_GT(Distance(mid.commanded_m, home), 0.1);
  EXPECT_GT(Distance(mid.commanded_m, end), 0.1);
}

TEST(RigPlot, ThePhysicalPathFollowsWithinTheBoomSag) {
  const physics::RigProfile p = BoomJib();
  const RigPlot plot = PlotOk(LoadFixture("dmc16-boom-move.jsonl"));
  ASSERT_FALSE(plot.samples.empty());
  // Statics (as in rig_dynamics_test): the boom's weight at its COM and the
  // head's at the tip against the boom drive's stiffness; the levelled head
  // drops with the tip, about sag x boom length.
  const double head_kg = p.extension.mass_kg + p.pan.mass_kg + p.tilt.mass_kg + p.camera.mass_kg;
  const double boom_rad = FixtureTargets()[physics::Index(Joint::kBoom)];
  const double sag_rad = p.gravity_m_s2 * std::cos(boom_rad) *
                         (p.boom.mass_kg * p.boom.com_m[1] + head_kg * p.boom_length_m) /
                         p.joint(Joint::kBoom).kp;
  const double sag_mm = sag_rad * p.boom_length_m * 1e3;
  const RigPlotSummary& sum = plot.summary;
  // At rest at the end the deviation is the static sag.
  EXPECT_NEAR(sum.final_deviation_mm, sag_mm, 0.1 * sag_mm);
  // While moving it lags a little more, but stays within 5 cm.
  EXPECT_GE(sum.peak_deviation_mm, sum.final_deviation_mm);
  EXPECT_GT(sum.peak_deviation_mm, 0);
  EXPECT_LT(sum.peak_deviation_mm, 50);
  EXPECT_LT(sum.peak_deviation_mm, 2.5 * sag_mm);
  // The fixture's speeds stay inside every motor's pull-out torque, and the
  // head clears the floor and the light stand.
  for (size_t j = 0; j < physics::kJointCount; ++j) EXPECT_EQ(sum.lost_steps[j], 0) << j;
  EXPECT_EQ(sum.collisions, 0);
  // The peak is a sample's deviation at its time.
  bool found = false;
  for (const auto& s : plot.samples) {
    if (s.time_s == sum.peak_time_s) {
      found = true;
      EXPECT_NEAR(Distance(s.commanded_m, s.physical_m) * 1e3, sum.peak_deviation_mm, 1e-9);
    }
  }
  EXPECT_TRUE(found);
}

// A DMC session of host requests, one every 10 ms from 0.1 s.
session::Session HostSession(const std::vector<dmc::HostMessage>& requests) {
  session::Session s;
  s.header.protocol = wire::Protocol::kDmc;
  uint32_t id = 1;
  sim::TimeNs t_ns = 100 * sim::kNsPerMs;
  for (const dmc::HostMessage& m : requests) {
    session::SessionEntry e;
    e.t_ns = t_ns;
    e.from = session::Origin::kHost;
    e.bytes = dmc::Encode(id++, m);
    s.entries.push_back(std::move(e));
    t_ns += 10 * sim::kNsPerMs;
  }
  return s;
}

TEST(RigPlot, AMoveBeyondThePullOutTorqueShowsLostSteps) {
  // Track motor 1 at 2e6 steps/s^2 (12.5 m/s^2) up to 1e5 steps/s (31 rev/s
  // at the motor): the cart's ~60 kg need ~750 N, more than the 0.4-0.8 N m
  // pull-out torque above 10 rev/s gives through 50 rev/m (250-500 N), so
  // the motor slips (behind while speeding up, ahead while braking).
  RigPlotOptions o;
  o.tail_s = 5;
  const RigPlot plot =
      PlotOk(HostSession({dmc::MotorSetSpeed{1, 100000, 2000000}, dmc::MotorMove{1, 80000}}), o);
  const int64_t track_lost = plot.summary.lost_steps[physics::Index(Joint::kTrack)];
  EXPECT_NE(track_lost, 0);
  EXPECT_LE(std::llabs(track_lost), 80000);
  for (Joint j : {Joint::kSwing, Joint::kBoom, Joint::kPan, Joint::kTilt, Joint::kRoll}) {
    EXPECT_EQ(plot.summary.lost_steps[physics::Index(j)], 0);
  }
  // Lost steps stay lost: at rest the head is off its commanded point by
  // about the lost travel (160 steps per mm), give or take the boom sag.
  const double lost_mm = static_cast<double>(std::llabs(track_lost)) / 160.0;
  EXPECT_NEAR(plot.summary.final_deviation_mm, std::hypot(lost_mm, 17.0), 5.0);
}

TEST(RigPlot, DrivingTheHeadIntoTheFloorCountsACollision) {
  // Boom motor 3 to -59 deg (888.9 steps/deg): the head box reaches below the
  // floor at z = -1.4 m (1.5 m x sin 59 deg = 1.29 m, plus the box's 0.2 m).
  RigPlotOptions o;
  o.tail_s = 10;  // the move takes 6.2 s
  const RigPlot plot =
      PlotOk(HostSession({dmc::MotorSetSpeed{3, 10000, 10000}, dmc::MotorMove{3, -52444}}), o);
  EXPECT_GE(plot.summary.collisions, 1);
  // The e-stop chain halted the boom short of its target.
  const physics::RigProfile rig = BoomJib();
  physics::JointVector target{};
  target[physics::Index(Joint::kBoom)] = -52444 / (3200.0 * 100 / 360) * kDeg;
  EXPECT_GT(Distance(plot.samples.back().commanded_m, physics::IdealNodal(rig, target)), 0.01);
}

TEST(RigPlot, TheWindowRestrictsTheSampleTimes) {
  const session::Session s = LoadFixture("dmc16-boom-move.jsonl");
  const RigPlot full = PlotOk(s);
  RigPlotOptions o;
  o.from_s = 1.0;
  o.to_s = 2.0;
  const RigPlot window = PlotOk(s, o);
  ASSERT_EQ(window.samples.size(), 101u);  // 1.00, 1.01, ..., 2.00
  EXPECT_NEAR(window.samples.front().time_s, 1.0, 1e-9);
  EXPECT_NEAR(window.samples.back().time_s, 2.0, 1e-9);
  EXPECT_NEAR(window.summary.duration_s, 1.0, 1e-9);
  // The same replay: the window's samples are those of the full plot.
  for (const auto& w : window.samples) {
    const auto& f = full.samples[static_cast<size_t>(std::llround(w.time_s * 100))];
    EXPECT_EQ(w.time_s, f.time_s);
    EXPECT_EQ(w.commanded_m, f.commanded_m);
    EXPECT_EQ(w.physical_m, f.physical_m);
  }
  // A tail of 0 ends at the last entry.
  RigPlotOptions no_tail;
  no_tail.tail_s = 0;
  const RigPlot short_plot = PlotOk(s, no_tail);
  EXPECT_LE(short_plot.samples.back().time_s, static_cast<double>(s.entries.back().t_ns) / 1e9);
}

TEST(RigPlot, AnEmptyWindowIsNamed) {
  const session::Session s = LoadFixture("dmc16-boom-move.jsonl");
  RigPlotOptions o;
  o.from_s = 3.0;
  o.to_s = 2.0;
  RigPlotResult r = PlotSession(s, kBoomProfile, o);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kEmptyWindow);
  o.to_s.reset();
  o.from_s = 100.0;  // long after the rig came to rest
  r = PlotSession(s, kBoomProfile, o);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kEmptyWindow);
  EXPECT_NE(r.error().message.find("ends at"), std::string::npos) << r.error().message;
  RigPlotOptions bad;
  bad.period_ns = 0;
  r = PlotSession(s, kBoomProfile, bad);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kBadOptions);
  // 8 s at 1 ns: far too many samples, refused before any is taken.
  bad.period_ns = 1;
  r = PlotSession(s, kBoomProfile, bad);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kBadOptions);
  EXPECT_NE(r.error().message.find("sample period"), std::string::npos) << r.error().message;
}

TEST(RigPlot, AProfileWithoutAPhysicalRigIsNamedWithTheFix) {
  const std::string plain = Source("fixtures/profiles/dmc16.json");
  const RigPlotResult r = PlotSession(LoadFixture("dmc16-boom-move.jsonl"), plain);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kNoPhysicalRig);
  const std::string& m = r.error().message;
  EXPECT_NE(m.find(plain), std::string::npos) << m;
  EXPECT_NE(m.find("\"physical_rig\""), std::string::npos) << m;
  EXPECT_NE(m.find("docs/profiles.md"), std::string::npos) << m;
  EXPECT_NE(m.find("fixtures/profiles/dmc16-boom.json"), std::string::npos) << m;
}

TEST(RigPlot, AnUnreadableOrForeignProfileIsABadProfile) {
  const session::Session s = LoadFixture("dmc16-boom-move.jsonl");
  RigPlotResult r = PlotSession(s, "/nonexistent/profile.json");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kBadProfile);
  EXPECT_NE(r.error().message.find("/nonexistent/profile.json"), std::string::npos);
  r = PlotSession(s, Source("fixtures/profiles/dfmoco-uno.json"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kBadProfile);
  // The ProfileError text: the file and the field.
  EXPECT_NE(r.error().message.find("dfmoco-uno.json"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("field"), std::string::npos) << r.error().message;
}

TEST(RigPlot, ANonDmcSessionIsNamed) {
  const RigPlotResult r = PlotSession(LoadFixture("dfmoco-uno-workflow.jsonl"), kBoomProfile);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, RigPlotError::Kind::kNotDmc);
  EXPECT_NE(r.error().message.find("dfmoco"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("dmc"), std::string::npos);
}

// The fixture with one event line inserted at `t_s`, in time order.
session::Session WithEvent(session::Session s, double t_s, nlohmann::json line) {
  session::SessionEntry e;
  e.t_ns = static_cast<sim::TimeNs>(t_s * 1e9);
  e.is_event = true;
  line["t_ns"] = e.t_ns;
  e.event = std::move(line);
  size_t i = 0;
  while (i < s.entries.size() && s.entries[i].t_ns <= e.t_ns) ++i;
  s.entries.insert(s.entries.begin() + static_cast<std::ptrdiff_t>(i), std::move(e));
  return s;
}

const nlohmann::json kEStop = {
    {"event", "estop"}, {"engaged", true}, {"source", "control"}, {"ok", true}};

// A sink that keeps nothing (the recording below keeps only host bytes and
// device events).
class DropSink final : public devices::ByteSink {
 public:
  void Write(wire::ByteView) override {}
};

TEST(RigPlot, AReplayReproducesTheRecordedStallsAndCollisions) {
  // The track driven beyond its pull-out torque, then the boom into the floor.
  session::Session s =
      HostSession({dmc::MotorSetSpeed{1, 100000, 2000000}, dmc::MotorMove{1, 80000},
                   dmc::MotorSetSpeed{3, 10000, 10000}, dmc::MotorMove{3, -52444}});
  // Record as mocosim does: the device events go into the session.
  {
    sim::Scheduler scheduler;
    DropSink sink;
    devices::Dmc16 device(scheduler, sink,
                          devices::LoadDmc16Profile(Source("fixtures/profiles/dmc16-boom.json")));
    control::ControlChannel channel(scheduler);
    channel.AddDevice("dmc16", device);
    std::vector<session::SessionEntry> events;
    channel.SetDeviceEventListener(
        [&](const control::DeviceEvent& e) { events.push_back(e.ToSessionEntry()); });
    device.PowerOn();
    for (const session::SessionEntry& e : std::vector(s.entries)) {
      scheduler.RunUntil(e.t_ns);
      device.OnHostBytes(e.bytes);
    }
    scheduler.RunUntil(12 * sim::kNsPerSecond);
    ASSERT_FALSE(events.empty());
    for (session::SessionEntry& e : events) s.entries.push_back(std::move(e));
    std::stable_sort(s.entries.begin(), s.entries.end(),
                     [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });
  }
  RigPlotOptions o;
  o.tail_s = 12;
  const RigPlot plot = PlotOk(s, o);
  const auto& recorded = plot.summary.recorded_device_events;
  EXPECT_GE(recorded.count("stall"), 1u);
  EXPECT_EQ(recorded.at("collision"), 1u);
  EXPECT_EQ(plot.summary.replayed_device_events, recorded);
  // A recording that does not match the replay shows as a difference.
  const RigPlot other =
      PlotOk(WithEvent(s, 0.05, {{"event", "stall"}, {"joint", "pan"}, {"source", "device"}}), o);
  EXPECT_EQ(other.summary.recorded_device_events.at("stall"), recorded.at("stall") + 1);
  EXPECT_NE(other.summary.replayed_device_events, other.summary.recorded_device_events);
}

TEST(RigPlot, ARecordedEStopStopsTheCommandedPath) {
  const session::Session plain = LoadFixture("dmc16-boom-move.jsonl");
  const RigPlot moving = PlotOk(plain);
  const RigPlot stopped = PlotOk(WithEvent(plain, 2.0, kEStop));
  EXPECT_EQ(stopped.summary.control_events_applied, 1u);
  ASSERT_GT(moving.samples.size(), 400u);
  ASSERT_GT(stopped.samples.size(), 210u);
  // Without the event the command keeps moving after 2 s.
  EXPECT_GT(Distance(moving.samples[201].commanded_m, moving.samples[400].commanded_m), 0.05);
  // With it every motor halts at once: the command stands still from the
  // next rig step (1 ms) on, to the end of the plot.
  for (size_t k = 201; k < stopped.samples.size(); ++k) {
    ASSERT_EQ(stopped.samples[k].commanded_m, stopped.samples.back().commanded_m) << k;
  }
  // Up to the event both plots are the same.
  for (size_t k = 0; k <= 200; ++k) {
    ASSERT_EQ(stopped.samples[k].commanded_m, moving.samples[k].commanded_m) << k;
    ASSERT_EQ(stopped.samples[k].physical_m, moving.samples[k].physical_m) << k;
  }
}

TEST(RigPlot, EventsOfOtherSourcesOrThatFailedAreNotReplayed) {
  const session::Session plain = LoadFixture("dmc16-boom-move.jsonl");
  const RigPlot reference = PlotOk(plain);
  nlohmann::json from_device = kEStop;
  from_device["source"] = "device";
  nlohmann::json refused = kEStop;
  refused["ok"] = false;
  nlohmann::json link = {{"event", "link_fault"}, {"detail", "cut 2000 ms"}};
  for (const nlohmann::json& line : {from_device, refused, link}) {
    const RigPlot p = PlotOk(WithEvent(plain, 2.0, line));
    EXPECT_EQ(p.summary.control_events_applied, 0u) << line.dump();
    EXPECT_TRUE(p.summary.warnings.empty()) << line.dump();
    ASSERT_EQ(p.samples.size(), reference.samples.size()) << line.dump();
    EXPECT_EQ(p.samples.back().commanded_m, reference.samples.back().commanded_m);
  }
  // A control command that needs a link the plot does not have is reported.
  const nlohmann::json cut = {
      {"event", "cut_link"}, {"ms", 500}, {"source", "control"}, {"ok", true}};
  const RigPlot p = PlotOk(WithEvent(plain, 2.0, cut));
  EXPECT_EQ(p.summary.control_events_applied, 0u);
  ASSERT_EQ(p.summary.warnings.size(), 1u);
  EXPECT_NE(p.summary.warnings[0].find("cut_link"), std::string::npos) << p.summary.warnings[0];
}

TEST(RigPlot, TheSameInputGivesTheSameSvg) {
  const session::Session s = LoadFixture("dmc16-boom-move.jsonl");
  const std::string a = physics::RigPathSvg(PlotOk(s).samples, "boom");
  const std::string b = physics::RigPathSvg(PlotOk(s).samples, "boom");
  EXPECT_EQ(a, b);
  EXPECT_TRUE(a.rfind("<?xml", 0) == 0 || a.rfind("<svg", 0) == 0) << a.substr(0, 40);
}

}  // namespace
}  // namespace moco::plot
