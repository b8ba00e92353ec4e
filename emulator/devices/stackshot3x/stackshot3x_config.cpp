// The StackShot 3X active configuration as stored in NVM slots
// (stackshot-protocol.txt CC_RAIL_CONFIG_SAVE / CC_RAIL_CONFIG_LOAD).
#include <cmath>

#include "devices/stackshot3x/stackshot3x.h"

namespace moco::devices {
namespace {

using nlohmann::json;

template <typename T>
bool Take(const json& j, const char* key, T& out) {
  const auto it = j.find(key);
  if (it == j.end()) return false;
  if constexpr (std::is_same_v<T, bool>) {
    if (!it->is_boolean()) return false;
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!it->is_string()) return false;
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!it->is_number()) return false;
  } else {
    if (!it->is_number_unsigned()) return false;
    if (it->get<uint64_t>() > std::numeric_limits<T>::max()) return false;
  }
  out = it->get<T>();
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(out)) return false;
  }
  return true;
}

template <typename E>
bool TakeEnum(const json& j, const char* key, E& out, unsigned max_exclusive) {
  uint8_t v = 0;
  if (!Take(j, key, v) || v >= max_exclusive) return false;
  out = static_cast<E>(v);
  return true;
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
  if (!j.is_object()) return std::nullopt;
  Stackshot3xConfig c;
  bool ok = Take(j, "name", c.name) && Take(j, "backlight", c.backlight) &&
            TakeEnum(j, "mode", c.mode, 8) &&
            TakeEnum(j, "units", c.units, stackshot::kUnitsMaxSpec) &&
            TakeEnum(j, "global_mode", c.global_mode, stackshot::kGlobalModeMax) &&
            Take(j, "settle_time_s", c.settle_time_s) && Take(j, "timelapse_s", c.timelapse_s) &&
            Take(j, "shutter_disable", c.shutter_disable) &&
            Take(j, "auto_return", c.auto_return) && Take(j, "toff_final", c.toff_final) &&
            TakeEnum(j, "io_mode", c.io_mode, stackshot::kIoModeMax) &&
            TakeEnum(j, "io_dir", c.io_dir, stackshot::kDirectionMax);
  if (!ok) return std::nullopt;
  const auto sh = j.find("shutters");
  const auto ax = j.find("axes");
  if (sh == j.end() || !sh->is_array() || sh->size() != c.shutters.size()) return std::nullopt;
  if (ax == j.end() || !ax->is_array() || ax->size() != c.axes.size()) return std::nullopt;
  for (size_t i = 0; i < c.shutters.size(); ++i) {
    const json& s = (*sh)[i];
    Shutter& o = c.shutters[i];
    if (!s.is_object() || !Take(s, "num_pulses", o.num_pulses)) return std::nullopt;
    for (const char* key : {"pulse_time_s", "off_time_s"}) {
      const auto it = s.find(key);
      if (it == s.end() || !it->is_array() || it->size() != 2) return std::nullopt;
      auto& dst = std::string_view(key) == "pulse_time_s" ? o.pulse_time_s : o.off_time_s;
      for (size_t k = 0; k < 2; ++k) {
        if (!(*it)[k].is_number()) return std::nullopt;
        dst[k] = (*it)[k].get<float>();
      }
    }
  }
  for (size_t i = 0; i < c.axes.size(); ++i) {
    const json& a = (*ax)[i];
    Axis& o = c.axes[i];
    ok = a.is_object() && Take(a, "torque", o.torque) &&
         Take(a, "holding_torque", o.holding_torque) &&
         Take(a, "speed_mm_per_s", o.speed_mm_per_s) &&
         Take(a, "move_speed_mm_per_s", o.move_speed_mm_per_s) &&
         Take(a, "ramp_time_s", o.ramp_time_s) &&
         Take(a, "distance_per_rev_mm", o.distance_per_rev_mm) &&
         Take(a, "backlash_mm", o.backlash_mm) && Take(a, "reverse", o.reverse) &&
         Take(a, "rotary_backlash_deg", o.rotary_backlash_deg) &&
         Take(a, "rotary_ratio", o.rotary_ratio) && Take(a, "rotary_degrees", o.rotary_degrees) &&
         TakeEnum(a, "shutter", o.shutter, stackshot::kShutterSettingMax) &&
         Take(a, "num_steps", o.num_steps) && Take(a, "total_distance_mm", o.total_distance_mm) &&
         Take(a, "distance_per_step_mm", o.distance_per_step_mm);
    if (!ok || o.distance_per_rev_mm <= 0 || o.speed_mm_per_s <= 0 || o.move_speed_mm_per_s <= 0 ||
        o.ramp_time_s < 0) {
      return std::nullopt;
    }
  }
  return c;
}

}  // namespace moco::devices
