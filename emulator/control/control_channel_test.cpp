// Tests for the control channel (control_channel.h, docs/control.md) in
// virtual time: each command's effect on the rig, GIO, power and link, the
// limit binding with the 0x80 swap (dmc-v2-protocol.txt MSG_MOTOR_SET_LIMITS),
// error replies, and the laws "one reply per line" and "no input crashes".
// The codec alone: command_codec_test.cpp.
#include "control/control_channel.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <memory>
#include <string>

#include "control/test_support.h"
#include "serve/link_control_adapter.h"
#include "session/session.h"
#include "transport/device_server.h"

namespace moco::control {
namespace {

using nlohmann::json;
using sim::kNsPerMs;
using testing::BareDevice;
using testing::FakeDevice;

json Reply(ControlChannel& channel, std::string_view line) {
  const std::string r = channel.Handle(line);
  EXPECT_EQ(r.find('\n'), std::string::npos) << r;
  return json::parse(r);
}

// The error text of a reply that must be an error.
std::string ErrorOf(ControlChannel& channel, std::string_view line) {
  const json r = Reply(channel, line);
  EXPECT_EQ(r["ok"], false) << line << " -> " << r.dump();
  return r.value("error", std::string());
}

bool Contains(const std::string& s, std::string_view part) {
  return s.find(part) != std::string::npos;
}

class ControlChannelTest : public ::testing::Test {
 protected:
  ControlChannelTest() {
    device_.PowerOn();
    channel_.AddDevice("rig1", device_);
  }
  sim::Scheduler scheduler_;
  FakeDevice device_{scheduler_};
  ControlChannel channel_{scheduler_};
};

// ---- e-stop -----------------------------------------------------------------

TEST_F(ControlChannelTest, EStopHaltsMotionAndRefusesMovesUntilReleased) {
  sim::Rig& rig = device_.the_rig();
  ASSERT_EQ(rig.motor(1).MoveTo(100000), sim::MoveStatus::kOk);
  scheduler_.RunUntil(50 * kNsPerMs);
  ASSERT_TRUE(rig.motor(1).IsMoving());

  json r = Reply(channel_, R"({"cmd":"estop","engaged":true})");
  EXPECT_EQ(r["ok"], true);
  EXPECT_EQ(r["was_engaged"], false);
  EXPECT_EQ(r["engaged"], true);
  EXPECT_EQ(r["t_ns"], 50 * kNsPerMs);
  EXPECT_TRUE(rig.estop_engaged());
  EXPECT_FALSE(rig.motor(1).IsMoving());
  EXPECT_EQ(rig.motor(1).MoveTo(0), sim::MoveStatus::kEStop);
  EXPECT_EQ(device_.estop_events, std::vector<bool>{true});

  r = Reply(channel_, R"({"cmd":"estop","engaged":false})");
  EXPECT_EQ(r["was_engaged"], true);
  EXPECT_FALSE(rig.estop_engaged());
  EXPECT_EQ(rig.motor(1).MoveTo(0), sim::MoveStatus::kOk);
  EXPECT_EQ(device_.estop_events, (std::vector<bool>{true, false}));
}

// ---- limit switches ---------------------------------------------------------

TEST_F(ControlChannelTest, LimitBySetAndInputForcesThatInput) {
  sim::Rig& rig = device_.the_rig();
  json r = Reply(channel_, R"({"cmd":"limit","set":2,"input":"high","active":true})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["input_active"], true);
  EXPECT_TRUE(rig.InputActive(2, sim::SwitchInput::kHigh));
  EXPECT_FALSE(rig.InputActive(2, sim::SwitchInput::kLow));
  EXPECT_FALSE(rig.InputActive(1, sim::SwitchInput::kHigh));
  Reply(channel_, R"({"cmd":"limit","set":2,"input":"high","active":false})");
  EXPECT_FALSE(rig.InputActive(2, sim::SwitchInput::kHigh));
}

TEST_F(ControlChannelTest, LimitByMotorAndEndFollowsTheBinding) {
  sim::Rig& rig = device_.the_rig();
  // Unswapped (0x01): the upper end is the set's HIGH input.
  ASSERT_EQ(rig.BindLimits(2, sim::HardLimitBinding::FromWire(0x01)), sim::MoveStatus::kOk);
  json r = Reply(channel_, R"({"cmd":"limit","motor":2,"end":"upper","active":true})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["set"], 1);
  EXPECT_EQ(r["input"], "high");
  EXPECT_EQ(r["swapped"], false);
  EXPECT_TRUE(rig.InputActive(1, sim::SwitchInput::kHigh));
  EXPECT_TRUE(rig.motor(2).SwitchTripped(sim::LimitEnd::kUpper));
  EXPECT_FALSE(rig.motor(2).SwitchTripped(sim::LimitEnd::kLower));
  Reply(channel_, R"({"cmd":"limit","motor":2,"end":"upper","active":false})");
  EXPECT_FALSE(rig.InputActive(1, sim::SwitchInput::kHigh));

  // Swapped (0x82, "flag 0x80 swaps high/low"): the upper end is set 2's LOW input.
  ASSERT_EQ(rig.BindLimits(3, sim::HardLimitBinding::FromWire(0x82)), sim::MoveStatus::kOk);
  r = Reply(channel_, R"({"cmd":"limit","motor":3,"end":"upper","active":true})");
  EXPECT_EQ(r["set"], 2);
  EXPECT_EQ(r["input"], "low");
  EXPECT_EQ(r["swapped"], true);
  EXPECT_TRUE(rig.InputActive(2, sim::SwitchInput::kLow));
  EXPECT_FALSE(rig.InputActive(2, sim::SwitchInput::kHigh));
  EXPECT_TRUE(rig.motor(3).SwitchTripped(sim::LimitEnd::kUpper));
  r = Reply(channel_, R"({"cmd":"limit","motor":3,"end":"lower","active":true})");
  EXPECT_EQ(r["input"], "high");
  EXPECT_TRUE(rig.InputActive(2, sim::SwitchInput::kHigh));
}

TEST_F(ControlChannelTest, TrippingTheLimitAheadOfAMovingMotorStopsIt) {
  sim::Rig& rig = device_.the_rig();
  ASSERT_EQ(rig.BindLimits(1, sim::HardLimitBinding::FromWire(0x81)), sim::MoveStatus::kOk);
  ASSERT_EQ(rig.motor(1).MoveTo(1000000), sim::MoveStatus::kOk);
  scheduler_.RunUntil(100 * kNsPerMs);
  ASSERT_TRUE(rig.motor(1).IsMoving());
  Reply(channel_, R"({"cmd":"limit","motor":1,"end":"upper","active":true})");
  ASSERT_EQ(device_.trips.size(), 1u);
  EXPECT_EQ(device_.trips[0].motor, 1);
  EXPECT_EQ(device_.trips[0].end, sim::LimitEnd::kUpper);
  EXPECT_EQ(device_.trips[0].set, 1);
  EXPECT_EQ(device_.trips[0].input, sim::SwitchInput::kLow);
  scheduler_.RunUntilIdle();
  EXPECT_FALSE(rig.motor(1).IsMoving());
  EXPECT_LT(rig.motor(1).Position(), 1000000);
}

TEST_F(ControlChannelTest, LimitByAMotorWithNoSetIsAClearError) {
  const std::string e =
      ErrorOf(channel_, R"({"cmd":"limit","motor":2,"end":"lower","active":true})");
  EXPECT_TRUE(Contains(e, "motor 2")) << e;
  EXPECT_TRUE(Contains(e, "no limit set")) << e;
  EXPECT_TRUE(Contains(e, "\"set\"")) << e;  // the fix: name the input by set
  EXPECT_FALSE(device_.the_rig().InputActive(1, sim::SwitchInput::kLow));
}

TEST_F(ControlChannelTest, LimitNumbersOutsideTheRigNameTheValidRange) {
  std::string e = ErrorOf(channel_, R"({"cmd":"limit","motor":4,"end":"lower","active":true})");
  EXPECT_TRUE(Contains(e, "motor 4 does not exist")) << e;
  EXPECT_TRUE(Contains(e, "1..3")) << e;
  e = ErrorOf(channel_, R"({"cmd":"limit","set":3,"input":"low","active":true})");
  EXPECT_TRUE(Contains(e, "limit set 3 does not exist")) << e;
  EXPECT_TRUE(Contains(e, "1..2")) << e;
}

// ---- GIO --------------------------------------------------------------------

TEST_F(ControlChannelTest, GioInputsAreRawLevelsTheDeviceDebounces) {
  sim::GioPort& gio = device_.the_gio();
  json r = Reply(channel_, R"({"cmd":"gio_in","bit":4,"level":true})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["raw_inputs"], 0x10u);
  EXPECT_EQ(gio.raw_inputs(), 0x10u);
  EXPECT_EQ(gio.inputs(), 0u);  // not yet debounced
  scheduler_.RunUntil(FakeDevice::kDebounceNs);
  EXPECT_EQ(gio.inputs(), 0x10u);

  r = Reply(channel_, R"({"cmd":"gio_in","bits":"0x8000ff00"})");
  EXPECT_EQ(gio.raw_inputs(), 0x8000ff00u);
  r = Reply(channel_, R"({"cmd":"gio_in","bits":4294967295})");
  EXPECT_EQ(gio.raw_inputs(), 0xffffffffu);
  r = Reply(channel_, R"({"cmd":"gio_in","bit":31,"level":false})");
  EXPECT_EQ(gio.raw_inputs(), 0x7fffffffu);
}

// ---- power ------------------------------------------------------------------

TEST_F(ControlChannelTest, InProcessPowerCycleTurnsOffNowAndOnAfterOffMs) {
  scheduler_.RunUntil(10 * kNsPerMs);
  json r = Reply(channel_, R"({"cmd":"power_cycle","off_ms":250})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["via"], "in-process");
  EXPECT_EQ(r["power_on_at_ns"], 260 * kNsPerMs);
  EXPECT_FALSE(device_.Powered());
  EXPECT_EQ(device_.power_off_ns, std::vector<sim::TimeNs>{10 * kNsPerMs});
  scheduler_.RunUntil(260 * kNsPerMs - 1);
  EXPECT_FALSE(device_.Powered());
  scheduler_.RunUntil(260 * kNsPerMs);
  EXPECT_TRUE(device_.Powered());
  EXPECT_EQ(device_.power_on_ns.back(), 260 * kNsPerMs);
}

TEST_F(ControlChannelTest, ASecondPowerCycleWhileOffRestartsTheOffTime) {
  Reply(channel_, R"({"cmd":"power_cycle","off_ms":100})");
  scheduler_.RunUntil(50 * kNsPerMs);
  Reply(channel_, R"({"cmd":"power_cycle","off_ms":100})");
  const size_t ons_before = device_.power_on_ns.size();
  scheduler_.RunUntilIdle();
  ASSERT_EQ(device_.power_on_ns.size(), ons_before + 1);  // one power-on, not two
  EXPECT_EQ(device_.power_on_ns.back(), 150 * kNsPerMs);
}

TEST_F(ControlChannelTest, DestroyingTheChannelCancelsAPendingPowerOn) {
  auto channel = std::make_unique<ControlChannel>(scheduler_);
  channel->AddDevice("d", device_);
  channel->Handle(R"({"cmd":"power_cycle","off_ms":100})");
  channel.reset();
  scheduler_.RunUntilIdle();
  EXPECT_FALSE(device_.Powered());
}

// ---- queries ----------------------------------------------------------------

TEST_F(ControlChannelTest, StateMergesDeviceStateRigGioAndTime) {
  device_.the_rig().EngageEStop();
  device_.the_gio().SetRawInput(0, true);
  ASSERT_EQ(device_.the_rig().BindLimits(2, sim::HardLimitBinding::FromWire(0x81)),
            sim::MoveStatus::kOk);
  scheduler_.RunUntil(123 * kNsPerMs);
  const json r = Reply(channel_, R"({"cmd":"state"})");
  EXPECT_EQ(r["ok"], true);
  EXPECT_EQ(r["device"], "rig1");
  EXPECT_EQ(r["model"], "fake");
  EXPECT_EQ(r["t_ns"], 123 * kNsPerMs);
  EXPECT_EQ(r["powered"], true);
  EXPECT_EQ(r["state"]["mode"], "idle");
  EXPECT_EQ(r["rig"]["estop"], true);
  EXPECT_EQ(r["rig"]["motors"].size(), 3u);
  EXPECT_EQ(r["rig"]["motors"][1]["limit_set"], 1);
  EXPECT_EQ(r["rig"]["motors"][1]["swapped"], true);
  EXPECT_EQ(r["rig"]["limit_inputs"].size(), 2u);
  EXPECT_EQ(r["gio"]["raw_inputs"], 1u);
  EXPECT_EQ(r["gio"]["inputs"], 1u);
  EXPECT_FALSE(r.contains("link"));  // in-process
}

TEST_F(ControlChannelTest, DevicesAndHelpNeedNoDevice) {
  // A channel detaches from its devices when destroyed, so they must outlive
  // it: the bare device is declared before this test's own channel.
  BareDevice bare;
  ControlChannel channel(scheduler_);
  channel.AddDevice("rig1", device_);
  channel.AddDevice("cam", bare);
  json r = Reply(channel, R"({"cmd":"devices"})");
  ASSERT_EQ(r["devices"].size(), 2u);
  EXPECT_EQ(r["devices"][0]["name"], "rig1");
  EXPECT_EQ(r["devices"][0]["model"], "fake");
  EXPECT_EQ(r["devices"][1]["name"], "cam");
  EXPECT_TRUE(r["devices"][1]["endpoint"].is_null());
  r = Reply(channel, R"({"cmd":"help"})");
  EXPECT_EQ(r["ok"], true);
  // estop, limit, gio_in, power_cycle, cut_link, faults, state, events,
  // devices, help (docs/control.md)
  ASSERT_EQ(r["commands"].size(), 10u);
  std::vector<std::string> names;
  for (const json& c : r["commands"]) names.push_back(c["cmd"].get<std::string>());
  EXPECT_NE(std::find(names.begin(), names.end(), "events"), names.end());
  EXPECT_EQ(names.back(), "help");
}

// ---- several devices, device errors -------------------------------------------

TEST_F(ControlChannelTest, WithSeveralDevicesTheDeviceFieldIsRequired) {
  FakeDevice other(scheduler_, 1, 1, "other");
  ControlChannel channel(scheduler_);  // after `other`: devices outlive the channel
  channel.AddDevice("rig1", device_);
  channel.AddDevice("rig2", other);
  std::string e = ErrorOf(channel, R"({"cmd":"estop","engaged":true})");
  EXPECT_TRUE(Contains(e, "several devices")) << e;
  EXPECT_TRUE(Contains(e, "rig1, rig2")) << e;
  e = ErrorOf(channel, R"({"cmd":"estop","engaged":true,"device":"rig9"})");
  EXPECT_TRUE(Contains(e, "unknown device \"rig9\"")) << e;
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  EXPECT_FALSE(other.the_rig().estop_engaged());

  EXPECT_EQ(Reply(channel, R"({"cmd":"estop","engaged":true,"device":"rig2"})")["ok"], true);
  EXPECT_TRUE(other.the_rig().estop_engaged());
  EXPECT_FALSE(device_.the_rig().estop_engaged());
}

TEST(ControlChannelDevicesTest, DevicesWithoutRigGioOrLinkRefuseThoseCommands) {
  sim::Scheduler scheduler;
  BareDevice bare;
  ControlChannel channel(scheduler);
  channel.AddDevice("cam", bare);
  EXPECT_TRUE(Contains(ErrorOf(channel, R"({"cmd":"estop","engaged":true})"), "has no rig"));
  EXPECT_TRUE(Contains(ErrorOf(channel, R"({"cmd":"limit","set":1,"input":"low","active":true})"),
                       "has no rig"));
  EXPECT_TRUE(Contains(ErrorOf(channel, R"({"cmd":"gio_in","bit":1,"level":true})"),
                       "no general-purpose inputs"));
  EXPECT_TRUE(Contains(ErrorOf(channel, R"({"cmd":"cut_link","ms":10})"), "without a link"));
  EXPECT_TRUE(
      Contains(ErrorOf(channel, R"({"cmd":"faults","config":"drop=0.5"})"), "without a link"));
  EXPECT_EQ(Reply(channel, R"({"cmd":"state"})")["ok"], true);
}

TEST(ControlChannelDevicesTest, NoDeviceServedIsAnErrorNotACrash) {
  sim::Scheduler scheduler;
  ControlChannel channel(scheduler);
  EXPECT_TRUE(Contains(ErrorOf(channel, R"({"cmd":"state"})"), "no device"));
  EXPECT_EQ(Reply(channel, R"({"cmd":"devices"})")["devices"].size(), 0u);
}

TEST(ControlChannelDevicesTest, BadOrDuplicateDeviceNamesAreStartUpErrors) {
  sim::Scheduler scheduler;
  BareDevice a;
  ControlChannel channel(scheduler);
  EXPECT_THROW(channel.AddDevice("", a), std::invalid_argument);
  EXPECT_THROW(channel.AddDevice("has space", a), std::invalid_argument);
  channel.AddDevice("dmc16", a);
  EXPECT_THROW(channel.AddDevice("dmc16", a), std::invalid_argument);
  EXPECT_EQ(channel.DeviceNames(), std::vector<std::string>{"dmc16"});
}

// ---- malformed requests -------------------------------------------------------

TEST_F(ControlChannelTest, BadRequestsGetErrorsNamingTheProblemAndTheFix) {
  struct Case {
    const char* line;
    std::vector<const char*> parts;
  };
  const Case cases[] = {
      {"", {"empty request"}},
      {"   ", {"empty request"}},
      {"{", {"malformed JSON at byte"}},
      {"estop", {"malformed JSON"}},
      {R"({"cmd":"power_cycle","off_ms":1e400})", {"malformed JSON", "out of range"}},
      {"[1,2]", {"must be a JSON object", "an array"}},
      {"{}", {"missing field \"cmd\"", "estop, limit"}},
      {R"({"cmd":5})", {"\"cmd\" must be a command name string", "an integer"}},
      {R"({"cmd":"reboot"})", {"unknown command \"reboot\"", "power_cycle", "help"}},
      {R"({"cmd":"estop"})", {"\"engaged\" is missing", "{\"cmd\":\"estop\",\"engaged\":true}"}},
      {R"({"cmd":"estop","engaged":"yes"})", {"\"engaged\" must be true or false", "a string"}},
      {R"({"cmd":"estop","engagd":true})", {"unknown field \"engagd\"", "engaged"}},
      {R"({"cmd":"estop","engaged":true,"device":7})", {"\"device\" must be a device name"}},
      {R"({"cmd":"limit","active":true})", {"\"set\" + \"input\"", "\"motor\" + \"end\""}},
      {R"({"cmd":"limit","set":1,"end":"upper","active":true})", {"not both"}},
      {R"({"cmd":"limit","set":1,"input":"middle","active":true})",
       {"\"input\" must be \"low\" or \"high\"", "\"middle\""}},
      {R"({"cmd":"limit","set":0,"input":"low","active":true})", {"\"set\"", "outside 1..127"}},
      {R"({"cmd":"limit","motor":1,"end":"upper"})", {"\"active\" is missing"}},
      {R"({"cmd":"limit","motor":1.5,"end":"upper","active":true})",
       {"\"motor\" must be a whole number"}},
      {R"({"cmd":"gio_in","bit":32,"level":true})", {"\"bit\"", "outside 0..31"}},
      {R"({"cmd":"gio_in","bit":3})", {"\"level\" is missing"}},
      {R"({"cmd":"gio_in","bits":"ff"})", {"\"bits\"", "hex string"}},
      {R"({"cmd":"gio_in","bits":"0x1ffffffff"})", {"\"bits\""}},
      {R"({"cmd":"gio_in","bits":-1})", {"\"bits\"", "outside 0..4294967295"}},
      {R"({"cmd":"gio_in","bit":1,"level":true,"bits":0})", {"not both"}},
      {R"({"cmd":"gio_in"})", {"\"bit\" + \"level\"", "\"bits\""}},
      {R"({"cmd":"power_cycle"})", {"\"off_ms\" is missing"}},
      {R"({"cmd":"power_cycle","off_ms":-5})", {"\"off_ms\"", "outside 0..86400000"}},
      {R"({"cmd":"power_cycle","off_ms":1e300})", {"\"off_ms\" must be a whole number"}},
      {R"({"cmd":"cut_link","ms":0})", {"\"ms\"", "outside 1..86400000"}},
      {R"({"cmd":"faults"})", {"\"config\" is missing"}},
      {R"({"cmd":"faults","config":"drop=2"})", {"\"config\""}},
      {R"({"cmd":"faults","config":"explode=1"})", {"\"config\" is not a fault list"}},
      {R"({"cmd":"faults","config":"seed=42,drop=0.01,dir=to-host"})",
       {"\"config\" ends with a \"dir=\"", "seed=42,dir=to-host,drop=0.01"}},
      {R"({"cmd":"state","verbose":true})", {"unknown field \"verbose\"", "none"}},
  };
  for (const Case& c : cases) {
    const std::string e = ErrorOf(channel_, c.line);
    for (const char* part : c.parts) {
      EXPECT_TRUE(Contains(e, part)) << c.line << " -> " << e << "\n  missing: " << part;
    }
  }
  // None of them touched the device.
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  EXPECT_TRUE(device_.Powered());
  EXPECT_EQ(device_.the_gio().raw_inputs(), 0u);
}

TEST_F(ControlChannelTest, DuplicateKeysAreRefusedNamingTheKey) {
  // The last "engaged" would have released the e-stop the first one pressed.
  std::string e = ErrorOf(channel_, R"({"cmd":"estop","engaged":true,"engaged":false})");
  EXPECT_TRUE(Contains(e, "\"engaged\" appears twice")) << e;
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  e = ErrorOf(channel_, R"({"cmd":"estop","cmd":"state","engaged":true,"id":4})");
  EXPECT_TRUE(Contains(e, "\"cmd\" appears twice")) << e;
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  // The same key in two different objects is no duplicate.
  EXPECT_EQ(Reply(channel_, R"({"cmd":"estop","engaged":true,"id":{"engaged":1}})")["ok"], true);
  EXPECT_TRUE(device_.the_rig().estop_engaged());
  // The id of a refused request is still echoed.
  EXPECT_EQ(Reply(channel_, R"({"cmd":"state","cmd":"state","id":9})")["id"], 9);
}

TEST_F(ControlChannelTest, TheIdIsEchoedOnSuccessAndOnError) {
  EXPECT_EQ(Reply(channel_, R"({"cmd":"state","id":17})")["id"], 17);
  EXPECT_EQ(Reply(channel_, R"({"cmd":"estop","id":"a"})")["id"], "a");
  EXPECT_EQ(Reply(channel_, R"({"cmd":"nope","id":[1]})")["id"], json::array({1}));
}

TEST_F(ControlChannelTest, CarriageReturnLineEndsAreAccepted) {
  EXPECT_EQ(Reply(channel_, "{\"cmd\":\"estop\",\"engaged\":true}\r\n")["ok"], true);
  EXPECT_TRUE(device_.the_rig().estop_engaged());
}

TEST_F(ControlChannelTest, DeeplyNestedJsonIsAnErrorNotAStackOverflow) {
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  EXPECT_TRUE(Contains(ErrorOf(channel_, deep), "must be a JSON object"));
  const std::string open = "{\"cmd\":" + std::string(200000, '[');
  EXPECT_TRUE(Contains(ErrorOf(channel_, open), "malformed JSON"));
}

// ---- events -------------------------------------------------------------------

TEST_F(ControlChannelTest, ActionsReachTheListenerAsSessionEventsQueriesDoNot) {
  std::vector<ControlEvent> events;
  channel_.SetActionListener([&](const ControlEvent& e) { events.push_back(e); });
  scheduler_.RunUntil(2 * sim::kNsPerSecond);
  Reply(channel_, R"({"cmd":"estop","engaged":true})");
  Reply(channel_, R"({"cmd":"state"})");
  Reply(channel_, R"({"cmd":"help"})");
  Reply(channel_, R"({"cmd":"limit","motor":1,"end":"upper","active":true})");  // unbound: fails
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].t_ns, 2 * sim::kNsPerSecond);
  EXPECT_EQ(events[0].source, "control");

  const json line = events[0].SessionLine();
  EXPECT_EQ(line["t_ns"], 2 * sim::kNsPerSecond);
  EXPECT_EQ(line["event"], "estop");
  EXPECT_EQ(line["engaged"], true);
  EXPECT_EQ(line["ok"], true);
  EXPECT_FALSE(line.contains("cmd"));
  const json failed = events[1].SessionLine();
  EXPECT_EQ(failed["event"], "limit");
  EXPECT_EQ(failed["ok"], false);
  EXPECT_TRUE(Contains(failed["error"].get<std::string>(), "no limit set"));

  // The entry is a valid session event line (docs/sessions.md).
  const std::string text = "{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n" +
                           session::EntryToJson(events[0].ToSessionEntry()).dump() + "\n";
  auto parsed = session::ParseSession(text);
  ASSERT_TRUE(std::holds_alternative<session::Session>(parsed))
      << std::get<session::SessionError>(parsed).message;
  const session::Session& s = std::get<session::Session>(parsed);
  ASSERT_EQ(s.entries.size(), 1u);
  EXPECT_TRUE(s.entries[0].is_event);
  EXPECT_EQ(s.entries[0].t_ns, 2 * sim::kNsPerSecond);
  EXPECT_EQ(s.entries[0].event["event"], "estop");
}

TEST_F(ControlChannelTest, DeviceEventsAreNumberedKeptForTheEventsQueryAndPassedOn) {
  std::vector<DeviceEvent> passed;
  std::vector<ControlEvent> actions;
  channel_.SetDeviceEventListener([&](const DeviceEvent& e) { passed.push_back(e); });
  channel_.SetActionListener([&](const ControlEvent& e) { actions.push_back(e); });
  scheduler_.RunUntil(3 * sim::kNsPerSecond);
  device_.Emit({{"event", "stall"}, {"joint", "boom"}, {"lost_steps", 120}});
  scheduler_.RunUntil(4 * sim::kNsPerSecond);
  device_.Emit({{"event", "collision"}, {"with", "floor"}});
  ASSERT_EQ(passed.size(), 2u);
  EXPECT_EQ(passed[0].device, "rig1");
  EXPECT_EQ(passed[0].seq, 1u);
  EXPECT_EQ(passed[1].seq, 2u);
  EXPECT_EQ(passed[1].t_ns, 4 * sim::kNsPerSecond);

  const json all = Reply(channel_, R"({"cmd":"events"})");
  ASSERT_EQ(all["ok"], true) << all.dump();
  ASSERT_EQ(all["events"].size(), 2u);
  EXPECT_EQ(all["events"][0]["event"], "stall");
  EXPECT_EQ(all["events"][0]["lost_steps"], 120);
  EXPECT_EQ(all["events"][0]["t_ns"], 3 * sim::kNsPerSecond);
  EXPECT_EQ(all["events"][0]["source"], "device");
  EXPECT_EQ(all["last_seq"], 2);
  EXPECT_EQ(all["missed"], 0);
  const json later = Reply(channel_, R"({"cmd":"events","after":1})");
  ASSERT_EQ(later["events"].size(), 1u);
  EXPECT_EQ(later["events"][0]["with"], "floor");
  EXPECT_EQ(Reply(channel_, R"({"cmd":"events","after":2})")["events"].size(), 0u);
  EXPECT_TRUE(Contains(ErrorOf(channel_, R"({"cmd":"events","after":-1})"), "after"));
  // A query, not an action.
  EXPECT_TRUE(actions.empty());

  // The session line is a valid event line that keeps the device's fields.
  const std::string text = "{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n" +
                           session::EntryToJson(passed[0].ToSessionEntry()).dump() + "\n";
  auto parsed = session::ParseSession(text);
  ASSERT_TRUE(std::holds_alternative<session::Session>(parsed))
      << std::get<session::SessionError>(parsed).message;
  const session::SessionEntry& e = std::get<session::Session>(parsed).entries.at(0);
  EXPECT_TRUE(e.is_event);
  EXPECT_EQ(e.t_ns, 3 * sim::kNsPerSecond);
  EXPECT_EQ(e.event["event"], "stall");
  EXPECT_EQ(e.event["joint"], "boom");
  EXPECT_EQ(e.event["source"], "device");
}

TEST_F(ControlChannelTest, OnlyTheLastEventsAreKeptAndTheMissedOnesAreCounted) {
  for (int i = 0; i < static_cast<int>(ControlChannel::kEventsKept) + 10; ++i) {
    device_.Emit({{"event", "stall"}, {"n", i}});
  }
  const json r = Reply(channel_, R"({"cmd":"events","after":5})");
  ASSERT_EQ(r["events"].size(), ControlChannel::kEventsKept);
  EXPECT_EQ(r["events"][0]["seq"], 11);
  EXPECT_EQ(r["missed"], 5);  // 6..10 were dropped
  EXPECT_EQ(r["last_seq"], ControlChannel::kEventsKept + 10);
}

TEST(ControlChannelDevicesTest, ADestroyedChannelNoLongerListensToItsDevices) {
  sim::Scheduler scheduler;
  FakeDevice device(scheduler);
  int passed = 0;
  {
    ControlChannel channel(scheduler);
    channel.AddDevice("rig", device);
    channel.SetDeviceEventListener([&](const DeviceEvent&) { ++passed; });
    device.Emit({{"event", "stall"}});
  }
  device.Emit({{"event", "stall"}});  // no channel to reach: not a crash
  EXPECT_EQ(passed, 1);
}

// ---- a device served on an endpoint -------------------------------------------

// A real DeviceServer on an ephemeral TCP port, reached through the serving
// layer's LinkControl; its driver is never started, so the link keeps the
// scheduler's virtual time.
class ServedDeviceTest : public ::testing::Test {
 protected:
  ServedDeviceTest() {
    transport::ServeOptions opts;
    opts.log = [](std::string_view) {};
    server_ = std::make_unique<transport::DeviceServer>(driver_, "tcp:127.0.0.1:0", opts);
    device_ = std::make_unique<FakeDevice>(scheduler_);
    server_->Serve(*device_);
    device_->PowerOn();
    link_ = std::make_unique<serve::DeviceServerLink>(*server_);
    channel_.AddDevice("dmc16", *device_, link_.get());
  }
  ~ServedDeviceTest() override { server_->Stop(); }

  transport::asio::io_context io_;
  sim::Scheduler scheduler_;
  transport::RealtimeDriver driver_{io_, scheduler_};
  std::unique_ptr<transport::DeviceServer> server_;
  std::unique_ptr<serve::DeviceServerLink> link_;
  std::unique_ptr<FakeDevice> device_;
  ControlChannel channel_{scheduler_};
};

TEST_F(ServedDeviceTest, PowerCycleGoesThroughTheLink) {
  scheduler_.RunUntil(5 * kNsPerMs);
  const json r = Reply(channel_, R"({"cmd":"power_cycle","off_ms":40})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["via"], "link");
  EXPECT_FALSE(device_->Powered());
  scheduler_.RunUntil(45 * kNsPerMs - 1);
  EXPECT_FALSE(device_->Powered());
  scheduler_.RunUntil(45 * kNsPerMs);
  EXPECT_TRUE(device_->Powered());
}

TEST_F(ServedDeviceTest, CutLinkCutsForTheGivenTime) {
  EXPECT_FALSE(server_->link().cut_active());
  const json r = Reply(channel_, R"({"cmd":"cut_link","ms":30})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_TRUE(server_->link().cut_active());
  scheduler_.RunUntil(30 * kNsPerMs - 1);
  EXPECT_TRUE(server_->link().cut_active());
  scheduler_.RunUntil(30 * kNsPerMs);
  EXPECT_FALSE(server_->link().cut_active());
  // Device output during the cut is dropped and counted.
  Reply(channel_, R"({"cmd":"cut_link","ms":30})");
  const uint8_t bytes[] = {1, 2, 3};
  server_->sink().Write(bytes);
  EXPECT_EQ(server_->link().stats().cut_dropped, 3u);
}

TEST_F(ServedDeviceTest, FaultsAreSetAndClearedOnTheLink) {
  json r = Reply(channel_, R"({"cmd":"faults","config":"seed=42,dir=to-host,drop=0.25"})");
  EXPECT_EQ(r["ok"], true) << r.dump();
  EXPECT_EQ(r["enabled"], true);
  const transport::FaultConfig& c = server_->link().faults().config();
  EXPECT_EQ(c.seed, 42u);
  EXPECT_DOUBLE_EQ(c.to_host.drop_rate, 0.25);
  EXPECT_DOUBLE_EQ(c.to_device.drop_rate, 0.0);
  EXPECT_TRUE(server_->link().faults().enabled());

  r = Reply(channel_, R"({"cmd":"faults","config":"off"})");
  EXPECT_EQ(r["enabled"], false);
  EXPECT_FALSE(server_->link().faults().enabled());
}

TEST_F(ServedDeviceTest, StateCarriesTheLinkAndItsStatistics) {
  const uint8_t bytes[] = {9, 9};
  server_->sink().Write(bytes);
  Reply(channel_, R"({"cmd":"faults","config":"seed=1,drop=0.5"})");
  const json r = Reply(channel_, R"({"cmd":"state"})");
  ASSERT_TRUE(r.contains("link")) << r.dump();
  EXPECT_TRUE(Contains(r["link"]["endpoint"].get<std::string>(), "tcp 127.0.0.1:"));
  EXPECT_EQ(r["link"]["stats"]["bytes_from_device"], 2u);
  EXPECT_EQ(r["link"]["cut_active"], false);
  EXPECT_EQ(r["link"]["faults"]["enabled"], true);
  EXPECT_EQ(r["link"]["faults"]["to_host"]["bytes_in"], 0u);
  const json d = Reply(channel_, R"({"cmd":"devices"})");
  EXPECT_EQ(d["devices"][0]["endpoint"], server_->Where());
}

// ---- laws ---------------------------------------------------------------------

// Every request line gets exactly one reply line, a JSON object with "ok",
// and an "error" string when not ok, whatever the line holds.
void CheckOneReply(ControlChannel& channel, const std::string& line) {
  const std::string reply = channel.Handle(line);
  RC_ASSERT(reply.find('\n') == std::string::npos);
  const json r = json::parse(reply, nullptr, false);
  RC_ASSERT(r.is_object());
  RC_ASSERT(r.contains("ok"));
  RC_ASSERT(r["ok"].is_boolean());
  if (!r["ok"].get<bool>()) RC_ASSERT(r["error"].is_string());
}

RC_GTEST_PROP(ControlChannelLaw, ArbitraryTextGetsExactlyOneReply, (const std::string& line)) {
  sim::Scheduler scheduler;
  FakeDevice device(scheduler);
  ControlChannel channel(scheduler);
  channel.AddDevice("d", device);
  CheckOneReply(channel, line);
}

// Requests close to valid ones: a known or unknown command with fields of
// every JSON type, so the field checks themselves are exercised.
rc::Gen<json> GenValue() {
  return rc::gen::oneOf(
      rc::gen::map(rc::gen::arbitrary<bool>(), [](bool b) { return json(b); }),
      rc::gen::map(rc::gen::arbitrary<int64_t>(), [](int64_t i) { return json(i); }),
      rc::gen::map(rc::gen::inRange(-3, 40), [](int i) { return json(i); }),
      rc::gen::map(rc::gen::arbitrary<double>(), [](double d) { return json(d); }),
      rc::gen::map(rc::gen::arbitrary<std::string>(), [](std::string s) { return json(s); }),
      rc::gen::element(json("low"), json("high"), json("upper"), json("lower"), json("0xff"),
                       json("seed=3,drop=0.5"), json("off"), json(nullptr), json::array(),
                       json::object(), json(1e300), json(0xffffffffULL)));
}

RC_GTEST_PROP(ControlChannelLaw, NearlyValidRequestsGetExactlyOneReply, ()) {
  sim::Scheduler scheduler;
  FakeDevice device(scheduler);
  BareDevice bare;
  ControlChannel channel(scheduler);
  channel.AddDevice("d", device);
  if (*rc::gen::arbitrary<bool>()) channel.AddDevice("bare", bare);
  const auto n = *rc::gen::inRange(1, 12);
  for (int i = 0; i < n; ++i) {
    json request = json::object();
    request["cmd"] =
        *rc::gen::element<std::string>("estop", "limit", "gio_in", "power_cycle", "cut_link",
                                       "faults", "state", "devices", "help", "bogus");
    const auto fields = *rc::gen::container<std::vector<std::string>>(rc::gen::element<std::string>(
        "engaged", "set", "input", "motor", "end", "active", "bit", "level", "bits", "off_ms", "ms",
        "config", "device", "id", "x"));
    for (const std::string& f : fields) request[f] = *GenValue();
    CheckOneReply(channel, request.dump(-1, ' ', false, json::error_handler_t::replace));
    scheduler.RunUntil(scheduler.Now() + *rc::gen::inRange<int64_t>(0, 500) * kNsPerMs);
  }
}

}  // namespace
}  // namespace moco::control
