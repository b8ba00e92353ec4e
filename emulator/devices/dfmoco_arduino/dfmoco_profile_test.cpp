// DFMoco profiles: defaults, the two boards and four sketch versions, and
// errors that name the field and the fix (FACTS.md "DFMoco ... Boards").
#include "devices/dfmoco_arduino/dfmoco_profile.h"

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "devices/profile.h"

namespace moco::devices {
namespace {

using nlohmann::json;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path SourceDir() {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

TEST(DfmocoProfile, DefaultsAreAnUnoWithSketch200) {
  const DfmocoProfile p = DfmocoProfile::FromJson(json::object(), "p");
  EXPECT_EQ(p.board, DfmocoBoard::kUno);
  EXPECT_EQ(p.MotorCount(), 4);
  EXPECT_EQ(p.firmware, DfmocoFirmware::k2_0_0);
  EXPECT_EQ(p.pulse_rate_steps_per_s, 5000);
  EXPECT_EQ(p.Dialect(), dfmoco::Dfmoco2(4));
  EXPECT_FALSE(p.reset_on_open);
}

TEST(DfmocoProfile, BoardsAndFirmwares) {
  const DfmocoProfile mega = DfmocoProfile::FromJson(
      json::parse(R"({"board": "mega", "firmware": "1.2.7", "pulse_rate_steps_per_s": 800})"), "p");
  EXPECT_EQ(mega.MotorCount(), 8);
  EXPECT_EQ(mega.Dialect(), dfmoco::Dfmoco1("1.2.7", 8));
  EXPECT_EQ(mega.pulse_rate_steps_per_s, 800);
  EXPECT_FALSE(mega.RefusesTooFastBlur());
  for (const char* v : {"1.3.1", "2.0.0"}) {
    EXPECT_TRUE(DfmocoProfile::FromJson(json{{"firmware", v}}, "p").RefusesTooFastBlur()) << v;
  }
  EXPECT_FALSE(DfmocoProfile::FromJson(json{{"firmware", "1.3.0"}}, "p").RefusesTooFastBlur());
  EXPECT_EQ(DfmocoProfile::FromJson(json{{"firmware", "1.3.0"}}, "p").ProtocolMajor(), 1);
}

TEST(DfmocoProfile, ToJsonReadsBack) {
  DfmocoProfile p;
  p.board = DfmocoBoard::kMega;
  p.firmware = DfmocoFirmware::k1_3_1;
  p.pulse_rate_steps_per_s = 1234;
  p.boot_delay_ms = 1500;
  p.reset_on_open = true;
  p.name = "bench rig";
  const DfmocoProfile q = DfmocoProfile::FromJson(p.ToJson(), "p");
  EXPECT_EQ(q.ToJson(), p.ToJson());
}

TEST(DfmocoProfile, ErrorsNameTheFieldAndTheFix) {
  const std::string board = ErrorOf([] {
    DfmocoProfile::FromJson(json{{"board", "nano"}}, "profile x.json");
  });
  EXPECT_NE(board.find("profile x.json"), std::string::npos) << board;
  EXPECT_NE(board.find("\"board\""), std::string::npos) << board;
  EXPECT_NE(board.find("\"uno\""), std::string::npos) << board;

  const std::string fw = ErrorOf([] { DfmocoProfile::FromJson(json{{"firmware", "2.1"}}, "p"); });
  EXPECT_NE(fw.find("\"firmware\""), std::string::npos) << fw;
  EXPECT_NE(fw.find("\"1.3.1\""), std::string::npos) << fw;

  const std::string rate = ErrorOf([] {
    DfmocoProfile::FromJson(json{{"pulse_rate_steps_per_s", 30000}}, "p");
  });
  EXPECT_NE(rate.find("pulse_rate_steps_per_s"), std::string::npos) << rate;
  EXPECT_NE(rate.find("100..20000"), std::string::npos) << rate;

  const std::string typo = ErrorOf([] { DfmocoProfile::FromJson(json{{"borad", "uno"}}, "p"); });
  EXPECT_NE(typo.find("\"borad\""), std::string::npos) << typo;
  EXPECT_NE(typo.find("spelling"), std::string::npos) << typo;

  const std::string device = ErrorOf([] {
    DfmocoProfile::FromJson(json{{"device", "dmc16"}}, "p");
  });
  EXPECT_NE(device.find("\"device\""), std::string::npos) << device;

  const std::string wrong_type = ErrorOf([] {
    DfmocoProfile::FromJson(json{{"reset_on_open", "yes"}}, "p");
  });
  EXPECT_NE(wrong_type.find("true or false"), std::string::npos) << wrong_type;
}

TEST(DfmocoProfile, LoadsTheFixtures) {
  const DfmocoProfile uno = LoadDfmocoProfile(SourceDir() / "fixtures/profiles/dfmoco-uno.json");
  EXPECT_EQ(uno.MotorCount(), 4);
  EXPECT_EQ(uno.Dialect(), dfmoco::Dfmoco2(4));
  const DfmocoProfile mega = LoadDfmocoProfile(SourceDir() / "fixtures/profiles/dfmoco-mega.json");
  EXPECT_EQ(mega.MotorCount(), 8);
  EXPECT_EQ(mega.Dialect(), dfmoco::Dfmoco2(8));
}

TEST(DfmocoProfile, UnreadableOrInvalidFilesSayWhy) {
  const std::string missing = ErrorOf([] { LoadDfmocoProfile("/nonexistent/dfmoco.json"); });
  EXPECT_NE(missing.find("/nonexistent/dfmoco.json"), std::string::npos) << missing;
  EXPECT_NE(missing.find("path"), std::string::npos) << missing;

  const std::filesystem::path bad =
      std::filesystem::temp_directory_path() / "dfmoco_profile_test_bad.json";
  {
    std::FILE* f = std::fopen(bad.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("{\"board\": \"uno\",}", f);
    std::fclose(f);
  }
  const std::string syntax = ErrorOf([&] { LoadDfmocoProfile(bad); });
  std::filesystem::remove(bad);
  EXPECT_NE(syntax.find("not valid JSON"), std::string::npos) << syntax;
}

}  // namespace
}  // namespace moco::devices
