// DFMoco ASCII protocol codec: line framing and every host command and device reply
// (dfmoco-protocol.txt "Message Format" and "Messages", ERRATA part 2, FACTS "DFMoco"),
// plus the StackShot 3X DfMoco dialect (stackshot-protocol.txt section 3, ERRATA 3.9).
// Pure functions and one streaming framer: no I/O, no clock, no logging.
//
// Readings taken (each is also stated where it is implemented):
//  - Framing follows the real sketch (FACTS): a line ends only where "\n" directly
//    follows "\r". A bare "\n" is discarded and the bytes on both sides of it join into
//    the same line (the sketch ignores "\n" in every parser state). A "\r" not followed
//    by "\n" stays in the line as an ordinary byte. LineTermination::kLenient accepts
//    "\r\n", a bare "\n" or a bare "\r" (ERRATA 2.1).
//  - The command word is everything before the first space. It must be one of the
//    known two-letter words, else the line is an UnknownCommand (the sketch answers
//    nothing, FACTS). Arguments are separated by one or more spaces; trailing spaces
//    are ignored.
//  - Every argument must be an optional '-' followed by decimal digits and fit a signed
//    32-bit integer (the sketch keeps int32 arguments); anything else is a parse error.
//  - 40 or more arguments after a known command word: `error: too many args` (FACTS;
//    the sketch holds 40 arguments), checked before anything else about the arguments.
//  - Motor numbers are not range-checked here (the device knows its motor count): use
//    MotorInRange() and AddressedMotor().
#ifndef MOCO_WIRE_DFMOCO_H_
#define MOCO_WIRE_DFMOCO_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "wire/bytes.h"
#include "wire/dfmoco_timing.h"

namespace moco::dfmoco {

// --- Wire constants (dfmoco-protocol.txt "Protocol", FACTS "DFMoco") ------------------
// The baud rate and the timing: wire/dfmoco_timing.h.
inline constexpr std::string_view kLineEnd = "\r\n";  // every line in and out
inline constexpr size_t kMaxArgs = 40;                // 40 or more: `error: too many args`
// Longest line the framer keeps, terminator excluded. The longest well-formed line is a
// `bf` with 38 arguments of 11 characters each ("-2147483648"): 2 + 38 * 12 = 458 bytes.
inline constexpr size_t kMaxLineBytes = 512;
inline constexpr int32_t kMaxJogVelocity = 10000;  // jm velocity 0..10000 = 0..100 %
inline constexpr int32_t kMaxBlur = 1000;          // bf blur 0..1000 (500 = 180 deg)
inline constexpr int32_t kMinPulseRate = 100;      // pr clamp (device side, FACTS)
inline constexpr int32_t kMaxPulseRate = 20000;
inline constexpr int32_t kDefaultPulseRate = 5000;
inline constexpr int32_t kBlurRefused = -1;         // `bf -1` (1.3.1 and later)
inline constexpr int32_t kStackShotMotorCount = 3;  // motors 1..3 (StackShot section 3)

// What the two ends agreed on in `hi`, and which device family speaks.
struct Dialect {
  int32_t protocol_major = 2;  // from `hi`; jm velocity exists when >= 2
  std::string firmware_version = "2.0.0";
  int32_t motor_count = 4;  // Uno 4, Mega 8, StackShot 3X 3
  bool stackshot = false;   // StackShot 3X DfMoco dialect (`mp *`, `sa <motor>`)

