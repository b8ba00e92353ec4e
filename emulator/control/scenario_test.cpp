// Tests for scenario files (scenario.h, docs/control.md "Scenario files") in
// virtual time: load-time errors that name the event, the field and the fix;
// events run at start + at_ms in (time, file) order through the control
// vocabulary; repeats; cancellation; and the session lines they produce.
#include "control/scenario.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "control/test_support.h"
#include "serve/link_control_adapter.h"
#include "transport/device_server.h"

namespace moco::control {
namespace {

using nlohmann::json;
using sim::kNsPerMs;
using testing::FakeDevice;
namespace fs = std::filesystem;

bool Contains(const std::string& s, std::string_view part) {
  return s.find(part) != std::string::npos;
}

std::string LoadError(std::string_view text) {
  try {
    Scenario::Parse(text, "scenario t.json");
  } catch (const ScenarioError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << text;
  return {};
}

TEST(ScenarioLoadTest, ReadsEventsWithTheirTimesAndCommands) {
  const Scenario s = Scenario::Parse(R"({
    "note": "e-stop during a move",
    "events": [
      {"at_ms": 1500, "cmd": "estop", "engaged": true},
      {"at_ms": 3000, "cmd": "estop", "engaged": false, "device": "rig1"},
      {"at_ms": 0, "every_ms": 250, "repeat": 4, "cmd": "gio_in", "bit": 2, "level": true}
    ]})");
  EXPECT_EQ(s.note(), "e-stop during a move");
  ASSERT_EQ(s.events().size(), 3u);
  EXPECT_EQ(s.events()[0].at_ms, 1500);
  EXPECT_EQ(s.events()[0].repeat, 1);
  EXPECT_TRUE(std::get<EStopCommand>(s.events()[0].command.body).engaged);
  EXPECT_EQ(s.events()[1].command.device, "rig1");
  EXPECT_EQ(s.events()[2].index, 2);
  EXPECT_EQ(s.events()[2].every_ms, 250);
  EXPECT_EQ(s.events()[2].repeat, 4);
  EXPECT_EQ(s.duration_ms(), 3000);
  EXPECT_EQ(Scenario::Parse(R"({"events":[]})").events().size(), 0u);
}

TEST(ScenarioLoadTest, ErrorsNameTheEventTheFieldAndTheFix) {
  struct Case {
    const char* text;
    std::vector<const char*> parts;
  };
  const Case cases[] = {
      {R"({"events":[{"at_ms":0,"cmd":"state"},)", {"scenario t.json", "malformed JSON at line 1"}},
      {"{\n\"events\": [\n  {\"at_ms\": 5 \"cmd\": \"state\"}]}",
       {"malformed JSON at line 3 column"}},
      {R"([1])", {"must be a JSON object", "an array", "\"events\""}},
      {R"({"events":[{"at_ms":1e999,"cmd":"state"}]})", {"scenario t.json", "out of range"}},
      {R"({})", {"\"events\" is missing"}},
      {R"({"events":{}})", {"\"events\" must be an array", "an object"}},
      {R"({"events":[],"evnets":[]})", {"unknown field \"evnets\"", "\"note\""}},
      {R"({"events":[],"note":3})", {"\"note\" must be a string"}},
      {R"({"events":[{"at_ms":0,"cmd":"estop","engaged":true,"engaged":false}]})",
       {"scenario t.json", "\"events[].engaged\" appears twice"}},
      {R"({"events":[{"at_ms":0,"cmd":"state"},7]})", {"events[1] must be an object"}},
      {R"({"events":[{"cmd":"state"}]})", {"events[0]", "\"at_ms\" is missing", "\"at_ms\": 1500"}},
      {R"({"events":[{"at_ms":-1,"cmd":"state"}]})",
       {"events[0]", "\"at_ms\"", "found an integer -1"}},
      {R"({"events":[{"at_ms":"1s","cmd":"state"}]})", {"\"at_ms\" must be whole milliseconds"}},
      {R"({"events":[{"at_ms":1.5,"cmd":"state"}]})", {"\"at_ms\"", "a number 1.5"}},
      {R"({"events":[{"at_ms":0,"every_ms":10,"cmd":"state"}]})",
       {"\"every_ms\" needs \"repeat\""}},
      {R"({"events":[{"at_ms":0,"repeat":3,"cmd":"state"}]})",
       {"\"repeat\" is 3", "\"every_ms\" is missing"}},
      {R"({"events":[{"at_ms":0,"repeat":0,"every_ms":5,"cmd":"state"}]})",
       {"\"repeat\" must be the number of runs"}},
      {R"({"events":[{"at_ms":0,"repeat":2,"every_ms":0,"cmd":"state"}]})",
       {"\"every_ms\" must be whole milliseconds 1.."}},
      {R"({"events":[{"at_ms":8640000000,"repeat":2,"every_ms":1,"cmd":"state"}]})",
       {"last run", "lower repeat"}},
      {R"({"events":[{"at_ms":0,"cmd":"state"},{"at_ms":10}]})",
       {"events[1] (at_ms 10)", "missing field \"cmd\""}},
      {R"({"events":[{"at_ms":10,"cmd":"estop","engagd":true}]})",
       {"events[0] (at_ms 10)", "unknown field \"engagd\"", "engaged"}},
      {R"({"events":[{"at_ms":10,"cmd":"estop","engaged":1}]})",
       {"events[0]", "\"engaged\" must be true or false", "{\"cmd\":\"estop\",\"engaged\":true}"}},
      {R"({"events":[{"at_ms":10,"cmd":"faults","config":"drop=7"}]})",
       {"events[0]", "\"config\""}},
  };
  for (const Case& c : cases) {
    const std::string e = LoadError(c.text);
    for (const char* part : c.parts) {
      EXPECT_TRUE(Contains(e, part)) << c.text << "\n -> " << e << "\n  missing: " << part;
    }
  }
}

TEST(ScenarioLoadTest, LoadsAFileAndNamesAnUnreadableOne) {
  const fs::path dir = fs::temp_directory_path() / ("moco_scenario_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "s.json";
  std::ofstream(file) << R"({"events":[{"at_ms":5,"cmd":"estop","engaged":true}]})";
  EXPECT_EQ(Scenario::Load(file).events().size(), 1u);
  EXPECT_EQ(Scenario::Load(file).where(), "scenario " + file.string());
  try {
    Scenario::Load(dir / "missing.json");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_TRUE(Contains(e.what(), "missing.json")) << e.what();
    EXPECT_TRUE(Contains(e.what(), "does not exist")) << e.what();
  }
  std::ofstream(file) << R"({"events":[{"at_ms":5,"cmd":"estop"}]})";
  try {
    Scenario::Load(file);
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_TRUE(Contains(e.what(), "scenario " + file.string() + ": events[0]")) << e.what();
  }
  fs::remove_all(dir);
}

class ScenarioRunTest : public ::testing::Test {
 protected:
  ScenarioRunTest() {
    device_.PowerOn();
    channel_.AddDevice("rig1", device_);
  }
  std::unique_ptr<ScenarioRun> Run(std::string_view text, sim::TimeNs start_ns) {
    return Scenario::Parse(text).Schedule(channel_, scheduler_, start_ns,
                                          [this](const ControlEvent& e) { log_.push_back(e); });
  }

  sim::Scheduler scheduler_;
  FakeDevice device_{scheduler_};
  ControlChannel channel_{scheduler_};
  std::vector<ControlEvent> log_;
};

TEST_F(ScenarioRunTest, EventsRunAtStartPlusAtMsAndAreLogged) {
  scheduler_.RunUntil(100 * kNsPerMs);
  auto run = Run(R"({"events":[
      {"at_ms":1500,"cmd":"estop","engaged":true},
      {"at_ms":3000,"cmd":"estop","engaged":false}]})",
                 200 * kNsPerMs);
  EXPECT_EQ(run->remaining(), 2u);
  EXPECT_EQ(run->end_ns(), 3200 * kNsPerMs);
  scheduler_.RunUntil(1700 * kNsPerMs - 1);
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  scheduler_.RunUntil(1700 * kNsPerMs);
  EXPECT_TRUE(device_.the_rig().estop_engaged());
  scheduler_.RunUntil(3200 * kNsPerMs - 1);
  EXPECT_TRUE(device_.the_rig().estop_engaged());
  scheduler_.RunUntil(3200 * kNsPerMs);
  EXPECT_FALSE(device_.the_rig().estop_engaged());
  EXPECT_TRUE(run->done());
  EXPECT_EQ(run->executed(), 2u);

