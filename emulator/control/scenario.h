// Scenario files (docs/control.md "Scenario files"): control commands at
// times after a start, validated whole at load, then run on the one clock
// through the control channel's vocabulary.
#ifndef MOCO_CONTROL_SCENARIO_H_
#define MOCO_CONTROL_SCENARIO_H_

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "control/control_channel.h"
#include "sim/scheduler.h"

namespace moco::control {

// A scenario that cannot be used (a start-up error). what() names the file,
// the event index and field, what was found and what to write instead.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The latest time an event may run, after the start: 100 days.
inline constexpr int64_t kMaxScenarioMs = 100LL * 24 * 60 * 60 * 1000;
// The most occurrences of one repeated event.
inline constexpr int64_t kMaxScenarioRepeat = 1'000'000;

// One entry of "events": the command runs at at_ms, at_ms + every_ms, ...,
// `repeat` times in all.
struct ScenarioEvent {
  int index = 0;  // position in "events"
  int64_t at_ms = 0;
  int64_t every_ms = 0;  // 0 when repeat == 1
  int64_t repeat = 1;
  Command command;
};

class ScenarioRun;

// A loaded, validated scenario. Immutable; schedule it any number of times.
class Scenario {
 public:
  // Called for each event as it runs, with its reply (source "scenario",
  // index = the event's index).
  using EventFn = std::function<void(const ControlEvent&)>;

  // Reads and validates `path`. Throws ScenarioError (unreadable file, bad
  // JSON, an event with a missing, unknown or ill-typed field).
  static Scenario Load(const std::filesystem::path& path);
  // The same from text; `where` prefixes messages (e.g. "scenario x.json").
  static Scenario Parse(std::string_view text, std::string where = "scenario");

  const std::vector<ScenarioEvent>& events() const { return events_; }
  const std::string& note() const { return note_; }
  const std::string& where() const { return where_; }
  // Time of the last occurrence after the start (0 for no events).
  int64_t duration_ms() const;

  // Checks every event against `channel` (its device exists or is the only
  // one, motor and set numbers exist, link commands have a link) and throws
  // ScenarioError naming the first that fails; then schedules all of them at
  // start_ns + at_ms on `scheduler`. Events due at the same time run in file
  // order. Each runs through channel.Execute(); a command that fails when it
  // runs (a motor bound to no limit set) is reported with ok false, and the
  // rest still run. `channel` and `scheduler` must outlive the run; destroying
  // the run cancels what has not run yet.
  [[nodiscard]] std::unique_ptr<ScenarioRun> Schedule(ControlChannel& channel,
                                                      sim::Scheduler& scheduler,
                                                      sim::TimeNs start_ns,
                                                      EventFn on_event = nullptr) const;

 private:
  std::string where_;
  std::string note_;
  std::vector<ScenarioEvent> events_;
};

// A scheduled scenario. Not copyable or movable (timers point at it).
class ScenarioRun {
 public:
  ScenarioRun(ControlChannel& channel, sim::Scheduler& scheduler, sim::TimeNs start_ns,
              std::vector<ScenarioEvent> events, Scenario::EventFn on_event);
  ~ScenarioRun();
  ScenarioRun(const ScenarioRun&) = delete;
  ScenarioRun& operator=(const ScenarioRun&) = delete;

  // Cancels every occurrence not yet run. Idempotent.
  void Cancel();
  // Occurrences run so far, and still to run.
  uint64_t executed() const { return executed_; }
  uint64_t remaining() const { return remaining_; }
  bool done() const { return remaining_ == 0; }
  // Scheduler time of the last occurrence.
  sim::TimeNs end_ns() const { return end_ns_; }

 private:
  struct Due {
    sim::TimeNs t_ns;
    size_t event;  // index into events_
    int64_t occurrence;
  };
  void Arm();
  void OnTimer();

  ControlChannel& channel_;
  sim::Scheduler& scheduler_;
  sim::TimeNs start_ns_;
  std::vector<ScenarioEvent> events_;
  Scenario::EventFn on_event_;
  std::vector<Due> heap_;  // min-heap on (t_ns, event)
  sim::Scheduler::TimerId timer_ = sim::Scheduler::kNoTimer;
  uint64_t executed_ = 0;
  uint64_t remaining_ = 0;
  sim::TimeNs end_ns_ = 0;
};

}  // namespace moco::control

#endif  // MOCO_CONTROL_SCENARIO_H_
