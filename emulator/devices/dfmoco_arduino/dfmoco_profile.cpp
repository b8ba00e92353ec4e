// DFMoco profile fields with errors naming the field and the fix (see dfmoco_profile.h).
#include "devices/dfmoco_arduino/dfmoco_profile.h"

#include <array>
#include <fstream>
#include <sstream>
#include <utility>

#include "devices/profile.h"

namespace moco::devices {
namespace {

constexpr std::array<std::pair<DfmocoFirmware, std::string_view>, 4> kFirmwares = {{
    {DfmocoFirmware::k1_2_7, "1.2.7"},
    {DfmocoFirmware::k1_3_0, "1.3.0"},
    {DfmocoFirmware::k1_3_1, "1.3.1"},
    {DfmocoFirmware::k2_0_0, "2.0.0"},
}};

}  // namespace

std::string_view BoardName(DfmocoBoard board) {
  return board == DfmocoBoard::kMega ? "mega" : "uno";
}

std::string_view FirmwareVersion(DfmocoFirmware firmware) {
  for (const auto& [f, name] : kFirmwares) {
    if (f == firmware) return name;
  }
  return "2.0.0";
}

dfmoco::Dialect DfmocoProfile::Dialect() const {
  return dfmoco::Dialect{ProtocolMajor(), std::string(FirmwareVersion(firmware)), MotorCount(),
                         false};
}

DfmocoProfile DfmocoProfile::FromJson(const nlohmann::json& object, const std::string& where) {
  ProfileReader r(object, where);
  DfmocoProfile p;
  const std::string device = r.GetString("device", "dfmoco");
  if (device != "dfmoco") {
    r.Fail("device", "is \"" + device + "\", but this profile is read as a DFMoco Arduino",
           "write \"dfmoco\", or give the file to the device it describes");
  }
  const std::string board = r.GetString("board", "uno");
  if (board == "uno") {
    p.board = DfmocoBoard::kUno;
  } else if (board == "mega") {
    p.board = DfmocoBoard::kMega;
  } else {
    r.Fail("board", "is \"" + board + "\", not a known board",
           "write \"uno\" (4 motors) or \"mega\" (8 motors)");
  }
  const std::string firmware = r.GetString("firmware", "2.0.0");
  bool known = false;
  for (const auto& [f, name] : kFirmwares) {
    if (firmware == name) {
      p.firmware = f;
      known = true;
    }
  }
  if (!known) {
    r.Fail("firmware", "is \"" + firmware + "\", not a modelled sketch version",
           "write one of \"1.2.7\", \"1.3.0\", \"1.3.1\", \"2.0.0\"");
  }
  p.pulse_rate_steps_per_s =
      static_cast<int32_t>(r.GetInt("pulse_rate_steps_per_s", dfmoco::kDefaultPulseRate,
                                    dfmoco::kMinPulseRate, dfmoco::kMaxPulseRate));
  p.boot_delay_ms = r.GetInt("boot_delay_ms", 0, 0, 60'000);
  p.reset_on_open = r.GetBool("reset_on_open", false);
  p.usb_bridge = ReadUsbBridge(r, p.usb_bridge);
  p.name = r.GetString("name", "", 200);
  (void)r.GetString("note", "");  // free text for the reader of the file
  r.Finish();
  return p;
}

nlohmann::json DfmocoProfile::ToJson() const {
  nlohmann::json j = {{"device", "dfmoco"},
                      {"board", BoardName(board)},
                      {"firmware", FirmwareVersion(firmware)},
                      {"pulse_rate_steps_per_s", pulse_rate_steps_per_s},
                      {"boot_delay_ms", boot_delay_ms},
                      {"reset_on_open", reset_on_open},
                      {"usb_bridge", usb_bridge.ToJson()}};
  if (!name.empty()) j["name"] = name;
  return j;
}

DfmocoProfile LoadDfmocoProfile(const std::filesystem::path& path) {
  std::string where;
  const nlohmann::json j = ReadProfileFile(path.string(), &where);
  return DfmocoProfile::FromJson(j, where);
}

}  // namespace moco::devices
