// JsonFields (json_fields.h): typed fields with defaults, required fields,
// ranges, unknown keys refused, nested paths, and problems that name the
// field and the fix.
#include "base/json_fields.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <array>
#include <string>
#include <string_view>

namespace moco::base {
namespace {

using nlohmann::json;
using Kind = FieldProblem::Kind;

TEST(JsonFields, AbsentOptionalFieldsTakeTheirDefaults) {
  const json j = json::object();
  JsonFields f(j);
  EXPECT_EQ(f.Int("n", 16, 0, 32), 16);
  EXPECT_EQ(f.Number("x", 2.5, 0, 10), 2.5);
  EXPECT_TRUE(f.Bool("b", true));
  EXPECT_EQ(f.String("s", "dflt"), "dflt");
  EXPECT_EQ(f.Bits32("caps", 0x7ff), 0x7ffu);
  EXPECT_EQ(f.Raw("r"), nullptr);
  EXPECT_EQ(f.Array("a"), nullptr);
  EXPECT_TRUE(f.Numbers("v", 0, 1, 1, 3).empty());
  f.Finish();
  EXPECT_FALSE(f.failed());
}

TEST(JsonFields, ReadsPresentFieldsOfEveryType) {
  const json j = json::parse(R"({"n": 8, "whole": 4.0, "x": 1.5, "b": false, "s": "abc",
                                 "hex": "0x0403", "bits": 12, "mode": "fast", "v": [1, 2.5],
                                 "r": {"k": 1}})");
  JsonFields f(j);
  EXPECT_EQ(f.Int("n", 0, 0, 32), 8);
  EXPECT_EQ(f.Int("whole", 0, 0, 10), 4);
  EXPECT_EQ(f.Number("x", 0, 0, 10), 1.5);
  EXPECT_FALSE(f.Bool("b", true));
  EXPECT_EQ(f.String("s", ""), "abc");
  EXPECT_EQ(f.Bits32("hex", 0), 0x0403u);
  EXPECT_EQ(f.Bits32("bits", 0), 12u);
  const std::array<std::string_view, 2> modes = {"slow", "fast"};
  EXPECT_EQ(f.Choice("mode", modes), 1u);
  EXPECT_EQ(f.Numbers("v", 0, 5, 2, 2), (std::vector<double>{1, 2.5}));
  ASSERT_NE(f.Raw("r"), nullptr);
  EXPECT_EQ((*f.Raw("r"))["k"], 1);
  f.Finish();
  EXPECT_FALSE(f.failed());
}

TEST(JsonFields, AnUnknownKeyIsRefusedWithItsName) {
  const json j = json::parse(R"({"motor_count": 4, "motor_cout": 4})");
  JsonFields f(j, "", "docs/profiles.md");
  f.Int("motor_count", 16, 0, 32);
  f.Finish();
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().kind, Kind::kUnknown);
  EXPECT_EQ(f.problem().field, "motor_cout");
  EXPECT_EQ(f.problem().Message(),
            "field \"motor_cout\" is not a known field; check its spelling against "
            "docs/profiles.md, or remove it");
}

TEST(JsonFields, WithoutADocumentTheUnknownKeyFixListsTheKnownKeys) {
  const json j = json::parse(R"({"kp": 1, "kpp": 2})");
  JsonFields f(j);
  f.Number("kp", 0, 0, 10);
  f.Number("kd", 0, 0, 10);
  f.Finish();
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().field, "kpp");
  EXPECT_EQ(f.problem().fix, "check its spelling (known here: kd, kp), or remove it");
}

TEST(JsonFields, HasDoesNotCountAsARead) {
  const json j = json::parse(R"({"a": 1})");
  JsonFields f(j);
  EXPECT_TRUE(f.Has("a"));
  EXPECT_FALSE(f.Has("b"));
  f.Finish();
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().field, "a");
}

