// DFMoco ASCII codec: parsing, formatting and description of every line
// (dfmoco-protocol.txt "Messages", ERRATA part 2, FACTS "DFMoco", stackshot-protocol.txt
// section 3 with ERRATA 3.9).
#include "wire/dfmoco.h"

#include <array>
#include <charconv>
#include <system_error>
#include <type_traits>
#include <utility>

namespace moco::dfmoco {
namespace {

using wire::DecodeError;
using Kind = DecodeError::Kind;

struct Token {
  std::string_view text;
  size_t offset = 0;
};

// The command word and up to kMaxArgs arguments of a line; `arg_count` counts all of
// them, also those beyond the stored ones.
struct SplitLine {
  std::string_view word;
  std::array<Token, kMaxArgs> args{};
  size_t arg_count = 0;
};

// The word is everything before the first space (so a leading space gives an empty
// word); arguments are the runs of non-space bytes after it.
SplitLine Split(std::string_view line) {
  SplitLine s;
  size_t pos = line.find(' ');
  s.word = line.substr(0, pos);
  while (pos < line.size()) {
    while (pos < line.size() && line[pos] == ' ') ++pos;
    if (pos >= line.size()) break;
    size_t end = pos;
    while (end < line.size() && line[end] != ' ') ++end;
    if (s.arg_count < s.args.size()) s.args[s.arg_count] = Token{line.substr(pos, end - pos), pos};
    ++s.arg_count;
    pos = end;
  }
  return s;
}

DecodeError Error(Kind kind, size_t offset, std::string detail) {
  return DecodeError{kind, offset, std::move(detail)};
}

// Strict decimal: an optional '-' and at least one digit, within int32.
// On failure fills `error` (kBadSyntax or kBadValue) and returns false.
bool ParseInt(const Token& t, std::string_view what, int32_t& out, DecodeError& error) {
  const std::string_view s = t.text;
  const size_t digits_from = (!s.empty() && s[0] == '-') ? 1 : 0;
  bool digits_only = s.size() > digits_from;
  for (size_t i = digits_from; i < s.size() && digits_only; ++i) {
    digits_only = s[i] >= '0' && s[i] <= '9';
  }
  if (!digits_only) {
    error = Error(Kind::kBadSyntax, t.offset,
                  std::string(what) + " is not a decimal integer: \"" + std::string(s) + "\"");
    return false;
  }
  int32_t v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec == std::errc::result_out_of_range) {
    error = Error(Kind::kBadValue, t.offset,
                  std::string(what) + " outside signed 32-bit range: " + std::string(s));
    return false;
  }
  if (ec != std::errc() || ptr != s.data() + s.size()) {
    error = Error(Kind::kBadSyntax, t.offset, std::string(what) + " is not a decimal integer");
    return false;
  }
  out = v;
  return true;
}

DecodeError WrongCount(std::string_view word, size_t got, std::string_view want, size_t offset) {
  return Error(Kind::kBadSyntax, offset,
               std::string(word) + " takes " + std::string(want) + " argument(s), got " +
                   std::to_string(got));
}

// Parses all arguments of `s` as int32 (arg_count <= kMaxArgs here).
bool ParseAllInts(const SplitLine& s, std::array<int32_t, kMaxArgs>& v, DecodeError& error) {
  static constexpr std::array<std::string_view, 4> kOrdinal = {"argument 1", "argument 2",
                                                               "argument 3", "argument 4"};
  for (size_t i = 0; i < s.arg_count; ++i) {
    const std::string_view what = i < kOrdinal.size() ? kOrdinal[i] : "argument";
    if (!ParseInt(s.args[i], what, v[i], error)) return false;
  }
  return true;
}

std::string_view TrimTrailingSpaces(std::string_view s) {
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return s;
}

bool IsVersionToken(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s) {
    if (c <= ' ' || c > '~') return false;
  }
  return true;
}

