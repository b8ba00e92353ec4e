// A Dragonframe-style DFMoco host over a Target (dfmoco-protocol.txt "Message
// Format", "Messages", "Notes"; ERRATA dfmoco 1-5; FACTS "DFMoco"): sends
// command lines, frames every device byte into lines with their times,
// matches replies to commands (the protocol has no message ids: by word,
// motor and, for `mp` answers, position) and checks every device line against
// the stream rules (terminator, ASCII, reply grammar, `ms` width, `hi`
// fields, one reply per command, deadlines).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_HOST_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_HOST_H_

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/verdicts.h"
#include "conformance/targets/target.h"
#include "wire/dfmoco.h"

namespace moco::conformance {

// One line the device sent.
struct DfmLine {
  TimeNs t_ns = 0;
  std::string text;                          // without its terminator
  wire::Bytes raw;                           // as it crossed the link, terminator included
  std::optional<dfmoco::DeviceReply> reply;  // nullopt: no reply of the grammar
  int command = -1;  // index of the command it answers; -1: unprompted (or stray)
};

// The dialects a DFMoco device is judged in (HostOptions::dialect, mococheck
// run --dialect; the JSON report's device "dialect"): the Arduino sketch's,
// and a StackShot 3X's DfMoco mode (stackshot-protocol.txt section 3).
inline constexpr std::string_view kSketchDialect = "sketch";
inline constexpr std::string_view kStackshotDialect = "stackshot3x";

// What a DFMoco device said of itself: its `hi`, and the dialect it is
// judged in (stackshot: the StackShot 3X's DfMoco mode, stackshot-protocol.txt
// section 3; else the Arduino sketch's).
struct DfmDevice : dfmoco::HelloReply {
  bool stackshot = false;
};

// What the host expects a command to get.
enum class DfmExpect {
  kReply,    // its OUT line
  kError,    // `parse error`
  kTooMany,  // `error: too many args`
  kSilence,  // nothing (an unknown word)
};

struct DfmCommand {
  std::string line;                           // without its terminator
  std::optional<dfmoco::HostCommand> parsed;  // in the device's dialect
  DfmExpect expect = DfmExpect::kReply;
  std::string_view error_rule;  // the rule judging the error answer (kError, kTooMany)
  TimeNs sent_ns = 0;
  bool timed = true;  // judged by the DFM-DL rules (ended by "\r\n")
  int answer = -1;    // index into lines()
  int answers = 0;
  // The host stopped waiting for its answer (Await timed out) and may have
  // sent it again: a later fitting line answers a newer command first.
  bool abandoned = false;
};

class DfmHost : public HostBase {
 public:
  // `target` and `verdicts` must outlive the host. The target is open.
  DfmHost(Target& target, Verdicts& verdicts, HostOptions options);

  // Sends `line` + `terminator`; returns the command's index. What the host
  // expects follows from parsing the line in the device's dialect (a bad
  // motor or argument: `parse error`; 40+ arguments: too many args; an
  // unknown word: silence); `error_rule` set means a valid line the device
  // must refuse with `parse error` (judged by that rule).
  int Send(std::string_view line, std::string_view error_rule = {},
           std::string_view terminator = "\r\n");
  // Sends every line in one write; returns the first command's index.
  int SendBatch(const std::vector<std::string>& lines);
  // Sends bytes that are no command (a lone terminator, noise).
  void SendRaw(std::string_view bytes);

  // Waits for the answer to command `index` (DFM-REPLY-001 fails after the
  // answer timeout); returns it or nullptr.
  const DfmLine* Await(int index);
  const DfmLine* Call(std::string_view line, std::string_view error_rule = {}) {
    return Await(Send(line, error_rule));
  }

  // Reads until a line with index >= `from` satisfies `pred` or `timeout_ns`
  // passes; returns its index or -1.
  int WaitFor(size_t from, TimeNs timeout_ns, const std::function<bool(const DfmLine&)>& pred);
  // Ends the case: listens for the quiet time and settles the stream rules
  // (an unfinished line fails DFM-LINE-003). Call once.
  void Close();

  // A deque: pointers to lines stay valid while more arrive.
  const std::deque<DfmLine>& lines() const { return lines_; }
  const std::vector<DfmCommand>& commands() const { return commands_; }

  // The last `hi` the device sent (answer or unprompted), if any.
  const std::optional<dfmoco::HelloReply>& hello() const { return hello_; }
  // The dialect learnt from `hi` (the 2.0.0 sketch with 4 motors before it),
  // the StackShot 3X's as HostOptions::dialect says.
  dfmoco::Dialect dialect() const;
  // Whether the device is judged in the StackShot 3X DfMoco dialect
  // (stackshot-protocol.txt section 3; ERRATA 3.9): HostOptions::dialect
  // kStackshotDialect, or kAutoDialect and a `hi` that is exactly `hi 1 3 1.2.6`.
  bool stackshot() const;
  // Axes from `hi` (0 before it).
  int32_t axes() const { return hello_ ? hello_->motor_count : 0; }

 private:
  // A command record for `line`: what the device must answer (see Send()).
  DfmCommand MakeCommand(std::string_view line, std::string_view error_rule) const;

  void OnBytes(wire::ByteView bytes);
  void EndLine(bool crlf);
  void OnLine(DfmLine line, bool crlf);
  int Match(const dfmoco::DeviceReply& reply) const;
  bool Fits(const DfmCommand& c, const dfmoco::DeviceReply& reply) const;
  void CheckAnswer(DfmCommand& c, const DfmLine& line);
  void CheckHello(const DfmLine& line, const dfmoco::HelloReply& hello);
  Evidence Ev(const DfmLine& line, std::string expected, std::string observed) const;

  std::deque<DfmLine> lines_;
  std::vector<DfmCommand> commands_;
  std::optional<dfmoco::HelloReply> hello_;
  wire::Bytes partial_;  // bytes of the line being received
  bool pending_cr_ = false;
  bool closed_ = false;
};

// Whether `hello` is exactly the StackShot 3X's in DfMoco mode, `hi 1 3 1.2.6`
// (stackshot-protocol.txt section 3).
bool IsStackShotHello(const dfmoco::HelloReply& hello);

// The reply of `line` as T, or nullptr.
template <typename T>
const T* As(const DfmLine* line) {
  if (line == nullptr || !line->reply) return nullptr;
  return std::get_if<T>(&*line->reply);
}
// "mp 1 250", or "no answer".
std::string Show(const DfmLine* line);
// The two-letter word of a command line ("mm").
std::string_view WordOf(std::string_view line);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_HOST_H_
