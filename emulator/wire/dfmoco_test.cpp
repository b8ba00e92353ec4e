// Tests for the DFMoco ASCII codec against dfmoco-protocol.txt ("Messages"), ERRATA part 2,
// FACTS "DFMoco" and the StackShot 3X dialect (stackshot-protocol.txt section 3): golden
// vectors from fixtures/wire/dfmoco.json, the sketch's error answers, framing, and laws.
#include "wire/dfmoco.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace moco::dfmoco {
namespace {

using Events = std::vector<LineFramer::OwnedEvent>;
using EventKind = FrameEvent::Kind;
using nlohmann::json;

LineFramer::OwnedEvent Line(std::string text) { return {EventKind::kLine, std::move(text)}; }
LineFramer::OwnedEvent Overflow(std::string text) {
  return {EventKind::kOverflow, std::move(text)};
}

Dialect DialectNamed(const std::string& name) {
  if (name == "dfmoco1") return Dfmoco1("1.3.0", 4);
  if (name == "stackshot") return StackShot3x();
  return Dfmoco2(4);
}

// The fixture's "meaning" object for a parsed value; written field by field from the
// spec's names, independently of the formatter.
json Meaning(const HostCommand& c) {
  if (std::holds_alternative<Hello>(c)) return {{"command", "hi"}};
  if (std::holds_alternative<MotorStatusQuery>(c)) return {{"command", "ms"}};
  if (auto* m = std::get_if<MoveMotor>(&c)) {
    return {{"command", "mm"}, {"motor", m->motor}, {"position", m->position_steps}};
  }
  if (auto* m = std::get_if<PositionQuery>(&c)) return {{"command", "mp"}, {"motor", m->motor}};
  if (std::holds_alternative<PositionQueryAll>(c)) return {{"command", "mp*"}};
  if (auto* m = std::get_if<StopMotor>(&c)) return {{"command", "sm"}, {"motor", m->motor}};
  if (auto* m = std::get_if<StopAll>(&c)) {
    json j = {{"command", "sa"}};
    if (m->motor) j["motor"] = *m->motor;
    return j;
  }
  if (auto* m = std::get_if<JogMotor>(&c)) {
    json j = {{"command", "jm"}, {"motor", m->motor}, {"destination", m->destination_steps}};
    if (m->velocity) j["velocity"] = *m->velocity;
    return j;
  }
  if (auto* m = std::get_if<InchMotor>(&c)) {
    return {{"command", "im"}, {"motor", m->motor}, {"destination", m->destination_steps}};
  }
  if (auto* m = std::get_if<SetPulseRate>(&c)) {
    return {{"command", "pr"}, {"motor", m->motor}, {"rate", m->rate_steps_per_s}};
  }
  if (auto* m = std::get_if<ZeroMotor>(&c)) return {{"command", "zm"}, {"motor", m->motor}};
  if (auto* m = std::get_if<NewPosition>(&c)) {
    return {{"command", "np"}, {"motor", m->motor}, {"position", m->position_steps}};
  }
  if (auto* m = std::get_if<BlurFrame>(&c)) {
    json channels = json::array();
    for (const auto& ch : m->channels) {
      channels.push_back({ch.channel, ch.p0_steps, ch.p1_steps, ch.p2_steps});
    }
    return {{"command", "bf"},
            {"exposure_ms", m->exposure_ms},
            {"blur", m->blur},
            {"channels", channels}};
  }
  if (std::holds_alternative<Go>(c)) return {{"command", "go"}};
  return {{"command", "unknown"}, {"line", std::get<UnknownCommand>(c).line}};
}

json Meaning(const DeviceReply& r) {
  if (auto* m = std::get_if<HelloReply>(&r)) {
    return {{"reply", "hi"},
            {"major", m->protocol_major},
            {"motors", m->motor_count},
            {"version", m->version}};
  }
  if (auto* m = std::get_if<MotorStatusReply>(&r)) {
    json moving = json::array();
    for (const bool b : m->moving) moving.push_back(b ? 1 : 0);
    return {{"reply", "ms"}, {"moving", moving}};
  }
  if (auto* m = std::get_if<MoveReply>(&r)) {
    return {{"reply", "mm"}, {"motor", m->motor}, {"position", m->position_steps}};
  }
  if (auto* m = std::get_if<PositionReply>(&r)) {
    return {{"reply", "mp"}, {"motor", m->motor}, {"position", m->position_steps}};
  }
  if (auto* m = std::get_if<StopMotorReply>(&r)) return {{"reply", "sm"}, {"motor", m->motor}};
  if (std::holds_alternative<StopAllReply>(r)) return {{"reply", "sa"}};
  if (auto* m = std::get_if<JogReply>(&r)) return {{"reply", "jm"}, {"motor", m->motor}};
  if (auto* m = std::get_if<InchReply>(&r)) return {{"reply", "im"}, {"motor", m->motor}};
  if (auto* m = std::get_if<PulseRateReply>(&r)) {
    return {{"reply", "pr"}, {"motor", m->motor}, {"rate", m->rate_steps_per_s}};
  }
  if (auto* m = std::get_if<ZeroReply>(&r)) return {{"reply", "zm"}, {"motor", m->motor}};
  if (auto* m = std::get_if<NewPositionReply>(&r)) {
    return {{"reply", "np"}, {"motor", m->motor}, {"position", m->position_steps}};
  }
  if (auto* m = std::get_if<BlurReply>(&r)) return {{"reply", "bf"}, {"value", m->value}};
  if (std::holds_alternative<GoReply>(r)) return {{"reply", "go"}};
  if (std::holds_alternative<ParseErrorReply>(r)) return {{"reply", "parse error"}};
  return {{"reply", "too many args"}};
}

// --- Golden vectors -----------------------------------------------------------------

json LoadVectors() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(root ? root : ".") + "/fixtures/wire/dfmoco.json";
  std::ifstream in(path);
  if (!in) return json();
  return json::parse(in, nullptr, /*allow_exceptions=*/false);
}

