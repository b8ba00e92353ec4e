// The DMC-16 profile: the shipped default, and errors that name the field.
#include "devices/dmc16/dmc16_profile.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include "devices/profile.h"

namespace moco::devices {
namespace {

std::string SourceDir() {
  const char* d = std::getenv("MOCO_SOURCE_DIR");
  return d != nullptr ? d : ".";
}

std::string ErrorOf(const nlohmann::json& j) {
  try {
    Dmc16ProfileFromJson(j, "profile t.json");
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "";
}

TEST(Dmc16Profile, ShippedProfileMatchesTheDefaults) {
  const Dmc16Profile p = LoadDmc16Profile(SourceDir() + "/fixtures/profiles/dmc16.json");
  const Dmc16Profile d;
  EXPECT_EQ(p.Hi(), d.Hi());
  EXPECT_EQ(p.baud, 115200u);
  EXPECT_EQ(Dmc16ProfileToJson(p), Dmc16ProfileToJson(d));
}

TEST(Dmc16Profile, RoundTripsThroughJson) {
  Dmc16Profile p;
  p.motor_count = 3;
  p.capabilities = 0x0003;
  p.protocol_version.reset();
  p.ack_width = dmc::AckWidth::k32;
  p.limit_sets = {{2, -5, 5}, {1, std::nullopt, 9}};
  const Dmc16Profile q = Dmc16ProfileFromJson(Dmc16ProfileToJson(p), "x");
  EXPECT_EQ(Dmc16ProfileToJson(q), Dmc16ProfileToJson(p));
  EXPECT_EQ(q.Hi(), p.Hi());
}

TEST(Dmc16Profile, ErrorsNameTheFieldAndTheFix) {
  EXPECT_NE(ErrorOf({{"motor_count", 40}}).find("\"motor_count\" is 40, outside 0..32"),
            std::string::npos);
  EXPECT_NE(ErrorOf({{"capabilities", "0x0004"}}).find("virtual_axes"), std::string::npos);
  EXPECT_NE(ErrorOf({{"virtual_axes", {{"capabilities", "0x0080"}}}})
                .find("\"virtual_axes.capabilities\""),
            std::string::npos);
  EXPECT_NE(
      ErrorOf({{"virtual_axes", {{"capabilities", "0x0040"}}}}).find("without a virtual mode"),
      std::string::npos);
  EXPECT_NE(ErrorOf({{"model", "dfmoco"}}).find("\"model\""), std::string::npos);
  EXPECT_NE(ErrorOf({{"ack_width_bits", 24}}).find("use 16"), std::string::npos);
  EXPECT_NE(ErrorOf({{"motion", {{"max_velocity_steps_per_s", -1}}}})
                .find("\"motion.max_velocity_steps_per_s\""),
            std::string::npos);
  EXPECT_NE(ErrorOf({{"limit_sets", {{{"set", 1}, {"low_steps", 5}, {"high_steps", 1}}}}})
                .find("limit_sets[0].high_steps"),
            std::string::npos);
  EXPECT_NE(ErrorOf({{"nmae", "x"}}).find("\"nmae\" is not a known field"), std::string::npos);
  EXPECT_NE(ErrorOf({{"name", std::string(33, 'x')}}).find("at most 32 bytes"), std::string::npos);
}

TEST(Dmc16Profile, VirtualProfileAdvertisesAllFourModesAndTheAimPoint) {
  // FACTS: the four virtual mode bits go together; 0x0040 is the aim point.
  const Dmc16Profile p = LoadDmc16Profile(SourceDir() + "/fixtures/profiles/dmc16-virtual.json");
  EXPECT_TRUE(p.virtual_axes.enabled);
  EXPECT_EQ(p.Hi().capabilities, 0x0783u | 0x007cu);
  Dmc16Profile off;
  EXPECT_EQ(off.Hi().capabilities & 0x007cu, 0u);
  const Dmc16Profile back = Dmc16ProfileFromJson(Dmc16ProfileToJson(p), "x");
  EXPECT_EQ(back.Hi(), p.Hi());
}

TEST(Dmc16Profile, BehaviourDefaultsAreTheSpecsReadingAndDmcLiteDepartsFromEach) {
  const Dmc16Behaviour spec;
  const Dmc16Profile lite = LoadDmc16Profile(SourceDir() + "/fixtures/profiles/dmc-lite.json");
  const Dmc16Behaviour& b = lite.behaviour;
  // FACTS "DMC v2": dmc-lite as measured on its public source.
  EXPECT_EQ(lite.motor_count, 8);
  EXPECT_EQ(lite.position_report_interval_ms, 50u);
  EXPECT_FALSE(lite.motors_enabled);
  EXPECT_EQ(spec.receive_buffer_bytes, 1048u);
  EXPECT_EQ(b.receive_buffer_bytes, 2048u);
  // Every switch of the reference firmware differs from the spec's default,
  // so the profile shows each departure (none is left at the spec's value).
  const nlohmann::json spec_j = Dmc16ProfileToJson(Dmc16Profile{})["behaviour"];
  const nlohmann::json lite_j = Dmc16ProfileToJson(lite)["behaviour"];
  ASSERT_EQ(spec_j.size(), lite_j.size());
  for (const auto& [key, value] : spec_j.items()) {
    EXPECT_NE(lite_j.at(key), value) << key;
  }
  const Dmc16Profile back = Dmc16ProfileFromJson(Dmc16ProfileToJson(lite), "x");
  EXPECT_EQ(Dmc16ProfileToJson(back), Dmc16ProfileToJson(lite));
}

TEST(Dmc16Profile, BehaviourErrorsNameTheField) {
  EXPECT_NE(ErrorOf({{"behaviour", {{"receive_buffer_bytes", 512}}}})
                .find("\"behaviour.receive_buffer_bytes\" is 512, outside 1048..4096"),
            std::string::npos)
      << ErrorOf({{"behaviour", {{"receive_buffer_bytes", 512}}}});
  EXPECT_NE(ErrorOf({{"behaviour", {{"move_reponse", false}}}}).find("\"behaviour.move_reponse\""),
            std::string::npos);
  // The switches of a few values name them.
  const std::string lengths = ErrorOf({{"behaviour", {{"length_checks", "none"}}}});
  EXPECT_NE(lengths.find("\"behaviour.length_checks\" is \"none\""), std::string::npos) << lengths;
  EXPECT_NE(lengths.find("use \"spec\" or \"move_and_reset_only\""), std::string::npos) << lengths;
  EXPECT_NE(ErrorOf({{"behaviour", {{"coupling", 2}}}}).find("\"behaviour.coupling\""),
            std::string::npos);
  EXPECT_NE(ErrorOf({{"behaviour", {{"position_confirm", "later"}}}}).find("\"after_ack\""),
            std::string::npos);
  EXPECT_NE(ErrorOf({{"behaviour", {{"jog_speed_scale", "log"}}}}).find("\"per_10000\""),
            std::string::npos);
  // The real-time engine: a tick of 5..100 ms; the upload's indexing and the
  // NaN pre-roll are the tick engine's, so they need one.
  EXPECT_NE(ErrorOf({{"behaviour", {{"playback_tick_ms", 3}}}})
                .find("\"behaviour.playback_tick_ms\" is 3"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf({{"behaviour", {{"playback_tick_ms", 101}}}}).find("\"behaviour.playback_tick_ms\""),
      std::string::npos);
  EXPECT_NE(ErrorOf({{"behaviour", {{"upload_index_from_start_frame", true}}}})
                .find("set \"playback_tick_ms\""),
            std::string::npos);
  EXPECT_NE(
      ErrorOf({{"behaviour", {{"zero_preroll_nan", true}}}}).find("\"behaviour.zero_preroll_nan\""),
      std::string::npos);
  EXPECT_EQ(ErrorOf({{"behaviour",
                      {{"playback_tick_ms", 20},
                       {"upload_index_from_start_frame", true},
                       {"zero_preroll_nan", true}}}}),
            "");
}

TEST(Dmc16Profile, MissingFileNamesThePath) {
  try {
    LoadDmc16Profile("/nonexistent/dmc.json");
    FAIL();
  } catch (const ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dmc.json"), std::string::npos);
  }
}

}  // namespace
}  // namespace moco::devices
