// Tests for the control vocabulary's codec alone (command_codec.h,
// docs/control.md): no device, no clock. Every example of the vocabulary
// parses as its own command, the canonical JSON form parses back to the same
// command, and a request line becomes a command or the error reply owed.
#include "control/command_codec.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <string>
#include <tuple>

namespace moco::control {
namespace {

using nlohmann::json;

TEST(VocabularyTest, EveryExampleInTheVocabularyParsesAsItsOwnCommand) {
  const json vocab = Vocabulary();
  ASSERT_FALSE(vocab.empty());
  for (const json& entry : vocab) {
    const json example = json::parse(entry["example"].get<std::string>());
    auto parsed = ParseCommand(example);
    ASSERT_TRUE(std::holds_alternative<Command>(parsed))
        << entry["cmd"] << ": " << std::get<std::string>(parsed);
    EXPECT_EQ(CommandName(std::get<Command>(parsed).body), entry["cmd"].get<std::string>());
  }
}

// A request line: the command, or the error reply with the request's id.
TEST(RequestLineTest, AValidLineIsItsCommand) {
  auto parsed = ParseRequestLine("{\"cmd\":\"estop\",\"engaged\":true,\"id\":7}\r\n");
  ASSERT_TRUE(std::holds_alternative<Command>(parsed)) << std::get<json>(parsed).dump();
  const Command& c = std::get<Command>(parsed);
  ASSERT_TRUE(std::holds_alternative<EStopCommand>(c.body));
  EXPECT_TRUE(std::get<EStopCommand>(c.body).engaged);
  EXPECT_EQ(c.id, json(7));
}

TEST(RequestLineTest, BadLinesAreErrorRepliesNamingTheProblem) {
  const auto error_of = [](std::string_view line) {
    auto parsed = ParseRequestLine(line);
    EXPECT_TRUE(std::holds_alternative<json>(parsed)) << line;
    if (!std::holds_alternative<json>(parsed)) return json();
    return std::get<json>(parsed);
  };
  EXPECT_NE(error_of(" \t\n")["error"].get<std::string>().find("empty request"), std::string::npos);
  EXPECT_NE(error_of("{\"cmd\":").value("error", "").find("malformed JSON at byte"),
            std::string::npos);
  const json dup = error_of(R"({"cmd":"estop","engaged":true,"engaged":false,"id":"a"})");
  EXPECT_EQ(dup["ok"], false);
  EXPECT_NE(dup["error"].get<std::string>().find("\"engaged\" appears twice"), std::string::npos);
  EXPECT_EQ(dup["id"], "a");
  const json unknown = error_of(R"({"cmd":"bogus","id":3})");
  EXPECT_NE(unknown["error"].get<std::string>().find("unknown command"), std::string::npos);
  EXPECT_EQ(unknown["id"], 3);
}

TEST(ReplyLineTest, OkComesFirstAndTheLineHasNoNewline) {
  EXPECT_EQ(ReplyLine({{"ok", true}, {"a", 1}, {"cmd", "state"}}),
            R"({"ok":true,"a":1,"cmd":"state"})");
  EXPECT_EQ(ReplyLine(ErrorReply("no")), R"({"ok":false,"error":"no"})");
  EXPECT_EQ(ReplyLine(ErrorReply("no", "x")), R"({"ok":false,"error":"no","id":"x"})");
}

// ToJson and ParseCommand are inverse: the canonical form parses back to the
// same command.
rc::Gen<CommandBody> GenBody() {
  return rc::gen::oneOf(
      rc::gen::map(rc::gen::arbitrary<bool>(), [](bool b) { return CommandBody(EStopCommand{b}); }),
      rc::gen::map(rc::gen::tuple(rc::gen::inRange(1, 128), rc::gen::arbitrary<bool>(),
                                  rc::gen::arbitrary<bool>(), rc::gen::arbitrary<bool>()),
                   [](std::tuple<int, bool, bool, bool> t) {
                     LimitCommand c;
                     if (std::get<1>(t)) {
                       c.set = std::get<0>(t);
                       c.input = std::get<2>(t) ? sim::SwitchInput::kHigh : sim::SwitchInput::kLow;
                     } else {
                       c.motor = std::get<0>(t);
                       c.end = std::get<2>(t) ? sim::LimitEnd::kUpper : sim::LimitEnd::kLower;
                     }
                     c.active = std::get<3>(t);
                     return CommandBody(c);
                   }),
      rc::gen::map(rc::gen::tuple(rc::gen::inRange(-1, 32), rc::gen::arbitrary<bool>(),
                                  rc::gen::arbitrary<uint32_t>()),
                   [](std::tuple<int, bool, uint32_t> t) {
                     GioInCommand c;
                     if (std::get<0>(t) >= 0) {
                       c.bit = std::get<0>(t);
                       c.level = std::get<1>(t);
                     } else {
                       c.bits = std::get<2>(t);
                     }
                     return CommandBody(c);
                   }),
      rc::gen::map(rc::gen::inRange<int64_t>(0, 86400001),
                   [](int64_t ms) { return CommandBody(PowerCycleCommand{ms}); }),
      rc::gen::map(rc::gen::inRange<int64_t>(1, 86400001),
                   [](int64_t ms) { return CommandBody(CutLinkCommand{ms}); }),
      rc::gen::just(CommandBody(StateCommand{})), rc::gen::just(CommandBody(DevicesCommand{})),
      rc::gen::just(CommandBody(HelpCommand{})));
}

RC_GTEST_PROP(CommandCodecLaw, CanonicalJsonParsesBackToTheSameCommand, ()) {
  Command c;
  c.body = *GenBody();
  if (*rc::gen::arbitrary<bool>()) c.device = "dev-1";
  const json j = ToJson(c);
  auto parsed = ParseCommand(j);
  RC_ASSERT(std::holds_alternative<Command>(parsed));
  const Command& back = std::get<Command>(parsed);
  RC_ASSERT(back.device == c.device);
  RC_ASSERT(ToJson(back) == j);
  RC_ASSERT(back.body.index() == c.body.index());
}

}  // namespace
}  // namespace moco::control
