// DFMoco under the fuzzer (core/fuzz_protocol.h): lines mutated per word
// (the sketch's grammar: a command word, then space-separated integers, CR LF
// or LF), sessions judged by the device's reply grammar and a `hi` after the
// session, and replays that allow the position tolerance in `mp` and `mm`.
// The StackShot 3X's DfMoco mode speaks the same lines: its sessions are
// mutated and replayed the same way, byte-exact.
#include <cstdlib>
#include <string_view>

#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "wire/dfmoco.h"

namespace moco::conformance {
namespace {

using dfmoco_cases::kFuzzBootGreetingNs;
using dfmoco_cases::kFuzzDrainMaxNs;
using dfmoco_cases::kFuzzGapNs;
using dfmoco_cases::kFuzzHiAnswerNs;
using dfmoco_cases::kFuzzSettleMaxNs;
using dfmoco_cases::kFuzzSettleQuietNs;
using dfmoco_cases::kFuzzTailNs;

constexpr std::string_view kWords[] = {"hi", "ms", "mm", "mp", "sm", "sa", "jm",
                                       "im", "pr", "zm", "np", "bf", "go", "mp *"};
constexpr std::string_view kNumbers[] = {
    "0",    "1",     "-1",    "2",          "4",           "8",          "9",
    "100",  "20000", "40000", "2147483647", "-2147483648", "2147483648", "99999999999",
    "1000", "-0",    "+5",    "0x10",       "1e3",         "3.5"};

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

FuzzVerdict Run(Target& target, const Messages& messages, TimeNs gap_ns,
                const wire::Bytes& boot_out) {
  wire::Bytes out = boot_out;
  auto settle = [&] {
    const TimeNs limit = target.Now() + kFuzzSettleMaxNs;
    while (target.Now() < limit) {
      const size_t n = out.size();
      if (!target.Receive(std::min(limit, target.Now() + kFuzzSettleQuietNs), out)) break;
      if (out.size() == n) break;
    }
  };
  for (const wire::Bytes& m : messages) {
    target.Send(m);
    target.Receive(target.Now() + gap_ns, out);
    settle();
  }
  // End any unterminated line, then greet.
  const std::string_view tail = "\r\nhi\r\n";
  const size_t before_hi = out.size();
  target.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(tail.data()), tail.size()));
  const TimeNs deadline = target.Now() + kFuzzHiAnswerNs;
  while (target.Now() < deadline) {
    if (!target.Receive(deadline, out)) break;
    if (out.size() > before_hi && out.back() == '\n') {
      // Stop once a hi reply has come after the greeting was sent.
      const std::string_view s(reinterpret_cast<const char*>(out.data()) + before_hi,
                               out.size() - before_hi);
      if (s.find("hi ") != std::string_view::npos) break;
    }
  }
  // What is still on its way, until the line has been quiet for kFuzzTailNs:
  // a firmware's transmitter may hold a backlog of replies at the line rate.
  const TimeNs drain_limit = target.Now() + kFuzzDrainMaxNs;
  while (target.Now() < drain_limit) {
    const size_t n = out.size();
    if (!target.Receive(std::min(drain_limit, target.Now() + kFuzzTailNs), out)) break;
    if (out.size() == n) break;
  }

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
                       messages.size(), replies);
    }
    if (nl == start || text[nl - 1] != '\r') {
      return Violation(
          "line grammar: a device line does not end in CR LF at byte " + std::to_string(nl),
          messages.size(), replies);
    }
    const std::string_view line = text.substr(start, nl - 1 - start);
    for (char c : line) {
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
        return Violation(
            "line grammar: a control or non-ASCII byte in \"" + std::string(line) + "\"",
            messages.size(), replies);
      }
    }
    auto parsed = dfmoco::ParseDeviceLine(line, dialect);
    if (!parsed.ok()) {
      return Violation("reply grammar: \"" + std::string(line) + "\" is no DFMoco reply (" +
                           parsed.error().detail + ")",
                       messages.size(), replies);
    }
    if (const auto* h = std::get_if<dfmoco::HelloReply>(&parsed.value())) {
      dialect = dfmoco::DialectFrom(*h, false);
      have_dialect = true;
      if (start >= before_hi) hi_after = true;
    } else if (const auto* ms = std::get_if<dfmoco::MotorStatusReply>(&parsed.value())) {
      if (have_dialect && static_cast<int32_t>(ms->moving.size()) != dialect.motor_count) {
        return Violation("ms width: \"" + std::string(line) + "\" has " +
                             std::to_string(ms->moving.size()) + " digits for " +
                             std::to_string(dialect.motor_count) + " motors",
                         messages.size(), replies);
      }
    }
    ++replies;
    start = nl + 1;
  }
  if (!hi_after) {
    return Violation("liveness: no `hi` reply to the greeting sent after the session",
                     messages.size(), replies);
  }
  return FuzzVerdict{true, "", messages.size(), replies};
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
        .mutate = &Mutate,
        .boot = &Boot,
        .run = &Run,
        .matcher = []() -> std::unique_ptr<ReplayMatcher> { return std::make_unique<Matcher>(); },
    },
    {
        .protocol = Protocol::kStackshotDfmoco,
        .gap_ns = kFuzzGapNs,
        .mutate = &Mutate,
        .run = nullptr,
        .matcher = []() { return ExactMatcher("the line differs"); },
    },
};

}  // namespace

std::span<const FuzzHooks> DfmocoProtocol::Fuzz() { return kHooks; }

}  // namespace moco::conformance
