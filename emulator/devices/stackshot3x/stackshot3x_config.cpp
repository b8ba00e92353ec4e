// The StackShot 3X active configuration as stored in NVM slots
// (stackshot-protocol.txt CC_RAIL_CONFIG_SAVE / CC_RAIL_CONFIG_LOAD).
#include <array>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "base/json_fields.h"
#include "devices/stackshot3x/stackshot3x.h"

namespace moco::devices {
namespace {

using base::JsonFields;
using base::kRequired;
using nlohmann::json;

// Every field of a saved configuration is required, of its member's type and
// within its range; the value read replaces `out`.
template <typename T>
void Take(JsonFields& f, const char* key, T& out) {
  if constexpr (std::is_same_v<T, bool>) {
    out = f.Bool(key, out, kRequired);
  } else if constexpr (std::is_same_v<T, std::string>) {
    out = f.String(key, out, 0, kRequired);
  } else if constexpr (std::is_floating_point_v<T>) {
    const double max = std::numeric_limits<T>::max();
    out = static_cast<T>(f.Number(key, out, -max, max, kRequired));
  } else {
    out = static_cast<T>(f.Int(key, out, 0, std::numeric_limits<T>::max(), kRequired));
  }
}

template <typename E>
void TakeEnum(JsonFields& f, const char* key, E& out, unsigned max_exclusive) {
  out = static_cast<E>(f.Int(key, static_cast<int64_t>(out), 0, max_exclusive - 1, kRequired));
}

// Two numbers [a, b].
void TakePair(JsonFields& f, const char* key, std::array<float, 2>& out) {
  const double max = std::numeric_limits<double>::max();
  const std::vector<double> v = f.Numbers(key, -max, max, 2, 2, kRequired);
  if (v.size() == 2) out = {static_cast<float>(v[0]), static_cast<float>(v[1])};
}

}  // namespace

Stackshot3xConfig Stackshot3xConfig::Defaults(const Stackshot3xProfile& profile) {
  Stackshot3xConfig c;
  for (size_t i = 0; i < c.axes.size(); ++i) {
    c.axes[i].distance_per_rev_mm = profile.axes[i].distance_per_rev_mm;
  }
  return c;
}

json Stackshot3xConfig::ToJson() const {
  json shutters_j = json::array();
  for (const Shutter& s : shutters) {
    shutters_j.push_back({{"num_pulses", s.num_pulses},
                          {"pulse_time_s", {s.pulse_time_s[0], s.pulse_time_s[1]}},
                          {"off_time_s", {s.off_time_s[0], s.off_time_s[1]}}});
  }
  json axes_j = json::array();
  for (const Axis& a : axes) {
    axes_j.push_back({{"torque", a.torque},
                      {"holding_torque", a.holding_torque},
                      {"speed_mm_per_s", a.speed_mm_per_s},
                      {"move_speed_mm_per_s", a.move_speed_mm_per_s},
                      {"ramp_time_s", a.ramp_time_s},
                      {"distance_per_rev_mm", a.distance_per_rev_mm},
                      {"backlash_mm", a.backlash_mm},
                      {"reverse", a.reverse},
                      {"rotary_backlash_deg", a.rotary_backlash_deg},
                      {"rotary_ratio", a.rotary_ratio},
                      {"rotary_degrees", a.rotary_degrees},
                      {"shutter", static_cast<unsigned>(a.shutter)},
                      {"num_steps", a.num_steps},
                      {"total_distance_mm", a.total_distance_mm},
                      {"distance_per_step_mm", a.distance_per_step_mm}});
  }
  return json{{"name", name},
              {"backlight", backlight},
              {"mode", static_cast<unsigned>(mode)},
              {"units", static_cast<unsigned>(units)},
              {"global_mode", static_cast<unsigned>(global_mode)},
              {"settle_time_s", settle_time_s},
              {"timelapse_s", timelapse_s},
              {"shutter_disable", shutter_disable},
              {"auto_return", auto_return},
              {"toff_final", toff_final},
              {"io_mode", static_cast<unsigned>(io_mode)},
              {"io_dir", static_cast<unsigned>(io_dir)},
              {"shutters", shutters_j},
              {"axes", axes_j}};
}

std::optional<Stackshot3xConfig> Stackshot3xConfig::FromJson(const json& j) {
  // Keys it does not know are passed over: a state file may come from a later
  // version.
  JsonFields f(j);
  Stackshot3xConfig c;
  Take(f, "name", c.name);
  Take(f, "backlight", c.backlight);
  TakeEnum(f, "mode", c.mode, 8);
  TakeEnum(f, "units", c.units, stackshot::kUnitsMaxSpec);
  TakeEnum(f, "global_mode", c.global_mode, stackshot::kGlobalModeMax);
  Take(f, "settle_time_s", c.settle_time_s);
  Take(f, "timelapse_s", c.timelapse_s);
  Take(f, "shutter_disable", c.shutter_disable);
  Take(f, "auto_return", c.auto_return);
  Take(f, "toff_final", c.toff_final);
  TakeEnum(f, "io_mode", c.io_mode, stackshot::kIoModeMax);
  TakeEnum(f, "io_dir", c.io_dir, stackshot::kDirectionMax);
  const json* shutters = f.Array("shutters", kRequired);
  const json* axes = f.Array("axes", kRequired);
  if (f.failed() || shutters->size() != c.shutters.size() || axes->size() != c.axes.size()) {
    return std::nullopt;
  }
  for (size_t i = 0; i < c.shutters.size(); ++i) {
    JsonFields s = f.Item("shutters", i);
    Shutter& o = c.shutters[i];
    Take(s, "num_pulses", o.num_pulses);
    TakePair(s, "pulse_time_s", o.pulse_time_s);
    TakePair(s, "off_time_s", o.off_time_s);
  }
  for (size_t i = 0; i < c.axes.size(); ++i) {
    JsonFields a = f.Item("axes", i);
    Axis& o = c.axes[i];
    Take(a, "torque", o.torque);
    Take(a, "holding_torque", o.holding_torque);
    Take(a, "speed_mm_per_s", o.speed_mm_per_s);
    Take(a, "move_speed_mm_per_s", o.move_speed_mm_per_s);
    Take(a, "ramp_time_s", o.ramp_time_s);
    Take(a, "distance_per_rev_mm", o.distance_per_rev_mm);
    Take(a, "backlash_mm", o.backlash_mm);
    Take(a, "reverse", o.reverse);
    Take(a, "rotary_backlash_deg", o.rotary_backlash_deg);
    Take(a, "rotary_ratio", o.rotary_ratio);
    Take(a, "rotary_degrees", o.rotary_degrees);
    TakeEnum(a, "shutter", o.shutter, stackshot::kShutterSettingMax);
    Take(a, "num_steps", o.num_steps);
    Take(a, "total_distance_mm", o.total_distance_mm);
    Take(a, "distance_per_step_mm", o.distance_per_step_mm);
    if (o.distance_per_rev_mm <= 0 || o.speed_mm_per_s <= 0 || o.move_speed_mm_per_s <= 0 ||
        o.ramp_time_s < 0) {
      return std::nullopt;
    }
  }
  if (f.failed()) return std::nullopt;
  return c;
}

}  // namespace moco::devices
