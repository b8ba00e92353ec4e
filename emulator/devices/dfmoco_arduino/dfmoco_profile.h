// The configuration of an emulated DFMoco Arduino (FACTS.md "DFMoco": boards
// Uno = 4 motors, Mega = 8; sketch versions 1.2.7, 1.3.0, 1.3.1, 2.0.0), read
// from a profile JSON file (fixtures/profiles/dfmoco-*.json, docs/devices/dfmoco.md).
#ifndef MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_PROFILE_H_
#define MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_PROFILE_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "devices/usb_bridge.h"
#include "wire/dfmoco.h"

namespace moco::devices {

enum class DfmocoBoard : uint8_t {
  kUno,   // 4 motors, step/dir pins 4/5, 6/7, 8/9, 10/11
  kMega,  // 8 motors
};

// The sketch versions whose behaviour is modelled (they differ in the `hi`
// reply, the `jm` velocity argument and the `bf -1` refusal).
enum class DfmocoFirmware : uint8_t { k1_2_7, k1_3_0, k1_3_1, k2_0_0 };

std::string_view BoardName(DfmocoBoard board);              // "uno", "mega"
std::string_view FirmwareVersion(DfmocoFirmware firmware);  // "1.2.7", ...

struct DfmocoProfile {
  DfmocoBoard board = DfmocoBoard::kUno;
  DfmocoFirmware firmware = DfmocoFirmware::k2_0_0;
  // Pulse rate every motor starts with (`pr`, clamped 100..20000 like `pr`).
  int32_t pulse_rate_steps_per_s = dfmoco::kDefaultPulseRate;
  // Time from power-on until the sketch runs and sends `hi` (a bootloader's
  // wait); host bytes arriving meanwhile are lost.
  int64_t boot_delay_ms = 0;
  // The board resets when the host opens the port (an Uno's DTR auto-reset).
  bool reset_on_open = false;
  // The USB serial bridge to the host: the Uno's and Mega's ATmega16U2
  // (FACTS "USB serial bridges").
  UsbBridge usb_bridge = UsbBridge::Arduino16u2();
  std::string name;  // free text for logs; "" = none

  int32_t MotorCount() const { return board == DfmocoBoard::kMega ? 8 : 4; }
  // The `hi` the sketch answers and the grammar it accepts.
  dfmoco::Dialect Dialect() const;
  // Protocol major version from `hi` (2 for 2.0.0, else 1).
  int32_t ProtocolMajor() const { return firmware == DfmocoFirmware::k2_0_0 ? 2 : 1; }
  // 1.3.1 and later answer `bf -1` when a go-motion speed would exceed 20000.
  bool RefusesTooFastBlur() const {
    return firmware == DfmocoFirmware::k1_3_1 || firmware == DfmocoFirmware::k2_0_0;
  }

  // Reads a profile object. Absent fields take the defaults above. Throws
  // ProfileError naming the field and the fix for a wrong type, an unknown
  // value or an unknown key. `where` prefixes messages (e.g. the file name).
  static DfmocoProfile FromJson(const nlohmann::json& object, const std::string& where);
  nlohmann::json ToJson() const;
};

// Reads and parses a profile file. Throws ProfileError (unreadable file,
// invalid JSON, bad field) with a message a user can act on.
DfmocoProfile LoadDfmocoProfile(const std::filesystem::path& path);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_PROFILE_H_
