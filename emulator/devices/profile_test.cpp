// Profile fields: defaults, ranges, and errors that name the field and the fix.
#include "devices/profile.h"

#include <gtest/gtest.h>

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

TEST(ProfileReader, AbsentFieldsTakeDefaults) {
  const json j = json::object();
  ProfileReader r(j, "profile p.json");
  EXPECT_EQ(r.GetInt("motor_count", 16, 0, 32), 16);
  EXPECT_EQ(r.GetNumber("rate", 2.5, 0, 10), 2.5);
  EXPECT_TRUE(r.GetBool("flag", true));
  EXPECT_EQ(r.GetString("name", "DMC-16"), "DMC-16");
  EXPECT_EQ(r.GetFlags("caps", 0x7ff), 0x7ffu);
  r.Finish();
}

TEST(ProfileReader, ReadsPresentFields) {
  const json j = json::parse(R"({"n": 8, "x": 1.5, "b": false, "s": "abc", "f": "0x0403",
                                 "g": 12, "whole": 4.0})");
  ProfileReader r(j, "p");
  EXPECT_EQ(r.GetInt("n", 16, 0, 32), 8);
  EXPECT_EQ(r.GetNumber("x", 0, 0, 10), 1.5);
  EXPECT_FALSE(r.GetBool("b", true));
  EXPECT_EQ(r.GetString("s", ""), "abc");
  EXPECT_EQ(r.GetFlags("f", 0), 0x0403u);
  EXPECT_EQ(r.GetFlags("g", 0), 12u);
  EXPECT_EQ(r.GetInt("whole", 0, 0, 10), 4);
  r.Finish();
}

TEST(ProfileReader, OutOfRangeNamesFieldRangeAndDefault) {
  const json j = json::parse(R"({"limits": {"motor_count": 40}})");
  ProfileReader root(j, "profile dmc16.json");
  ProfileReader r = root.Child("limits");
  const std::string msg = ErrorOf([&] { r.GetInt("motor_count", 16, 0, 32); });
  EXPECT_NE(msg.find("profile dmc16.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("\"limits.motor_count\""), std::string::npos) << msg;
  EXPECT_NE(msg.find("0..32"), std::string::npos) << msg;
  EXPECT_NE(msg.find("default 16"), std::string::npos) << msg;
}

TEST(ProfileReader, WrongTypesAreRefused) {
  const json j = json::parse(R"({"n": "eight", "x": [1], "b": 1, "s": 3, "f": "0xZZ",
                                 "h": -1, "frac": 2.5})");
  ProfileReader r(j, "p");
  EXPECT_NE(ErrorOf([&] { r.GetInt("n", 0, 0, 9); }).find("found a string"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetNumber("x", 0, 0, 9); }).find("found a array"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetBool("b", false); }).find("true or false"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetString("s", ""); }).find("must be a string"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetFlags("f", 0); }).find("hex string"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetFlags("h", 0); }).find("32-bit"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { r.GetInt("frac", 0, 0, 9); }).find("integer"), std::string::npos);
}

TEST(ProfileReader, StringLengthBound) {
  const json j = json::parse(R"({"name": "0123456789012345678901234567890123"})");
  ProfileReader r(j, "p");
  EXPECT_NE(ErrorOf([&] { r.GetString("name", "", 32); }).find("at most 32 bytes"),
            std::string::npos);
}

TEST(ProfileReader, UnknownKeyIsReportedByFinish) {
  const json j = json::parse(R"({"motor_count": 4, "motor_cout": 4})");
  ProfileReader r(j, "p");
  r.GetInt("motor_count", 16, 0, 32);
  const std::string msg = ErrorOf([&] { r.Finish(); });
  EXPECT_NE(msg.find("\"motor_cout\" is not a known field"), std::string::npos) << msg;
}

TEST(ParseProfileText, SyntaxErrorGivesOffset) {
  const std::string msg = ErrorOf([] { ParseProfileText("{\"a\": 1,, }", "profile x.json"); });
  EXPECT_NE(msg.find("profile x.json: not valid JSON at byte"), std::string::npos) << msg;
  EXPECT_NE(ErrorOf([] { ParseProfileText("[1,2]", "p"); }).find("must be a JSON object"),
            std::string::npos);
  EXPECT_EQ(ParseProfileText("// comment\n{\"a\": 1}", "p")["a"], 1);
}

// A key given twice in one object is refused by its path, at any depth (a run
// file's second "devices" list, a profile's second "motor_count"); the same
// key in two different objects is fine.
TEST(ParseProfileText, AKeyGivenTwiceInOneObjectIsRefusedByItsPath) {
  std::string msg = ErrorOf([] {
    ParseProfileText(R"({"motor_count": 4, "name": "x", "motor_count": 32})", "profile x.json");
  });
  EXPECT_NE(msg.find("profile x.json: field \"motor_count\" is given twice"), std::string::npos)
      << msg;
  msg = ErrorOf([] {
    ParseProfileText(R"({"devices": [{"model": "dmc16"}], "devices": [{"model": "dfmoco"}]})",
                     "run r.json");
  });
  EXPECT_NE(msg.find("field \"devices\" is given twice"), std::string::npos) << msg;
  msg = ErrorOf(
      [] { ParseProfileText(R"({"motors": [{"a": 1}, {"max_speed": 1, "max_speed": 2}]})", "p"); });
  EXPECT_NE(msg.find("field \"motors[].max_speed\" is given twice"), std::string::npos) << msg;
  const auto j =
      ParseProfileText(R"({"a": {"x": 1}, "b": {"x": 2}, "c": [{"x": 3}, {"x": 4}]})", "p");
  EXPECT_EQ(j["c"][1]["x"], 4);
}

TEST(ParseProfileText, NumberBeyondADoubleNamesTheFileAndTheField) {
  std::string msg =
      ErrorOf([] { ParseProfileText(R"({"motor_count": 1e400})", "profile x.json"); });
  EXPECT_NE(msg.find("profile x.json: field \"motor_count\" is a number beyond the range"),
            std::string::npos)
      << msg;
  msg = ErrorOf([] {
    ParseProfileText(R"({"motors": [{"a": 1}, {"max_speed": -1e999}]})", "profile y.json");
  });
  EXPECT_NE(msg.find("profile y.json: field \"motors[].max_speed\""), std::string::npos) << msg;
}

TEST(ProfileReader, AMisspeltKeyPointsToTheDocumentGiven) {
  const json j = json::parse(R"({"devics": []})");
  ProfileReader r(j, "run file r.json", "", "docs/run-files.md");
  const std::string msg = ErrorOf([&] { r.Finish(); });
  EXPECT_NE(msg.find("docs/run-files.md"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("profile"), std::string::npos) << msg;
}

}  // namespace
}  // namespace moco::devices
