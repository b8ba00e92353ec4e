// DMC v2 under the fuzzer (core/fuzz_protocol.h): frames mutated per field
// and re-framed (dmc-v2-protocol.txt "Message Format"), sessions run through
// the conformance host so that every stream rule of the catalogue is an
// invariant, and replays that allow a device's own IDs and the position
// tolerance.
#include <map>
#include <optional>

#include "conformance/protocols/dmc/dmc_host.h"
#include "conformance/protocols/dmc/dmc_protocol.h"
#include "conformance/protocols/dmc/dmc_timing.h"
#include "wire/dmc.h"
#include "wire/dmc_frame.h"

namespace moco::conformance {
namespace {

// The frame's ID, Type and data section when `m` starts with a whole DMC header.
bool DmcParts(const wire::Bytes& m, uint32_t& id, uint16_t& type, wire::Bytes& data) {
  const auto h = dmc::PeekHeader(m);
  if (!h) return false;
  id = h->id;
  type = h->type;
  const size_t have = m.size() - dmc::kHeaderSize;
  // Data runs to the declared length, or to what is there before the check bytes.
  const size_t n =
      std::min<size_t>(h->length, have >= dmc::kCheckSize ? have - dmc::kCheckSize : 0);
  data.assign(m.begin() + dmc::kHeaderSize,
              m.begin() + static_cast<ptrdiff_t>(dmc::kHeaderSize + n));
  return true;
}

void Mutate(MutationSource& s, wire::Bytes& m) {
  uint32_t id = 0;
  uint16_t type = 0;
  wire::Bytes data;
  if (!DmcParts(m, id, type, data)) {
    if (!m.empty()) m[s.Below(m.size())] ^= static_cast<uint8_t>(1u << s.Below(8));
    s.Note("noise-flip");
    return;
  }
  if (s.Chance(15)) {
    // Another message type, so the data meets a different decoder.
    static constexpr uint16_t kTypes[] = {
        0x0001, 0x0020, 0x0021, 0x0022, 0x0023, 0x0030, 0x0031, 0x0032, 0x0033, 0x0034,
        0x0035, 0x0036, 0x0037, 0x0038, 0x0039, 0x003a, 0x0100, 0x0101, 0x0102, 0x0103,
        0x0104, 0x0110, 0x0111, 0x0112, 0x0113, 0x0114, 0x0115, 0x0116, 0x0120, 0x0200,
        0x0201, 0x0202, 0x0203, 0x0204, 0x0205, 0x0206, 0x0207, 0x8001, 0x0400, 0xffff};
    type = kTypes[s.Below(std::size(kTypes))];
    s.Note("type");
  } else {
    s.MutateDataBytes(data);
  }
  m.clear();
  dmc::EncodeFrame(id, type, data, m);
  if (s.Chance(3)) {
    // A wrong checksum on purpose: the device must answer ERR_CHECKSUM.
    m.back() = static_cast<uint8_t>(m.back() ^ 0x5a);
    s.Note("bad-checksum");
  }
}

// A frame the device must answer: marker, header and a Length within the
// receive buffer (ERRATA 1.2: an oversize Length is dropped unanswered, and
// the scan resumes inside it, so it counts as noise).
bool WholeDmcFrame(const wire::Bytes& m) {
  return m.size() >= dmc::kHeaderSize + dmc::kCheckSize && m.size() <= dmc::kMaxFrameSize &&
         m[0] == dmc::kMarker0 && m[1] == dmc::kMarker1 &&
         static_cast<size_t>(m[8] | (m[9] << 8)) + dmc::kHeaderSize + dmc::kCheckSize == m.size();
}

// A frame with a bad checksum whose bytes after its marker hold another 'D'
// 'F': the device rescans from the byte after a rejected candidate's 'D'
// ("Message Format" resync, FACTS), so it may find and answer a frame inside.
bool HidesAFrame(const wire::Bytes& m) {
  if (dmc::DecodeFrame(m).ok()) return false;
  for (size_t i = 1; i + 1 < m.size(); ++i) {
    if (m[i] == dmc::kMarker0 && m[i + 1] == dmc::kMarker1) return true;
  }
  return false;
}

// One run. Whole frames go through the host as requests (renumbered: the ID
// is echo-only, and distinct IDs let every answer be matched); anything else
// is noise. A stream with noise or cut frames may legitimately leave a frame
// swallowed or pending, so only the framing rules and liveness judge it.
class DmcPlay final : public FuzzPlay {
 public:
  void Play(Target& target, const wire::Bytes& m) override {
    DmcHost& host = Host(target);
    if (m.empty()) {  // a pause: what the device sends meanwhile is read
      host.Idle(dmc_cases::kFuzzPauseNs);
      return;
    }
    strict_ = strict_ && WholeDmcFrame(m) && !HidesAFrame(m);
    ++messages_;
    if (WholeDmcFrame(m)) {
      const uint16_t type = static_cast<uint16_t>(m[6] | (m[7] << 8));
      const bool good = dmc::DecodeFrame(m).ok();
      const uint32_t id =
          host.SendFrame(type, wire::ByteView(m).subspan(dmc::kHeaderSize, m.size() - 12), !good);
      // A frame with the ACK flag is the host's acknowledgement, not a
      // request: nothing answers it ("MSG_FLAG_ACK"), even when damaged. A
      // damaged frame whose Type no request has (bits outside 0x83FF) is a
      // false "DF" to the device, dropped unanswered (PlausibleRequestHeader).
      if (dmc::PlausibleRequestHeader(type) || (good && (type & dmc::kFlagAck) == 0)) {
        ids_.push_back(id);
      }
    } else {
      host.SendNoise(m);
    }
    host.Idle(dmc_cases::kFuzzGapNs);
  }