TEST(DfmocoGolden, EveryVectorParsesDescribesAndReformats) {
  const json doc = LoadVectors();
  ASSERT_TRUE(doc.is_object()) << "cannot read fixtures/wire/dfmoco.json (MOCO_SOURCE_DIR?)";
  ASSERT_EQ(doc.value("protocol", ""), "dfmoco");
  const json& vectors = doc.at("vectors");
  ASSERT_GE(vectors.size(), 30u);
  std::vector<std::string> host_words, device_words;
  for (const json& v : vectors) {
    const std::string name = v.at("name");
    SCOPED_TRACE(name);
    const std::string text = v.at("text");
    const Dialect dialect = DialectNamed(v.value("dialect", "dfmoco2"));
    // The line comes out of the sketch's framer as exactly one line.
    LineFramer framer;
    const Events events = framer.Feed(text);
    ASSERT_EQ(events.size(), 1u);
    ASSERT_EQ(events[0].kind, EventKind::kLine);
    ASSERT_EQ(events[0].text + "\r\n", text);
    if (v.at("direction") == "host") {
      const auto parsed = ParseHostLine(events[0].text, dialect);
      ASSERT_TRUE(parsed.ok()) << wire::Describe(parsed.error());
      EXPECT_EQ(Meaning(*parsed), v.at("meaning"));
      EXPECT_EQ(Describe(*parsed), v.at("describe"));
      EXPECT_EQ(FormatHost(*parsed), text);
      host_words.emplace_back(CommandWord(*parsed));
    } else {
      ASSERT_EQ(v.at("direction"), "device");
      const auto parsed = ParseDeviceLine(events[0].text, dialect);
      ASSERT_TRUE(parsed.ok()) << wire::Describe(parsed.error());
      EXPECT_EQ(Meaning(*parsed), v.at("meaning"));
      EXPECT_EQ(Describe(*parsed, dialect), v.at("describe"));
      EXPECT_EQ(FormatDevice(*parsed), text);
      device_words.push_back(text.substr(0, 2));
    }
  }
  // At least one vector per command and per reply of the protocol text.
  for (const char* w :
       {"hi", "ms", "mm", "mp", "sm", "sa", "jm", "im", "pr", "zm", "np", "bf", "go", "xx"}) {
    EXPECT_NE(std::find(host_words.begin(), host_words.end(), w), host_words.end()) << w;
  }
  for (const char* w :
       {"hi", "ms", "mm", "mp", "sm", "sa", "jm", "im", "pr", "zm", "np", "bf", "go", "pa", "er"}) {
    EXPECT_NE(std::find(device_words.begin(), device_words.end(), w), device_words.end()) << w;
  }
}

// --- Host lines: what the sketch answers ---------------------------------------------

wire::Result<HostCommand> Host(std::string_view line, const Dialect& d = Dfmoco2()) {
  return ParseHostLine(line, d);
}

// The device's answer to a line that failed: `parse error` or `error: too many args`.
std::string Answer(std::string_view line, const Dialect& d = Dfmoco2()) {
  const auto r = Host(line, d);
  if (r.ok()) return "ok";
  return FormatDevice(ErrorReply(r.error()));
}