  ASSERT_EQ(log_.size(), 2u);
  EXPECT_EQ(log_[0].t_ns, 1700 * kNsPerMs);
  EXPECT_EQ(log_[0].source, "scenario");
  EXPECT_EQ(log_[0].index, 0);
  EXPECT_EQ(log_[0].reply["ok"], true);
  const json line = log_[1].SessionLine();
  EXPECT_EQ(line["t_ns"], 3200 * kNsPerMs);
  EXPECT_EQ(line["event"], "estop");
  EXPECT_EQ(line["engaged"], false);
  EXPECT_EQ(line["source"], "scenario");
  EXPECT_EQ(line["index"], 1);
  EXPECT_EQ(line["ok"], true);
}

TEST_F(ScenarioRunTest, EventsDueTogetherRunInFileOrderWhateverTheListingOrder) {
  // Listed out of time order; the two at 50 ms must run as listed.
  auto run = Run(R"({"events":[
      {"at_ms":90,"cmd":"gio_in","bits":"0x0"},
      {"at_ms":50,"cmd":"gio_in","bits":"0xff"},
      {"at_ms":50,"cmd":"gio_in","bit":0,"level":false},
      {"at_ms":10,"cmd":"gio_in","bit":9,"level":true}]})",
                 0);
  scheduler_.RunUntil(60 * kNsPerMs);
  EXPECT_EQ(device_.the_gio().raw_inputs(), 0xfeu);
  ASSERT_EQ(log_.size(), 3u);
  EXPECT_EQ(log_[0].index, 3);
  EXPECT_EQ(log_[1].index, 1);
  EXPECT_EQ(log_[2].index, 2);
  scheduler_.RunUntilIdle();
  EXPECT_EQ(device_.the_gio().raw_inputs(), 0u);
}

