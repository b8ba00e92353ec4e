// Reading and writing the DMC-16 profile (see dmc16_profile.h).
#include "devices/dmc16/dmc16_profile.h"

#include <filesystem>

#include <cstdint>
#include <fstream>
#include <sstream>

#include "base/format.h"
#include "devices/profile.h"

namespace moco::devices {
namespace {

// The names of the behaviour switches that take one of a few values.
template <class E>
struct Choice {
  const char* name;
  E value;
};
constexpr Choice<Dmc16Behaviour::LengthChecks> kLengthChecks[] = {
    {"spec", Dmc16Behaviour::LengthChecks::kSpec},
    {"move_and_reset_only", Dmc16Behaviour::LengthChecks::kMoveAndResetOnly}};
constexpr Choice<Dmc16Behaviour::PositionConfirm> kPositionConfirm[] = {
    {"after_ack", Dmc16Behaviour::PositionConfirm::kAfterAck},
    {"before_ack", Dmc16Behaviour::PositionConfirm::kBeforeAck}};
constexpr Choice<Dmc16Behaviour::JogSpeedScale> kJogSpeedScale[] = {
    {"spec", Dmc16Behaviour::JogSpeedScale::kSpec},
    {"per_10000", Dmc16Behaviour::JogSpeedScale::kPer10000}};
constexpr Choice<Dmc16Behaviour::Coupling> kCoupling[] = {
    {"follows_previous", Dmc16Behaviour::Coupling::kFollowsPrevious},
    {"drives_next", Dmc16Behaviour::Coupling::kDrivesNext}};

template <class E, size_t N>
E GetChoice(ProfileReader& r, std::string_view key, E def, const Choice<E> (&choices)[N]) {
  if (!r.Has(key)) return def;
  const std::string text = r.GetString(key, "", 64);
  std::string names;
  for (const Choice<E>& c : choices) {
    if (text == c.name) return c.value;
    names += std::string(names.empty() ? "" : " or ") + "\"" + c.name + "\"";
  }
  r.Fail(key, "is \"" + text + "\"", "use " + names);
}

template <class E, size_t N>
const char* ChoiceName(E value, const Choice<E> (&choices)[N]) {
  for (const Choice<E>& c : choices) {
    if (c.value == value) return c.name;
  }
  return choices[0].name;
}

}  // namespace

dmc::HiResponse Dmc16Profile::Hi() const {
  dmc::HiResponse hi;
  hi.name = dmc::HiResponse::MakeName(name);
  hi.fw_major = fw_major;
  hi.fw_minor = fw_minor;
  hi.fw_rev = fw_rev;
  hi.motor_count = motor_count;
  hi.dmx_count = dmx_channels;
  hi.gio_out_count = gio_outputs;
  hi.gio_in_count = gio_inputs;
  hi.hw_limit_count = hw_limit_sets;
  hi.upload_frame_count = upload_frame_count;
  hi.capabilities = Advertised();
  hi.protocol_version = protocol_version;
  return hi;
}

namespace {

// The capability bits of the virtual modes and the aim point (0x007c).
constexpr uint32_t kVirtual = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                              dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz | dmc::kCapAimPoint;

// "virtual_axes": the virtual modes advertised and the virtual jog speeds.
void ReadVirtualAxes(ProfileReader& r, Dmc16Profile& p) {
  ProfileReader v = r.Child("virtual_axes");
  p.virtual_axes.enabled = v.GetBool("enabled", p.virtual_axes.enabled);
  p.virtual_axes.capabilities = v.GetFlags("capabilities", p.virtual_axes.capabilities);
  if ((p.virtual_axes.capabilities & ~kVirtual) != 0) {
    v.Fail("capabilities", "has bits outside the virtual modes and the aim point",
           "keep to 0x0004, 0x0008, 0x0010, 0x0020 and 0x0040");
  }
  if ((p.virtual_axes.capabilities & dmc::kCapAimPoint) != 0 &&
      (p.virtual_axes.capabilities & (kVirtual & ~dmc::kCapAimPoint)) == 0) {
    v.Fail("capabilities", "advertises the aim point without a virtual mode",
           "add the mode bits (0x003c, all four as the real firmware does)");
  }
  p.virtual_axes.jog_line_units_per_s =
      v.GetNumber("jog_line_units_per_s", p.virtual_axes.jog_line_units_per_s, 1e-6, 1e6);
  p.virtual_axes.jog_angle_deg_per_s =
      v.GetNumber("jog_angle_deg_per_s", p.virtual_axes.jog_angle_deg_per_s, 1e-6, 1e6);
  v.Finish();
}

// "physical_rig": the rig profile the motors drive (read relative to the
// device profile's folder, `base_dir`) and the motor of each joint.
void ReadPhysicalRig(ProfileReader& r, Dmc16Profile& p, const std::string& base_dir) {
  ProfileReader v = r.Child("physical_rig");
  p.physical_rig.enabled = v.GetBool("enabled", true);
  p.physical_rig.rig_path = v.GetString("rig", "", 4096);
  if (p.physical_rig.rig_path.empty()) {
    v.Fail("rig", "is missing", "name a rig profile, e.g. \"rig\": \"../rigs/boom-jib.json\"");
  }
  if (v.Has("motors")) {
    ProfileReader m = v.Child("motors");
    for (size_t joint = 0; joint < physics::kJointCount; ++joint) {
      p.physical_rig.motors[joint] = static_cast<int>(
          m.GetInt(physics::kJointNames[joint], p.physical_rig.motors[joint], 0, p.motor_count));
    }
    m.Finish();
  }
  for (size_t joint = 0; joint < physics::kJointCount; ++joint) {
    const int motor = p.physical_rig.motors[joint];
    if (motor > p.motor_count) {
      v.Fail("motors", "names a motor beyond motor_count",
             "use motors 1.." + std::to_string(p.motor_count) + " or 0 for a fixed joint");
    }
    // One stepper drives one joint: a motor shared by two joints would
    // command both with the same steps.
    for (size_t other = 0; other < joint && motor != 0; ++other) {
      if (p.physical_rig.motors[other] == motor) {
        v.Fail("motors." + std::string(physics::kJointNames[joint]),
               "is motor " + std::to_string(motor) + ", which already drives the " +
                   std::string(physics::kJointNames[other]),
               "give each joint its own motor, or 0 for a fixed joint");
      }
    }
  }
  // The rig file is read with the device profile, relative to its folder.
  std::filesystem::path rig = p.physical_rig.rig_path;
  if (rig.is_relative() && !base_dir.empty()) {
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::path(base_dir) / rig, ec)) {
      rig = std::filesystem::path(base_dir) / rig;
    }
  }
  const physics::RigProfileResult loaded = physics::ReadRigProfile(rig.string());
  if (!loaded.ok()) {
    v.Fail("rig",
           "(" + rig.string() + ") is not a usable rig profile: " + loaded.error().field + ": " +
               loaded.error().message,
           "fix the rig profile (docs/rig-dynamics.md)");
  }
  p.physical_rig.rig = loaded.value();
  v.Finish();
}