  bool operator==(const Dialect&) const = default;
};

// The real sketch, protocol 2 (2.0.0), with `motor_count` motors.
Dialect Dfmoco2(int32_t motor_count = 4);
// A 1.x sketch (no jm velocity), e.g. version "1.3.0" or "1.2.7".
Dialect Dfmoco1(std::string version = "1.3.0", int32_t motor_count = 4);
// StackShot 3X in DfMoco mode: answers `hi 1 3 1.2.6` (stackshot-protocol.txt section 3).
Dialect StackShot3x();

// --- Host -> device commands -----------------------------------------------------------
struct Hello {  // hi
  bool operator==(const Hello&) const = default;
};
struct MotorStatusQuery {  // ms
  bool operator==(const MotorStatusQuery&) const = default;
};
struct MoveMotor {  // mm <motor> <position>
  int32_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const MoveMotor&) const = default;
};
struct PositionQuery {  // mp <motor>
  int32_t motor = 1;
  bool operator==(const PositionQuery&) const = default;
};
struct PositionQueryAll {  // mp *   (StackShot dialect only: every motor's position)
  bool operator==(const PositionQueryAll&) const = default;
};
struct StopMotor {  // sm <motor>
  int32_t motor = 1;
  bool operator==(const StopMotor&) const = default;
};
struct StopAll {  // sa, or `sa <motor>` in the StackShot dialect
  std::optional<int32_t> motor;
  bool operator==(const StopAll&) const = default;
};
struct JogMotor {  // jm <motor> <destination> [<velocity 0..10000>]  (velocity: major >= 2)
  int32_t motor = 1;
  int32_t destination_steps = 0;
  std::optional<int32_t> velocity;
  bool operator==(const JogMotor&) const = default;
};
struct InchMotor {  // im <motor> <destination>
  int32_t motor = 1;
  int32_t destination_steps = 0;
  bool operator==(const InchMotor&) const = default;
};
struct SetPulseRate {  // pr <motor> <steps/second>  (the device clamps, the codec does not)
  int32_t motor = 1;
  int32_t rate_steps_per_s = kDefaultPulseRate;
  bool operator==(const SetPulseRate&) const = default;
};
struct ZeroMotor {  // zm <motor>
  int32_t motor = 1;
  bool operator==(const ZeroMotor&) const = default;
};
struct NewPosition {  // np <motor> <position>
  int32_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const NewPosition&) const = default;
};
struct BlurChannel {  // one `ch p0 p1 p2` group of bf: previous, current, next frame
  int32_t channel = 1;
  int32_t p0_steps = 0;
  int32_t p1_steps = 0;
  int32_t p2_steps = 0;
  bool operator==(const BlurChannel&) const = default;
};
struct BlurFrame {  // bf <exposure ms> <blur 0..1000> {ch p0 p1 p2}...
  int32_t exposure_ms = 0;
  int32_t blur = 500;  // not range-checked here: the device decides what 0..1000 means
  std::vector<BlurChannel> channels;
  bool operator==(const BlurFrame&) const = default;
};
struct Go {  // go
  bool operator==(const Go&) const = default;
};
// A line whose command word is not a known command (including the empty line). The real
// device does not answer it. `line` is the whole line as received, terminator excluded.
struct UnknownCommand {
  std::string line;
  bool operator==(const UnknownCommand&) const = default;
};

using HostCommand =
    std::variant<Hello, MotorStatusQuery, MoveMotor, PositionQuery, PositionQueryAll, StopMotor,
                 StopAll, JogMotor, InchMotor, SetPulseRate, ZeroMotor, NewPosition, BlurFrame, Go,
                 UnknownCommand>;

// --- Device -> host replies ------------------------------------------------------------
struct HelloReply {  // hi <major> <axes> <version>
  int32_t protocol_major = 2;
  int32_t motor_count = 4;
  std::string version = "2.0.0";  // one token: printable ASCII, no spaces
  bool operator==(const HelloReply&) const = default;
};
struct MotorStatusReply {    // ms <one 0/1 digit per motor>, no spaces
  std::vector<bool> moving;  // moving[i] is motor i + 1; at least one entry on the wire
  bool operator==(const MotorStatusReply&) const = default;
};
// mm <motor> <position>: DFMoco sends the target when the motor must move; the
// StackShot sends it periodically with the *current* position while moving.
struct MoveReply {
  int32_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const MoveReply&) const = default;
};
struct PositionReply {  // mp <motor> <position>
  int32_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const PositionReply&) const = default;
};
struct StopMotorReply {  // sm <motor>
  int32_t motor = 1;
  bool operator==(const StopMotorReply&) const = default;
};
struct StopAllReply {  // sa
  bool operator==(const StopAllReply&) const = default;
};
struct JogReply {  // jm <motor>
  int32_t motor = 1;
  bool operator==(const JogReply&) const = default;
};
struct InchReply {  // im <motor>
  int32_t motor = 1;
  bool operator==(const InchReply&) const = default;
};
struct PulseRateReply {  // pr <motor> <steps/second>
  int32_t motor = 1;
  int32_t rate_steps_per_s = kDefaultPulseRate;
  bool operator==(const PulseRateReply&) const = default;
};
struct ZeroReply {  // zm <motor>  (protocol text; the real sketch answers `mp m 0` twice)
  int32_t motor = 1;
  bool operator==(const ZeroReply&) const = default;
};
struct NewPositionReply {  // np <motor> <position>  (protocol text; real devices answer mp)
  int32_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const NewPositionReply&) const = default;
};
struct BlurReply {  // bf <n>: `bf 1000` when prepared, `bf -1` when a speed is too high
  int32_t value = 1000;
  bool operator==(const BlurReply&) const = default;
};
struct GoReply {  // go
  bool operator==(const GoReply&) const = default;
};
struct ParseErrorReply {  // parse error
  bool operator==(const ParseErrorReply&) const = default;
};
struct TooManyArgsReply {  // error: too many args
  bool operator==(const TooManyArgsReply&) const = default;
};

