// The "usb_bridge" profile field (devices/usb_bridge.h): each device's
// default is the bridge the real device has, the presets and the FTDI
// latency read back, and a bad value names the field and the fix.
#include "devices/usb_bridge.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "devices/dfmoco_arduino/dfmoco_profile.h"
#include "devices/dmc16/dmc16_profile.h"
#include "devices/profile.h"
#include "devices/stackshot3x/stackshot3x_profile.h"

namespace moco::devices {
namespace {

using nlohmann::json;

UsbBridge Read(const std::string& text) {
  const json j = ParseProfileText(text, "profile t.json");
  ProfileReader r(j, "profile t.json");
  const UsbBridge b = ReadUsbBridge(r, UsbBridge::None());
  r.Finish();
  return b;
}

std::string ErrorOf(const std::string& text) {
  try {
    Read(text);
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "";
}

TEST(UsbBridgeProfile, EachDeviceDefaultsToTheBridgeTheRealDeviceHas) {
  // FACTS "USB serial bridges": the StackShot's FTDI chip, the Uno's and
  // Mega's 16U2; the DMC-16's bridge is not known, so it keeps the UART.
  EXPECT_EQ(Stackshot3xProfile::FromJson(json::object(), "t").usb_bridge, UsbBridge::Ftdi());
  EXPECT_EQ(DfmocoProfile::FromJson(json::object(), "t").usb_bridge, UsbBridge::Arduino16u2());
  EXPECT_EQ(DfmocoProfile::FromJson(json{{"board", "mega"}}, "t").usb_bridge,
            UsbBridge::Arduino16u2());
  EXPECT_EQ(Dmc16ProfileFromJson(json::object(), "t").usb_bridge, UsbBridge::None());
  // dmc-lite's GIGA answers on its CDC port (FACTS "DMC v2").
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  EXPECT_EQ(LoadDmc16Profile(std::string(root != nullptr ? root : ".") +
                             "/fixtures/profiles/dmc-lite.json")
                .usb_bridge,
            UsbBridge::Cdc());
}

TEST(UsbBridgeProfile, PresetsAndTheFtdiLatencyReadBack) {
  EXPECT_EQ(Read(R"({})"), UsbBridge::None());
  EXPECT_EQ(Read(R"({"usb_bridge": "none"})"), UsbBridge::None());
  EXPECT_EQ(Read(R"({"usb_bridge": "ftdi"})"), UsbBridge::Ftdi());
  EXPECT_EQ(Read(R"({"usb_bridge": "cdc"})"), UsbBridge::Cdc());
  EXPECT_EQ(Read(R"({"usb_bridge": "arduino-16u2"})"), UsbBridge::Arduino16u2());
  const UsbBridge one = Read(R"({"usb_bridge": {"kind": "ftdi", "latency_ms": 1}})");
  EXPECT_EQ(one, UsbBridge::Ftdi(1));
  EXPECT_EQ(one.period_ns, 1'000'000);
  EXPECT_EQ(Read(R"({"usb_bridge": {"kind": "cdc"}})"), UsbBridge::Cdc());
  // What ToJson writes reads back as the same bridge.
  for (const UsbBridge& b : {UsbBridge::None(), UsbBridge::Ftdi(), UsbBridge::Ftdi(7),
                             UsbBridge::Cdc(), UsbBridge::Arduino16u2()}) {
    const json doc = {{"usb_bridge", b.ToJson()}};
    EXPECT_EQ(Read(doc.dump()), b) << doc.dump();
  }
  // And through a whole profile.
  Stackshot3xProfile s = Stackshot3xProfile::FromJson(json::object(), "t");
  s.usb_bridge = UsbBridge::Ftdi(4);
  EXPECT_EQ(Stackshot3xProfile::FromJson(s.ToJson(), "t").usb_bridge, UsbBridge::Ftdi(4));
  Dmc16Profile d = Dmc16ProfileFromJson(json::object(), "t");
  d.usb_bridge = UsbBridge::Cdc();
  EXPECT_EQ(Dmc16ProfileFromJson(Dmc16ProfileToJson(d), "t").usb_bridge, UsbBridge::Cdc());
}

TEST(UsbBridgeProfile, BadValuesNameTheFieldAndTheFix) {
  std::string e = ErrorOf(R"({"usb_bridge": "ch340"})");
  EXPECT_NE(e.find("usb_bridge"), std::string::npos) << e;
  EXPECT_NE(e.find("\"ch340\""), std::string::npos) << e;
  EXPECT_NE(e.find("\"arduino-16u2\""), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": 16})");
  EXPECT_NE(e.find("usb_bridge"), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": {"kind": "ftdi", "latency_ms": 0}})");
  EXPECT_NE(e.find("latency_ms"), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": {"kind": "ftdi", "latency_ms": 256}})");
  EXPECT_NE(e.find("latency_ms"), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": {"kind": "cdc", "latency_ms": 4}})");
  EXPECT_NE(e.find("only an FTDI chip"), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": {"kind": "ftdi", "latncy_ms": 4}})");
  EXPECT_NE(e.find("latncy_ms"), std::string::npos) << e;
  e = ErrorOf(R"({"usb_bridge": {}})");
  EXPECT_NE(e.find("kind"), std::string::npos) << e;
}

}  // namespace
}  // namespace moco::devices