// "behaviour": the switches between the firmware behaviours that differ.
void ReadBehaviour(ProfileReader& r, Dmc16Behaviour& v) {
  ProfileReader b = r.Child("behaviour");
  v.receive_buffer_bytes = static_cast<uint32_t>(b.GetInt(
      "receive_buffer_bytes", v.receive_buffer_bytes, dmc::kReceiveBufferSize, kMaxReceiveBuffer));
  v.rescan_after_bad_frame = b.GetBool("rescan_after_bad_frame", v.rescan_after_bad_frame);
  v.move_response = b.GetBool("move_response", v.move_response);
  v.position_response = b.GetBool("position_response", v.position_response);
  v.gio_in_request = b.GetBool("gio_in_request", v.gio_in_request);
  v.host_acks_silent = b.GetBool("host_acks_silent", v.host_acks_silent);
  v.jog_speed_checked = b.GetBool("jog_speed_checked", v.jog_speed_checked);
  v.disabled_motors_ignore_motion =
      b.GetBool("disabled_motors_ignore_motion", v.disabled_motors_ignore_motion);
  v.soft_limits_bound_moves = b.GetBool("soft_limits_bound_moves", v.soft_limits_bound_moves);
  v.arming_ms = static_cast<uint32_t>(b.GetInt("arming_ms", v.arming_ms, 0, 10'000));
  v.stop_all_lockout_ms =
      static_cast<uint32_t>(b.GetInt("stop_all_lockout_ms", v.stop_all_lockout_ms, 0, 60'000));
  v.stop_all_within_ms =
      static_cast<uint32_t>(b.GetInt("stop_all_within_ms", v.stop_all_within_ms, 0, 60'000));
  v.positions_truncate = b.GetBool("positions_truncate", v.positions_truncate);
  v.preroll_move_time_is_start_frame =
      b.GetBool("preroll_move_time_is_start_frame", v.preroll_move_time_is_start_frame);
  v.rt_end_at_last_frame = b.GetBool("rt_end_at_last_frame", v.rt_end_at_last_frame);
  v.rt_end_after_shot = b.GetBool("rt_end_after_shot", v.rt_end_after_shot);
  v.length_checks = GetChoice(b, "length_checks", v.length_checks, kLengthChecks);
  v.set_speed_checked = b.GetBool("set_speed_checked", v.set_speed_checked);
  v.position_confirm = GetChoice(b, "position_confirm", v.position_confirm, kPositionConfirm);
  v.jog_speed_scale = GetChoice(b, "jog_speed_scale", v.jog_speed_scale, kJogSpeedScale);
  v.jog_horizon_ms = static_cast<uint32_t>(b.GetInt("jog_horizon_ms", v.jog_horizon_ms, 0, 60'000));
  v.coupling = GetChoice(b, "coupling", v.coupling, kCoupling);
  // The real-time engine (dmc16_profile.h).
  v.playback_tick_ms =
      static_cast<uint32_t>(b.GetInt("playback_tick_ms", v.playback_tick_ms, 0, 100));
  if (v.playback_tick_ms != 0 && v.playback_tick_ms < 5) {
    b.Fail("playback_tick_ms", "is " + std::to_string(v.playback_tick_ms),
           "use 0 (continuous playback) or a tick of 5..100 ms (dmc-lite: 20)");
  }
  v.upload_index_from_start_frame =
      b.GetBool("upload_index_from_start_frame", v.upload_index_from_start_frame);
  if (v.upload_index_from_start_frame && v.playback_tick_ms == 0) {
    b.Fail("upload_index_from_start_frame", "is true without a playback tick",
           "set \"playback_tick_ms\" (dmc-lite: 20), the engine that reads the upload so");
  }
  v.position_frame_clamped = b.GetBool("position_frame_clamped", v.position_frame_clamped);
  v.rt_end_after_stop = b.GetBool("rt_end_after_stop", v.rt_end_after_stop);
  v.trigger_frames_checked = b.GetBool("trigger_frames_checked", v.trigger_frames_checked);
  v.camera_angles_checked = b.GetBool("camera_angles_checked", v.camera_angles_checked);
  v.zero_preroll_nan = b.GetBool("zero_preroll_nan", v.zero_preroll_nan);
  if (v.zero_preroll_nan && v.playback_tick_ms == 0) {
    b.Fail("zero_preroll_nan", "is true without a playback tick",
           "set \"playback_tick_ms\" (dmc-lite: 20), the engine whose ramp has it");
  }
  v.unsolicited_id_zero = b.GetBool("unsolicited_id_zero", v.unsolicited_id_zero);
  v.reset_refused_while_any_moves =
      b.GetBool("reset_refused_while_any_moves", v.reset_refused_while_any_moves);
  v.host_hard_stop = b.GetBool("host_hard_stop", v.host_hard_stop);
  b.Finish();
}

// "limit_sets": the hardware limit switches of each set.
void ReadLimitSets(ProfileReader& r, Dmc16Profile& p, const std::string& where) {
  const nlohmann::json& sets = r.GetRaw("limit_sets");
  if (!sets.is_null()) {
    if (!sets.is_array()) {
      r.Fail("limit_sets", "must be an array", "write [ {\"set\": 1, \"low_steps\": -1000}, ... ]");
    }
    for (size_t i = 0; i < sets.size(); ++i) {
      ProfileReader s(sets[i], where, "limit_sets[" + std::to_string(i) + "]");
      Dmc16LimitSet ls;
      ls.set = static_cast<int>(s.GetInt("set", 0, 1, p.hw_limit_sets == 0 ? 1 : p.hw_limit_sets));
      if (!s.Has("set")) s.Fail("set", "is missing", "give the limit set number 1..hw_limit_sets");
      if (p.hw_limit_sets == 0) {
        s.Fail("set", "names a set, but hw_limit_sets is 0",
               "raise hw_limit_sets or drop limit_sets");
      }
      constexpr int64_t kI32Min = INT32_MIN, kI32Max = INT32_MAX;
      if (s.Has("low_steps")) ls.low_steps = s.GetInt("low_steps", 0, kI32Min, kI32Max);
      if (s.Has("high_steps")) ls.high_steps = s.GetInt("high_steps", 0, kI32Min, kI32Max);
      if (ls.low_steps && ls.high_steps && *ls.low_steps >= *ls.high_steps) {
        s.Fail("high_steps", "is not above low_steps", "place the high switch above the low one");
      }
      s.Finish();
      p.limit_sets.push_back(ls);
    }
  }
}

}  // namespace

Dmc16Profile Dmc16ProfileFromJson(const nlohmann::json& j, const std::string& where,
                                  const std::string& base_dir) {
  Dmc16Profile p;
  ProfileReader r(j, where);
  const std::string model = r.GetString("model", "dmc16");
  if (model != "dmc16") {
    r.Fail("model", "is \"" + model + "\", but this is a DMC-16 profile",
           "use \"dmc16\", or pass the profile to the device it describes");
  }
  p.name = r.GetString("name", p.name, dmc::kHiNameSize);
  {
    ProfileReader fw = r.Child("firmware");
    p.fw_major = static_cast<uint8_t>(fw.GetInt("major", p.fw_major, 0, 255));
    p.fw_minor = static_cast<uint8_t>(fw.GetInt("minor", p.fw_minor, 0, 255));
    p.fw_rev = static_cast<uint8_t>(fw.GetInt("rev", p.fw_rev, 0, 255));
    fw.Finish();
  }
  p.motor_count = static_cast<uint8_t>(r.GetInt("motor_count", p.motor_count, 0, dmc::kMaxMotors));
  p.dmx_channels =
      static_cast<uint16_t>(r.GetInt("dmx_channels", p.dmx_channels, 0, dmc::kMaxDmxChannels));
  p.gio_outputs = static_cast<uint8_t>(r.GetInt("gio_outputs", p.gio_outputs, 0, dmc::kMaxGio));
  p.gio_inputs = static_cast<uint8_t>(r.GetInt("gio_inputs", p.gio_inputs, 0, dmc::kMaxGio));
  p.hw_limit_sets = static_cast<uint8_t>(r.GetInt("hw_limit_sets", p.hw_limit_sets, 0, 0x7f));
  // The store is sized by this: 1M frames of 32 motors is 128 MiB, the most accepted.
  p.upload_frame_count =
      static_cast<uint32_t>(r.GetInt("upload_frame_count", p.upload_frame_count, 1, 1'000'000));
  p.capabilities = r.GetFlags("capabilities", p.capabilities);
  if ((p.capabilities & kVirtual) != 0) {
    r.Fail("capabilities", "carries virtual-mode or aim-point bits (0x007c)",
           "clear them and write \"virtual_axes\": {\"enabled\": true} (it advertises 0x007c)");
  }
  ReadVirtualAxes(r, p);
  if (r.Has("physical_rig")) ReadPhysicalRig(r, p, base_dir);
  const int64_t version = r.GetInt("protocol_version", 2, 0, 0xffff);
  p.protocol_version = version == 0 ? std::nullopt : std::optional<uint16_t>(version);
  const int64_t width = r.GetInt("ack_width_bits", 16, 16, 32);
  if (width != 16 && width != 32) {
    r.Fail("ack_width_bits", "is " + std::to_string(width),
           "use 16 (the spec) or 32 (as some firmware writes, docs/device-facts.md)");
  }
  p.ack_width = width == 32 ? dmc::AckWidth::k32 : dmc::AckWidth::k16;
  p.baud = static_cast<uint32_t>(r.GetInt("baud", p.baud, 300, 4'000'000));
  p.usb_bridge = ReadUsbBridge(r, p.usb_bridge);
  p.position_report_interval_ms = static_cast<uint32_t>(
      r.GetInt("position_report_interval_ms", p.position_report_interval_ms, 10, 10'000));
  p.hard_stop_window_ms =
      static_cast<uint32_t>(r.GetInt("hard_stop_window_ms", p.hard_stop_window_ms, 0, 60'000));
  p.gio_debounce_ms =
      static_cast<uint32_t>(r.GetInt("gio_debounce_ms", p.gio_debounce_ms, 0, 10'000));
  p.dmx_ramp_rate_per_s = r.GetNumber("dmx_ramp_rate_per_s", p.dmx_ramp_rate_per_s, 0.001, 1e6);
  {
    ProfileReader m = r.Child("motion");
    p.max_velocity_steps_per_s =
        m.GetNumber("max_velocity_steps_per_s", p.max_velocity_steps_per_s, 0.001, 1e7);
    p.max_accel_steps_per_s2 =
        m.GetNumber("max_accel_steps_per_s2", p.max_accel_steps_per_s2, 0.001, 1e9);
    p.hard_stop_multiple = m.GetNumber("hard_stop_multiple", p.hard_stop_multiple, 1, 1000);
    p.motors_enabled = m.GetBool("motors_enabled", p.motors_enabled);
    m.Finish();
  }
  ReadBehaviour(r, p.behaviour);
  ReadLimitSets(r, p, where);
  r.Finish();
  return p;
}

Dmc16Profile LoadDmc16Profile(const std::string& path) {
  std::string where;
  const nlohmann::json j = ReadProfileFile(path, &where);
  return Dmc16ProfileFromJson(j, where, std::filesystem::path(path).parent_path().string());
}

nlohmann::json Dmc16ProfileToJson(const Dmc16Profile& p) {
  nlohmann::json sets = nlohmann::json::array();
  for (const Dmc16LimitSet& s : p.limit_sets) {
    nlohmann::json e = {{"set", s.set}};
    if (s.low_steps) e["low_steps"] = *s.low_steps;
    if (s.high_steps) e["high_steps"] = *s.high_steps;
    sets.push_back(e);
  }
  nlohmann::json out = {
      {"model", "dmc16"},
      {"name", p.name},
      {"firmware", {{"major", p.fw_major}, {"minor", p.fw_minor}, {"rev", p.fw_rev}}},
      {"motor_count", p.motor_count},
      {"dmx_channels", p.dmx_channels},
      {"gio_outputs", p.gio_outputs},
      {"gio_inputs", p.gio_inputs},
      {"hw_limit_sets", p.hw_limit_sets},
      {"upload_frame_count", p.upload_frame_count},
      {"capabilities", base::Hex(p.capabilities, 4)},
      {"protocol_version", p.protocol_version.value_or(0)},
      {"ack_width_bits", p.ack_width == dmc::AckWidth::k32 ? 32 : 16},
      {"baud", p.baud},
      {"usb_bridge", p.usb_bridge.ToJson()},
      {"position_report_interval_ms", p.position_report_interval_ms},
      {"hard_stop_window_ms", p.hard_stop_window_ms},
      {"gio_debounce_ms", p.gio_debounce_ms},
      {"dmx_ramp_rate_per_s", p.dmx_ramp_rate_per_s},
      {"motion",
       {{"max_velocity_steps_per_s", p.max_velocity_steps_per_s},
        {"max_accel_steps_per_s2", p.max_accel_steps_per_s2},
        {"hard_stop_multiple", p.hard_stop_multiple},
        {"motors_enabled", p.motors_enabled}}},
      {"limit_sets", sets},
      {"behaviour",
       {{"receive_buffer_bytes", p.behaviour.receive_buffer_bytes},
        {"rescan_after_bad_frame", p.behaviour.rescan_after_bad_frame},
        {"move_response", p.behaviour.move_response},
        {"position_response", p.behaviour.position_response},
        {"gio_in_request", p.behaviour.gio_in_request},
        {"host_acks_silent", p.behaviour.host_acks_silent},
        {"jog_speed_checked", p.behaviour.jog_speed_checked},
        {"disabled_motors_ignore_motion", p.behaviour.disabled_motors_ignore_motion},
        {"soft_limits_bound_moves", p.behaviour.soft_limits_bound_moves},
        {"arming_ms", p.behaviour.arming_ms},
        {"stop_all_lockout_ms", p.behaviour.stop_all_lockout_ms},
        {"stop_all_within_ms", p.behaviour.stop_all_within_ms},
        {"positions_truncate", p.behaviour.positions_truncate},
        {"preroll_move_time_is_start_frame", p.behaviour.preroll_move_time_is_start_frame},
        {"rt_end_at_last_frame", p.behaviour.rt_end_at_last_frame},
        {"rt_end_after_shot", p.behaviour.rt_end_after_shot},
        {"length_checks", ChoiceName(p.behaviour.length_checks, kLengthChecks)},
        {"set_speed_checked", p.behaviour.set_speed_checked},
        {"position_confirm", ChoiceName(p.behaviour.position_confirm, kPositionConfirm)},
        {"jog_speed_scale", ChoiceName(p.behaviour.jog_speed_scale, kJogSpeedScale)},
        {"jog_horizon_ms", p.behaviour.jog_horizon_ms},
        {"coupling", ChoiceName(p.behaviour.coupling, kCoupling)},
        {"playback_tick_ms", p.behaviour.playback_tick_ms},
        {"upload_index_from_start_frame", p.behaviour.upload_index_from_start_frame},
        {"position_frame_clamped", p.behaviour.position_frame_clamped},
        {"rt_end_after_stop", p.behaviour.rt_end_after_stop},
        {"trigger_frames_checked", p.behaviour.trigger_frames_checked},
        {"camera_angles_checked", p.behaviour.camera_angles_checked},
        {"zero_preroll_nan", p.behaviour.zero_preroll_nan},
        {"unsolicited_id_zero", p.behaviour.unsolicited_id_zero},
        {"reset_refused_while_any_moves", p.behaviour.reset_refused_while_any_moves},
        {"host_hard_stop", p.behaviour.host_hard_stop}}},
      {"virtual_axes",
       {{"enabled", p.virtual_axes.enabled},
        {"capabilities", base::Hex(p.virtual_axes.capabilities, 4)},
        {"jog_line_units_per_s", p.virtual_axes.jog_line_units_per_s},
        {"jog_angle_deg_per_s", p.virtual_axes.jog_angle_deg_per_s}}},
  };
  if (p.physical_rig.enabled) {
    nlohmann::json motors;
    for (size_t joint = 0; joint < physics::kJointCount; ++joint) {
      motors[std::string(physics::kJointNames[joint])] = p.physical_rig.motors[joint];
    }
    out["physical_rig"] = {{"rig", p.physical_rig.rig_path}, {"motors", motors}};
  }
  return out;
}

}  // namespace moco::devices