TEST(DfmocoHost, WrongArgumentCountIsParseError) {  // FACTS: wrong argument count
  EXPECT_EQ(Answer("mm 1"), "parse error\r\n");
  EXPECT_EQ(Answer("mm 1 2 3"), "parse error\r\n");
  EXPECT_EQ(Answer("mp"), "parse error\r\n");
  EXPECT_EQ(Answer("sm"), "parse error\r\n");
  EXPECT_EQ(Answer("zm 1 2"), "parse error\r\n");
  EXPECT_EQ(Answer("pr 1"), "parse error\r\n");
  EXPECT_EQ(Answer("np 1"), "parse error\r\n");
  EXPECT_EQ(Answer("im 1"), "parse error\r\n");
  EXPECT_EQ(Answer("jm 1"), "parse error\r\n");
  EXPECT_EQ(Answer("jm 1 2 3 4"), "parse error\r\n");
  EXPECT_EQ(Answer("hi 1"), "parse error\r\n");
  EXPECT_EQ(Answer("go 1"), "parse error\r\n");
  EXPECT_EQ(Answer("bf 1000"), "parse error\r\n");
  EXPECT_EQ(Answer("bf 1000 500 1 0 100"), "parse error\r\n");  // incomplete channel group
}

TEST(DfmocoHost, JogVelocityOnlyFromProtocolTwo) {  // dfmoco-protocol.txt jm Note; ERRATA 2.2
  EXPECT_EQ(Answer("jm 1 100 5000", Dfmoco1()), "parse error\r\n");
  EXPECT_EQ(Answer("jm 1 100 5000", StackShot3x()), "parse error\r\n");
  const auto r = Host("jm 1 100 5000", Dfmoco2());
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(std::get<JogMotor>(*r), (JogMotor{1, 100, 5000}));
  EXPECT_EQ(Answer("jm 1 100 0"), "ok");
  EXPECT_EQ(Answer("jm 1 100 10000"), "ok");
  EXPECT_EQ(Answer("jm 1 100 10001"), "parse error\r\n");
  EXPECT_EQ(Answer("jm 1 100 -1"), "parse error\r\n");
  EXPECT_EQ(Host("jm 1 100 10001").error().kind, wire::DecodeError::Kind::kBadValue);
}

TEST(DfmocoHost, InvalidNumbersAreParseErrors) {
  EXPECT_EQ(Answer("mm 1 abc"), "parse error\r\n");
  EXPECT_EQ(Answer("mm 1 25x"), "parse error\r\n");
  EXPECT_EQ(Answer("mm 1 +25"), "parse error\r\n");
  EXPECT_EQ(Answer("mm 1 -"), "parse error\r\n");
  EXPECT_EQ(Answer("mm 1 2.5"), "parse error\r\n");
  EXPECT_EQ(Answer("mm x 25"), "parse error\r\n");
  const auto r = Host("mm 1 25x");
  EXPECT_EQ(r.error().kind, wire::DecodeError::Kind::kBadSyntax);
  EXPECT_EQ(r.error().offset, 5u);  // the offending token
}

TEST(DfmocoHost, PositionsAreSigned32Bit) {  // "All positions are in steps"; int32 args
  EXPECT_EQ(std::get<MoveMotor>(*Host("mm 1 2147483647")).position_steps, 2147483647);
  EXPECT_EQ(std::get<MoveMotor>(*Host("mm 1 -2147483648")).position_steps, INT32_MIN);
  const auto over = Host("mm 1 2147483648");
  ASSERT_FALSE(over.ok());
  EXPECT_EQ(over.error().kind, wire::DecodeError::Kind::kBadValue);
  EXPECT_EQ(Answer("mm 1 2147483648"), "parse error\r\n");
  EXPECT_EQ(Answer("np 1 -2147483649"), "parse error\r\n");
  EXPECT_EQ(Answer("pr 1 99999999999999999999"), "parse error\r\n");
  EXPECT_EQ(std::get<MoveMotor>(*Host("mm 01 -0007")), (MoveMotor{1, -7}));
}

