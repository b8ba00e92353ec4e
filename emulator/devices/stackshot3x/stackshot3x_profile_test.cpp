// StackShot 3X profile reading: defaults, the shipped fixture, and start-up
// errors that name the field (devices/profile.h).
#include "devices/stackshot3x/stackshot3x_profile.h"

#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "devices/profile.h"
#include "devices/registry.h"
#include "sim/rig.h"

namespace moco::devices {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    Stackshot3xProfile::FromJson(ParseProfileText(text, "profile t.json"), "profile t.json");
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "";
}

TEST(Stackshot3xProfileTest, EmptyObjectGivesTheDefaults) {
  const Stackshot3xProfile p = Stackshot3xProfile::FromJson(nlohmann::json::object(), "t");
  EXPECT_EQ(p.serial_number, 0xFFFFFFFFu);
  EXPECT_EQ(p.nvm_registers, 128);
  EXPECT_EQ(p.checksum, stackshot::ChecksumAlgorithm::kNegatedSum);
  EXPECT_EQ(p.axes[2].steps_per_rev, 3200);
}

TEST(Stackshot3xProfileTest, ShippedFixtureLoadsAndRoundTrips) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string dir = root != nullptr ? root : ".";
  const Stackshot3xProfile p = LoadStackshot3xProfile(dir + "/fixtures/profiles/stackshot3x.json");
  EXPECT_EQ(p.software_string, "StackShot 3X 1.2.6");
  EXPECT_EQ(p.software_checksum, 0x5A3C0F1Eu);
  const Stackshot3xProfile again = Stackshot3xProfile::FromJson(p.ToJson(), "round trip");
  EXPECT_EQ(again.ToJson(), p.ToJson());
}

TEST(Stackshot3xProfileTest, ErrorsNameTheField) {
  EXPECT_NE(ErrorOf(R"({"axis_count": 2})").find("axis_count"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"software_id": "12"})").find("software_id"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"checksum": "crc"})").find("checksum"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"nvm_registers": 300})").find("nvm_registers"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"axes": [{}, {}]})").find("axes"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"axes": [{}, {"steps_per_rev": 0}, {}]})").find("axes[1]"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"device": "dmc16"})").find("device"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"seral_number": 1})").find("seral_number"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"dfmoco_version": "1 2"})").find("dfmoco_version"), std::string::npos);
}

TEST(Stackshot3xProfileTest, RegistryBuildsTheModel) {
  const DeviceModel* m = FindDeviceModel("stackshot3x");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->protocol, wire::Protocol::kStackshot);
  sim::Scheduler sched;
  struct Null final : ByteSink {
    void Write(wire::ByteView) override {}
  } sink;
  auto dev = CreateDevice("stackshot3x", "", sched, sink);
  EXPECT_EQ(dev->Model(), "stackshot3x");
  EXPECT_EQ(dev->Line().serial.baud, 38400u);
  EXPECT_NE(dev->rig(), nullptr);
  EXPECT_EQ(dev->rig()->motor_count(), 3);
}

}  // namespace
}  // namespace moco::devices
