// Recorded DFMoco traffic read back with the codec (wire/dfmoco.h): the
// positions the device reported, for plots, and the position events the pin
// rules judge the watched STEP and DIR pins against (core/pin_judge.h).
#include <algorithm>
#include <deque>
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
// answering an np or zm (FACTS DFMoco: np is answered at once with the
// position, zm later from the main loop), as resets; `pr m v` answers as
// pulse rates.
//
// The resets asked for are kept per motor in the order asked, since a host
// may send several in one write and a device answers them in order, with
// other replies between (a `parse error` for a garbled line among them). An
// `mp m p` equal to one asked for answers it, and the earlier ones asked for
// that motor are given up (answered otherwise, or refused): the device
// answers in order. A `parse error` is not matched to a request: the sketch
// silently drops lines it cannot read at all, so replies cannot be counted
// against requests. An np or zm refused stays asked for: a later report
// equal to it reads as a reset: that takes the device's word for where it
// was at that moment, which can hide a step lost before it but cannot make
// up one after it.
std::vector<PinPositionEvent> DfmocoProtocol::PinEvents(const std::vector<Chunk>& traffic) {
  using Kind = PinPositionEvent::Kind;
  // A bound on the resets kept per motor, for a flood of np: the oldest go.
  constexpr size_t kMaxAsked = 256;
  std::vector<PinPositionEvent> out;
  std::map<int, std::deque<int64_t>> asked;  // motor -> the positions np / zm asked for
  const auto ask = [&](int32_t motor, int64_t position) {
    std::deque<int64_t>& q = asked[motor];
    if (q.size() == kMaxAsked) q.pop_front();
    q.push_back(position);
  };
  // Whether `position` answers one of the resets asked for `motor`; that one
  // and those asked before it are then done.
  const auto answers = [&](int32_t motor, int64_t position) {
    const auto m = asked.find(motor);
    if (m == asked.end()) return false;
    std::deque<int64_t>& q = m->second;
    const auto it = std::find(q.begin(), q.end(), position);
    if (it == q.end()) return false;
    q.erase(q.begin(), std::next(it));
    return true;
  };
  const dfmoco::Dialect dialect;
  ForEachLine(traffic, [&](const Chunk& c, std::string_view line) {
    if (c.from_host) {
      const auto command = dfmoco::ParseHostLine(line, dialect);
      if (!command) return;
      if (const auto* np = std::get_if<dfmoco::NewPosition>(&*command);
          np && KnownMotor(np->motor)) {
        ask(np->motor, np->position_steps);
      } else if (const auto* zm = std::get_if<dfmoco::ZeroMotor>(&*command);
                 zm && KnownMotor(zm->motor)) {
        ask(zm->motor, 0);
      }
      return;
    }
    const auto reply = dfmoco::ParseDeviceLine(line, dialect);
    if (!reply) return;
    if (const auto* np = std::get_if<dfmoco::NewPositionReply>(&*reply);
        np && KnownMotor(np->motor)) {
      answers(np->motor, np->position_steps);
      out.push_back({Kind::kReset, c.t_ns, np->motor, np->position_steps});
    } else if (const auto* zm = std::get_if<dfmoco::ZeroReply>(&*reply);
               zm && KnownMotor(zm->motor)) {
      answers(zm->motor, 0);
      out.push_back({Kind::kReset, c.t_ns, zm->motor, 0});
    } else if (const auto* mp = std::get_if<dfmoco::PositionReply>(&*reply);
               mp && KnownMotor(mp->motor)) {
      const bool reset = answers(mp->motor, mp->position_steps);
      out.push_back({reset ? Kind::kReset : Kind::kReport, c.t_ns, mp->motor, mp->position_steps});
    } else if (const auto* pr = std::get_if<dfmoco::PulseRateReply>(&*reply);
               pr && KnownMotor(pr->motor)) {
      out.push_back({Kind::kPulseRate, c.t_ns, pr->motor, pr->rate_steps_per_s});
    }
  });
  return out;
}

}  // namespace moco::conformance
