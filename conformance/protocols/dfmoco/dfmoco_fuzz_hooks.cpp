// DFMoco under the fuzzer (core/fuzz_protocol.h): lines mutated per word
// (the sketch's grammar: a command word, then space-separated integers, CR LF
// or LF), sessions judged by the device's reply grammar and a `hi` after the
// session, and replays that allow the position tolerance in `mp` and `mm`.
// The StackShot 3X's DfMoco mode speaks the same lines: its sessions are
// mutated and replayed the same way, byte-exact.
#include <cstdlib>
#include <optional>
#include <string_view>

#include "conformance/core/host_link.h"
#include "conformance/core/pin_judge.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "wire/dfmoco.h"

namespace moco::conformance {
namespace {

using dfmoco_cases::kFuzzBootGreetingNs;
using dfmoco_cases::kFuzzDrainMaxNs;
using dfmoco_cases::kFuzzGapNs;
using dfmoco_cases::kFuzzHiAnswerNs;
using dfmoco_cases::kFuzzJudgedWriteBytes;
using dfmoco_cases::kFuzzPauseNs;
using dfmoco_cases::kFuzzReplyQuietNs;
using dfmoco_cases::kFuzzSettleMaxNs;
using dfmoco_cases::kFuzzSettleQuietNs;
using dfmoco_cases::kFuzzTailNs;
using dfmoco_cases::kMs;

constexpr std::string_view kWords[] = {"hi", "ms", "mm", "mp", "sm", "sa", "jm",
                                       "im", "pr", "zm", "np", "bf", "go", "mp *"};
constexpr std::string_view kNumbers[] = {
    "0",    "1",     "-1",    "2",          "4",           "8",          "9",
    "100",  "20000", "40000", "2147483647", "-2147483648", "2147483648", "99999999999",
    "1000", "-0",    "+5",    "0x10",       "1e3",         "3.5",        "5"};

void Mutate(MutationSource& s, wire::Bytes& m) {
  constexpr size_t kMaxLine = DfmocoProtocol::kMaxFuzzLine;
  std::string line(m.begin(), m.end());
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  std::vector<std::string> tokens;
  size_t i = 0;
  while (i < line.size()) {
    const size_t j = line.find(' ', i);
    tokens.push_back(line.substr(i, j == std::string::npos ? std::string::npos : j - i));
    i = j == std::string::npos ? line.size() : j + 1;
  }
  switch (s.Below(7)) {
    case 0:  // a number replaced
      if (tokens.size() > 1) {
        tokens[1 + s.Below(tokens.size() - 1)] = kNumbers[s.Below(std::size(kNumbers))];
      } else {
        tokens.emplace_back(kNumbers[s.Below(std::size(kNumbers))]);
      }
      s.Note("number");
      break;
    case 1:  // the word replaced
      if (tokens.empty()) tokens.emplace_back();
      tokens[0] = kWords[s.Below(std::size(kWords))];
      s.Note("word");
      break;
    case 2:  // an argument dropped or added
      if (tokens.size() > 1 && s.Chance(50)) {
        tokens.erase(tokens.begin() + 1 + static_cast<ptrdiff_t>(s.Below(tokens.size() - 1)));
      } else {
        const size_t n = s.Chance(10) ? 40 : 1;
        for (size_t k = 0; k < n; ++k) tokens.emplace_back(std::to_string(s.Below(20)));
      }
      s.Note("arity");
      break;
    case 3:  // a random byte, maybe not ASCII
      if (!line.empty()) {
        line[s.Below(line.size())] = static_cast<char>(s.Next());
        tokens = {line};
      }
      s.Note("byte");
      break;
    case 4:  // whitespace games
      tokens = {s.Chance(50) ? "  " + line : line + "   "};
      s.Note("spaces");
      break;
    case 5:  // the line end dropped: runs into the next line
      m.assign(line.begin(), line.end());
      s.Note("no-line-end");
      return;
    default: {  // a long line
      std::string longer = line;
      while (longer.size() < kMaxLine) longer += " 7";
      tokens = {longer};
      s.Note("long-line");
      break;
    }
  }
  std::string out;
  for (size_t k = 0; k < tokens.size(); ++k) out += (k ? " " : "") + tokens[k];
  if (out.size() > kMaxLine) out.resize(kMaxLine);
  out += s.Chance(90) ? "\r\n" : "\n";
  m.assign(out.begin(), out.end());
}

// The boot greeting, its whole line (the sketch starts after its boot delay).
void Boot(Target& target, wire::Bytes& out) {
  const TimeNs boot_deadline = target.Now() + kFuzzBootGreetingNs;
  // A target whose firmware stopped receives nothing more (Receive is false).
  while ((out.empty() || out.back() != '\n') && target.Now() < boot_deadline) {
    if (!target.Receive(boot_deadline, out)) break;
  }
}

// Whether `line` (its CR LF taken off) is a command every DFMoco sketch answers
// with at least one line (FACTS "DFMoco": each of these words is answered, even
// with a bad motor or on a moving motor; only unknown words are not): the word,
// then exactly its arguments, each a decimal of at most 9 digits (the first a
// motor of the greeting's count), one space apart. Anything else a sketch may
// answer or not.
bool MustBeAnswered(std::string_view line, int32_t motor_count) {
  static constexpr struct {
    std::string_view word;
    size_t args;
  } kAnswered[] = {{"hi", 0}, {"ms", 0}, {"sa", 0}, {"mp", 1}, {"sm", 1}, {"zm", 1},
                   {"mm", 2}, {"jm", 2}, {"im", 2}, {"pr", 2}, {"np", 2}};
  if (line.size() < 2) return false;
  size_t want = SIZE_MAX;
  for (const auto& w : kAnswered) {
    if (line.substr(0, 2) == w.word) want = w.args;
  }
  if (want == SIZE_MAX) return false;
  size_t at = 2;
  for (size_t arg = 0; arg < want; ++arg) {
    if (at >= line.size() || line[at] != ' ') return false;
    ++at;
    const size_t start = at;
    if (arg > 0 && at < line.size() && line[at] == '-') ++at;
    const size_t digits_from = at;
    while (at < line.size() && line[at] >= '0' && line[at] <= '9') ++at;
    if (at == digits_from || at - digits_from > 9) return false;
    if (arg == 0) {
      const long motor =
          std::strtol(std::string(line.substr(start, at - start)).c_str(), nullptr, 10);
      if (motor < 1 || motor > motor_count) return false;
    }
  }
  return at == line.size();
}

// The host's side of the line: which complete lines a write finishes, across
// writes (a message without its line end runs into the next one).
class HostLines {
 public:
  // How many lines `bytes` completes that must be answered.
  size_t MustAnswer(wire::ByteView bytes, int32_t motor_count, std::string* first) {
    size_t n = 0;
    for (const uint8_t b : bytes) {
      // The sketch takes a command only where CR LF ends it; a bare LF is one
      // more byte of the line (FACTS "DFMoco").
      if (b != '\n' || pending_.empty() || pending_.back() != '\r') {
        pending_.push_back(static_cast<char>(b));
        continue;
      }
      pending_.pop_back();
      if (MustBeAnswered(pending_, motor_count)) {
        if (n == 0 && first != nullptr) *first = pending_;
        ++n;
      }
      pending_.clear();
    }
    return n;
  }

