// The configuration of an emulated Cognisys StackShot 3X controller
// (stackshot-protocol.txt sections 1.1.10-1.1.15 identities, section 2
// CC_RAIL_CONFIG_DISTANCE_PER_REV and the speed settings; ERRATA 3.2 checksum)
// read from a profile JSON file (fixtures/profiles/stackshot3x.json,
// docs/devices/stackshot3x.md).
#ifndef MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_PROFILE_H_
#define MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_PROFILE_H_

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "devices/usb_bridge.h"
#include "wire/stackshot.h"

namespace moco::devices {

// One motor output of the controller and the mechanics behind it.
struct Stackshot3xAxisProfile {
  // Motor steps (microsteps) per revolution of the motor shaft.
  int32_t steps_per_rev = 3200;
  // Linear travel per motor revolution: the default of CC_RAIL_CONFIG_DISTANCE_PER_REV.
  double distance_per_rev_mm = 2.0;
  // The fastest step rate the controller drives this output at; speeds
  // written above it (in any units) are refused with BAD_PARAM.
  double max_speed_steps_per_s = 8000;
};

struct Stackshot3xProfile {
  static constexpr int kAxisCount = 3;  // StackShot 3X: X, Y, Z

  // CC_SOFTWARE_ID / STRING, CC_HARDWARE_ID, CC_BOOTLOADER_ID, CC_SOFTWARE_CHECKSUM.
  uint32_t software_id = 0x00010206;
  std::string software_string = "StackShot 3X 1.2.6";
  uint32_t hardware_id = 0x00000003;
  uint32_t bootloader_id = 0x00000101;
  uint32_t software_checksum = 0x5A3C0F1E;
  // The flash checksum "is performed upon command issue so a delay in the
  // response is to be expected": the reply waits this long.
  int64_t checksum_delay_ms = 250;
  // Serial number of a factory-fresh unit (0xFFFFFFFF = unprogrammed). Once a
  // number is stored in NVM, the stored one wins.
  uint32_t serial_number = stackshot::kUnprogrammed;
  // NVM registers served by CC_NVM_ACCESS: 32 (API section) or 128 (table).
  int32_t nvm_registers = stackshot::kNvmRegisterCountSerial;
  // How the emulator computes the trailing checksum byte it sends (ERRATA 3.2).
  stackshot::ChecksumAlgorithm checksum = stackshot::kDefaultChecksum;
  // `hi` version token in DfMoco mode (section 3: "hi 1 3 1.2.6").
  std::string dfmoco_version = "1.2.6";
  // Period of the unprompted `mm <motor> <position>` lines while a DfMoco
  // move runs (section 3: "transmitted periodically").
  int64_t dfmoco_report_ms = 500;
  // Time from power-on (or CC_RESET) until the controller answers.
  int64_t boot_delay_ms = 0;
  // The USB serial bridge of the serial port: an FTDI chip (FACTS "USB
  // serial bridges"). The Wi-Fi link has none.
  UsbBridge usb_bridge = UsbBridge::Ftdi();
  std::array<Stackshot3xAxisProfile, kAxisCount> axes{};
  std::string name;  // free text for logs

  // Reads a profile object; absent fields take the defaults above. Throws
  // ProfileError naming the field and the fix for a wrong type, a value out
  // of range or an unknown key. `where` prefixes messages (the file name).
  static Stackshot3xProfile FromJson(const nlohmann::json& object, const std::string& where);
  nlohmann::json ToJson() const;
};

// Reads and parses a profile file. Throws ProfileError (unreadable file,
// invalid JSON, bad field) with a message a user can act on.
Stackshot3xProfile LoadStackshot3xProfile(const std::filesystem::path& path);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_PROFILE_H_