TEST(DfmocoHost, FortyOrMoreArgumentsAnswerTooManyArgs) {  // FACTS: 40 or more arguments
  std::string bf38 = "bf 1000 500";
  for (int i = 0; i < 36; ++i) bf38 += " " + std::to_string(i);
  const auto ok = Host(bf38);
  ASSERT_TRUE(ok.ok());  // 38 arguments: 9 channels
  EXPECT_EQ(std::get<BlurFrame>(*ok).channels.size(), 9u);
  EXPECT_EQ(Answer(bf38 + " 1"), "parse error\r\n");  // 39: wrong count, still fits
  EXPECT_EQ(Answer(bf38 + " 1 2"), "error: too many args\r\n");
  std::string hi40 = "hi";
  for (int i = 0; i < 40; ++i) hi40 += " 1";
  EXPECT_EQ(Answer(hi40), "error: too many args\r\n");
  EXPECT_EQ(Answer(hi40 + " x y z"), "error: too many args\r\n");  // before any number check
  EXPECT_TRUE(IsTooManyArgs(Host(hi40).error()));
}

TEST(DfmocoHost, UnknownCommandsAreValuesWithNoReply) {  // FACTS: no reply at all
  for (const std::string_view line : {"xx", "xx 1 2", "HI", "hix", "", " hi", "m", "mmm 1 2"}) {
    const auto r = Host(line);
    ASSERT_TRUE(r.ok()) << line;
    EXPECT_EQ(std::get<UnknownCommand>(*r).line, line);
  }
  std::string many = "zz";
  for (int i = 0; i < 50; ++i) many += " 1";
  EXPECT_TRUE(std::holds_alternative<UnknownCommand>(*Host(many)));  // never counted
  EXPECT_EQ(CommandWord(*Host("xx 1 2")), "xx");
}

TEST(DfmocoHost, SpacingIsTolerated) {
  EXPECT_EQ(std::get<MoveMotor>(*Host("mm  1   250  ")), (MoveMotor{1, 250}));
  EXPECT_TRUE(std::holds_alternative<Hello>(*Host("hi ")));
}

TEST(DfmocoHost, BlurFrameChannelsAndNoChannels) {
  const auto r = Host("bf 1000 500 1 0 100 200 2 -50 0 50");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(std::get<BlurFrame>(*r),
            (BlurFrame{1000, 500, {BlurChannel{1, 0, 100, 200}, BlurChannel{2, -50, 0, 50}}}));
  // Reading: the channel groups are all optional ("[ch#1 number] ..."), so none is valid.
  EXPECT_EQ(std::get<BlurFrame>(*Host("bf 1000 500")), (BlurFrame{1000, 500, {}}));
}

TEST(DfmocoHost, StackShotDialectForms) {  // stackshot-protocol.txt section 3
  EXPECT_TRUE(std::holds_alternative<PositionQueryAll>(*Host("mp *", StackShot3x())));
  EXPECT_EQ(Answer("mp *", Dfmoco2()), "parse error\r\n");
  EXPECT_EQ(std::get<StopAll>(*Host("sa 3", StackShot3x())).motor, 3);
  EXPECT_EQ(std::get<StopAll>(*Host("sa", StackShot3x())).motor, std::nullopt);
  EXPECT_EQ(Answer("sa 3", Dfmoco2()), "parse error\r\n");
  EXPECT_EQ(Answer("sa 1 2", StackShot3x()), "parse error\r\n");
  EXPECT_EQ(Answer("mp * 1", StackShot3x()), "parse error\r\n");
}

TEST(DfmocoHost, MotorRangeBelongsToTheDevice) {
  // Motor 9 parses; the device with its motor count decides (FACTS: invalid motor ->
  // parse error).
  const auto r = Host("mm 9 100");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(AddressedMotor(*r), 9);
  EXPECT_FALSE(MotorInRange(9, Dfmoco2(4)));
  EXPECT_FALSE(MotorInRange(9, Dfmoco2(8)));
  EXPECT_TRUE(MotorInRange(8, Dfmoco2(8)));
  EXPECT_FALSE(MotorInRange(0, Dfmoco2(8)));  // motor numbers start at 1
  EXPECT_TRUE(MotorInRange(3, StackShot3x()));
  EXPECT_FALSE(MotorInRange(4, StackShot3x()));  // "Motors are specified as 1, 2, or 3"
  EXPECT_EQ(AddressedMotor(Hello{}), std::nullopt);
  EXPECT_EQ(AddressedMotor(StopAll{}), std::nullopt);
  EXPECT_EQ(AddressedMotor(StopAll{2}), 2);
  EXPECT_EQ(AddressedMotor(PositionQueryAll{}), std::nullopt);
  EXPECT_EQ(AddressedMotor(BlurFrame{}), std::nullopt);
}

