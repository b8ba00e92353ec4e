// The protocols the project speaks, in one table: what a protocol is called,
// how its bytes are cut into messages and repaired, how a host greets a device,
// and its line settings. Every program and library asks this table (and the
// codecs it names) instead of switching on the protocol itself; a new protocol
// is one row here plus its codec (docs/architecture.md "Adding a protocol").
#ifndef MOCO_WIRE_PROTOCOL_H_
#define MOCO_WIRE_PROTOCOL_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "wire/bytes.h"
#include "wire/line.h"

namespace moco::wire {

enum class Protocol { kDmc, kDfmoco, kStackshot, kStackshotDfmoco };

enum class Side { kHost, kDevice };

class TranscriptSides;  // wire/transcript_sides.h

// Where a line's traffic switches protocol: after the first `offset` bytes of
// the chunk that showed it, the line speaks `protocol`; `note` says so for a
// transcript ("DfMoco mode: DFMoco text at 57600 baud").
struct LineSwitchAt {
  size_t offset = 0;
  Protocol protocol = Protocol::kDmc;
  std::string note;
};

// Reads a line's traffic for the device's switch to another protocol, as
// its acknowledgement shows it (a StackShot 3X entering DfMoco mode,
// stackshot-protocol.txt section 3). One per line; feeds of both directions
// in the order they crossed.
class LineSwitchWatcher {
 public:
  virtual ~LineSwitchWatcher() = default;
  // A chunk that crossed from `side`; the switch it completes, if any. The
  // watcher is done after a switch: the new protocol's row gives the next.
  virtual std::optional<LineSwitchAt> Feed(Side side, ByteView bytes) = 0;
};

struct MessageCut {
  size_t skip = 0;
  size_t length = 0;
};

struct ProtocolInfo {
  Protocol id = Protocol::kDmc;
  std::string_view name;         // "dmc": sessions, --protocol, reports
  std::string_view title;        // "DMC v2": prose
  std::string_view rule_prefix;  // "DMC-": the conformance rules' ids ("" when none)
  std::string_view alias;        // another name accepted on command lines ("dmc2"), or ""
  // The line a real device of this protocol uses by default: 8N1 at the rate
  // its codec names (dmc::kBaudRate, dfmoco::kBaudRate, stackshot::kBaudRate,
  // stackshot::kDfMocoBaudRate).
  LineSettings line;
  // Where the first whole message from `side` in `bytes` is: `skip` bytes of
  // noise, then `length` bytes of message (framing plausible, every byte
  // present); {bytes.size(), 0} when no whole message is there.
  MessageCut (*next_message)(Side side, ByteView bytes) = nullptr;
  // Makes a host message frame correctly again (length and checksum set from
  // its data, or its line end appended). Bytes that cannot start a message are
  // left as they are.
  void (*repair)(Bytes& message) = nullptr;
  // The message a host sends first to learn what is there (HI, `hi`, PING).
  Bytes (*greeting)() = nullptr;
  // Decoders of both directions for transcripts (wire/transcript.h).
  std::unique_ptr<TranscriptSides> (*transcript)() = nullptr;
  // A line of this protocol that can switch to another one by a message of
  // its own: the watcher that reads the switch from the traffic. Null for a
  // line that never switches (or only in ways the traffic does not show).
  std::unique_ptr<LineSwitchWatcher> (*line_switches)() = nullptr;
  // A dialect of another protocol: that protocol's hosts, rules and runner
  // apply to it (a StackShot in DfMoco mode is a DFMoco device); nullopt
  // for a protocol of its own.
  std::optional<Protocol> dialect_of = std::nullopt;
};

// The watcher of a line speaking `p` (ProtocolInfo::line_switches); null
// when such a line never switches by its traffic.
std::unique_ptr<LineSwitchWatcher> WatchLineSwitches(Protocol p);

// Every protocol, in the enum's order.
std::span<const ProtocolInfo> Protocols();
const ProtocolInfo& Info(Protocol p);

// "dmc", "dfmoco", "stackshot", "stackshot-dfmoco".
std::string_view ProtocolName(Protocol p);
// Exactly one of the names above; nullopt otherwise (session files).
std::optional<Protocol> ParseProtocol(std::string_view name);
// A name or an alias ("dmc2", "stackshot3x"), for command lines.
std::optional<Protocol> ParseProtocolOrAlias(std::string_view text);
// "dmc, dfmoco or stackshot": the names of `protocols`, for messages.
std::string NameList(std::span<const Protocol> protocols);
// "DMC v2 115200, DFMoco 57600, StackShot 38400": the default line rate of
// each protocol a device starts in, for help texts and messages.
std::string DefaultBaudList();

// Cuts a byte stream from `side` into whole messages; the bytes between them
// (noise, a message cut short) are kept as messages of their own, so joining
// the result gives the stream back.
std::vector<Bytes> SplitMessages(Protocol p, Side side, ByteView stream);
Bytes JoinMessages(const std::vector<Bytes>& messages);

}  // namespace moco::wire

#endif  // MOCO_WIRE_PROTOCOL_H_