TEST(JsonFields, AWrongTypeNamesTheFieldTheExpectedTypeAndWhatWasFound) {
  struct Case {
    const char* text;
    const char* expected;
    const char* found;
    const char* message;
  };
  const Case cases[] = {
      {R"({"f": "eight"})", "an integer 0..9", "a string",
       "field \"f\" must be an integer 0..9, found a string; write a whole number, or remove the "
       "field to use the default 3"},
      {R"({"f": 2.5})", "an integer 0..9", "a number", nullptr},
      {R"({"f": [1]})", "a number 0.0..9.0", "a array", nullptr},
      {R"({"f": 1})", "true or false", "an integer", nullptr},
      {R"({"f": 3})", "a string", "an integer", nullptr},
      {R"({"f": "0xZZ"})", "a 32-bit unsigned value", "a string", nullptr},
      {R"({"f": -1})", "a 32-bit unsigned value", "an integer", nullptr},
      {R"({"f": 3})", "an object", "an integer", nullptr},
      {R"({"f": {}})", "an array", "a object", nullptr},
  };
  for (size_t i = 0; i < std::size(cases); ++i) {
    const json j = json::parse(cases[i].text);
    JsonFields f(j);
    switch (i) {
      case 0:
      case 1:
        EXPECT_EQ(f.Int("f", 3, 0, 9), 3);
        break;
      case 2:
        EXPECT_EQ(f.Number("f", 1, 0, 9), 1);
        break;
      case 3:
        EXPECT_TRUE(f.Bool("f", true));
        break;
      case 4:
        EXPECT_EQ(f.String("f", "d"), "d");
        break;
      case 5:
      case 6:
        EXPECT_EQ(f.Bits32("f", 7), 7u);
        break;
      case 7:
        f.Child("f");
        break;
      default:
        EXPECT_EQ(f.Array("f"), nullptr);
        break;
    }
    ASSERT_TRUE(f.failed()) << cases[i].text;
    EXPECT_EQ(f.problem().kind, Kind::kType) << cases[i].text;
    EXPECT_EQ(f.problem().field, "f");
    EXPECT_EQ(f.problem().expected, cases[i].expected) << cases[i].text;
    EXPECT_EQ(f.problem().found, cases[i].found) << cases[i].text;
    if (cases[i].message != nullptr) {
      EXPECT_EQ(f.problem().Message(), cases[i].message);
    }
  }
}

TEST(JsonFields, AValueOutOfRangeNamesTheRangeAndTheDefault) {
  const json j = json::parse(R"({"n": 40, "x": -0.5, "big": 18446744073709551615})");
  JsonFields f(j);
  EXPECT_EQ(f.Int("n", 16, 0, 32), 16);
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().kind, Kind::kRange);
  EXPECT_EQ(f.problem().value, "40");
  EXPECT_EQ(f.problem().Message(),
            "field \"n\" is 40, outside 0..32; use a value in 0..32, or remove the field to use "
            "the default 16");

  JsonFields g(j);
  g.Number("x", 1, 0, 10);
  ASSERT_TRUE(g.failed());
  EXPECT_EQ(g.problem().problem, "is -0.5, outside 0.0..10.0");

  JsonFields h(j);
  h.Int("big", 0, 0, 100);
  ASSERT_TRUE(h.failed());
  EXPECT_EQ(h.problem().problem, "is 18446744073709551615, outside 0..100");
}

TEST(JsonFields, ARequiredFieldLeftOutIsMissingAndTheFixSaysWhatToAdd) {
  const json j = json::object();
  JsonFields f(j);
  EXPECT_EQ(f.Number("boom_length_m", 1.5, 0.05, 50, kRequired, "m"), 1.5);
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().kind, Kind::kMissing);
  EXPECT_EQ(f.problem().Message(),
            "field \"boom_length_m\" is missing; add a number 0.05..50.0 in m");
  // A required fix never offers the default.
  const json k = json::parse(R"({"n": "x"})");
  JsonFields g(k);
  g.Int("n", 3, 0, 9, kRequired);
  EXPECT_EQ(g.problem().fix, "write a whole number");
}

TEST(JsonFields, StringsLongerThanTheirBoundAreRefused) {
  const json j = json::parse(R"({"name": "0123456789012345678901234567890123"})");
  JsonFields f(j);
  EXPECT_EQ(f.String("name", "", 32), "");
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().kind, Kind::kRange);
  EXPECT_EQ(f.problem().fix, "shorten it to at most 32 bytes (UTF-8)");
}