void AppendInt(std::string& out, int64_t v) {
  std::array<char, 24> buf{};
  const auto [ptr, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  (void)ec;  // 24 bytes hold any int64
  out.append(buf.data(), ptr);
}

void AppendWordInts(std::string& out, std::string_view word, std::initializer_list<int32_t> v) {
  out.append(word);
  for (const int32_t x : v) {
    out.push_back(' ');
    AppendInt(out, x);
  }
  out.append(kLineEnd);
}

std::string Quoted(std::string_view s) {
  std::string q = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      q.push_back('\\');
      q.push_back(c);
    } else if (u < 0x20 || u > 0x7e) {
      static constexpr char kHex[] = "0123456789abcdef";
      q += "\\x";
      q.push_back(kHex[u >> 4]);
      q.push_back(kHex[u & 0xF]);
    } else {
      q.push_back(c);
    }
  }
  q.push_back('"');
  return q;
}

std::string Str(int32_t v) { return std::to_string(v); }

}  // namespace

Dialect Dfmoco2(int32_t motor_count) { return Dialect{2, "2.0.0", motor_count, false}; }

Dialect Dfmoco1(std::string version, int32_t motor_count) {
  return Dialect{1, std::move(version), motor_count, false};
}

Dialect StackShot3x() { return Dialect{1, "1.2.6", kStackShotMotorCount, true}; }

// --- Host lines --------------------------------------------------------------------------

wire::Result<HostCommand> ParseHostLine(std::string_view line, const Dialect& dialect) {
  const SplitLine s = Split(line);
  const std::string_view w = s.word;
  const bool known = w == "hi" || w == "ms" || w == "mm" || w == "mp" || w == "sm" || w == "sa" ||
                     w == "jm" || w == "im" || w == "pr" || w == "zm" || w == "np" || w == "bf" ||
                     w == "go";
  // An unknown word gets no reply at all (FACTS), so its arguments are never counted.
  if (!known) return HostCommand{UnknownCommand{std::string(line)}};
  // 40 or more arguments answer `error: too many args` (FACTS), whatever they hold.
  if (s.arg_count >= kMaxArgs) {
    return Error(Kind::kBadLength, s.args[kMaxArgs - 1].offset,
                 std::to_string(s.arg_count) + " arguments; at most " +
                     std::to_string(kMaxArgs - 1) + " fit");
  }
  const size_t n = s.arg_count;
  const size_t end_offset = line.size();
  auto count_error = [&](size_t want_max, std::string_view want) {
    return WrongCount(w, n, want, n > want_max ? s.args[want_max].offset : end_offset);
  };

  // StackShot: `mp *` asks for every motor's position (stackshot-protocol.txt section 3).
  if (w == "mp" && dialect.stackshot && n == 1 && s.args[0].text == "*") {
    return HostCommand{PositionQueryAll{}};
  }

  std::array<int32_t, kMaxArgs> v{};
  DecodeError error;
  if (!ParseAllInts(s, v, error)) {
    // Reading: when both the count and a number are wrong, the count is reported
    // (the answer is `parse error` either way).
    const bool count_ok = (w == "hi" || w == "ms" || w == "go") ? n == 0
                          : (w == "sa") ? (n == 0 || (dialect.stackshot && n == 1))
                          : (w == "mp" || w == "sm" || w == "zm")              ? n == 1
                          : (w == "mm" || w == "im" || w == "pr" || w == "np") ? n == 2
                          : (w == "jm") ? (n == 2 || (dialect.protocol_major >= 2 && n == 3))
                                        : (n >= 2 && (n - 2) % 4 == 0);  // bf
    if (count_ok) return error;
  }

  if (w == "hi" || w == "ms" || w == "go") {
    if (n != 0) return count_error(0, "no");
    if (w == "hi") return HostCommand{Hello{}};
    if (w == "ms") return HostCommand{MotorStatusQuery{}};
    return HostCommand{Go{}};
  }
  if (w == "sa") {
    // `sa <motor>` is the StackShot document's form; DFMoco's text has no argument.
    if (dialect.stackshot) {
      if (n > 1) return count_error(1, "0 or 1");
      if (n == 1) return HostCommand{StopAll{v[0]}};
      return HostCommand{StopAll{}};
    }
    if (n != 0) return count_error(0, "no");
    return HostCommand{StopAll{}};
  }
  if (w == "mp" || w == "sm" || w == "zm") {
    if (n != 1) return count_error(1, "1");
    if (w == "mp") return HostCommand{PositionQuery{v[0]}};
    if (w == "sm") return HostCommand{StopMotor{v[0]}};
    return HostCommand{ZeroMotor{v[0]}};
  }
  if (w == "mm" || w == "im" || w == "pr" || w == "np") {
    if (n != 2) return count_error(2, "2");
    if (w == "mm") return HostCommand{MoveMotor{v[0], v[1]}};
    if (w == "im") return HostCommand{InchMotor{v[0], v[1]}};
    if (w == "pr") return HostCommand{SetPulseRate{v[0], v[1]}};
    return HostCommand{NewPosition{v[0], v[1]}};
  }
  if (w == "jm") {
    // The velocity exists only when the `hi` major version is 2 or more.
    if (dialect.protocol_major >= 2) {
      if (n != 2 && n != 3) return count_error(3, "2 or 3");
    } else if (n != 2) {
      return count_error(2, "2 (protocol 1 has no velocity)");
    }
    JogMotor jog{v[0], v[1], std::nullopt};
    if (n == 3) {
      if (v[2] < 0 || v[2] > kMaxJogVelocity) {
        return Error(Kind::kBadValue, s.args[2].offset,
                     "jm velocity " + Str(v[2]) + " outside 0..10000");
      }
      jog.velocity = v[2];
    }
    return HostCommand{jog};
  }
  // bf <exposure> <blur> {ch p0 p1 p2}...: the two leading values and whole groups of four.
  if (n < 2 || (n - 2) % 4 != 0) {
    return WrongCount(w, n, "2 + 4 per channel",
                      n < 2 ? end_offset : s.args[n - (n - 2) % 4].offset);
  }
  BlurFrame bf{v[0], v[1], {}};
  bf.channels.reserve((n - 2) / 4);
  for (size_t i = 2; i + 4 <= n; i += 4) {
    bf.channels.push_back(BlurChannel{v[i], v[i + 1], v[i + 2], v[i + 3]});
  }
  return HostCommand{std::move(bf)};
}