 private:
  std::string pending_;
};

size_t CountLines(const wire::Bytes& out) {
  return static_cast<size_t>(std::count(out.begin(), out.end(), uint8_t{'\n'}));
}

// What the device wrote in a run (after what it wrote while it booted), read
// through a HostLink (core/host_link.h), which also keeps every chunk either
// way with its time: the pin judge's traffic. The link is made at the first
// read or write, where the target is known.
class Written {
 public:
  explicit Written(const wire::Bytes& boot_out) : out(boot_out) {}
  Written(const Written&) = delete;
  Written& operator=(const Written&) = delete;

  wire::Bytes out;

  // Whether the link is still up (the firmware runs, no stop was requested).
  bool Receive(Target& target, TimeNs deadline) {
    HostLink& link = Link(target);
    link.Pump(deadline);
    return !link.lost();
  }
  void Send(Target& target, wire::ByteView bytes) { Link(target).WriteWithoutReading(bytes); }
  void Idle(Target& target, TimeNs duration_ns) { Link(target).Idle(duration_ns); }
  const std::vector<Chunk>& traffic() const {
    static const std::vector<Chunk> kNone;
    return link_ ? link_->traffic() : kNone;
  }

 private:
  HostLink& Link(Target& target) {
    if (!link_) {
      link_.emplace(target,
                    [this](wire::ByteView b) { out.insert(out.end(), b.begin(), b.end()); });
    }
    return *link_;
  }