TEST(JsonFields, NestedObjectsAndArrayElementsCarryTheirPath) {
  const json j = json::parse(R"({"motors": [{"max_speed": 1}, {"max_speed": 1},
                                            {"max_speed": 900}], "limits": {"fw": {"x": true}}})");
  JsonFields root(j);
  const json* motors = root.Array("motors", kRequired);
  ASSERT_NE(motors, nullptr);
  for (size_t i = 0; i < motors->size() && !root.failed(); ++i) {
    JsonFields m = root.Item("motors", i);
    m.Number("max_speed", 1, 0, 100);
    m.Finish();
  }
  ASSERT_TRUE(root.failed());
  EXPECT_EQ(root.problem().field, "motors[2].max_speed");
  EXPECT_NE(root.problem().Message().find("\"motors[2].max_speed\" is 900, outside"),
            std::string::npos);

  JsonFields other(j);
  other.Raw("motors");
  JsonFields fw = other.Child("limits").Child("fw");
  EXPECT_EQ(fw.path(), "limits.fw");
  EXPECT_EQ(fw.FieldName("x"), "limits.fw.x");
  fw.Int("x", 0, 0, 1);
  ASSERT_TRUE(other.failed());  // the problem is shared with the parent
  EXPECT_EQ(other.problem().field, "limits.fw.x");
}

TEST(JsonFields, AnArrayElementThatIsNotAnObjectIsNamed) {
  const json j = json::parse(R"({"obstacles": [{}, 3]})");
  JsonFields root(j);
  root.Array("obstacles");
  root.Item("obstacles", 0).Finish();
  EXPECT_FALSE(root.failed());
  root.Item("obstacles", 1);
  ASSERT_TRUE(root.failed());
  EXPECT_EQ(root.problem().kind, Kind::kNotObject);
  EXPECT_EQ(root.problem().Message(),
            "obstacles[1] must be a JSON object, found an integer; write it as { \"field\": "
            "value, ... }");
}

TEST(JsonFields, TheTopLevelMustBeAnObject) {
  const json j = json::array();
  JsonFields f(j);
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().field, "");
  EXPECT_EQ(f.problem().Message().rfind("the top level must be a JSON object, found a array", 0),
            0u);
  // Reads after a problem return their defaults and keep the first problem.
  EXPECT_EQ(f.Int("n", 5, 0, 9, kRequired), 5);
  EXPECT_EQ(f.problem().kind, Kind::kNotObject);
}

TEST(JsonFields, AnAbsentOptionalObjectReadsAsDefaultsWithNothingRequired) {
  const json j = json::object();
  JsonFields root(j);
  JsonFields level = root.Child("parallelogram");
  EXPECT_EQ(level.Number("kp", 5e4, 1, 1e9, kRequired), 5e4);
  level.Finish();
  EXPECT_FALSE(root.failed());
  JsonFields required = root.Child("geometry", kRequired);
  ASSERT_TRUE(root.failed());
  EXPECT_EQ(root.problem().kind, Kind::kMissing);
  EXPECT_EQ(root.problem().field, "geometry");
}

TEST(JsonFields, NumberArraysCheckTheirCountAndEachElement) {
  const json j = json::parse(R"({"two": [1, 2, 3], "bad": [0, "x"], "far": [0, 1e6]})");
  JsonFields f(j);
  EXPECT_TRUE(f.Numbers("two", 0, 10, 2, 2).empty());
  EXPECT_EQ(f.problem().kind, Kind::kType);
  EXPECT_EQ(f.problem().problem, "must be an array of 2 numbers 0.0..10.0, found an array of 3");
  JsonFields g(j);
  g.Numbers("bad", 0, 10, 1, 64);
  EXPECT_EQ(g.problem().field, "bad[1]");
  EXPECT_EQ(g.problem().kind, Kind::kType);
  JsonFields h(j);
  h.Numbers("far", 0, 10, 1, 64);
  EXPECT_EQ(h.problem().field, "far[1]");
  EXPECT_EQ(h.problem().kind, Kind::kRange);
}

TEST(JsonFields, AChoiceNamesItsChoices) {
  const json j = json::parse(R"({"end": "middle"})");
  JsonFields f(j);
  const std::array<std::string_view, 2> ends = {"lower", "upper"};
  EXPECT_EQ(f.Choice("end", ends), std::nullopt);
  ASSERT_TRUE(f.failed());
  EXPECT_EQ(f.problem().Message(),
            "field \"end\" must be \"lower\" or \"upper\", found a string \"middle\"; write "
            "\"lower\" or \"upper\"");
}