  FuzzVerdict Finish(Target& target) override;

 private:
  DmcHost& Host(Target& target) {
    if (!host_) {
      HostOptions options;
      options.quiet_ns = dmc_cases::kFuzzQuietNs;
      host_.emplace(target, verdicts_, options);
    }
    return *host_;
  }

  Verdicts verdicts_;
  std::optional<DmcHost> host_;  // made at the first message (it holds the target)
  bool strict_ = true;           // every message so far a whole frame hiding no other
  std::vector<uint32_t> ids_;    // the requests sent
  size_t messages_ = 0;
};

FuzzVerdict DmcPlay::Finish(Target& target) {
  DmcHost& host = Host(target);
  if (!strict_) {
    // Complete whatever candidate frame the noise opened (its data is zeros,
    // so its check fails and the device resynchronises) before asking again.
    host.SendNoise(wire::Bytes(dmc::kMaxFrameSize, 0));
    host.Idle(dmc_cases::kFuzzGapNs);
  }
  // Every request answered (DMC-ACK-001); in a noisy stream one may be swallowed.
  if (strict_) {
    for (uint32_t id : ids_) host.Await(id);
  }
  const uint32_t hi_id = host.Send(dmc::HiRequest{});
  const DmcRecord* hi = host.Await(hi_id);
  host.Close();
  const size_t replies = host.records().size();
  if (hi == nullptr || As<dmc::HiResponse>(hi) == nullptr) {
    return Violation(
        "liveness: the device did not answer MSG_HI after the session (got " + Show(hi) + ")",
        messages_, replies);
  }
  // A noisy stream is judged by the framing rules alone.
  const std::string judged = strict_ ? std::string() : std::string("DMC-FRAME-*,DMC-CSUM-*");
  for (const auto& [id, o] : verdicts_.outcomes()) {
    const Rule* r = FindRule(id);
    if (o.status != Status::kFail || r == nullptr || r->level != Level::kMust) continue;
    if (!judged.empty() && !GlobMatch(judged, id)) continue;
    std::string what = id + " " + std::string(r->title);
    if (!o.evidence.empty()) {
      const Evidence& e = o.evidence.front();
      what += ": expected " + e.expected + ", observed " + e.observed;
      if (!e.hex.empty()) what += " [" + e.hex + "]";
    }
    return Violation(what, messages_, replies);
  }
  return Passed(messages_, replies);
}

// Answers carry their request's ID; unsolicited messages carry the device's
// own ("Message Format"), so only an answer's ID must agree. Position reports
// agree within the position tolerance.
class Matcher final : public ReplayMatcher {
 public:
  void HostSent(wire::ByteView bytes, TimeNs t_ns) override {
    for (const wire::Bytes& m : wire::SplitMessages(Protocol::kDmc, wire::Side::kHost, bytes)) {
      if (const auto h = dmc::PeekHeader(m)) host_ids_.emplace(h->id, t_ns);
    }
  }

  bool Match(const wire::Bytes& e, const wire::Bytes& o, TimeNs t_ns, int64_t tol,
             std::string& why) override {
    auto fe = dmc::DecodeFrame(e);
    auto fo = dmc::DecodeFrame(o);
    if (!fe.ok() || !fo.ok()) {
      why = "the bytes differ and one of the frames does not decode";
      return false;
    }
    const dmc::Frame& a = fe.value();
    const dmc::Frame& b = fo.value();
    if (a.type != b.type) {
      why = "a different message type";
      return false;
    }
    // An answer: its ID is one the host had sent by then.
    const auto sent = host_ids_.find(a.id);
    if (a.id != b.id && sent != host_ids_.end() && sent->second <= t_ns) {
      why = "the ID of an answer differs (an answer carries its request's ID)";
      return false;
    }
    if (a.data == b.data) return true;
    auto ma = dmc::DecodeDeviceMessage(a);
    auto mb = dmc::DecodeDeviceMessage(b);
    if (ma.ok() && mb.ok()) {
      const auto* pa = std::get_if<dmc::MotorPositionReport>(&ma.value());
      const auto* pb = std::get_if<dmc::MotorPositionReport>(&mb.value());
      if (pa != nullptr && pb != nullptr && pa->move_time_x1000 == pb->move_time_x1000 &&
          pa->positions_steps.size() == pb->positions_steps.size()) {
        for (size_t i = 0; i < pa->positions_steps.size(); ++i) {
          const int64_t d = static_cast<int64_t>(pa->positions_steps[i]) - pb->positions_steps[i];
          if (std::llabs(d) > tol) {
            why = "motor " + std::to_string(i + 1) + " is " + std::to_string(d) +
                  " steps off (tolerance " + std::to_string(tol) + ")";
            return false;
          }
        }
        return true;
      }
    }
    why = "the data differ";
    return false;
  }

 private:
  std::map<uint32_t, TimeNs> host_ids_;  // ID -> when first sent (recorded time)
};

const FuzzHooks kHooks[] = {{
    .protocol = Protocol::kDmc,
    .gap_ns = dmc_cases::kFuzzGapNs,
    .pause_ns = dmc_cases::kFuzzPauseNs,
    .mutate = &Mutate,
    // The pin rules are DFMoco's (no DMC or StackShot firmware runs under simavr).
    .start = [](const wire::Bytes&, const PinJudgeOptions*) -> std::unique_ptr<FuzzPlay> {
      return std::make_unique<DmcPlay>();
    },
    .matcher = []() -> std::unique_ptr<ReplayMatcher> { return std::make_unique<Matcher>(); },
}};

}  // namespace

std::span<const FuzzHooks> DmcProtocol::Fuzz() { return kHooks; }

}  // namespace moco::conformance