  std::optional<HostLink> link_;
};

// Reads until the device has written `want` more lines and then
// kept quiet for kFuzzReplyQuietNs (want > 0), or kept quiet for
// kFuzzSettleQuietNs (want == 0); at most kFuzzSettleMaxNs from when the bytes
// sent so far have reached the device (Target::SentBy: writes sent without an
// answer to wait for queue on the line). Whether the lines came.
bool AwaitReplies(Target& target, Written& w, size_t want) {
  const TimeNs limit = target.SentBy() + kFuzzSettleMaxNs;
  size_t seen = w.out.size();
  size_t got = 0;
  const TimeNs quiet = want > 0 ? kFuzzReplyQuietNs : kFuzzSettleQuietNs;
  while (target.Now() < limit) {
    if (got < want) {
      if (!w.Receive(target, limit)) break;
    } else if (!w.Receive(target, std::min(limit, target.Now() + quiet)) || w.out.size() == seen) {
      break;  // quiet (or the firmware stopped)
    }
    got += static_cast<size_t>(
        std::count(w.out.begin() + static_cast<ptrdiff_t>(seen), w.out.end(), uint8_t{'\n'}));
    seen = w.out.size();
  }
  return got >= want;
}

// Sends `hi` and reads until a `hi` reply has come after it (within
// kFuzzHiAnswerNs); whether it did.
bool Greet(Target& target, Written& w) {
  const std::string_view hi = "hi\r\n";
  const size_t before = w.out.size();
  w.Send(target, wire::ByteView(reinterpret_cast<const uint8_t*>(hi.data()), hi.size()));
  const TimeNs deadline = target.Now() + kFuzzHiAnswerNs;
  while (target.Now() < deadline) {
    if (!w.Receive(target, deadline)) break;
    if (w.out.size() > before && w.out.back() == '\n') {
      const std::string_view s(reinterpret_cast<const char*>(w.out.data()) + before,
                               w.out.size() - before);
      if (s.find("hi ") != std::string_view::npos) return true;
    }
  }
  return false;
}

FuzzVerdict Judge(const wire::Bytes& out, size_t before_hi, size_t sent, const std::string& lost);

// The motors of the boot greeting's `hi` line (4 when there is none).
int32_t GreetingMotors(const wire::Bytes& boot_out) {
  const std::string_view text(reinterpret_cast<const char*>(boot_out.data()), boot_out.size());
  const size_t at = text.find("hi ");
  if (at == std::string_view::npos) return 4;
  const size_t end = text.find('\r', at);
  auto parsed = dfmoco::ParseDeviceLine(
      text.substr(at, end == std::string_view::npos ? end : end - at), dfmoco::Dialect());
  if (!parsed.ok()) return 4;
  const auto* h = std::get_if<dfmoco::HelloReply>(&parsed.value());
  return h == nullptr ? 4 : dfmoco::DialectFrom(*h, false).motor_count;
}

// One run: each message followed as soon as the lines every sketch must
// answer have come (AwaitReplies), as Dragonframe does; then a line end and a
// `hi` (twice when unanswered), and what is still on its way read.
class DfmocoPlay final : public FuzzPlay {
 public:
  DfmocoPlay(const wire::Bytes& boot_out, const PinJudgeOptions* pins)
      : w_(boot_out), motors_(GreetingMotors(boot_out)), pins_(pins) {}

  void Play(Target& target, const wire::Bytes& m) override {
    if (m.empty()) {  // a pause: what the device writes meanwhile is read
      w_.Idle(target, kFuzzPauseNs);
      return;
    }
    ++messages_;
    w_.Send(target, m);
    std::string first;
    size_t want = host_.MustAnswer(m, motors_, &first);
    if (m.size() > kFuzzJudgedWriteBytes) want = 0;
    if (!AwaitReplies(target, w_, want) && lost_.empty() && !target.FirmwareStopped()) {
      lost_ = "every request answered: message " + std::to_string(messages_) + " (\"" + first +
              "\"" +
              (want > 1 ? " and " + std::to_string(want - 1) + " more in the same write" : "") +
              ") got " + (want > 1 ? "fewer reply lines than commands" : "no reply") + " within " +
              std::to_string(kFuzzSettleMaxNs / kMs) + " ms of its arrival";
    }
  }

  FuzzVerdict Finish(Target& target) override;

 private:
  // With a board: the pin rules (rules/pin_rules.cpp) over the whole run,
  // the first MUST rule broken as a finding; else nullopt.
  std::optional<FuzzVerdict> JudgePinLaws(Target& target) const;