TEST_F(ScenarioRunTest, RepeatRunsEveryIntervalTheGivenNumberOfTimes) {
  auto run = Run(R"({"events":[
      {"at_ms":100,"every_ms":250,"repeat":4,"cmd":"power_cycle","off_ms":50}]})",
                 0);
  EXPECT_EQ(run->remaining(), 4u);
  EXPECT_EQ(run->end_ns(), 850 * kNsPerMs);
  scheduler_.RunUntilIdle();
  EXPECT_EQ(device_.power_off_ns, (std::vector<sim::TimeNs>{100 * kNsPerMs, 350 * kNsPerMs,
                                                            600 * kNsPerMs, 850 * kNsPerMs}));
  // The first power-on was the fixture's, at 0.
  EXPECT_EQ(device_.power_on_ns, (std::vector<sim::TimeNs>{0, 150 * kNsPerMs, 400 * kNsPerMs,
                                                           650 * kNsPerMs, 900 * kNsPerMs}));
  EXPECT_EQ(run->executed(), 4u);
  EXPECT_TRUE(run->done());
}

TEST_F(ScenarioRunTest, ARuntimeFailureIsLoggedAndTheRestStillRuns) {
  auto run = Run(R"({"events":[
      {"at_ms":10,"cmd":"limit","motor":2,"end":"upper","active":true},
      {"at_ms":20,"cmd":"estop","engaged":true}]})",
                 0);
  scheduler_.RunUntilIdle();
  ASSERT_EQ(log_.size(), 2u);
  EXPECT_EQ(log_[0].reply["ok"], false);
  EXPECT_TRUE(Contains(log_[0].reply["error"].get<std::string>(), "no limit set"));
  EXPECT_EQ(log_[0].SessionLine()["ok"], false);
  EXPECT_EQ(log_[1].reply["ok"], true);
  EXPECT_TRUE(device_.the_rig().estop_engaged());
}

TEST_F(ScenarioRunTest, ScheduleRefusesEventsTheChannelCannotRun) {
  const auto error_of = [this](std::string_view text) {
    try {
      auto run = Scenario::Parse(text, "scenario t.json").Schedule(channel_, scheduler_, 0);
      ADD_FAILURE() << "no error for " << text;
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string e = error_of(
      R"({"events":[{"at_ms":0,"cmd":"state"},{"at_ms":5,"cmd":"estop","engaged":true,"device":"x"}]})");
  EXPECT_TRUE(Contains(e, "scenario t.json: events[1] (at_ms 5, \"estop\")")) << e;
  EXPECT_TRUE(Contains(e, "unknown device \"x\"")) << e;
  e = error_of(R"({"events":[{"at_ms":0,"cmd":"limit","motor":7,"end":"upper","active":true}]})");
  EXPECT_TRUE(Contains(e, "events[0]")) << e;
  EXPECT_TRUE(Contains(e, "motor 7 does not exist")) << e;
  e = error_of(R"({"events":[{"at_ms":0,"cmd":"cut_link","ms":100}]})");
  EXPECT_TRUE(Contains(e, "without a link")) << e;
  // Nothing was scheduled by the refused scenarios.
  EXPECT_EQ(scheduler_.PendingCount(), 0u);
}

TEST_F(ScenarioRunTest, DestroyingTheRunCancelsWhatHasNotRun) {
  auto run = Run(R"({"events":[
      {"at_ms":10,"cmd":"estop","engaged":true},
      {"at_ms":20,"cmd":"estop","engaged":false},
      {"at_ms":30,"every_ms":5,"repeat":100,"cmd":"gio_in","bit":1,"level":true}]})",
                 0);
  scheduler_.RunUntil(15 * kNsPerMs);
  EXPECT_EQ(run->executed(), 1u);
  EXPECT_EQ(run->remaining(), 101u);
  run.reset();
  scheduler_.RunUntilIdle();
  EXPECT_TRUE(device_.the_rig().estop_engaged());
  EXPECT_EQ(device_.the_gio().raw_inputs(), 0u);
  EXPECT_EQ(log_.size(), 1u);
}

