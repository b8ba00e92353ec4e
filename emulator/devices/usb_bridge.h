// The USB serial bridge between a device's UART and the host's serial port
// (FACTS "USB serial bridges"): a host never reads a device's bytes one at a
// time as the UART clocks them, but in USB packets, when the bridge's buffer
// holds a full packet or its timer expires. A profile's "usb_bridge" field
// (docs/profiles.md) names one of the presets below or tunes one.
#ifndef MOCO_DEVICES_USB_BRIDGE_H_
#define MOCO_DEVICES_USB_BRIDGE_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace moco::devices {

class ProfileReader;

struct UsbBridge {
  enum class Kind : uint8_t {
    kNone,         // no bridge: the host reads bytes as the UART completes them
    kFtdi,         // FTDI FT232-family chip (the StackShot, many Arduino clones)
    kCdc,          // the device's own USB port in CDC-ACM mode (DMC boards, GIGA)
    kArduino16u2,  // an Uno/Mega's ATmega16U2 running Arduino's usbserial firmware
  };
  Kind kind = Kind::kNone;
  // Bytes cross a UART at the line rate before the bridge has them (false for
  // CDC: the device writes into its USB endpoint and the baud rate is ignored).
  bool uart_paced = true;
  // A packet leaves at once when this many bytes wait (0: never by size).
  uint32_t flush_at_bytes = 0;
  // Otherwise the bytes waiting leave at the next tick of this period, counted
  // from time 0 of the device's clock.
  int64_t period_ns = 0;
  // FTDI: sending a full packet restarts the latency timer, so the next tick
  // is one period after that packet.
  bool full_packet_restarts_timer = false;

  bool active() const { return kind != Kind::kNone; }
  std::string_view Name() const;
  // {"kind": "ftdi", "latency_ms": 16} and so on: what a profile would write.
  nlohmann::json ToJson() const;
  bool operator==(const UsbBridge&) const = default;

  // No bridge: bytes reach the host as the UART completes each one.
  static UsbBridge None();
  // FTDI: a packet of 62 payload bytes (64 less 2 status bytes) leaves when
  // full; fewer leave when the latency timer expires (16 ms by default, which
  // host software may set from 1 to 255 ms).
  static UsbBridge Ftdi(int latency_ms = kFtdiDefaultLatencyMs);
  // CDC-ACM on a full-speed port: unpaced, 64-byte bulk packets, a short
  // packet in the next 1 ms USB frame.
  static UsbBridge Cdc();
  // Arduino-usbserial on the 16U2 (its public firmware): UART bytes collect
  // in a 128-byte ring and are all sent when Timer0 (clk/256 at 16 MHz)
  // overflows, every 4.096 ms, or at once when more than 96 wait.
  static UsbBridge Arduino16u2();

  static constexpr int kFtdiDefaultLatencyMs = 16;
  static constexpr int kFtdiMinLatencyMs = 1;
  static constexpr int kFtdiMaxLatencyMs = 255;
  static constexpr uint32_t kFtdiPacketPayload = 62;
  static constexpr uint32_t kUsbFullSpeedBulkPacket = 64;
  static constexpr int64_t kUsbFrameNs = 1'000'000;
  static constexpr int64_t k16u2FlushPeriodNs = 4'096'000;  // 256 * 256 / 16 MHz
  static constexpr uint32_t k16u2NearlyFull = 96;
};

// The preset of this name ("none", "ftdi", "cdc", "arduino-16u2"), if any.
std::optional<UsbBridge> UsbBridgePreset(std::string_view name);
// The names above, for messages: "\"none\", \"ftdi\", ...".
std::string UsbBridgePresetNames();

// Reads a profile's "usb_bridge": absent gives `def`; a preset's name; or an
// object {"kind": NAME, "latency_ms": N} (latency only for "ftdi", 1..255).
// Anything else throws ProfileError naming the field and the fix.
UsbBridge ReadUsbBridge(ProfileReader& reader, const UsbBridge& def);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_USB_BRIDGE_H_