using DeviceReply =
    std::variant<HelloReply, MotorStatusReply, MoveReply, PositionReply, StopMotorReply,
                 StopAllReply, JogReply, InchReply, PulseRateReply, ZeroReply, NewPositionReply,
                 BlurReply, GoReply, ParseErrorReply, TooManyArgsReply>;

// --- Parsing ---------------------------------------------------------------------------
// Parses one host line, terminator already removed (as LineFramer delivers it).
// Outcomes:
//  - ok, a command (UnknownCommand when the word is not known: the device stays silent);
//  - DecodeError kBadLength: 40 or more arguments, the device answers
//    `error: too many args` (IsTooManyArgs);
//  - DecodeError kBadSyntax: wrong argument count or malformed number, and
//    kBadValue: a number outside int32 or jm velocity outside 0..10000; the device
//    answers `parse error`. ErrorReply() gives the answer for any error.
// The error offset is the byte offset in `line` of the offending token.
// Dialect: `jm` takes a velocity only when protocol_major >= 2; `mp *` and `sa <motor>`
// parse only when stackshot is set (elsewhere they are a wrong argument -> parse error).
wire::Result<HostCommand> ParseHostLine(std::string_view line, const Dialect& dialect);

// Parses one device line, terminator already removed. Trailing spaces are ignored (the
// StackShot document shows `hi 1 3 1.2.6 `). A line that is no known reply is
// DecodeError kUnknown; a known reply with bad fields is kBadSyntax / kBadValue.
// `ms` accepts any number (>= 1) of 0/1 digits: comparing it with the motor count is
// the host's check. The grammar is the same for both dialects.
wire::Result<DeviceReply> ParseDeviceLine(std::string_view line, const Dialect& dialect);

// True when `e` means 40 or more arguments (`error: too many args`).
bool IsTooManyArgs(const wire::DecodeError& e);
// The sketch's answer to a host line that failed to parse: TooManyArgsReply or
// ParseErrorReply.
DeviceReply ErrorReply(const wire::DecodeError& e);

// --- Formatting ------------------------------------------------------------------------
// The line for a message, "\r\n" included. Formatting never fails; what it writes parses
// back to the same value when the value is valid for the dialect (jm velocity only for
// major >= 2, PositionQueryAll / StopAll with a motor only for the StackShot, version a
// single printable token, at least one ms digit, UnknownCommand with an unknown word).
std::string FormatHost(const HostCommand& command);
std::string FormatDevice(const DeviceReply& reply);
// Same, appending to `out` (no allocation when `out` has capacity).
void AppendHost(const HostCommand& command, std::string& out);
void AppendDevice(const DeviceReply& reply, std::string& out);

// --- Transcripts -----------------------------------------------------------------------
// One line of human-readable text, no terminator.
std::string Describe(const HostCommand& command);
// `dialect` only changes the wording of `mm` (target vs the StackShot's current position).
std::string Describe(const DeviceReply& reply, const Dialect& dialect = Dialect{});

// The two-letter word of a command ("mm"); UnknownCommand gives its first word.
std::string_view CommandWord(const HostCommand& command);
// The motor a command addresses, if it addresses one (not for `mp *` or plain `sa`).
std::optional<int32_t> AddressedMotor(const HostCommand& command);
// Motor numbers start at 1 (dfmoco-protocol.txt): 1..dialect.motor_count.
bool MotorInRange(int32_t motor, const Dialect& dialect);
// The `hi` reply a device of this dialect sends, and the dialect a host learns from it.
HelloReply HelloFor(const Dialect& dialect);
Dialect DialectFrom(const HelloReply& hello, bool stackshot);

