// Board and step-driver profiles and the pin trace (FACTS "Step drivers",
// "DFMoco" boards; fixtures/boards/*.json, fixtures/drivers/*.json).
#include "conformance/targets/simavr_pins.h"

#include <algorithm>
#include <cctype>

#include <nlohmann/json.hpp>

#include "base/file_io.h"
#include "base/json_fields.h"

namespace moco::conformance {
namespace {

constexpr std::string_view kBoardDoc = "docs/pins.md";

std::variant<nlohmann::json, std::string> ParseJsonText(std::string_view text,
                                                        const std::string& name) {
  if (text.empty()) return name + ": empty file; write a JSON object (see docs/pins.md)";
  std::string duplicate;
  nlohmann::json j;
  try {
    j = base::ParseJsonNotingDuplicateKeys(text, duplicate);
  } catch (const nlohmann::json::exception&) {
    return name + ": not valid JSON; write a JSON object (see docs/pins.md)";
  }
  if (!duplicate.empty()) {
    return name + ": field \"" + duplicate +
           "\" is given twice in one object; only one would count: keep the one you mean and "
           "delete the other";
  }
  return j;
}

std::optional<std::string> ReadText(const std::string& path, const std::string& what,
                                    std::string* text) {
  if (auto err = base::ReadFileBounded(path, text, {.max_bytes = 1 << 20})) {
    return what + " \"" + path + "\": " + *err + "; give a JSON file (see docs/pins.md)";
  }
  return std::nullopt;
}

// Reads an optional pin field ("PD4"); records a problem for anything else.
std::optional<PinRef> ReadPin(base::JsonFields& f, std::string_view key, base::Presence p) {
  const std::string text = f.String(key, "", 8, p);
  if (f.failed() || text.empty()) return std::nullopt;
  auto pin = ParsePinRef(text);
  if (!pin) {
    f.Fail(key, "is \"" + text + "\", not a pin",
           "write the AVR port and bit, e.g. \"PD4\" (Arduino Uno pin 4), or a pin number for "
           "a native target's board, e.g. \"GPIO26\" or \"D26\"");
  }
  return pin;
}

}  // namespace

std::optional<PinRef> ParsePinRef(std::string_view text) {
  for (const std::string_view prefix : {"GPIO", "D"}) {
    if (text.size() <= prefix.size() || text.size() > prefix.size() + 3) continue;
    bool same = true;
    for (size_t i = 0; i < prefix.size(); ++i)
      same = same && std::toupper(static_cast<unsigned char>(text[i])) == prefix[i];
    if (!same) continue;
    int number = 0;
    for (const char c : text.substr(prefix.size())) {
      if (c < '0' || c > '9') return std::nullopt;
      number = number * 10 + (c - '0');
    }
    if (number > 255) return std::nullopt;
    return PinRef{'B', 0, number};
  }
  if (text.size() != 3) return std::nullopt;
  if (std::toupper(static_cast<unsigned char>(text[0])) != 'P') return std::nullopt;
  const char port = static_cast<char>(std::toupper(static_cast<unsigned char>(text[1])));
  if (port < 'A' || port > 'L' || text[2] < '0' || text[2] > '7') return std::nullopt;
  return PinRef{port, static_cast<uint8_t>(text[2] - '0')};
}

std::variant<Board, std::string> ParseBoard(std::string_view text, const std::string& name) {
  auto parsed = ParseJsonText(text, name);
  if (auto* err = std::get_if<std::string>(&parsed)) return *err;
  const nlohmann::json& j = std::get<nlohmann::json>(parsed);
  base::JsonFields f(j, "", std::string(kBoardDoc));
  Board b;
  b.name = f.String("board", "", 64, base::kRequired);
  b.description = f.String("description", "", 1024);
  b.max_step_rate_hz = f.Number("max_step_rate_hz", 20000, 1, 10e6, base::kOptional, "Hz");
  b.reversal_max_rate_hz = f.Number("reversal_max_rate_hz", 1000, 1, 10e6, base::kOptional, "Hz");
  b.report_period_ms = f.Int("report_period_ms", 1000, 1, 3'600'000);
  if (const nlohmann::json* motors = f.Array("motors", base::kRequired)) {
    if (motors->empty() || motors->size() > 16) {
      f.Fail("motors", "holds " + std::to_string(motors->size()) + " motors",
             "list 1..16 motors, each {\"step\": \"PD4\", \"dir\": \"PD5\"}");
    }
    for (size_t i = 0; i < motors->size() && i < 16 && !f.failed(); ++i) {
      base::JsonFields m = f.Item("motors", i);
      BoardMotor bm;
      const auto step = ReadPin(m, "step", base::kRequired);
      const auto dir = ReadPin(m, "dir", base::kRequired);
      bm.enable = ReadPin(m, "enable", base::kOptional);
      m.Finish();
      if (step && dir) {
        bm.step = *step;
        bm.dir = *dir;
        b.motors.push_back(bm);
      }
    }
  }
  {
    base::JsonFields c = f.Child("camera");
    b.shutter = ReadPin(c, "shutter", base::kOptional);
    b.focus = ReadPin(c, "focus", base::kOptional);
    if (f.Has("camera")) c.Finish();
  }
  f.Finish();
  if (f.failed()) return name + ": " + f.problem().Message();
  // One pin, one signal: a pin named twice is a typing error.
  std::vector<PinRef> used;
  for (const BoardMotor& m : b.motors) {
    used.push_back(m.step);
    used.push_back(m.dir);
    if (m.enable) used.push_back(*m.enable);
  }
  if (b.shutter) used.push_back(*b.shutter);
  if (b.focus) used.push_back(*b.focus);
  for (size_t i = 0; i < used.size(); ++i) {
    for (size_t k = i + 1; k < used.size(); ++k) {
      if (used[i] == used[k]) {
        return name + ": pin " + used[i].Name() +
               " is named twice; give each motor and camera signal its own pin";
      }
    }
  }
  return b;
}

std::variant<Board, std::string> LoadBoard(const std::string& path) {
  std::string text;
  if (auto err = ReadText(path, "board profile", &text)) return *err;
  return ParseBoard(text, "board profile \"" + path + "\"");
}

const std::vector<DriverProfile>& BuiltInDrivers() {
  static const std::vector<DriverProfile> kDrivers = {
      {"a4988", 1000, 1000, 200, 200,
       "Allegro A4988 datasheet, timing: STEP high/low >= 1 us, DIR setup/hold >= 200 ns"},
      {"drv8825", 1900, 1900, 650, 650,
       "TI DRV8825 datasheet, timing: STEP high/low >= 1.9 us, DIR setup/hold >= 650 ns"},
      {"tmc2209", 100, 100, 100, 100,
       "Trinamic TMC2209 datasheet, STEP/DIR timing: about 100 ns high, low, setup, hold"},
  };
  return kDrivers;
}

std::variant<DriverProfile, std::string> ParseDriver(std::string_view text,
                                                     const std::string& name) {
  auto parsed = ParseJsonText(text, name);
  if (auto* err = std::get_if<std::string>(&parsed)) return *err;
  const nlohmann::json& j = std::get<nlohmann::json>(parsed);
  base::JsonFields f(j, "", std::string(kBoardDoc));
  DriverProfile d;
  constexpr int64_t kMaxNs = 1'000'000'000;
  d.name = f.String("driver", "", 64, base::kRequired);
  d.step_high_min_ns = f.Int("step_high_min_ns", 0, 0, kMaxNs, base::kRequired);
  d.step_low_min_ns = f.Int("step_low_min_ns", 0, 0, kMaxNs, base::kRequired);
  d.dir_setup_min_ns = f.Int("dir_setup_min_ns", 0, 0, kMaxNs, base::kRequired);
  d.dir_hold_min_ns = f.Int("dir_hold_min_ns", 0, 0, kMaxNs, base::kRequired);
  d.source = f.String("source", "", 1024);
  f.Finish();
  if (f.failed()) return name + ": " + f.problem().Message();
  return d;
}

std::variant<DriverProfile, std::string> LoadDriver(const std::string& name_or_path) {
  for (const DriverProfile& d : BuiltInDrivers()) {
    if (d.name == name_or_path) return d;
  }
  if (name_or_path.find('/') == std::string::npos &&
      name_or_path.find(".json") == std::string::npos) {
    std::string known;
    for (const DriverProfile& d : BuiltInDrivers()) known += (known.empty() ? "" : ", ") + d.name;
    return "--driver " + name_or_path + ": not a known driver; give one of " + known +
           ", or the path of a driver profile (JSON, see fixtures/drivers/)";
  }
  std::string text;
  if (auto err = ReadText(name_or_path, "driver profile", &text)) return *err;
  return ParseDriver(text, "driver profile \"" + name_or_path + "\"");
}

bool PinSignal::LevelAt(sim::TimeNs t_ns) const {
  auto it = std::upper_bound(edges.begin(), edges.end(), t_ns,
                             [](sim::TimeNs t, const PinEdge& e) { return t < e.t_ns; });
  return it == edges.begin() ? initial : std::prev(it)->level;
}

PinTrace PinTrace::For(const Board& board) {
  PinTrace t;
  t.board = board.name;
  auto add = [&](std::string name, PinRef pin) {
    t.signals.push_back(PinSignal{std::move(name), pin, false, {}});
    return static_cast<int>(t.signals.size() - 1);
  };
  for (size_t i = 0; i < board.motors.size(); ++i) {
    const std::string m = "m" + std::to_string(i + 1);
    MotorSignals ms;
    ms.step = add(m + "_step", board.motors[i].step);
    ms.dir = add(m + "_dir", board.motors[i].dir);
    if (board.motors[i].enable) ms.enable = add(m + "_enable", *board.motors[i].enable);
    t.motors.push_back(ms);
  }
  if (board.shutter) t.shutter = add("shutter", *board.shutter);
  if (board.focus) t.focus = add("focus", *board.focus);
  return t;
}

size_t PinTrace::EdgeCount() const {
  size_t n = 0;
  for (const PinSignal& s : signals) n += s.edges.size();
  return n;
}

}  // namespace moco::conformance
