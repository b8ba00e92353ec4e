// USB serial bridge presets and the profile field that picks one (see usb_bridge.h).
#include "devices/usb_bridge.h"

#include <array>
#include <utility>

#include "devices/profile.h"

namespace moco::devices {
namespace {

constexpr std::array<std::pair<UsbBridge::Kind, std::string_view>, 4> kNames = {{
    {UsbBridge::Kind::kNone, "none"},
    {UsbBridge::Kind::kFtdi, "ftdi"},
    {UsbBridge::Kind::kCdc, "cdc"},
    {UsbBridge::Kind::kArduino16u2, "arduino-16u2"},
}};

constexpr std::string_view kField = "usb_bridge";

}  // namespace

std::string_view UsbBridge::Name() const {
  for (const auto& [k, name] : kNames) {
    if (k == kind) return name;
  }
  return "none";
}

nlohmann::json UsbBridge::ToJson() const {
  if (kind == Kind::kFtdi && period_ns != kFtdiDefaultLatencyMs * kUsbFrameNs) {
    return {{"kind", Name()}, {"latency_ms", period_ns / kUsbFrameNs}};
  }
  return std::string(Name());
}

UsbBridge UsbBridge::None() { return UsbBridge{}; }

UsbBridge UsbBridge::Ftdi(int latency_ms) {
  UsbBridge b;
  b.kind = Kind::kFtdi;
  b.uart_paced = true;
  b.flush_at_bytes = kFtdiPacketPayload;
  b.period_ns = static_cast<int64_t>(latency_ms) * kUsbFrameNs;
  b.full_packet_restarts_timer = true;
  return b;
}

UsbBridge UsbBridge::Cdc() {
  UsbBridge b;
  b.kind = Kind::kCdc;
  b.uart_paced = false;
  b.flush_at_bytes = kUsbFullSpeedBulkPacket;
  b.period_ns = kUsbFrameNs;
  return b;
}

UsbBridge UsbBridge::Arduino16u2() {
  UsbBridge b;
  b.kind = Kind::kArduino16u2;
  b.uart_paced = true;
  // The firmware sends the whole ring once its count is above 96.
  b.flush_at_bytes = k16u2NearlyFull + 1;
  b.period_ns = k16u2FlushPeriodNs;
  return b;
}

std::optional<UsbBridge> UsbBridgePreset(std::string_view name) {
  if (name == "none") return UsbBridge::None();
  if (name == "ftdi") return UsbBridge::Ftdi();
  if (name == "cdc") return UsbBridge::Cdc();
  if (name == "arduino-16u2") return UsbBridge::Arduino16u2();
  return std::nullopt;
}

std::string UsbBridgePresetNames() {
  std::string out;
  for (const auto& [k, name] : kNames) {
    if (!out.empty()) out += ", ";
    out += "\"" + std::string(name) + "\"";
  }
  return out;
}

UsbBridge ReadUsbBridge(ProfileReader& reader, const UsbBridge& def) {
  if (!reader.Has(kField)) return def;
  const std::string fix = "write one of " + UsbBridgePresetNames() +
                          ", or {\"kind\": \"ftdi\", \"latency_ms\": 1..255} for an FTDI chip "
                          "whose latency timer the host changed";
  const nlohmann::json& raw = reader.GetRaw(kField);
  if (raw.is_string()) {
    const std::string name = raw.get<std::string>();
    if (std::optional<UsbBridge> b = UsbBridgePreset(name)) return *b;
    reader.Fail(kField, "is \"" + name + "\", not a known USB serial bridge", fix);
  }
  if (!raw.is_object()) reader.Fail(kField, "is neither a bridge's name nor an object", fix);
  ProfileReader c = reader.Child(kField);
  const std::string name = c.GetString("kind", "", 64);
  std::optional<UsbBridge> b = UsbBridgePreset(name);
  if (!b) c.Fail("kind", "is \"" + name + "\", not a known USB serial bridge", fix);
  if (b->kind == UsbBridge::Kind::kFtdi) {
    const int64_t latency = c.GetInt("latency_ms", UsbBridge::kFtdiDefaultLatencyMs,
                                     UsbBridge::kFtdiMinLatencyMs, UsbBridge::kFtdiMaxLatencyMs);
    *b = UsbBridge::Ftdi(static_cast<int>(latency));
  } else if (c.Has("latency_ms")) {
    c.Fail("latency_ms", "is set, but only an FTDI chip has a latency timer to set",
           "leave it out, or write \"kind\": \"ftdi\"");
  }
  c.Finish();
  return *b;
}

}  // namespace moco::devices