bool IsTooManyArgs(const wire::DecodeError& e) { return e.kind == Kind::kBadLength; }

DeviceReply ErrorReply(const wire::DecodeError& e) {
  if (IsTooManyArgs(e)) return TooManyArgsReply{};
  return ParseErrorReply{};
}

void AppendHost(const HostCommand& command, std::string& out) {
  std::visit(wire::Overloaded{
                 [&](const Hello&) { out.append("hi\r\n"); },
                 [&](const MotorStatusQuery&) { out.append("ms\r\n"); },
                 [&](const MoveMotor& c) {
                   AppendWordInts(out, "mm", {c.motor, c.position_steps});
                 },
                 [&](const PositionQuery& c) { AppendWordInts(out, "mp", {c.motor}); },
                 [&](const PositionQueryAll&) { out.append("mp *\r\n"); },
                 [&](const StopMotor& c) { AppendWordInts(out, "sm", {c.motor}); },
                 [&](const StopAll& c) {
                   if (c.motor) {
                     AppendWordInts(out, "sa", {*c.motor});
                   } else {
                     out.append("sa\r\n");
                   }
                 },
                 [&](const JogMotor& c) {
                   if (c.velocity) {
                     AppendWordInts(out, "jm", {c.motor, c.destination_steps, *c.velocity});
                   } else {
                     AppendWordInts(out, "jm", {c.motor, c.destination_steps});
                   }
                 },
                 [&](const InchMotor& c) {
                   AppendWordInts(out, "im", {c.motor, c.destination_steps});
                 },
                 [&](const SetPulseRate& c) {
                   AppendWordInts(out, "pr", {c.motor, c.rate_steps_per_s});
                 },
                 [&](const ZeroMotor& c) { AppendWordInts(out, "zm", {c.motor}); },
                 [&](const NewPosition& c) {
                   AppendWordInts(out, "np", {c.motor, c.position_steps});
                 },
                 [&](const BlurFrame& c) {
                   out.append("bf ");
                   AppendInt(out, c.exposure_ms);
                   out.push_back(' ');
                   AppendInt(out, c.blur);
                   for (const BlurChannel& ch : c.channels) {
                     for (const int32_t x : {ch.channel, ch.p0_steps, ch.p1_steps, ch.p2_steps}) {
                       out.push_back(' ');
                       AppendInt(out, x);
                     }
                   }
                   out.append(kLineEnd);
                 },
                 [&](const Go&) { out.append("go\r\n"); },
                 [&](const UnknownCommand& c) {
                   out.append(c.line);
                   out.append(kLineEnd);
                 },
             },
             command);
}