// --- Line framing ----------------------------------------------------------------------
enum class LineTermination : uint8_t {
  kSketch,   // only "\r\n" ends a line; a bare "\n" is discarded (FACTS)
  kLenient,  // "\r\n", a bare "\n" or a bare "\r" ends a line (ERRATA 2.1)
};

struct FramerOptions {
  LineTermination termination = LineTermination::kSketch;
  // REQUIRES: >= 1. Bytes kept per line, terminator excluded.
  size_t max_line_bytes = kMaxLineBytes;
};

struct FrameEvent {
  enum class Kind : uint8_t {
    kLine,      // a complete line (possibly empty), terminator removed
    kOverflow,  // the line outgrew max_line_bytes: `text` is its first max_line_bytes
                // bytes; the rest up to the next terminator is discarded, no kLine follows
  };
  Kind kind = Kind::kLine;
  std::string_view text;  // valid only during the callback
};

// Splits a byte stream into lines. Gives the same events for any chunking of the same
// bytes. Memory is bounded by max_line_bytes. Not thread-safe.
class LineFramer {
 public:
  explicit LineFramer(FramerOptions options = {});

  // Consumes `bytes`, calling on_event(const FrameEvent&) for each event in stream order.
  template <typename OnEvent>
  void Feed(std::string_view bytes, OnEvent&& on_event);

  // Owned form of the events, for tests and transcripts.
  struct OwnedEvent {
    FrameEvent::Kind kind = FrameEvent::Kind::kLine;
    std::string text;
    bool operator==(const OwnedEvent&) const = default;
  };
  std::vector<OwnedEvent> Feed(std::string_view bytes);

  // Bytes of the current incomplete line held (never more than max_line_bytes).
  size_t buffered() const { return line_.size(); }
  // Bare "\n" bytes discarded so far (kSketch only).
  uint64_t ignored_line_feeds() const { return ignored_lf_; }
  const FramerOptions& options() const { return options_; }
  // Forgets any partial line (a device reset).
  void Reset();

 private:
  template <typename OnEvent>
  void Append(char c, OnEvent& on_event);

  FramerOptions options_;
  std::string line_;
  bool pending_cr_ = false;  // kSketch: a "\r" whose meaning depends on the next byte
  bool skip_lf_ = false;     // kLenient: a "\r" just ended a line; a "\n" next belongs to it
  bool discarding_ = false;  // after kOverflow, until the next terminator
  uint64_t ignored_lf_ = 0;
};

template <typename OnEvent>
void LineFramer::Append(char c, OnEvent& on_event) {
  if (discarding_) return;
  if (line_.size() >= options_.max_line_bytes) {
    on_event(FrameEvent{FrameEvent::Kind::kOverflow, std::string_view(line_)});
    line_.clear();
    discarding_ = true;
    return;
  }
  line_.push_back(c);
}

template <typename OnEvent>
void LineFramer::Feed(std::string_view bytes, OnEvent&& on_event) {
  for (const char c : bytes) {
    if (options_.termination == LineTermination::kSketch) {
      if (c == '\n') {
        if (pending_cr_) {
          pending_cr_ = false;
          if (!discarding_) on_event(FrameEvent{FrameEvent::Kind::kLine, std::string_view(line_)});
          line_.clear();
          discarding_ = false;
        } else {
          ++ignored_lf_;  // the sketch ignores "\n" unless it follows "\r"
        }
        continue;
      }
      if (pending_cr_) Append('\r', on_event);  // that "\r" was an ordinary byte after all
      pending_cr_ = (c == '\r');
      if (!pending_cr_) Append(c, on_event);
      continue;
    }
    // kLenient
    if (c == '\n' && skip_lf_) {
      skip_lf_ = false;
      continue;
    }
    skip_lf_ = false;
    if (c == '\r' || c == '\n') {
      if (!discarding_) on_event(FrameEvent{FrameEvent::Kind::kLine, std::string_view(line_)});
      line_.clear();
      discarding_ = false;
      skip_lf_ = (c == '\r');
      continue;
    }
    Append(c, on_event);
  }
}

}  // namespace moco::dfmoco

#endif  // MOCO_WIRE_DFMOCO_H_
