// Session files: timestamped host/device traffic in JSON Lines (docs/sessions.md).
// Read by `mocosim decode`, `mococheck replay` and `mococheck fuzz`; written by
// `mocosim --record`. The recording format is its own layer (docs/architecture.md):
// below devices, transport, control and conformance, it uses only base and wire.
#ifndef MOCO_SESSION_SESSION_H_
#define MOCO_SESSION_SESSION_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/file_io.h"
#include "wire/bytes.h"
#include "wire/line.h"
#include "wire/transcript.h"

namespace moco::session {

inline constexpr int kSessionFormatVersion = 1;

using wire::ParseProtocol;
using wire::Protocol;
using wire::ProtocolName;

struct SessionHeader {
  Protocol protocol = Protocol::kDmc;
  std::string device;             // optional device model name
  std::string clock = "virtual";  // "virtual" or "real"
  std::string note;
  std::optional<int64_t> tolerance_position_steps;
  std::optional<int64_t> tolerance_time_ms;
  nlohmann::json extra = nlohmann::json::object();  // unknown fields, kept verbatim
};

enum class Origin { kHost, kDevice };

// One line after the header: traffic (origin + bytes) or an event.
struct SessionEntry {
  int64_t t_ns = 0;
  bool is_event = false;
  Origin from = Origin::kHost;       // traffic only
  wire::Bytes bytes;                 // traffic only
  std::vector<std::string> decoded;  // traffic only, informational
  nlohmann::json event;              // event only: the whole line

  // An event entry from its session line (an object with "t_ns", which the
  // entry keeps as its time instead).
  static SessionEntry Event(nlohmann::json line);
};

// The event a recording writes where the device's line switches protocol
// (docs/sessions.md "line_switch"): {"event": "line_switch", "protocol":
// <name>, "baud": <rate>, "t_ns": t_ns}, and "detail" when not empty. The
// traffic after it speaks `protocol`.
SessionEntry LineSwitchEvent(int64_t t_ns, Protocol protocol, const wire::LineSettings& line,
                             std::string_view detail = {});
// The protocol a "line_switch" event switches the line to; nullopt for any
// other entry (and for a protocol this program does not know).
std::optional<Protocol> LineSwitchOf(const SessionEntry& e);

struct Session {
  SessionHeader header;
  std::vector<SessionEntry> entries;
  // The 1-based number of the file's last line when it was cut short (no
  // newline and not valid JSON: a recording that did not finish, see
  // SessionWriter); the entries before it are read. 0 when the file is whole.
  size_t cut_line = 0;
};

// What a reader should tell the user about a session it read: the cut last
// line, if any ("line 28 is cut short: ..."); empty when there is nothing.
std::string SessionWarning(const Session& s);

// A failure to read a session, with the 1-based line number and a message that
// names the problem and the fix.
struct SessionError {
  size_t line = 0;
  std::string message;
};

// Parses a whole session from text. Never throws.
std::variant<Session, SessionError> ParseSession(std::string_view text);
// The longest line a session file may have (a line is one message or event;
// a longer one is not a session, e.g. /dev/zero behind a FIFO).
inline constexpr size_t kMaxSessionLineBytes = size_t{4} << 20;

// Reads and parses a file (any length, each line at most
// kMaxSessionLineBytes; a directory or device is refused). Never throws.
std::variant<Session, SessionError> LoadSession(const std::filesystem::path& path);

nlohmann::json HeaderToJson(const SessionHeader& h);
nlohmann::json EntryToJson(const SessionEntry& e);
// Appends e's session line: EntryToJson(e) as compact JSON (invalid UTF-8
// replaced) and a newline, byte for byte; traffic lines without building
// the JSON value.
void AppendEntryLine(const SessionEntry& e, std::string& out);

// Writes a session line by line: every line is written through as it comes
// to an exclusively created "<path>.partial-<pid>-<n>" beside <path> (after
// its symlinks), and Finish() renames it to <path>, so a finished file is
// always whole and a crash leaves at most the last line cut short in the
// .partial file. A FIFO or character device (/dev/null) at <path> is written
// in place and stays what it is (base::OutputFile).
class SessionWriter {
 public:
  // Throws std::runtime_error with a user-facing message if the file cannot be
  // created (a directory, a socket, a missing directory, ...).
  SessionWriter(std::filesystem::path path, const SessionHeader& header);
  ~SessionWriter();  // Finish()es if not done yet; never throws.
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  void Append(const SessionEntry& entry);
  // Appends entries in order with one write (a recorder that batches its
  // lines off a latency-critical path). A crash during the write leaves, as
  // ever, at most the last line cut short.
  void Append(std::span<const SessionEntry> entries);
  // Flushes, closes and renames into place. Returns false (with a message) on an I/O error.
  bool Finish(std::string* error = nullptr);
  // Drops the recording: an existing file at path() stays as it was (a
  // temporary file is removed). Finish() then does nothing.
  void Abandon();
  const std::filesystem::path& path() const { return path_; }
  // Finish() replaces a regular file that was at path() when the writer opened.
  bool replaces_existing() const { return file_.replaces_existing(); }
  // Where the lines go until Finish() (empty when written in place).
  const std::string& partial_path() const { return file_.temporary_path(); }

 private:
  void WriteLine(const nlohmann::json& j);
  std::filesystem::path path_;
  base::OutputFile file_;
  bool finished_ = false;
};

}  // namespace moco::session

#endif  // MOCO_SESSION_SESSION_H_