std::string FormatHost(const HostCommand& command) {
  std::string out;
  AppendHost(command, out);
  return out;
}

std::string Describe(const HostCommand& command) {
  return std::visit(
      wire::Overloaded{
          [](const Hello&) -> std::string { return "hello"; },
          [](const MotorStatusQuery&) -> std::string { return "motor status query"; },
          [](const MoveMotor& c) {
            return "move motor " + Str(c.motor) + " to " + Str(c.position_steps);
          },
          [](const PositionQuery& c) { return "position query, motor " + Str(c.motor); },
          [](const PositionQueryAll&) -> std::string { return "position query, all motors"; },
          [](const StopMotor& c) { return "stop motor " + Str(c.motor); },
          [](const StopAll& c) -> std::string {
            if (c.motor) return "stop all motors (motor " + Str(*c.motor) + " given)";
            return "stop all motors";
          },
          [](const JogMotor& c) {
            std::string d = "jog motor " + Str(c.motor) + " toward " + Str(c.destination_steps);
            if (c.velocity) d += " at velocity " + Str(*c.velocity) + "/10000";
            return d;
          },
          [](const InchMotor& c) {
            return "inch motor " + Str(c.motor) + " toward " + Str(c.destination_steps);
          },
          [](const SetPulseRate& c) {
            return "set pulse rate of motor " + Str(c.motor) + " to " + Str(c.rate_steps_per_s) +
                   " steps/s";
          },
          [](const ZeroMotor& c) { return "zero motor " + Str(c.motor); },
          [](const NewPosition& c) {
            return "set position of motor " + Str(c.motor) + " to " + Str(c.position_steps) +
                   " (no movement)";
          },
          [](const BlurFrame& c) {
            std::string d = "blur frame: exposure " + Str(c.exposure_ms) + " ms, blur " +
                            Str(c.blur) + "/1000, " + std::to_string(c.channels.size()) +
                            " channel(s)";
            for (const BlurChannel& ch : c.channels) {
              d += "; ch " + Str(ch.channel) + " " + Str(ch.p0_steps) + " -> " + Str(ch.p1_steps) +
                   " -> " + Str(ch.p2_steps);
            }
            return d;
          },
          [](const Go&) -> std::string { return "go (start go-motion move)"; },
          [](const UnknownCommand& c) {
            return "unknown command " + Quoted(c.line) + " (no reply)";
          },
      },
      command);
}

std::string_view CommandWord(const HostCommand& command) {
  return std::visit(wire::Overloaded{
                        [](const Hello&) -> std::string_view { return "hi"; },
                        [](const MotorStatusQuery&) -> std::string_view { return "ms"; },
                        [](const MoveMotor&) -> std::string_view { return "mm"; },
                        [](const PositionQuery&) -> std::string_view { return "mp"; },
                        [](const PositionQueryAll&) -> std::string_view { return "mp"; },
                        [](const StopMotor&) -> std::string_view { return "sm"; },
                        [](const StopAll&) -> std::string_view { return "sa"; },
                        [](const JogMotor&) -> std::string_view { return "jm"; },
                        [](const InchMotor&) -> std::string_view { return "im"; },
                        [](const SetPulseRate&) -> std::string_view { return "pr"; },
                        [](const ZeroMotor&) -> std::string_view { return "zm"; },
                        [](const NewPosition&) -> std::string_view { return "np"; },
                        [](const BlurFrame&) -> std::string_view { return "bf"; },
                        [](const Go&) -> std::string_view { return "go"; },
                        [](const UnknownCommand& c) -> std::string_view {
                          const std::string_view line = c.line;
                          return line.substr(0, line.find(' '));
                        },
                    },
                    command);
}

std::optional<int32_t> AddressedMotor(const HostCommand& command) {
  return std::visit(
      [](const auto& c) -> std::optional<int32_t> {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, StopAll>) {
          return c.motor;
        } else if constexpr (requires { c.motor; }) {
          return c.motor;
        } else {
          return std::nullopt;
        }
      },
      command);
}

bool MotorInRange(int32_t motor, const Dialect& dialect) {
  return motor >= 1 && motor <= dialect.motor_count;
}

HelloReply HelloFor(const Dialect& dialect) {
  return HelloReply{dialect.protocol_major, dialect.motor_count, dialect.firmware_version};
}

