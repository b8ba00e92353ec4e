// The Dragonframe-style DFMoco host of the conformance runner and its stream
// checks (dfmoco-protocol.txt "Message Format", "Messages"; ERRATA dfmoco
// 1-5; FACTS "DFMoco").
#include "conformance/protocols/dfmoco/dfmoco_host.h"

#include "base/format.h"

#include <algorithm>
#include <cstdio>

#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "wire/dfmoco_sketch_reader.h"

namespace moco::conformance {
namespace {

// A command's kind for HostBase::Unanswered: its word ("mm", "hi").
std::string CommandWord(const std::string& line) { return line.substr(0, line.find(' ')); }

using dfmoco::DeviceReply;

using base::Ms;

std::string Quote(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\r') {
      out += "\\r";
    } else if (c == '\n') {
      out += "\\n";
    } else if (u < 0x20 || u > 0x7e) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// The motor a reply names, if it names one.
std::optional<int32_t> ReplyMotor(const DeviceReply& r) {
  return std::visit(
      wire::Overloaded{
          [](const dfmoco::MoveReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::PositionReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::StopMotorReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::JogReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::InchReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::PulseRateReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::ZeroReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const dfmoco::NewPositionReply& m) -> std::optional<int32_t> { return m.motor; },
          [](const auto&) -> std::optional<int32_t> { return std::nullopt; },
      },
      r);
}

bool IsError(const DeviceReply& r) {
  return std::holds_alternative<dfmoco::ParseErrorReply>(r) ||
         std::holds_alternative<dfmoco::TooManyArgsReply>(r);
}

// The rule that judges the normal answer to a command word.
std::string_view AnswerRule(std::string_view word, const dfmoco::HostCommand* parsed) {
  if (word == "hi") return "DFM-HI-002";
  if (word == "ms") return "DFM-MS-001";
  if (word == "mm") return "DFM-MM-001";
  if (word == "mp") return "DFM-MP-001";
  if (word == "sm") return "DFM-SM-001";
  if (word == "sa") return "DFM-SA-001";
  if (word == "jm") {
    const auto* j = parsed != nullptr ? std::get_if<dfmoco::JogMotor>(parsed) : nullptr;
    return j != nullptr && j->velocity ? "DFM-JM-003" : "DFM-JM-001";
  }
  if (word == "im") return "DFM-IM-001";
  if (word == "pr") return "DFM-PR-001";
  if (word == "zm") return "DFM-ZM-001";
  if (word == "np") return "DFM-NP-001";
  if (word == "bf") return "DFM-GO-001";
  if (word == "go") return "DFM-GO-004";
  return "DFM-REPLY-001";
}

// The deadline rule and kind of a command word.
std::pair<std::string_view, std::string_view> DeadlineRule(std::string_view word) {
  if (word == "hi") return {"DFM-DL-001", "hi"};
  if (word == "ms" || word == "mp") return {"DFM-DL-002", "query"};
  if (word == "bf" || word == "go") return {"DFM-DL-004", "rt"};
  return {"DFM-DL-003", "command"};
}

bool IsDottedDecimal(std::string_view v) {
  bool digit = false;
  for (const char c : v) {
    if (c >= '0' && c <= '9') {
      digit = true;
    } else if (c == '.' && digit) {
      digit = false;
    } else {
      return false;
    }
  }
  return digit;
}

}  // namespace

std::string_view WordOf(std::string_view line) { return line.substr(0, line.find(' ')); }

std::string Show(const DfmLine* line) {
  if (line == nullptr) return "no answer";
  return Quote(line->text);
}

DfmHost::DfmHost(Target& target, Verdicts& verdicts, HostOptions options)
    : HostBase(target, verdicts, std::move(options),
               [this](wire::ByteView bytes) { OnBytes(bytes); }) {}

bool IsStackShotHello(const dfmoco::HelloReply& hello) {
  const dfmoco::Dialect ss = dfmoco::StackShot3x();
  return hello.protocol_major == ss.protocol_major && hello.motor_count == ss.motor_count &&
         hello.version == ss.firmware_version;
}

bool DfmHost::stackshot() const {
  const std::string& d = options().dialect;
  if (d == kStackshotDialect) return true;
  if (d == kSketchDialect) return false;
  return hello_ && IsStackShotHello(*hello_);
}

dfmoco::Dialect DfmHost::dialect() const {
  if (!hello_) return stackshot() ? dfmoco::StackShot3x() : dfmoco::Dfmoco2(4);
  return dfmoco::DialectFrom(*hello_, stackshot());
}

Evidence DfmHost::Ev(const DfmLine& line, std::string expected, std::string observed) const {
  return Evidence{std::move(expected), std::move(observed), wire::ToHex(line.raw), line.t_ns};
}

DfmCommand DfmHost::MakeCommand(std::string_view line, std::string_view error_rule) const {
  DfmCommand c;
  c.line = std::string(line);
  c.sent_ns = Now();
  const dfmoco::Dialect d = dialect();
  // A real sketch reads the line byte by byte (wire/dfmoco_sketch_reader.h):
  // "mm 1 --5" is a move to -5, "mm 1 99999999999" wraps, "ms 1" is `ms`;
  // only what it then reads is judged for counts and motors (FACTS DFMoco).
  // The StackShot 3X is no sketch: its lines are read by the protocol's
  // grammar in its dialect (`mp *`, `sa <motor>`).
  const bool ss = stackshot();
  const dfmoco::SketchReading sketch = dfmoco::ReadLineAsSketch(line);
  if (!ss && sketch.kind == dfmoco::SketchReading::Kind::kTooManyArgs) {
    c.expect = DfmExpect::kTooMany;
    c.error_rule = "DFM-ERR-003";
    return c;
  }
  if (!ss && sketch.kind == dfmoco::SketchReading::Kind::kNothing) {
    c.parsed = dfmoco::HostCommand{dfmoco::UnknownCommand{std::string(line)}};
    c.expect = DfmExpect::kSilence;
    return c;
  }
  const auto parsed = dfmoco::ParseHostLine(ss ? std::string(line) : sketch.CanonicalLine(), d);
  if (!parsed.ok()) {
    c.expect = dfmoco::IsTooManyArgs(parsed.error()) ? DfmExpect::kTooMany : DfmExpect::kError;
    c.error_rule = c.expect == DfmExpect::kTooMany ? "DFM-ERR-003" : "DFM-ERR-001";
    return c;
  }
  c.parsed = parsed.value();
  const auto motor = dfmoco::AddressedMotor(*c.parsed);
  if (std::holds_alternative<dfmoco::UnknownCommand>(*c.parsed)) {
    c.expect = DfmExpect::kSilence;
  } else if (stackshot() && (std::holds_alternative<dfmoco::BlurFrame>(*c.parsed) ||
                             std::holds_alternative<dfmoco::Go>(*c.parsed))) {
    // "The DfMoco interface does not support real-time motion control"
    // (stackshot-protocol.txt section 3): no go-motion answer (DFM-SS-009).
    c.expect = DfmExpect::kSilence;
  } else if (motor && hello_ && !dfmoco::MotorInRange(*motor, d)) {
    c.expect = DfmExpect::kError;
    c.error_rule = "DFM-ERR-002";
  } else if (!error_rule.empty()) {
    c.expect = DfmExpect::kError;
    c.error_rule = error_rule;
  }
  return c;
}

int DfmHost::Send(std::string_view line, std::string_view error_rule, std::string_view terminator) {
  link_.Pump(Now());  // what the device wrote before this command is not its answer
  DfmCommand c = MakeCommand(line, error_rule);
  c.timed = terminator == "\r\n";
  commands_.push_back(std::move(c));
  SendRaw(std::string(line) + std::string(terminator));
  return static_cast<int>(commands_.size() - 1);
}

int DfmHost::SendBatch(const std::vector<std::string>& lines) {
  link_.Pump(Now());
  const int first = static_cast<int>(commands_.size());
  std::string bytes;
  for (const std::string& l : lines) {
    commands_.push_back(MakeCommand(l, {}));
    bytes += l + "\r\n";
  }
  SendRaw(bytes);
  return first;
}

void DfmHost::SendRaw(std::string_view bytes) {
  const wire::ByteView view(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  link_.Write(view);
}

void DfmHost::OnBytes(wire::ByteView bytes) {
  // A lenient framer, so that a wrong terminator is reported and the lines
  // still count: "\r\n" is right; a bare "\n" or a bare "\r" also ends a line.
  for (const uint8_t b : bytes) {
    if (pending_cr_) {
      pending_cr_ = false;
      if (b == '\n') {
        partial_.push_back(b);
        EndLine(true);
        continue;
      }
      EndLine(false);
    }
    partial_.push_back(b);
    if (b == '\r') {
      pending_cr_ = true;
    } else if (b == '\n') {
      EndLine(false);
    } else if (partial_.size() > 4096) {
      EndLine(false);  // no terminator in sight: judge what came
    }
  }
}

void DfmHost::EndLine(bool crlf) {
  DfmLine line;
  line.t_ns = Now();
  line.raw = std::move(partial_);
  partial_.clear();
  size_t n = line.raw.size();
  while (n > 0 && (line.raw[n - 1] == '\r' || line.raw[n - 1] == '\n')) --n;
  line.text.assign(line.raw.begin(), line.raw.begin() + static_cast<std::ptrdiff_t>(n));
  OnLine(std::move(line), crlf);
}

void DfmHost::OnLine(DfmLine line, bool crlf) {
  const DfmLine& l = line;
  verdicts_.Check("DFM-LINE-001", crlf, [&] {
    return Ev(l, "a line ending in \\r\\n",
              "a line ending in " +
                  Quote(std::string(l.raw.begin() + static_cast<std::ptrdiff_t>(l.text.size()),
                                    l.raw.end())));
  });
  bool ascii = true;
  for (const char c : l.text) ascii = ascii && c >= 0x20 && c <= 0x7e;
  verdicts_.Check("DFM-LINE-002", ascii,
                  [&] { return Ev(l, "printable ASCII", "the line " + Quote(l.text)); });
  auto parsed = dfmoco::ParseDeviceLine(l.text, dialect());
  if (parsed.ok()) line.reply = parsed.value();
  verdicts_.Check("DFM-LINE-004", parsed.ok(), [&] {
    return Ev(l, "a reply of the protocol",
              Quote(l.text) + " (" + wire::Describe(parsed.error()) + ")");
  });
  const std::string_view word = WordOf(l.text);
  if (!parsed.ok()) {
    if (word == "hi") {
      verdicts_.Fail("DFM-HI-002", Ev(l, "hi <major> <axes> <version>", Quote(l.text)));
    }
    if (word == "ms") {
      verdicts_.Fail("DFM-MS-001", Ev(l, "ms and one 0/1 digit per motor", Quote(l.text)));
    }
    lines_.push_back(std::move(line));
    return;
  }
  const DeviceReply& reply = *line.reply;
  verdicts_.Check("DFM-LINE-006", dfmoco::FormatDevice(reply) == l.text + "\r\n", [&] {
    std::string plain = dfmoco::FormatDevice(reply);
    plain.resize(plain.size() - 2);
    return Ev(l, Quote(plain), Quote(l.text));
  });
  if (const auto motor = ReplyMotor(reply); motor && hello_) {
    verdicts_.Check("DFM-MOTOR-001", *motor >= 1 && *motor <= hello_->motor_count, [&] {
      return Ev(l, "a motor 1-" + std::to_string(hello_->motor_count), Quote(l.text));
    });
  }
  if (const auto* ms = std::get_if<dfmoco::MotorStatusReply>(&reply)) {
    verdicts_.Pass("DFM-MS-001");
    if (hello_) {
      verdicts_.Check(
          "DFM-MS-002", ms->moving.size() == static_cast<size_t>(hello_->motor_count), [&] {
            return Ev(l, std::to_string(hello_->motor_count) + " digits (hi axes)",
                      std::to_string(ms->moving.size()) + " digits in " + Quote(l.text));
          });
    }
  }
  if (const auto* hi = std::get_if<dfmoco::HelloReply>(&reply)) CheckHello(l, *hi);

  const int k = Match(reply);
  const size_t index = lines_.size();
  line.command = k;
  lines_.push_back(std::move(line));
  const DfmLine& stored = lines_.back();
  if (k >= 0) {
    DfmCommand& c = commands_[static_cast<size_t>(k)];
    ++c.answers;
    c.answer = static_cast<int>(index);
    Answered(CommandWord(c.line));
    CheckAnswer(c, stored);
    return;
  }
  if (std::holds_alternative<dfmoco::PositionReply>(reply)) return;  // a report
  // The StackShot 3X reports a moving motor with `mm <motor> <current
  // position>` "transmitted periodically" (stackshot-protocol.txt section 3).
  if (stackshot() && std::holds_alternative<dfmoco::MoveReply>(reply)) return;
  if (std::holds_alternative<dfmoco::HelloReply>(reply) && commands_.empty()) return;  // boot
  // A second answer to a command already answered?
  for (size_t i = commands_.size(); i-- > 0;) {
    const DfmCommand& c = commands_[i];
    if (c.answers == 0 || !Fits(c, reply)) continue;
    verdicts_.Fail("DFM-REPLY-002", Ev(stored, "one answer to " + Quote(c.line),
                                       "a second answer " + Quote(stored.text)));
    return;
  }
  verdicts_.Fail("DFM-LINE-005",
                 Ev(stored, "an answer to a command sent, or an mp report",
                    Quote(stored.text) + (commands_.empty()
                                              ? " before any command"
                                              : ", last command " + Quote(commands_.back().line))));
}

bool DfmHost::Fits(const DfmCommand& c, const DeviceReply& reply) const {
  if (IsError(reply)) return c.expect != DfmExpect::kSilence;
  if (!c.parsed) return false;
  using namespace dfmoco;
  return std::visit(
      wire::Overloaded{
          [&](const Hello&) { return std::holds_alternative<HelloReply>(reply); },
          [&](const MotorStatusQuery&) { return std::holds_alternative<MotorStatusReply>(reply); },
          [&](const MoveMotor& m) {
            if (std::holds_alternative<MoveReply>(reply)) return true;
            const auto* p = std::get_if<PositionReply>(&reply);
            return p != nullptr && p->motor == m.motor && p->position_steps == m.position_steps;
          },
          [&](const PositionQuery& m) {
            const auto* p = std::get_if<PositionReply>(&reply);
            return p != nullptr && p->motor == m.motor;
          },
          // `mp *`: one `mp` per motor (the StackShot dialect); the first answers.
          [&](const PositionQueryAll&) { return std::holds_alternative<PositionReply>(reply); },
          [&](const StopMotor&) { return std::holds_alternative<StopMotorReply>(reply); },
          [&](const StopAll&) { return std::holds_alternative<StopAllReply>(reply); },
          [&](const JogMotor&) { return std::holds_alternative<JogReply>(reply); },
          [&](const InchMotor&) { return std::holds_alternative<InchReply>(reply); },
          [&](const SetPulseRate&) { return std::holds_alternative<PulseRateReply>(reply); },
          [&](const ZeroMotor& m) {
            if (std::holds_alternative<ZeroReply>(reply)) return true;
            const auto* p = std::get_if<PositionReply>(&reply);
            return p != nullptr && p->motor == m.motor && p->position_steps == 0;
          },
          [&](const NewPosition& m) {
            if (std::holds_alternative<NewPositionReply>(reply)) return true;
            const auto* p = std::get_if<PositionReply>(&reply);
            // The StackShot answers `mp <motor> <current position>`: the motor
            // may be moving to the new target (stackshot-protocol.txt section 3).
            return p != nullptr && p->motor == m.motor &&
                   (p->position_steps == m.position_steps || stackshot());
          },
          [&](const BlurFrame&) { return std::holds_alternative<BlurReply>(reply); },
          [&](const Go&) { return std::holds_alternative<GoReply>(reply); },
          [&](const UnknownCommand&) { return false; },
      },
      *c.parsed);
}

int DfmHost::Match(const DeviceReply& reply) const {
  // Error lines bypass the sketch's queue: they answer the oldest command
  // that expects one, else the oldest unanswered command.
  if (IsError(reply)) {
    int fallback = -1;
    for (size_t i = 0; i < commands_.size(); ++i) {
      const DfmCommand& c = commands_[i];
      if (c.answers > 0 || c.expect == DfmExpect::kSilence) continue;
      if (c.expect != DfmExpect::kReply) return static_cast<int>(i);
      if (fallback < 0) fallback = static_cast<int>(i);
    }
    return fallback;
  }
  // The oldest unanswered command it fits, those the host gave up on last (a
  // `hi` asked again after a swallowed one is answered by this line).
  int abandoned = -1;
  for (size_t i = 0; i < commands_.size(); ++i) {
    const DfmCommand& c = commands_[i];
    if (c.answers != 0 || !Fits(c, reply)) continue;
    if (!c.abandoned) return static_cast<int>(i);
    if (abandoned < 0) abandoned = static_cast<int>(i);
  }
  return abandoned;
}

void DfmHost::CheckAnswer(DfmCommand& c, const DfmLine& line) {
  verdicts_.Pass("DFM-REPLY-002");
  const std::string_view word = WordOf(c.line);
  const auto [dl_rule, kind] = DeadlineRule(word);
  const auto custom = options_.deadline_by_kind_ns.find(kind);
  const TimeNs deadline =
      custom != options_.deadline_by_kind_ns.end() ? custom->second : options_.deadline_ns;
  const TimeNs latency = line.t_ns - c.sent_ns;
  verdicts_.Check(dl_rule, !c.timed || latency <= deadline, [&] {
    return Ev(line, "an answer to " + Quote(c.line) + " within " + Ms(deadline),
              "answered after " + Ms(latency));
  });
  const DeviceReply& reply = *line.reply;
  const bool is_error = IsError(reply);
  // Errors expected: the right error line.
  if (c.expect == DfmExpect::kError || c.expect == DfmExpect::kTooMany) {
    const bool right = c.expect == DfmExpect::kError
                           ? std::holds_alternative<dfmoco::ParseErrorReply>(reply)
                           : std::holds_alternative<dfmoco::TooManyArgsReply>(reply);
    verdicts_.Check(c.error_rule, right, [&] {
      return Ev(
          line,
          std::string(c.expect == DfmExpect::kError ? "parse error" : "error: too many args") +
              " for " + Quote(c.line),
          Quote(line.text));
    });
    return;
  }
  const std::string_view rule = AnswerRule(word, c.parsed ? &*c.parsed : nullptr);
  if (is_error) {
    verdicts_.Fail(rule, Ev(line, "the " + std::string(word) + " answer to " + Quote(c.line),
                            Quote(line.text)));
    return;
  }
  if (const auto want = c.parsed ? dfmoco::AddressedMotor(*c.parsed) : std::nullopt) {
    if (const auto got = ReplyMotor(reply)) {
      verdicts_.Check("DFM-REPLY-005", *got == *want, [&] {
        return Ev(line, "motor " + std::to_string(*want) + " as in " + Quote(c.line),
                  Quote(line.text));
      });
    }
  }
  using namespace dfmoco;
  const auto* parsed = c.parsed ? &*c.parsed : nullptr;
  if (parsed == nullptr) return;
  if (const auto* mm = std::get_if<MoveMotor>(parsed)) {
    if (const auto* r = std::get_if<MoveReply>(&reply)) {
      verdicts_.Check("DFM-MM-001", r->position_steps == mm->position_steps, [&] {
        return Ev(line,
                  "mm " + std::to_string(mm->motor) + " " + std::to_string(mm->position_steps),
                  Quote(line.text));
      });
    } else {
      verdicts_.Pass("DFM-MM-002");
    }
  } else if (std::holds_alternative<PositionQuery>(*parsed)) {
    verdicts_.Pass("DFM-MP-001");
  } else if (const auto* pr = std::get_if<SetPulseRate>(parsed)) {
    const auto* r = std::get_if<PulseRateReply>(&reply);
    const int32_t want = std::clamp(pr->rate_steps_per_s, kMinPulseRate, kMaxPulseRate);
    const bool in_range = want == pr->rate_steps_per_s;
    verdicts_.Check(
        in_range ? "DFM-PR-001" : "DFM-PR-002", r != nullptr && r->rate_steps_per_s == want, [&] {
          return Ev(line, "pr " + std::to_string(pr->motor) + " " + std::to_string(want),
                    Quote(line.text));
        });
  } else if (std::holds_alternative<NewPosition>(*parsed)) {
    verdicts_.Pass("DFM-NP-001");
    verdicts_.Check("DFM-NP-003", !std::holds_alternative<NewPositionReply>(reply), [&] {
      return Ev(line, "mp m p (the sketch)", Quote(line.text) + " (the protocol text)");
    });
    if (const auto* r = std::get_if<NewPositionReply>(&reply)) {
      const auto& np = std::get<NewPosition>(*parsed);
      verdicts_.Check("DFM-NP-001", r->position_steps == np.position_steps, [&] {
        return Ev(line, "the new position " + std::to_string(np.position_steps), Quote(line.text));
      });
    }
  } else if (std::holds_alternative<ZeroMotor>(*parsed)) {
    verdicts_.Pass("DFM-ZM-001");
    verdicts_.Check("DFM-ZM-003", !std::holds_alternative<ZeroReply>(reply), [&] {
      return Ev(line, "mp m 0 (the sketch)", Quote(line.text) + " (the protocol text)");
    });
  } else if (std::holds_alternative<StopMotor>(*parsed)) {
    verdicts_.Pass("DFM-SM-001");
  } else if (std::holds_alternative<StopAll>(*parsed)) {
    verdicts_.Pass("DFM-SA-001");
  } else if (std::holds_alternative<JogMotor>(*parsed)) {
    verdicts_.Pass(rule);
  } else if (std::holds_alternative<InchMotor>(*parsed)) {
    verdicts_.Pass("DFM-IM-001");
  } else if (std::holds_alternative<Hello>(*parsed)) {
    verdicts_.Pass("DFM-HI-002");
  } else if (const auto* bf = std::get_if<BlurFrame>(parsed)) {
    const int32_t n = std::get<BlurReply>(reply).value;
    verdicts_.Check("DFM-GO-001", n == 1000 || n == bf->exposure_ms || n == kBlurRefused, [&] {
      return Ev(line, "bf 1000, bf " + std::to_string(bf->exposure_ms) + " or bf -1",
                Quote(line.text));
    });
    if (bf->exposure_ms != 1000 && n != kBlurRefused) {
      verdicts_.Check("DFM-GO-002", n != 1000, [&] {
        return Ev(line, "bf " + std::to_string(bf->exposure_ms) + " (ERRATA 2.5)",
                  Quote(line.text) + " (the sketch's, docs/device-facts.md)");
      });
    }
  } else if (std::holds_alternative<Go>(*parsed)) {
    verdicts_.Pass("DFM-GO-004");
  }
}

void DfmHost::CheckHello(const DfmLine& line, const dfmoco::HelloReply& hi) {
  verdicts_.Pass("DFM-HI-002");
  const auto version = ParseDfmocoVersion(hi.version);
  verdicts_.Check(
      "DFM-HI-003", hi.protocol_major >= 1 && version && (*version)[0] == hi.protocol_major, [&] {
        return Ev(line, "major >= 1, the version string's leading number", Quote(line.text));
      });
  verdicts_.Check("DFM-HI-004", hi.motor_count >= 1,
                  [&] { return Ev(line, "at least 1 axis", Quote(line.text)); });
  verdicts_.Check("DFM-HI-005", IsDottedDecimal(hi.version),
                  [&] { return Ev(line, "a dotted decimal version", Quote(hi.version)); });
  const bool known_version = hi.version == "1.2.7" || hi.version == "1.3.0" ||
                             hi.version == "1.3.1" || hi.version == "2.0.0";
  verdicts_.Check("DFM-HI-007", known_version && (hi.motor_count == 4 || hi.motor_count == 8), [&] {
    return Ev(line, "a known sketch (1.2.7, 1.3.0, 1.3.1, 2.0.0; 4 or 8 axes)", Quote(line.text));
  });
  if (hello_) {
    verdicts_.Check("DFM-HI-006", *hello_ == hi, [&] {
      return Ev(line, "the same hi as before: " + Quote(dfmoco::FormatDevice(*hello_)),
                Quote(line.text));
    });
  }
  hello_ = hi;
}

const DfmLine* DfmHost::Await(int index) {
  if (index < 0 || static_cast<size_t>(index) >= commands_.size()) return nullptr;
  const auto i = static_cast<size_t>(index);
  const std::string kind = CommandWord(commands_[i].line);
  const auto fail = [&](std::string observed) {
    DfmCommand& c = commands_[i];
    c.abandoned = true;
    // A missing answer is judged under the rule of its command's clause where
    // one exists for exactly that: `go` (DFM-GO-004) and the host's first `hi`
    // (DFM-HI-008, asked again as a host does after its timeout).
    const std::string_view word = std::string_view(c.line).substr(0, 2);
    bool first_hi = word == "hi" && c.line.size() == 2;
    for (size_t k = 0; first_hi && k < i; ++k) first_hi = commands_[k].line != "hi";
    const std::string_view rule = first_hi                         ? "DFM-HI-008"
                                  : word == "go" && c.line == "go" ? "DFM-GO-004"
                                                                   : "DFM-REPLY-001";
    verdicts_.Fail(rule,
                   Evidence{"an answer to " + Quote(c.line), std::move(observed), "", c.sent_ns});
  };
  if (commands_[i].answer < 0 && JudgedWithoutWaiting(kind, fail)) return nullptr;
  const TimeNs give_up = commands_[i].sent_ns + options_.answer_timeout_ns;
  if (!link_.ReadUntil(give_up, [&] { return commands_[i].answer >= 0; })) {
    fail(link_.lost() ? "the link closed" : "nothing after " + Ms(options_.answer_timeout_ns));
    Unanswered(kind);
    return nullptr;
  }
  verdicts_.Pass("DFM-REPLY-001");
  if (commands_[i].line == "hi") verdicts_.Pass("DFM-HI-008");
  return &lines_[static_cast<size_t>(commands_[i].answer)];
}

int DfmHost::WaitFor(size_t from, TimeNs timeout_ns,
                     const std::function<bool(const DfmLine&)>& pred) {
  return link_.WaitFor(lines_, from, timeout_ns, pred);
}

void DfmHost::Close() {
  if (closed_) return;
  closed_ = true;
  Idle(options_.quiet_ns);
  if (pending_cr_) {
    pending_cr_ = false;
    EndLine(false);
  }
  if (!partial_.empty()) {
    verdicts_.Fail("DFM-LINE-003",
                   Evidence{"every line finished with \\r\\n",
                            "the device stopped after " + std::to_string(partial_.size()) +
                                " byte(s) of a line",
                            wire::ToHex(partial_), Now()});
  } else if (!lines_.empty()) {
    verdicts_.Pass("DFM-LINE-003");
  }
  if (!lines_.empty()) verdicts_.Pass("DFM-LINE-005");
}

}  // namespace moco::conformance
