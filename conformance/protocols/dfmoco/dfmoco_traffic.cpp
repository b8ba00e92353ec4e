// Recorded DFMoco traffic read back with the codec (wire/dfmoco.h): the
// positions the device reported, for plots, and the position events the pin
// rules judge the watched STEP and DIR pins against (core/pin_judge.h).
#include <map>
#include <string_view>
#include <variant>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "wire/dfmoco.h"

namespace moco::conformance {
namespace {

// The highest motor number read from traffic: beyond any board's, and a
// bound on the per-motor maps a corrupted line could otherwise grow.
constexpr int32_t kHighestMotor = 64;

// Calls on_line(chunk, line) for every complete line of either side, framed
// as the codec frames a line; any line end is accepted (ERRATA 2.1), since a
// device under test may end its lines either way.
template <typename OnLine>
void ForEachLine(const std::vector<Chunk>& traffic, OnLine&& on_line) {
  dfmoco::FramerOptions options;
  options.termination = dfmoco::LineTermination::kLenient;
  dfmoco::LineFramer host(options);
  dfmoco::LineFramer device(options);
  for (const Chunk& c : traffic) {
    dfmoco::LineFramer& framer = c.from_host ? host : device;
    const std::string_view bytes(reinterpret_cast<const char*>(c.bytes.data()), c.bytes.size());
    framer.Feed(bytes, [&](const dfmoco::FrameEvent& e) {
      if (e.kind == dfmoco::FrameEvent::Kind::kLine) on_line(c, e.text);
    });
  }
}

bool KnownMotor(int32_t motor) { return motor >= 1 && motor <= kHighestMotor; }

}  // namespace

PositionSeries DfmocoProtocol::Positions(const std::vector<Chunk>& traffic) {
  PositionSeries s;
  const dfmoco::Dialect dialect;
  ForEachLine(traffic, [&](const Chunk& c, std::string_view line) {
    if (c.from_host) return;
    const auto reply = dfmoco::ParseDeviceLine(line, dialect);
    if (!reply) return;
    if (const auto* mp = std::get_if<dfmoco::PositionReply>(&*reply); mp && KnownMotor(mp->motor)) {
      s[mp->motor].emplace_back(c.t_ns, mp->position_steps);
    }
  });
  return s;
}

// `mp m p` reports; `np m p` and `zm m` answers, and the sketch's `mp m p`
// answering an np or zm (FACTS DFMoco: it answers with the position), as
// resets; `pr m v` answers as pulse rates. A `parse error` forgets the
// resets asked for (the request it answers was not one).
std::vector<PinPositionEvent> DfmocoProtocol::PinEvents(const std::vector<Chunk>& traffic) {
  using Kind = PinPositionEvent::Kind;
  std::vector<PinPositionEvent> out;
  std::map<int, int64_t> pending;  // motor -> the position an np / zm asked for
  const dfmoco::Dialect dialect;
  ForEachLine(traffic, [&](const Chunk& c, std::string_view line) {
    if (c.from_host) {
      const auto command = dfmoco::ParseHostLine(line, dialect);
      if (!command) return;
      if (const auto* np = std::get_if<dfmoco::NewPosition>(&*command);
          np && KnownMotor(np->motor)) {
        pending[np->motor] = np->position_steps;
      } else if (const auto* zm = std::get_if<dfmoco::ZeroMotor>(&*command);
                 zm && KnownMotor(zm->motor)) {
        pending[zm->motor] = 0;
      }
      return;
    }
    const auto reply = dfmoco::ParseDeviceLine(line, dialect);
    if (!reply) return;
    if (const auto* np = std::get_if<dfmoco::NewPositionReply>(&*reply);
        np && KnownMotor(np->motor)) {
      out.push_back({Kind::kReset, c.t_ns, np->motor, np->position_steps});
      pending.erase(np->motor);
    } else if (const auto* zm = std::get_if<dfmoco::ZeroReply>(&*reply);
               zm && KnownMotor(zm->motor)) {
      out.push_back({Kind::kReset, c.t_ns, zm->motor, 0});
      pending.erase(zm->motor);
    } else if (const auto* mp = std::get_if<dfmoco::PositionReply>(&*reply);
               mp && KnownMotor(mp->motor)) {
      const auto asked = pending.find(mp->motor);
      const bool reset = asked != pending.end() && asked->second == mp->position_steps;
      out.push_back({reset ? Kind::kReset : Kind::kReport, c.t_ns, mp->motor, mp->position_steps});
      if (reset) pending.erase(asked);
    } else if (const auto* pr = std::get_if<dfmoco::PulseRateReply>(&*reply);
               pr && KnownMotor(pr->motor)) {
      out.push_back({Kind::kPulseRate, c.t_ns, pr->motor, pr->rate_steps_per_s});
    } else if (std::holds_alternative<dfmoco::ParseErrorReply>(*reply)) {
      pending.clear();
    }
  });
  return out;
}

}  // namespace moco::conformance