Dialect DialectFrom(const HelloReply& hello, bool stackshot) {
  return Dialect{hello.protocol_major, hello.version, hello.motor_count, stackshot};
}

// --- Device lines --------------------------------------------------------------------

wire::Result<DeviceReply> ParseDeviceLine(std::string_view line, const Dialect& dialect) {
  (void)dialect;  // one grammar for both dialects (see the header)
  const std::string_view t = TrimTrailingSpaces(line);
  if (t == "parse error") return DeviceReply{ParseErrorReply{}};
  if (t == "error: too many args") return DeviceReply{TooManyArgsReply{}};
  const SplitLine s = Split(t);
  const std::string_view w = s.word;
  const size_t n = s.arg_count;
  auto count_error = [&](size_t want) {
    return WrongCount(w, n, std::to_string(want), n > want ? s.args[want].offset : t.size());
  };
  DecodeError error;

  if (w == "hi") {
    if (n != 3) return count_error(3);
    int32_t major = 0;
    int32_t motors = 0;
    if (!ParseInt(s.args[0], "protocol major", major, error)) return error;
    if (!ParseInt(s.args[1], "motor count", motors, error)) return error;
    if (!IsVersionToken(s.args[2].text)) {
      return Error(Kind::kBadSyntax, s.args[2].offset, "version is not printable ASCII");
    }
    return DeviceReply{HelloReply{major, motors, std::string(s.args[2].text)}};
  }
  if (w == "ms") {
    if (n != 1) return count_error(1);
    MotorStatusReply ms;
    ms.moving.reserve(s.args[0].text.size());
    for (size_t i = 0; i < s.args[0].text.size(); ++i) {
      const char c = s.args[0].text[i];
      if (c != '0' && c != '1') {
        return Error(Kind::kBadSyntax, s.args[0].offset + i,
                     "ms digit for motor " + std::to_string(i + 1) + " is not 0 or 1");
      }
      ms.moving.push_back(c == '1');
    }
    return DeviceReply{std::move(ms)};
  }
  const bool two_ints = w == "mm" || w == "mp" || w == "pr" || w == "np";
  const bool one_int = w == "sm" || w == "jm" || w == "im" || w == "zm" || w == "bf";
  const bool no_args = w == "sa" || w == "go";
  if (!two_ints && !one_int && !no_args) {
    return Error(Kind::kUnknown, 0, "not a DFMoco reply: " + Quoted(line));
  }
  const size_t want = two_ints ? 2 : one_int ? 1 : 0;
  if (n != want) return count_error(want);
  if (no_args) {
    if (w == "sa") return DeviceReply{StopAllReply{}};
    return DeviceReply{GoReply{}};
  }
  std::array<int32_t, kMaxArgs> v{};
  if (!ParseAllInts(s, v, error)) return error;
  if (w == "mm") return DeviceReply{MoveReply{v[0], v[1]}};
  if (w == "mp") return DeviceReply{PositionReply{v[0], v[1]}};
  if (w == "pr") return DeviceReply{PulseRateReply{v[0], v[1]}};
  if (w == "np") return DeviceReply{NewPositionReply{v[0], v[1]}};
  if (w == "sm") return DeviceReply{StopMotorReply{v[0]}};
  if (w == "jm") return DeviceReply{JogReply{v[0]}};
  if (w == "im") return DeviceReply{InchReply{v[0]}};
  if (w == "zm") return DeviceReply{ZeroReply{v[0]}};
  return DeviceReply{BlurReply{v[0]}};
}

