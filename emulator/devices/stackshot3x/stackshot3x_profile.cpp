// StackShot 3X profile fields with errors naming the field and the fix (see
// stackshot3x_profile.h).
#include "devices/stackshot3x/stackshot3x_profile.h"

#include <fstream>
#include <sstream>

#include "devices/profile.h"

namespace moco::devices {

Stackshot3xProfile Stackshot3xProfile::FromJson(const nlohmann::json& object,
                                                const std::string& where) {
  ProfileReader r(object, where);
  Stackshot3xProfile p;
  const std::string device = r.GetString("device", "stackshot3x");
  if (device != "stackshot3x") {
    r.Fail("device", "is \"" + device + "\", but this profile is read as a StackShot 3X",
           "write \"stackshot3x\", or give the file to the device it describes");
  }
  const int64_t axis_count = r.GetInt("axis_count", kAxisCount, 1, 16);
  if (axis_count != kAxisCount) {
    r.Fail("axis_count", "is " + std::to_string(axis_count) + ", but a StackShot 3X drives 3 axes",
           "write 3 (X, Y and Z)");
  }
  p.software_id = r.GetFlags("software_id", p.software_id);
  p.software_string = r.GetString("software_string", p.software_string, 200);
  if (p.software_string.find('\0') != std::string::npos) {
    r.Fail("software_string", "contains a NUL byte",
           "remove it: the string is sent NUL-terminated");
  }
  p.hardware_id = r.GetFlags("hardware_id", p.hardware_id);
  p.bootloader_id = r.GetFlags("bootloader_id", p.bootloader_id);
  p.software_checksum = r.GetFlags("software_checksum", p.software_checksum);
  p.checksum_delay_ms = r.GetInt("checksum_delay_ms", p.checksum_delay_ms, 0, 10'000);
  p.serial_number = r.GetFlags("serial_number", p.serial_number);
  p.nvm_registers = static_cast<int32_t>(
      r.GetInt("nvm_registers", p.nvm_registers, 1, stackshot::kNvmRegisterCountSerial));
  const std::string checksum = r.GetString(
      "checksum", std::string(stackshot::ChecksumAlgorithmName(stackshot::kDefaultChecksum)));
  const auto algorithm = stackshot::ParseChecksumAlgorithm(checksum);
  if (!algorithm) {
    r.Fail("checksum", "is \"" + checksum + "\", not a known checksum algorithm",
           "write \"negated-sum\", \"constant-0x69\" or \"constant-0x00\"");
  }
  p.checksum = *algorithm;
  p.dfmoco_version = r.GetString("dfmoco_version", p.dfmoco_version, 32);
  if (p.dfmoco_version.empty() || p.dfmoco_version.find_first_of(" \t\r\n") != std::string::npos) {
    r.Fail("dfmoco_version", "must be one token without spaces", "write e.g. \"1.2.6\"");
  }
  p.dfmoco_report_ms = r.GetInt("dfmoco_report_ms", p.dfmoco_report_ms, 10, 60'000);
  p.boot_delay_ms = r.GetInt("boot_delay_ms", p.boot_delay_ms, 0, 60'000);
  p.usb_bridge = ReadUsbBridge(r, p.usb_bridge);
  const nlohmann::json& axes = r.GetRaw("axes");
  if (!axes.is_null()) {
    if (!axes.is_array() || axes.size() != kAxisCount) {
      r.Fail("axes", "must be an array of 3 objects (X, Y, Z)",
             "write \"axes\": [{...}, {...}, {...}] or leave it out for the defaults");
    }
    for (size_t i = 0; i < kAxisCount; ++i) {
      ProfileReader a(axes[i], where, "axes[" + std::to_string(i) + "]");
      Stackshot3xAxisProfile& ax = p.axes[i];
      ax.steps_per_rev =
          static_cast<int32_t>(a.GetInt("steps_per_rev", ax.steps_per_rev, 1, 1'000'000));
      ax.distance_per_rev_mm =
          a.GetNumber("distance_per_rev_mm", ax.distance_per_rev_mm, 1e-3, 10'000);
      ax.max_speed_steps_per_s =
          a.GetNumber("max_speed_steps_per_s", ax.max_speed_steps_per_s, 1, 1'000'000);
      (void)a.GetString("note", "");
      a.Finish();
    }
  }
  p.name = r.GetString("name", "", 200);
  (void)r.GetString("note", "");
  r.Finish();
  return p;
}

nlohmann::json Stackshot3xProfile::ToJson() const {
  nlohmann::json axes_j = nlohmann::json::array();
  for (const Stackshot3xAxisProfile& a : this->axes) {
    axes_j.push_back({{"steps_per_rev", a.steps_per_rev},
                      {"distance_per_rev_mm", a.distance_per_rev_mm},
                      {"max_speed_steps_per_s", a.max_speed_steps_per_s}});
  }
  nlohmann::json j = {{"device", "stackshot3x"},
                      {"axis_count", kAxisCount},
                      {"software_id", software_id},
                      {"software_string", software_string},
                      {"hardware_id", hardware_id},
                      {"bootloader_id", bootloader_id},
                      {"software_checksum", software_checksum},
                      {"checksum_delay_ms", checksum_delay_ms},
                      {"serial_number", serial_number},
                      {"nvm_registers", nvm_registers},
                      {"checksum", stackshot::ChecksumAlgorithmName(checksum)},
                      {"dfmoco_version", dfmoco_version},
                      {"dfmoco_report_ms", dfmoco_report_ms},
                      {"boot_delay_ms", boot_delay_ms},
                      {"usb_bridge", usb_bridge.ToJson()},
                      {"axes", axes_j}};
  if (!name.empty()) j["name"] = name;
  return j;
}

Stackshot3xProfile LoadStackshot3xProfile(const std::filesystem::path& path) {
  std::string where;
  const nlohmann::json j = ReadProfileFile(path.string(), &where);
  return Stackshot3xProfile::FromJson(j, where);
}

}  // namespace moco::devices