TEST(JsonFields, TheFirstProblemIsKept) {
  const json j = json::parse(R"({"a": "x", "b": "y"})");
  JsonFields f(j);
  f.Int("a", 0, 0, 1);
  f.Int("b", 0, 0, 1);
  f.Fail("c", "is wrong", "fix it");
  EXPECT_EQ(f.problem().field, "a");
  JsonFields g(j);
  g.Fail("a", "is wrong", "fix it");
  EXPECT_EQ(g.problem().kind, Kind::kOther);
  EXPECT_EQ(g.problem().Message(), "field \"a\" is wrong; fix it");
}

TEST(JsonFields, ATakenProblemIsForgottenAndReadingGoesOn) {
  const json j = json::parse(R"({"a": "x", "c": {"d": "y"}})");
  JsonFields f(j);
  f.Int("a", 0, 0, 1);
  std::optional<FieldProblem> p = f.TakeProblem();
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->field, "a");
  EXPECT_FALSE(f.failed());
  EXPECT_FALSE(f.TakeProblem().has_value());
  JsonFields c = f.Child("c");
  c.Bool("d", false);
  ASSERT_TRUE(f.failed());  // shared with the child
  EXPECT_EQ(c.TakeProblem()->field, "c.d");
  EXPECT_FALSE(f.failed());
}

// Whatever the value, a read returns (the default or the value) and a problem,
// if any, names the field it was read from.
RC_GTEST_PROP(JsonFieldsProperty, AnyValueIsReadOrRefusedByName, ()) {
  const json value = *rc::gen::oneOf(
      rc::gen::map(rc::gen::arbitrary<double>(), [](double d) { return json(d); }),
      rc::gen::map(rc::gen::arbitrary<int64_t>(), [](int64_t i) { return json(i); }),
      rc::gen::map(rc::gen::arbitrary<std::string>(), [](std::string t) { return json(t); }),
      rc::gen::map(rc::gen::arbitrary<bool>(), [](bool b) { return json(b); }),
      rc::gen::map(rc::gen::arbitrary<int>(), [](int i) { return json::array({i}); }));
  const json j = {{"k", value}};
  JsonFields f(j, "p");
  const int read = *rc::gen::inRange(0, 6);
  if (read == 0) f.Int("k", 0, -10, 10);
  if (read == 1) f.Number("k", 0, -10, 10);
  if (read == 2) f.Bool("k", false);
  if (read == 3) f.String("k", "", 4);
  if (read == 4) f.Bits32("k", 0);
  if (read == 5) f.Numbers("k", -10, 10, 1, 1);
  f.Finish();
  if (f.failed()) {
    RC_ASSERT(f.problem().field.rfind("p.k", 0) == 0u);
    RC_ASSERT(f.problem().Message().find(f.problem().field) != std::string::npos);
    RC_ASSERT(!f.problem().fix.empty());
  }
}

// The first key given twice in one object is named by its path; the same key
// in different objects, or nested under different keys, is not a duplicate.
TEST(ParseJsonNotingDuplicateKeys, NamesTheFirstDuplicateByItsPath) {
  std::string dup;
  ParseJsonNotingDuplicateKeys(R"({"a": 1, "b": {"x": 1, "y": 2}, "c": [{"x": 1}, {"x": 2}]})",
                               dup);
  EXPECT_EQ(dup, "");
  ParseJsonNotingDuplicateKeys(R"({"devices": [], "name": "n", "devices": [1]})", dup);
  EXPECT_EQ(dup, "devices");
  ParseJsonNotingDuplicateKeys(R"({"rig": {"motors": [{"max": 1, "max": 2}]}, "rig2": 1})", dup);
  EXPECT_EQ(dup, "rig.motors[].max");
  ParseJsonNotingDuplicateKeys(R"({"a": {"k": 1}, "b": {"k": 1, "j": {"k": 2}, "k": 3}})", dup);
  EXPECT_EQ(dup, "b.k");
  std::string at;
  EXPECT_THROW(ParseJsonNotingDuplicateKeys(R"({"a": {"big": 1e400}})", dup, &at),
               nlohmann::json::exception);
  EXPECT_EQ(at, "a.big");
  EXPECT_THROW(ParseJsonNotingDuplicateKeys("{\"a\": 1 // no\n}", dup), nlohmann::json::exception);
  EXPECT_EQ(ParseJsonNotingDuplicateKeys("{\"a\": 1 // yes\n}", dup, nullptr, true)["a"], 1);
}

}  // namespace
}  // namespace moco::base