TEST(DfmocoDialect, HelloAndDialectAgree) {
  EXPECT_EQ(FormatDevice(HelloFor(Dfmoco2(4))), "hi 2 4 2.0.0\r\n");
  EXPECT_EQ(FormatDevice(HelloFor(Dfmoco2(8))), "hi 2 8 2.0.0\r\n");
  EXPECT_EQ(FormatDevice(HelloFor(Dfmoco1("1.2.7", 4))), "hi 1 4 1.2.7\r\n");
  EXPECT_EQ(FormatDevice(HelloFor(StackShot3x())), "hi 1 3 1.2.6\r\n");
  EXPECT_EQ(DialectFrom(HelloFor(StackShot3x()), true), StackShot3x());
}

// --- Device lines ----------------------------------------------------------------------

TEST(DfmocoDevice, StackShotHelloWithTrailingSpace) {  // the document shows "hi 1 3 1.2.6 "
  const auto r = ParseDeviceLine("hi 1 3 1.2.6 ", StackShot3x());
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(std::get<HelloReply>(*r), (HelloReply{1, 3, "1.2.6"}));
}

TEST(DfmocoDevice, MalformedReplies) {
  const Dialect d = Dfmoco2();
  EXPECT_EQ(ParseDeviceLine("ms 1020", d).error().kind, wire::DecodeError::Kind::kBadSyntax);
  EXPECT_EQ(ParseDeviceLine("ms 1020", d).error().offset, 5u);
  EXPECT_FALSE(ParseDeviceLine("ms", d).ok());
  EXPECT_FALSE(ParseDeviceLine("ms 10 01", d).ok());  // no spaces between digits
  EXPECT_FALSE(ParseDeviceLine("mp 1", d).ok());
  EXPECT_FALSE(ParseDeviceLine("hi 2 4", d).ok());
  EXPECT_FALSE(ParseDeviceLine("hi x 4 2.0.0", d).ok());
  EXPECT_FALSE(ParseDeviceLine("bf", d).ok());
  EXPECT_FALSE(ParseDeviceLine("sa 1", d).ok());
  EXPECT_EQ(ParseDeviceLine("hello", d).error().kind, wire::DecodeError::Kind::kUnknown);
  EXPECT_EQ(ParseDeviceLine("parse  error", d).error().kind, wire::DecodeError::Kind::kUnknown);
  EXPECT_EQ(ParseDeviceLine("", d).error().kind, wire::DecodeError::Kind::kUnknown);
}

// --- Framing ---------------------------------------------------------------------------

TEST(DfmocoFramer, SketchTakesOnlyCrLf) {  // FACTS: a bare "\n" completes nothing
  LineFramer f;
  EXPECT_EQ(f.Feed("hi\r\n"), Events{Line("hi")});
  EXPECT_EQ(f.Feed("ms\n"), Events{});
  EXPECT_EQ(f.ignored_line_feeds(), 1u);
  EXPECT_EQ(f.buffered(), 2u);
  // The bare "\n" was dropped: the bytes around it join into one line.
  EXPECT_EQ(f.Feed("mp 1\r\n"), Events{Line("msmp 1")});
  EXPECT_EQ(f.Feed("mm 1 5\n0\r\n"), Events{Line("mm 1 50")});
  // A "\r" not followed by "\n" is an ordinary byte of the line.
  EXPECT_EQ(f.Feed("a\rb\r\n"), Events{Line("a\rb")});
  EXPECT_EQ(f.Feed("\r\r\n"), Events{Line("\r")});
  EXPECT_EQ(f.Feed("\r\n"), Events{Line("")});
  EXPECT_EQ(f.Feed("go\r"), Events{});
  EXPECT_EQ(f.Feed("\n"), Events{Line("go")});
}

TEST(DfmocoFramer, LenientTakesAnyTerminator) {  // ERRATA 2.1
  LineFramer f(FramerOptions{LineTermination::kLenient, kMaxLineBytes});
  EXPECT_EQ(f.Feed("hi\nms\rmp 1\r\nsa"), (Events{Line("hi"), Line("ms"), Line("mp 1")}));
  EXPECT_EQ(f.Feed("\r"), Events{Line("sa")});
  EXPECT_EQ(f.Feed("\n"), Events{});  // the "\n" of that "\r\n", across chunks
  EXPECT_EQ(f.Feed("\n\r"), (Events{Line(""), Line("")}));
  EXPECT_EQ(f.ignored_line_feeds(), 0u);
}

