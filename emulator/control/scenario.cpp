// Scenario files: load-time validation naming event and field, and a run that
// executes due events in (time, file order) on the scheduler.
#include "control/scenario.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "base/file_io.h"
#include "base/json_fields.h"

namespace moco::control {
namespace {

using nlohmann::json;

const std::vector<std::string> kTimingFields = {"at_ms", "every_ms", "repeat"};
constexpr const char* kFormatExample = R"({"events":[{"at_ms":1500,"cmd":"estop","engaged":true},)"
                                       R"({"at_ms":3000,"cmd":"estop","engaged":false}]})";

std::string TypeNameOf(const json& v) {
  if (v.is_number_integer()) return "an integer";
  if (v.is_number()) return "a number";
  if (v.is_object()) return "an object";
  if (v.is_array()) return "an array";
  return std::string("a ") + v.type_name();
}

// A whole number in [min, max], or nullopt.
std::optional<int64_t> WholeNumber(const json& v, int64_t min, int64_t max) {
  std::optional<int64_t> x;
  if (v.is_number_unsigned()) {
    const uint64_t u = v.get<uint64_t>();
    if (u <= static_cast<uint64_t>(max)) x = static_cast<int64_t>(u);
  } else if (v.is_number_integer()) {
    x = v.get<int64_t>();
  } else if (v.is_number_float()) {
    const double d = v.get<double>();
    if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15) {
      x = static_cast<int64_t>(d);
    }
  }
  if (!x || *x < min || *x > max) return std::nullopt;
  return x;
}

// 1-based line and column of byte `offset` in `text`.
std::string LineColumn(std::string_view text, size_t offset) {
  offset = std::min(offset, text.size());
  size_t line = 1;
  size_t column = 1;
  for (size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + " column " + std::to_string(column);
}

sim::TimeNs SaturatingAdd(sim::TimeNs a, sim::TimeNs b) {
  if (b > 0 && a > std::numeric_limits<sim::TimeNs>::max() - b) {
    return std::numeric_limits<sim::TimeNs>::max();
  }
  return a + b;
}

bool Later(const auto& a, const auto& b) {
  if (a.t_ns != b.t_ns) return a.t_ns > b.t_ns;
  return a.event > b.event;
}

}  // namespace

// ---- Loading ----------------------------------------------------------------

Scenario Scenario::Load(const std::filesystem::path& path) {
  const std::string where = "scenario " + path.string();
  std::string text;
  if (auto error = base::ReadFileBounded(path.string(), &text)) {
    throw ScenarioError(where + " " + *error);
  }
  return Parse(text, where);
}

Scenario Scenario::Parse(std::string_view text, std::string where) {
  json doc;
  std::string duplicate;
  try {
    doc = base::ParseJsonNotingDuplicateKeys(text, duplicate);
  } catch (const json::parse_error& e) {
    throw ScenarioError(where + ": malformed JSON at " +
                        LineColumn(text, e.byte > 0 ? e.byte - 1 : 0) +
                        ": write a JSON object such as " + kFormatExample);
  } catch (const json::exception&) {
    throw ScenarioError(where + ": malformed JSON: a number is out of range (beyond a double)");
  }
  if (!duplicate.empty()) {
    throw ScenarioError(where + ": the key \"" + duplicate +
                        "\" appears twice in one object; give each key once (the last one would "
                        "silently win)");
  }
  if (!doc.is_object()) {
    throw ScenarioError(where + ": the scenario must be a JSON object, found " + TypeNameOf(doc) +
                        "; write e.g. " + kFormatExample);
  }
  Scenario s;
  s.where_ = where;
  for (const auto& [key, value] : doc.items()) {
    if (key != "events" && key != "note") {
      throw ScenarioError(where + ": unknown field \"" + key +
                          "\" at the top level: a scenario has \"events\" and an optional "
                          "\"note\"");
    }
  }
  if (auto it = doc.find("note"); it != doc.end()) {
    if (!it->is_string()) {
      throw ScenarioError(where + ": field \"note\" must be a string, found " + TypeNameOf(*it));
    }
    s.note_ = it->get<std::string>();
  }
  const auto events = doc.find("events");
  if (events == doc.end()) {
    throw ScenarioError(where + ": field \"events\" is missing: write e.g. " + kFormatExample);
  }
  if (!events->is_array()) {
    throw ScenarioError(where + ": field \"events\" must be an array of event objects, found " +
                        TypeNameOf(*events) + "; write e.g. " + kFormatExample);
  }

  int index = 0;
  for (const json& e : *events) {
    const std::string at = where + ": events[" + std::to_string(index) + "]";
    if (!e.is_object()) {
      throw ScenarioError(at + " must be an object, found " + TypeNameOf(e) +
                          "; write e.g. {\"at_ms\":1500,\"cmd\":\"estop\",\"engaged\":true}");
    }
    ScenarioEvent ev;
    ev.index = index;
    const auto at_it = e.find("at_ms");
    if (at_it == e.end()) {
      throw ScenarioError(at +
                          ": field \"at_ms\" is missing: write the time after the start in "
                          "whole milliseconds, e.g. \"at_ms\": 1500");
    }
    const auto at_ms = WholeNumber(*at_it, 0, kMaxScenarioMs);
    if (!at_ms) {
      throw ScenarioError(at + ": field \"at_ms\" must be whole milliseconds 0.." +
                          std::to_string(kMaxScenarioMs) + ", found " + TypeNameOf(*at_it) + " " +
                          at_it->dump(-1, ' ', false, json::error_handler_t::replace));
    }
    ev.at_ms = *at_ms;
    const auto repeat_it = e.find("repeat");
    const auto every_it = e.find("every_ms");
    if (repeat_it != e.end()) {
      const auto repeat = WholeNumber(*repeat_it, 1, kMaxScenarioRepeat);
      if (!repeat) {
        throw ScenarioError(at + ": field \"repeat\" must be the number of runs in all, 1.." +
                            std::to_string(kMaxScenarioRepeat) + ", found " +
                            TypeNameOf(*repeat_it) + " " +
                            repeat_it->dump(-1, ' ', false, json::error_handler_t::replace));
      }
      ev.repeat = *repeat;
    }
    if (every_it != e.end()) {
      const auto every = WholeNumber(*every_it, 1, kMaxScenarioMs);
      if (!every) {
        throw ScenarioError(at + ": field \"every_ms\" must be whole milliseconds 1.." +
                            std::to_string(kMaxScenarioMs) + ", found " + TypeNameOf(*every_it) +
                            " " + every_it->dump(-1, ' ', false, json::error_handler_t::replace));
      }
      if (repeat_it == e.end()) {
        throw ScenarioError(at +
                            ": field \"every_ms\" needs \"repeat\" (the number of runs in "
                            "all), e.g. \"every_ms\": 1000, \"repeat\": 5");
      }
      ev.every_ms = *every;
    } else if (ev.repeat > 1) {
      throw ScenarioError(at + ": field \"repeat\" is " + std::to_string(ev.repeat) +
                          " but \"every_ms\" is missing: add the interval, e.g. \"every_ms\": "
                          "1000");
    }
    if (ev.repeat == 1) ev.every_ms = 0;
    // Last occurrence within the limit (no overflow: both factors are bounded).
    if (ev.at_ms + ev.every_ms * (ev.repeat - 1) > kMaxScenarioMs) {
      throw ScenarioError(at + ": its last run (at_ms + every_ms x (repeat - 1)) falls after " +
                          std::to_string(kMaxScenarioMs) + " ms: lower repeat or every_ms");
    }
    auto parsed = ParseCommand(e, kTimingFields);
    if (auto* err = std::get_if<std::string>(&parsed)) {
      throw ScenarioError(at + " (at_ms " + std::to_string(ev.at_ms) + "): " + *err);
    }
    ev.command = std::get<Command>(std::move(parsed));
    s.events_.push_back(std::move(ev));
    ++index;
  }
  return s;
}

int64_t Scenario::duration_ms() const {
  int64_t end = 0;
  for (const ScenarioEvent& e : events_) end = std::max(end, e.at_ms + e.every_ms * (e.repeat - 1));
  return end;
}

std::unique_ptr<ScenarioRun> Scenario::Schedule(ControlChannel& channel, sim::Scheduler& scheduler,
                                                sim::TimeNs start_ns, EventFn on_event) const {
  for (const ScenarioEvent& e : events_) {
    if (auto problem = channel.Check(e.command)) {
      throw ScenarioError(where_ + ": events[" + std::to_string(e.index) + "] (at_ms " +
                          std::to_string(e.at_ms) + ", \"" +
                          std::string(CommandName(e.command.body)) + "\"): " + *problem);
    }
  }
  return std::make_unique<ScenarioRun>(channel, scheduler, start_ns, events_, std::move(on_event));
}

// ---- Running ----------------------------------------------------------------

ScenarioRun::ScenarioRun(ControlChannel& channel, sim::Scheduler& scheduler, sim::TimeNs start_ns,
                         std::vector<ScenarioEvent> events, Scenario::EventFn on_event)
    : channel_(channel),
      scheduler_(scheduler),
      start_ns_(start_ns),
      events_(std::move(events)),
      on_event_(std::move(on_event)) {
  end_ns_ = start_ns_;
  for (size_t i = 0; i < events_.size(); ++i) {
    const ScenarioEvent& e = events_[i];
    heap_.push_back({SaturatingAdd(start_ns_, e.at_ms * sim::kNsPerMs), i, 0});
    remaining_ += static_cast<uint64_t>(e.repeat);
    end_ns_ = std::max(
        end_ns_, SaturatingAdd(start_ns_, (e.at_ms + e.every_ms * (e.repeat - 1)) * sim::kNsPerMs));
  }
  std::make_heap(heap_.begin(), heap_.end(),
                 [](const Due& a, const Due& b) { return Later(a, b); });
  Arm();
}

ScenarioRun::~ScenarioRun() { Cancel(); }

void ScenarioRun::Cancel() {
  if (timer_ != sim::Scheduler::kNoTimer) scheduler_.Cancel(timer_);
  timer_ = sim::Scheduler::kNoTimer;
  heap_.clear();
  remaining_ = 0;
}

void ScenarioRun::Arm() {
  if (heap_.empty()) return;
  timer_ = scheduler_.At(heap_.front().t_ns, [this] {
    timer_ = sim::Scheduler::kNoTimer;
    OnTimer();
  });
}

void ScenarioRun::OnTimer() {
  const auto later = [](const Due& a, const Due& b) { return Later(a, b); };
  const sim::TimeNs now = scheduler_.Now();
  // Every occurrence due by now, in (time, file order). A command may cancel
  // the run from the event callback; the heap is then empty.
  while (!heap_.empty() && heap_.front().t_ns <= now) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const Due due = heap_.back();
    heap_.pop_back();
    const ScenarioEvent& e = events_[due.event];
    if (due.occurrence + 1 < e.repeat) {
      heap_.push_back(
          {SaturatingAdd(due.t_ns, e.every_ms * sim::kNsPerMs), due.event, due.occurrence + 1});
      std::push_heap(heap_.begin(), heap_.end(), later);
    }
    --remaining_;
    ++executed_;
    ControlEvent ev;
    ev.t_ns = now;
    ev.source = "scenario";
    ev.index = e.index;
    ev.request = ToJson(e.command);
    ev.reply = channel_.Execute(e.command, "scenario", e.index);
    if (on_event_) on_event_(ev);
  }
  if (timer_ == sim::Scheduler::kNoTimer) Arm();
}

}  // namespace moco::control