  Written w_;
  int32_t motors_;
  const PinJudgeOptions* pins_;  // nullptr: the pins are not judged
  HostLines host_;
  std::string lost_;  // the first request left without a reply
  size_t messages_ = 0;
};

FuzzVerdict DfmocoPlay::Finish(Target& target) {
  // End any unterminated line and greet at once (the `hi` queues behind the
  // line end on the wire, and whatever answers that line comes before the
  // greeting's answer); greet again when no answer came.
  const std::string_view line_end = "\r\n";
  const size_t before_hi = w_.out.size();
  w_.Send(target,
          wire::ByteView(reinterpret_cast<const uint8_t*>(line_end.data()), line_end.size()));
  const bool answered = Greet(target, w_) || Greet(target, w_);
  // What is still on its way, until the line has been quiet for kFuzzTailNs:
  // a firmware's transmitter may hold a backlog of replies at the line rate.
  const TimeNs drain_limit = target.Now() + kFuzzDrainMaxNs;
  while (target.Now() < drain_limit) {
    const size_t n = w_.out.size();
    if (!w_.Receive(target, std::min(drain_limit, target.Now() + kFuzzTailNs))) break;
    if (w_.out.size() == n) break;
  }
  if (!answered && !target.FirmwareStopped()) {
    FuzzVerdict v = Violation(
        "hang: the device answered neither of two `hi` sent after the "
        "session (" +
            std::to_string(kFuzzHiAnswerNs / kMs) + " ms each), while its firmware runs",
        messages_, CountLines(w_.out));
    v.kind = FuzzVerdict::Kind::kHang;
    v.backtrace = target.FirmwareBacktrace();
    return v;
  }
  FuzzVerdict v = Judge(w_.out, before_hi, messages_, lost_);
  if (!v.ok) return v;
  if (auto pin = JudgePinLaws(target)) return *pin;
  return v;
}

std::optional<FuzzVerdict> DfmocoPlay::JudgePinLaws(Target& target) const {
  const PinTrace* trace = target.Pins();
  if (pins_ == nullptr || trace == nullptr) return std::nullopt;
  // The run stops with its session, perhaps while a motor still moves: the
  // judge leaves a report whose window runs past the trace unjudged.
  Verdicts v;
  JudgePins(DfmocoProtocol::kPinRulePrefix, *trace, DfmocoProtocol::PinEvents(w_.traffic()), *pins_,
            target.Now(), v);
  for (const auto& [id, o] : v.outcomes()) {
    const Rule* r = FindRule(id);
    if (o.status != Status::kFail || r == nullptr || r->level != Level::kMust) continue;
    std::string what = "pin law: " + id + " " + std::string(r->title);
    if (!o.evidence.empty()) {
      const Evidence& e = o.evidence.front();
      what += ": expected " + e.expected + ", observed " + e.observed;
    }
    FuzzVerdict verdict = Violation(what, messages_, CountLines(w_.out));
    verdict.kind = FuzzVerdict::Kind::kPinLaw;
    return verdict;
  }
  return std::nullopt;
}

// The stream laws over everything the device wrote: CR LF lines of printable
// ASCII, each a DFMoco reply, `ms` as wide as the greeting's motor count, a `hi`
// reply after `before_hi`; then `lost` (a request left without a reply), if any.
FuzzVerdict Judge(const wire::Bytes& out, size_t before_hi, size_t sent, const std::string& lost) {
  const size_t messages_size = sent;
  const std::string_view text(reinterpret_cast<const char*>(out.data()), out.size());
  dfmoco::Dialect dialect;
  bool have_dialect = false;
  bool hi_after = false;
  size_t replies = 0;
  size_t start = 0;
  while (start < text.size()) {
    const size_t nl = text.find('\n', start);
    if (nl == std::string_view::npos) {
      return Violation("line grammar: the device left an unterminated line \"" +
                           std::string(text.substr(start)) + "\"",
                       messages_size, replies);
    }
    if (nl == start || text[nl - 1] != '\r') {
      return Violation(
          "line grammar: a device line does not end in CR LF at byte " + std::to_string(nl),
          messages_size, replies);
    }
    const std::string_view line = text.substr(start, nl - 1 - start);
    for (char c : line) {
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
        return Violation(
            "line grammar: a control or non-ASCII byte in \"" + std::string(line) + "\"",
            messages_size, replies);
      }
    }
    auto parsed = dfmoco::ParseDeviceLine(line, dialect);
    if (!parsed.ok()) {
      return Violation("reply grammar: \"" + std::string(line) + "\" is no DFMoco reply (" +
                           parsed.error().detail + ")",
                       messages_size, replies);
    }
    if (const auto* h = std::get_if<dfmoco::HelloReply>(&parsed.value())) {
      dialect = dfmoco::DialectFrom(*h, false);
      have_dialect = true;
      if (start >= before_hi) hi_after = true;
    } else if (const int32_t motor = std::visit(
                   [](const auto& r) -> int32_t {
                     if constexpr (requires { r.motor; }) {
                       return r.motor;
                     } else {
                       return 1;
                     }
                   },
                   parsed.value());
               have_dialect && (motor < 1 || motor > dialect.motor_count)) {
      // FACTS "DFMoco": a command naming no motor of the device answers `parse error`.
      return Violation("motor range: \"" + std::string(line) + "\" names motor " +
                           std::to_string(motor) + " of a device with " +
                           std::to_string(dialect.motor_count) + " motors",
                       messages_size, replies);
    } else if (const auto* ms = std::get_if<dfmoco::MotorStatusReply>(&parsed.value())) {
      if (have_dialect && static_cast<int32_t>(ms->moving.size()) != dialect.motor_count) {
        return Violation("ms width: \"" + std::string(line) + "\" has " +
                             std::to_string(ms->moving.size()) + " digits for " +
                             std::to_string(dialect.motor_count) + " motors",
                         messages_size, replies);
      }
    }
    ++replies;
    start = nl + 1;
  }
  if (!hi_after) {
    return Violation("liveness: no `hi` reply to the greeting sent after the session",
                     messages_size, replies);
  }
  if (!lost.empty()) return Violation(lost, messages_size, replies);
  return Passed(messages_size, replies);
}

// Whether two DFMoco lines differ only in numbers within `tol` (positions).
bool Close(std::string_view a, std::string_view b, int64_t tol) {
  auto split = [](std::string_view s) {
    std::vector<std::string_view> t;
    size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && (s[i] == ' ' || s[i] == '\r' || s[i] == '\n')) ++i;
      size_t j = i;
      while (j < s.size() && s[j] != ' ' && s[j] != '\r' && s[j] != '\n') ++j;
      if (j > i) t.push_back(s.substr(i, j - i));
      i = j;
    }
    return t;
  };
  const auto ta = split(a), tb = split(b);
  if (ta.size() != tb.size() || ta.empty() || ta[0] != tb[0]) return false;
  if (ta[0] != "mp" && ta[0] != "mm") return false;
  for (size_t i = 1; i < ta.size(); ++i) {
    if (ta[i] == tb[i]) continue;
    if (i == 1) return false;  // the motor number must agree
    char* end_a = nullptr;
    char* end_b = nullptr;
    const std::string sa(ta[i]), sb(tb[i]);
    const long long va = std::strtoll(sa.c_str(), &end_a, 10);
    const long long vb = std::strtoll(sb.c_str(), &end_b, 10);
    if (*end_a != 0 || *end_b != 0 || std::llabs(va - vb) > tol) return false;
  }
  return true;
}