TEST_F(ScenarioRunTest, TheSameScenarioCanBeScheduledTwice) {
  const Scenario s = Scenario::Parse(R"({"events":[{"at_ms":10,"cmd":"gio_in","bits":1}]})");
  auto a = s.Schedule(channel_, scheduler_, 0);
  auto b = s.Schedule(channel_, scheduler_, 100 * kNsPerMs);
  scheduler_.RunUntil(50 * kNsPerMs);
  EXPECT_TRUE(a->done());
  EXPECT_FALSE(b->done());
  scheduler_.RunUntilIdle();
  EXPECT_TRUE(b->done());
}

// The example of docs/control.md "Scenario files" loads, passes the schedule
// checks against a served device, and every event runs with ok true.
TEST(ScenarioDocsTest, TheDocumentedExampleRunsCleanly) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const fs::path doc = fs::path(root != nullptr ? root : ".") / "docs" / "control.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in) << doc;
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t section = text.find("## Scenario files");
  ASSERT_NE(section, std::string::npos);
  const size_t begin = text.find("```json\n", section);
  ASSERT_NE(begin, std::string::npos);
  const size_t end = text.find("```", begin + 8);
  const Scenario s = Scenario::Parse(text.substr(begin + 8, end - begin - 8), "docs example");
  EXPECT_EQ(s.events().size(), 11u);

  transport::asio::io_context io;
  sim::Scheduler scheduler;
  transport::RealtimeDriver driver(io, scheduler);
  transport::ServeOptions opts;
  opts.log = [](std::string_view) {};
  transport::DeviceServer server(driver, "tcp:127.0.0.1:0", opts);
  FakeDevice device(scheduler, 2, 1, "dmc16");
  server.Serve(device);
  device.PowerOn();
  ASSERT_EQ(device.the_rig().BindLimits(1, sim::HardLimitBinding::FromWire(0x01)),
            sim::MoveStatus::kOk);
  serve::DeviceServerLink link(server);
  ControlChannel channel(scheduler);
  channel.AddDevice("dmc16", device, &link);
  std::vector<ControlEvent> log;
  auto run = s.Schedule(channel, scheduler, 0, [&](const ControlEvent& e) { log.push_back(e); });
  scheduler.RunUntilIdle();
  EXPECT_EQ(log.size(), 13u);  // one event repeats 3 times
  for (const ControlEvent& e : log) EXPECT_EQ(e.reply["ok"], true) << e.reply.dump();
  EXPECT_TRUE(device.Powered());
  EXPECT_FALSE(device.the_rig().estop_engaged());
  server.Stop();
}

// Law: every occurrence runs exactly once, at start + at_ms + k * every_ms,
// and the log is in (time, file order).
RC_GTEST_PROP(ScenarioLaw, EveryOccurrenceRunsOnceAtItsTimeInOrder, ()) {
  sim::Scheduler scheduler;
  FakeDevice device(scheduler);
  ControlChannel channel(scheduler);
  channel.AddDevice("d", device);
  const auto n = *rc::gen::inRange(0, 8);
  json events = json::array();
  std::vector<std::pair<sim::TimeNs, int>> expected;
  const sim::TimeNs start_ns = *rc::gen::inRange<int64_t>(0, 1000) * kNsPerMs;
  for (int i = 0; i < n; ++i) {
    const int64_t at_ms = *rc::gen::inRange<int64_t>(0, 50);
    const int64_t repeat = *rc::gen::inRange<int64_t>(1, 5);
    const int64_t every_ms = *rc::gen::inRange<int64_t>(1, 30);
    json e = {{"at_ms", at_ms}, {"cmd", "gio_in"}, {"bit", i}, {"level", true}};
    if (repeat > 1) {
      e["repeat"] = repeat;
      e["every_ms"] = every_ms;
    }
    events.push_back(e);
    for (int64_t k = 0; k < repeat; ++k) {
      expected.emplace_back(start_ns + (at_ms + k * every_ms) * kNsPerMs, i);
    }
  }
  std::sort(expected.begin(), expected.end());
  std::vector<std::pair<sim::TimeNs, int>> seen;
  auto run = Scenario::Parse(json{{"events", events}}.dump())
                 .Schedule(channel, scheduler, start_ns,
                           [&](const ControlEvent& e) { seen.emplace_back(e.t_ns, e.index); });
  scheduler.RunUntilIdle();
  RC_ASSERT(seen == expected);
  RC_ASSERT(run->done());
}

}  // namespace
}  // namespace moco::control