void AppendDevice(const DeviceReply& reply, std::string& out) {
  std::visit(wire::Overloaded{
                 [&](const HelloReply& r) {
                   out.append("hi ");
                   AppendInt(out, r.protocol_major);
                   out.push_back(' ');
                   AppendInt(out, r.motor_count);
                   out.push_back(' ');
                   out.append(r.version);
                   out.append(kLineEnd);
                 },
                 [&](const MotorStatusReply& r) {
                   out.append("ms ");
                   for (const bool m : r.moving) out.push_back(m ? '1' : '0');
                   out.append(kLineEnd);
                 },
                 [&](const MoveReply& r) {
                   AppendWordInts(out, "mm", {r.motor, r.position_steps});
                 },
                 [&](const PositionReply& r) {
                   AppendWordInts(out, "mp", {r.motor, r.position_steps});
                 },
                 [&](const StopMotorReply& r) { AppendWordInts(out, "sm", {r.motor}); },
                 [&](const StopAllReply&) { out.append("sa\r\n"); },
                 [&](const JogReply& r) { AppendWordInts(out, "jm", {r.motor}); },
                 [&](const InchReply& r) { AppendWordInts(out, "im", {r.motor}); },
                 [&](const PulseRateReply& r) {
                   AppendWordInts(out, "pr", {r.motor, r.rate_steps_per_s});
                 },
                 [&](const ZeroReply& r) { AppendWordInts(out, "zm", {r.motor}); },
                 [&](const NewPositionReply& r) {
                   AppendWordInts(out, "np", {r.motor, r.position_steps});
                 },
                 [&](const BlurReply& r) { AppendWordInts(out, "bf", {r.value}); },
                 [&](const GoReply&) { out.append("go\r\n"); },
                 [&](const ParseErrorReply&) { out.append("parse error\r\n"); },
                 [&](const TooManyArgsReply&) { out.append("error: too many args\r\n"); },
             },
             reply);
}

std::string FormatDevice(const DeviceReply& reply) {
  std::string out;
  AppendDevice(reply, out);
  return out;
}

std::string Describe(const DeviceReply& reply, const Dialect& dialect) {
  return std::visit(
      wire::Overloaded{
          [](const HelloReply& r) {
            return "hello: protocol " + Str(r.protocol_major) + ", " + Str(r.motor_count) +
                   " motors, firmware " + r.version;
          },
          [](const MotorStatusReply& r) {
            std::string moving;
            for (size_t i = 0; i < r.moving.size(); ++i) {
              if (!r.moving[i]) continue;
              if (!moving.empty()) moving += ",";
              moving += std::to_string(i + 1);
            }
            return "motor status: " + std::to_string(r.moving.size()) +
                   " motors, moving: " + (moving.empty() ? std::string("none") : moving);
          },
          [&](const MoveReply& r) {
            if (dialect.stackshot) {
              return "motor " + Str(r.motor) + " moving, now at " + Str(r.position_steps);
            }
            return "motor " + Str(r.motor) + " moving to " + Str(r.position_steps);
          },
          [](const PositionReply& r) {
            return "motor " + Str(r.motor) + " at " + Str(r.position_steps);
          },
          [](const StopMotorReply& r) { return "stopping motor " + Str(r.motor); },
          [](const StopAllReply&) -> std::string { return "stopping all motors"; },
          [](const JogReply& r) { return "jogging motor " + Str(r.motor); },
          [](const InchReply& r) { return "inching motor " + Str(r.motor); },
          [](const PulseRateReply& r) {
            return "motor " + Str(r.motor) + " pulse rate " + Str(r.rate_steps_per_s) + " steps/s";
          },
          [](const ZeroReply& r) { return "zeroed motor " + Str(r.motor); },
          [](const NewPositionReply& r) {
            return "motor " + Str(r.motor) + " position set to " + Str(r.position_steps);
          },
          [](const BlurReply& r) -> std::string {
            if (r.value == kBlurRefused)
              return "blur frame refused: a speed would exceed 20000 steps/s";
            return "blur frame prepared (" + Str(r.value) + ")";
          },
          [](const GoReply&) -> std::string { return "go-motion move started"; },
          [](const ParseErrorReply&) -> std::string { return "parse error"; },
          [](const TooManyArgsReply&) -> std::string {
            return "error: too many args (40 or more arguments)";
          },
      },
      reply);
}

// --- Framer ----------------------------------------------------------------------------

LineFramer::LineFramer(FramerOptions options) : options_(options) {
  if (options_.max_line_bytes == 0) options_.max_line_bytes = 1;
  line_.reserve(options_.max_line_bytes);
}

std::vector<LineFramer::OwnedEvent> LineFramer::Feed(std::string_view bytes) {
  std::vector<OwnedEvent> events;
  Feed(bytes, [&](const FrameEvent& e) {
    events.push_back(OwnedEvent{e.kind, std::string(e.text)});
  });
  return events;
}

void LineFramer::Reset() {
  line_.clear();
  pending_cr_ = false;
  skip_lf_ = false;
  discarding_ = false;
}

}  // namespace moco::dfmoco
