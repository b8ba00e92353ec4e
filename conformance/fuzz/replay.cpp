// Session replay (see replay.h). Messages match when their bytes are equal or
// when the protocol's matcher (FuzzHooks::matcher: positions within the step
// tolerance, a device's own message IDs) accepts their difference, and
// arrive within the time tolerance.
#include "conformance/fuzz/replay.h"

#include "base/format.h"

#include <algorithm>
#include <string_view>

#include "conformance/protocols/registry.h"
#include "wire/protocol.h"
#include "wire/transcript.h"

namespace moco::conformance {
namespace {

std::string Describe(Protocol protocol, const wire::Bytes& bytes) {
  wire::TranscriptDecoder d(protocol);
  std::string s;
  for (const auto& l : d.Feed(wire::Side::kDevice, bytes)) s += (s.empty() ? "" : "; ") + l.text;
  for (const auto& l : d.Finish()) s += (s.empty() ? "" : "; ") + l.text;
  if (s.empty()) s = wire::ToHex(bytes);
  return s;
}

}  // namespace

std::vector<TimedMessage> SplitDeviceChunks(Protocol protocol,
                                            const std::vector<TimedMessage>& chunks) {
  wire::Bytes all;
  std::vector<std::pair<size_t, TimeNs>> ends;  // end offset of each chunk, its time
  for (const TimedMessage& c : chunks) {
    all.insert(all.end(), c.bytes.begin(), c.bytes.end());
    ends.emplace_back(all.size(), c.t_ns);
  }
  auto time_of_end = [&](size_t end) {
    // The first chunk whose end reaches `end` completed the message.
    auto it = std::lower_bound(ends.begin(), ends.end(), end,
                               [](const auto& p, size_t v) { return p.first < v; });
    return it == ends.end() ? (ends.empty() ? TimeNs{0} : ends.back().second) : it->second;
  };
  std::vector<TimedMessage> out;
  size_t end = 0;
  for (wire::Bytes& m : wire::SplitMessages(protocol, wire::Side::kDevice, all)) {
    end += m.size();
    out.push_back({time_of_end(end), std::move(m)});
  }
  return out;
}

ReplayResult Replay(const session::Session& session, Protocol protocol, Target& target,
                    const ReplayOptions& options) {
  ReplayResult result;
  result.from_power_on = target.CanRestart();
  result.position_tolerance_steps =
      options.position_steps.value_or(session.header.tolerance_position_steps.value_or(0));
  result.time_tolerance_ms = options.time_ms.value_or(
      session.header.tolerance_time_ms.value_or(target.VirtualClock() ? 0 : 50));
  const TimeNs time_tol = result.time_tolerance_ms * sim::kNsPerMs;

  std::vector<TimedMessage> expected_chunks;
  TimeNs first_host = -1;
  TimeNs last_t = 0;
  for (const session::SessionEntry& e : session.entries) {
    if (e.is_event) continue;
    last_t = std::max(last_t, e.t_ns);
    if (e.from == session::Origin::kHost && first_host < 0) first_host = e.t_ns;
    if (e.from == session::Origin::kDevice) expected_chunks.push_back({e.t_ns, e.bytes});
  }
  if (first_host < 0) first_host = 0;
  // Recorded times map to target times: from power-on as they are; on a
  // running target, the first host message is sent at once.
  if (result.from_power_on) target.Restart();
  const TimeNs origin = target.Now();
  const TimeNs base = result.from_power_on ? 0 : first_host;
  std::vector<TimedMessage> expected = SplitDeviceChunks(protocol, expected_chunks);
  if (!result.from_power_on) {
    std::erase_if(expected, [&](const TimedMessage& m) { return m.t_ns < first_host; });
  }
  for (TimedMessage& m : expected) m.t_ns -= base;

  const FuzzHooks* hooks = FindFuzzHooks(protocol);
  const std::unique_ptr<ReplayMatcher> matcher =
      hooks != nullptr && hooks->matcher != nullptr ? hooks->matcher() : nullptr;
  std::vector<TimedMessage> observed_chunks;
  auto pump_until = [&](TimeNs t_target) {
    while (true) {
      wire::Bytes in;
      if (!target.Receive(t_target, in)) return false;
      if (!in.empty()) observed_chunks.push_back({target.Now() - origin, std::move(in)});
      if (target.Now() >= t_target) return true;
    }
  };
  for (const session::SessionEntry& e : session.entries) {
    if (e.is_event || e.from != session::Origin::kHost) continue;
    if (!pump_until(origin + (e.t_ns - base))) break;
    if (matcher != nullptr) matcher->HostSent(e.bytes, e.t_ns - base);
    if (!target.Send(e.bytes)) break;
    ++result.host_messages_sent;
  }
  // Listen to the end of the recording (plus the time tolerance); what the
  // device sends later was not recorded and is not compared.
  const TimeNs end_ns = (last_t - base) + time_tol;
  pump_until(origin + end_ns + 1);
  std::vector<TimedMessage> observed = SplitDeviceChunks(protocol, observed_chunks);
  std::erase_if(observed, [&](const TimedMessage& m) { return m.t_ns > end_ns; });

  result.expected_messages = expected.size();
  result.observed_messages = observed.size();
  const size_t n = std::max(expected.size(), observed.size());
  for (size_t i = 0; i < n && result.differences.size() < options.max_differences; ++i) {
    ReplayDifference d;
    d.index = i;
    if (i < expected.size()) {
      d.expected_t_ns = expected[i].t_ns;
      d.expected = Describe(protocol, expected[i].bytes);
    }
    if (i < observed.size()) {
      d.observed_t_ns = observed[i].t_ns;
      d.observed = Describe(protocol, observed[i].bytes);
    }
    if (i >= observed.size()) {
      d.why = "the device sent nothing more";
      result.differences.push_back(std::move(d));
      continue;
    }
    if (i >= expected.size()) {
      d.why = "the device sent more than was recorded";
      result.differences.push_back(std::move(d));
      continue;
    }
    const wire::Bytes& e = expected[i].bytes;
    const wire::Bytes& o = observed[i].bytes;
    bool same = e == o;
    std::string why;
    if (!same) {
      if (matcher != nullptr) {
        same = matcher->Match(e, o, expected[i].t_ns, result.position_tolerance_steps, why);
      } else {
        why = "the bytes differ";
      }
    }
    const TimeNs dt = observed[i].t_ns - expected[i].t_ns;
    if (same && (dt > time_tol || dt < -time_tol)) {
      same = false;
      why = "arrived " + base::Ms(dt, 3) + " from the recorded time (tolerance " +
            std::to_string(result.time_tolerance_ms) + " ms)";
    }
    if (same) {
      ++result.matched;
    } else {
      d.why = why;
      result.differences.push_back(std::move(d));
    }
  }
  return result;
}

std::string ReplayText(const ReplayResult& r) {
  std::string s;
  s += "replay: " + std::to_string(r.host_messages_sent) + " host chunks sent; " +
       std::to_string(r.matched) + " of " + std::to_string(r.expected_messages) +
       " recorded device messages matched (" + std::to_string(r.observed_messages) +
       " observed); tolerances " + std::to_string(r.position_tolerance_steps) + " steps, " +
       std::to_string(r.time_tolerance_ms) + " ms" +
       (r.from_power_on ? "" : "; boot messages not expected (target already running)") + "\n";
  for (const ReplayDifference& d : r.differences) {
    s += "  #" + std::to_string(d.index) + ": " + d.why + "\n";
    s += "    recorded: " +
         (d.expected_t_ns < 0 ? std::string("(nothing)")
                              : base::Ms(d.expected_t_ns, 3) + "  " + d.expected) +
         "\n";
    s += "    observed: " +
         (d.observed_t_ns < 0 ? std::string("(nothing)")
                              : base::Ms(d.observed_t_ns, 3) + "  " + d.observed) +
         "\n";
  }
  s += r.ok() ? "result: MATCH\n" : "result: DIFFERENT\n";
  return s;
}

}  // namespace moco::conformance