class Matcher final : public ReplayMatcher {
 public:
  bool Match(const wire::Bytes& e, const wire::Bytes& o, TimeNs, int64_t tol,
             std::string& why) override {
    const bool same =
        Close(std::string_view(reinterpret_cast<const char*>(e.data()), e.size()),
              std::string_view(reinterpret_cast<const char*>(o.data()), o.size()), tol);
    if (!same) why = "the line differs";
    return same;
  }
};

const FuzzHooks kHooks[] = {
    {
        .protocol = Protocol::kDfmoco,
        .gap_ns = kFuzzGapNs,
        .pause_ns = kFuzzPauseNs,
        .mutate = &Mutate,
        .boot = &Boot,
        .start = [](const wire::Bytes& boot_out, const PinJudgeOptions* pins)
            -> std::unique_ptr<FuzzPlay> { return std::make_unique<DfmocoPlay>(boot_out, pins); },
        .matcher = []() -> std::unique_ptr<ReplayMatcher> { return std::make_unique<Matcher>(); },
    },
    {
        .protocol = Protocol::kStackshotDfmoco,
        .gap_ns = kFuzzGapNs,
        .pause_ns = kFuzzPauseNs,
        .mutate = &Mutate,
        .matcher = []() { return ExactMatcher("the line differs"); },
    },
};

}  // namespace

std::span<const FuzzHooks> DfmocoProtocol::Fuzz() { return kHooks; }

}  // namespace moco::conformance