TEST(DfmocoFramer, OverflowIsReportedOnceAndResyncs) {
  LineFramer f(FramerOptions{LineTermination::kSketch, 8});
  EXPECT_EQ(f.Feed("12345678\r\n"), Events{Line("12345678")});  // exactly the bound fits
  EXPECT_EQ(f.Feed("123456789abc"), Events{Overflow("12345678")});
  EXPECT_EQ(f.buffered(), 0u);
  EXPECT_EQ(f.Feed("def\nxyz\r"), Events{});
  EXPECT_EQ(f.Feed("\nhi\r\n"), Events{Line("hi")});
  LineFramer g(FramerOptions{LineTermination::kLenient, 4});
  EXPECT_EQ(g.Feed("abcdefgh\rhi\n"), (Events{Overflow("abcd"), Line("hi")}));
}

TEST(DfmocoFramer, ResetForgetsThePartialLine) {
  LineFramer f;
  f.Feed("mm 1 2\r");
  f.Reset();
  EXPECT_EQ(f.buffered(), 0u);
  EXPECT_EQ(f.Feed("\nhi\r\n"), Events{Line("hi")});  // the "\n" is now bare
}

// --- Properties ------------------------------------------------------------------------

rc::Gen<int32_t> AnyInt() { return rc::gen::arbitrary<int32_t>(); }

rc::Gen<std::string> UnknownLine() {
  return rc::gen::exec([] {
    const auto is_known = [](const std::string& w) {
      for (const char* k :
           {"hi", "ms", "mm", "mp", "sm", "sa", "jm", "im", "pr", "zm", "np", "bf", "go"}) {
        if (w == k) return true;
      }
      return false;
    };
    const std::string word = *rc::gen::suchThat(
        rc::gen::container<std::string>(rc::gen::inRange('a', static_cast<char>('z' + 1))),
        [&](const std::string& w) { return !is_known(w); });
    const std::string rest =
        *rc::gen::container<std::string>(rc::gen::inRange(' ', static_cast<char>('~' + 1)));
    return rest.empty() ? word : word + " " + rest;
  });
}

rc::Gen<HostCommand> GenHost(const Dialect& d) {
  return rc::gen::exec([d]() -> HostCommand {
    switch (*rc::gen::inRange(0, 15)) {
      case 0:
        return Hello{};
      case 1:
        return MotorStatusQuery{};
      case 2:
        return MoveMotor{*AnyInt(), *AnyInt()};
      case 3:
        return PositionQuery{*AnyInt()};
      case 4:
        if (d.stackshot) return PositionQueryAll{};
        return PositionQuery{*AnyInt()};
      case 5:
        return StopMotor{*AnyInt()};
      case 6:
        if (d.stackshot && *rc::gen::arbitrary<bool>()) return StopAll{*AnyInt()};
        return StopAll{};
      case 7: {
        JogMotor j{*AnyInt(), *AnyInt(), std::nullopt};
        if (d.protocol_major >= 2 && *rc::gen::arbitrary<bool>()) {
          j.velocity = *rc::gen::inRange(0, kMaxJogVelocity + 1);
        }
        return j;
      }
      case 8:
        return InchMotor{*AnyInt(), *AnyInt()};
      case 9:
        return SetPulseRate{*AnyInt(), *AnyInt()};
      case 10:
        return ZeroMotor{*AnyInt()};
      case 11:
        return NewPosition{*AnyInt(), *AnyInt()};
      case 12: {
        BlurFrame bf{*AnyInt(), *AnyInt(), {}};
        const int channels = *rc::gen::inRange(0, 10);  // 2 + 4 * 9 = 38 arguments at most
        for (int i = 0; i < channels; ++i) {
          bf.channels.push_back(BlurChannel{*AnyInt(), *AnyInt(), *AnyInt(), *AnyInt()});
        }
        return bf;
      }
      case 13:
        return Go{};
      default:
        return UnknownCommand{*UnknownLine()};
    }
  });
}

rc::Gen<DeviceReply> GenDevice() {
  return rc::gen::exec([]() -> DeviceReply {
    switch (*rc::gen::inRange(0, 15)) {
      case 0:
        return HelloReply{*AnyInt(), *AnyInt(),
                          *rc::gen::nonEmpty(rc::gen::container<std::string>(
                              rc::gen::inRange('!', static_cast<char>('~' + 1))))};
      case 1:
        return MotorStatusReply{
            *rc::gen::nonEmpty(rc::gen::container<std::vector<bool>>(rc::gen::arbitrary<bool>()))};
      case 2:
        return MoveReply{*AnyInt(), *AnyInt()};
      case 3:
        return PositionReply{*AnyInt(), *AnyInt()};
      case 4:
        return StopMotorReply{*AnyInt()};
      case 5:
        return StopAllReply{};
      case 6:
        return JogReply{*AnyInt()};
      case 7:
        return InchReply{*AnyInt()};
      case 8:
        return PulseRateReply{*AnyInt(), *AnyInt()};
      case 9:
        return ZeroReply{*AnyInt()};
      case 10:
        return NewPositionReply{*AnyInt(), *AnyInt()};
      case 11:
        return BlurReply{*AnyInt()};
      case 12:
        return GoReply{};
      case 13:
        return ParseErrorReply{};
      default:
        return TooManyArgsReply{};
    }
  });
}

