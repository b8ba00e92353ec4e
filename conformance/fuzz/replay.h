// `mococheck replay`: resends the host side of a recorded session
// (docs/sessions.md) to a target at the recorded times and compares what the
// device sends with the recorded device side, message by message, within the
// tolerances the session states (positions in steps, times in ms).
#ifndef MOCO_CONFORMANCE_FUZZ_REPLAY_H_
#define MOCO_CONFORMANCE_FUZZ_REPLAY_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "conformance/fuzz/mutator.h"
#include "conformance/targets/target.h"
#include "session/session.h"

namespace moco::conformance {

// A message cut from one direction of the traffic, with the time of the chunk
// that completed it.
struct TimedMessage {
  TimeNs t_ns = 0;
  wire::Bytes bytes;
};

// Cuts a device byte stream, given as timed chunks, into messages (DMC
// frames, DFMoco lines, StackShot device packets); bytes between messages
// form noise messages of their own.
std::vector<TimedMessage> SplitDeviceChunks(Protocol protocol,
                                            const std::vector<TimedMessage>& chunks);

struct ReplayOptions {
  // Override the session's tolerances; otherwise the session's, else 0 steps
  // and 0 ms on a virtual-clock target, 0 steps and 50 ms on a real one.
  std::optional<int64_t> position_steps;
  std::optional<int64_t> time_ms;
  size_t max_differences = 20;
};

struct ReplayDifference {
  size_t index = 0;           // of the recorded device message (or of the first extra observed one)
  TimeNs expected_t_ns = -1;  // -1: nothing was expected here
  TimeNs observed_t_ns = -1;  // -1: nothing arrived
  std::string expected;       // described (transcript line)
  std::string observed;
  std::string why;
};

struct ReplayResult {
  size_t host_messages_sent = 0;
  size_t expected_messages = 0;
  size_t observed_messages = 0;
  size_t matched = 0;
  bool from_power_on = true;  // false: the target was already running; boot messages skipped
  int64_t position_tolerance_steps = 0;
  int64_t time_tolerance_ms = 0;
  std::vector<ReplayDifference> differences;
  bool ok() const { return differences.empty(); }
};

// Replays `session` to an open `target` (restarted first when it can be, so
// the device starts from power-on as recorded; otherwise recorded device
// messages before the first host message are not expected).
// REQUIRES: the session's protocol is `protocol`.
ReplayResult Replay(const session::Session& session, Protocol protocol, Target& target,
                    const ReplayOptions& options);

// Human-readable summary and the differences.
std::string ReplayText(const ReplayResult& result);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_REPLAY_H_