rc::Gen<Dialect> GenDialect() {
  return rc::gen::element(Dfmoco2(4), Dfmoco2(8), Dfmoco1("1.2.7", 4), StackShot3x());
}

// Splits `s` at random points.
std::vector<std::string> Chunk(const std::string& s) {
  std::vector<std::string> chunks;
  size_t pos = 0;
  while (pos < s.size()) {
    const size_t n = *rc::gen::inRange<size_t>(1, s.size() - pos + 1);
    chunks.push_back(s.substr(pos, n));
    pos += n;
  }
  return chunks;
}

// Bytes rich in terminators and spaces.
rc::Gen<std::string> StreamBytes() {
  return rc::gen::container<std::string>(
      rc::gen::weightedOneOf<char>({{3, rc::gen::element('\r', '\n')},
                                    {2, rc::gen::element(' ', 'h', 'i', 'm', '1', '-')},
                                    {1, rc::gen::arbitrary<char>()}}));
}

RC_GTEST_PROP(DfmocoProp, HostRoundTrip, ()) {
  const Dialect d = *GenDialect();
  const HostCommand c = *GenHost(d);
  const std::string text = FormatHost(c);
  RC_ASSERT(text.ends_with("\r\n"));
  const auto parsed = ParseHostLine(std::string_view(text).substr(0, text.size() - 2), d);
  RC_ASSERT(parsed.ok());
  RC_ASSERT(*parsed == c);
}

RC_GTEST_PROP(DfmocoProp, DeviceRoundTrip, ()) {
  const Dialect d = *GenDialect();
  const DeviceReply r = *GenDevice();
  const std::string text = FormatDevice(r);
  RC_ASSERT(text.ends_with("\r\n"));
  const auto parsed = ParseDeviceLine(std::string_view(text).substr(0, text.size() - 2), d);
  RC_ASSERT(parsed.ok());
  RC_ASSERT(*parsed == r);
}

// A stream of formatted commands, chunked anyhow, frames into the same commands.
RC_GTEST_PROP(DfmocoProp, FormattedStreamFramesBackInEveryMode, ()) {
  const Dialect d = *GenDialect();
  const auto commands = *rc::gen::container<std::vector<HostCommand>>(GenHost(d));
  std::string stream;
  for (const auto& c : commands) AppendHost(c, stream);
  for (const auto mode : {LineTermination::kSketch, LineTermination::kLenient}) {
    LineFramer f(FramerOptions{mode, kMaxLineBytes});
    std::vector<HostCommand> got;
    for (const auto& chunk : Chunk(stream)) {
      f.Feed(chunk, [&](const FrameEvent& e) {
        RC_ASSERT(e.kind == EventKind::kLine);
        const auto p = ParseHostLine(e.text, d);
        RC_ASSERT(p.ok());
        got.push_back(*p);
      });
    }
    RC_ASSERT(got == commands);
    RC_ASSERT(f.buffered() == 0u);
  }
}

RC_GTEST_PROP(DfmocoProp, AnyChunkingGivesTheSameEvents, ()) {
  const std::string bytes = *StreamBytes();
  const size_t bound = *rc::gen::inRange<size_t>(1, 40);
  for (const auto mode : {LineTermination::kSketch, LineTermination::kLenient}) {
    LineFramer whole(FramerOptions{mode, bound});
    const Events expected = whole.Feed(bytes);
    LineFramer pieces(FramerOptions{mode, bound});
    Events got;
    for (const auto& chunk : Chunk(bytes)) {
      for (auto& e : pieces.Feed(chunk)) got.push_back(std::move(e));
    }
    RC_ASSERT(got == expected);
    RC_ASSERT(pieces.buffered() == whole.buffered());
  }
}

// Sketch mode: a stream with no "\r\n" pair completes nothing, and inserting a bare "\n"
// anywhere (not right after "\r") changes no event.
RC_GTEST_PROP(DfmocoProp, BareLineFeedNeverCompletesACommand, ()) {
  std::string bytes = *StreamBytes();
  for (size_t i = 1; i < bytes.size(); ++i) {
    if (bytes[i - 1] == '\r' && bytes[i] == '\n') bytes[i] = 'x';
  }
  LineFramer f;
  RC_ASSERT(f.Feed(bytes).empty());

  const std::string stream = *StreamBytes();
  const size_t at = *rc::gen::inRange<size_t>(0, stream.size() + 1);
  // (computed first: RC_PRE decomposes its expression and would not short-circuit)
  const bool after_cr = at > 0 && stream[at - 1] == '\r';
  RC_PRE(!after_cr);
  const std::string with_lf = stream.substr(0, at) + "\n" + stream.substr(at);
  LineFramer a, b;
  RC_ASSERT(a.Feed(stream) == b.Feed(with_lf));
  RC_ASSERT(a.buffered() == b.buffered());
  RC_ASSERT(b.ignored_line_feeds() == a.ignored_line_feeds() + 1);
}

RC_GTEST_PROP(DfmocoProp, FramerStaysWithinItsBound, ()) {
  const size_t bound = *rc::gen::inRange<size_t>(1, 64);
  const auto mode = *rc::gen::element(LineTermination::kSketch, LineTermination::kLenient);
  const std::string bytes = *rc::gen::weightedOneOf<std::string>(
      {{1, rc::gen::arbitrary<std::string>()}, {2, StreamBytes()}});
  LineFramer f(FramerOptions{mode, bound});
  for (const auto& chunk : Chunk(bytes)) {
    f.Feed(chunk, [&](const FrameEvent& e) {
      if (e.kind == EventKind::kOverflow) {
        RC_ASSERT(e.text.size() == bound);
      } else {
        RC_ASSERT(e.text.size() <= bound);
      }
    });
    RC_ASSERT(f.buffered() <= bound);
  }
}

RC_GTEST_PROP(DfmocoProp, FortyOrMoreArgumentsAlwaysTooManyArgs, ()) {
  const Dialect d = *GenDialect();
  const std::string word = *rc::gen::element<std::string>("hi", "ms", "mm", "mp", "sm", "sa", "jm",
                                                          "im", "pr", "zm", "np", "bf", "go");
  const auto args = *rc::gen::container<std::vector<std::string>>(
      *rc::gen::inRange<size_t>(kMaxArgs, 120),
      rc::gen::nonEmpty(rc::gen::container<std::string>(rc::gen::arbitrary<char>())));
  std::string line = word;
  for (std::string a : args) {
    for (char& c : a) {
      if (c == ' ') c = '_';
    }
    line += " " + a;
  }
  const auto r = ParseHostLine(line, d);
  RC_ASSERT(!r.ok());
  RC_ASSERT(IsTooManyArgs(r.error()));
  RC_ASSERT(FormatDevice(ErrorReply(r.error())) == "error: too many args\r\n");
}

// After garbage of any length, one "\r\n" resynchronises: the next line is intact.
RC_GTEST_PROP(DfmocoProp, ResyncAfterGarbage, ()) {
  const Dialect d = *GenDialect();
  std::string garbage = *rc::gen::arbitrary<std::string>();
  for (char& c : garbage) {
    if (c == '\r' || c == '\n') c = '.';
  }
  const HostCommand c = *GenHost(d);
  RC_PRE(FormatHost(c).size() <= 66u);
  LineFramer f(FramerOptions{LineTermination::kSketch, 64});
  f.Feed(garbage + "\r\n");
  const Events events = f.Feed(FormatHost(c));
  RC_ASSERT(events.size() == 1u);
  const auto p = ParseHostLine(events[0].text, d);
  RC_ASSERT(p.ok());
  RC_ASSERT(*p == c);
}

RC_GTEST_PROP(DfmocoProp, ParsersNeverFailOnArbitraryLines, (const std::string& line)) {
  for (const Dialect& d : {Dfmoco2(4), Dfmoco1("1.2.7", 4), StackShot3x()}) {
    const auto h = ParseHostLine(line, d);
    if (h.ok()) {
      const std::string text = FormatHost(*h);
      const auto again = ParseHostLine(std::string_view(text).substr(0, text.size() - 2), d);
      RC_ASSERT(again.ok());
      RC_ASSERT(*again == *h);
      (void)Describe(*h);
    } else {
      RC_ASSERT(h.error().offset <= line.size());
    }
    const auto r = ParseDeviceLine(line, d);
    if (r.ok()) {
      const std::string text = FormatDevice(*r);
      const auto again = ParseDeviceLine(std::string_view(text).substr(0, text.size() - 2), d);
      RC_ASSERT(again.ok());
      RC_ASSERT(*again == *r);
    } else {
      RC_ASSERT(r.error().offset <= line.size());
    }
  }
}

}  // namespace
}  // namespace moco::dfmoco
