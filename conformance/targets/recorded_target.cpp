// The call log of a run (recorded_target.h). Format: "MOCOLOG1", the target's
// name (a string), its clock and restart ability (one byte each), then one
// entry per call: an op byte and its arguments and result. Integers are
// LEB128 varints, signed ones zigzag-coded; times are deltas from the clock
// value last logged; strings are a varint length and the bytes.
#include "conformance/targets/recorded_target.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace moco::conformance {
namespace {

constexpr std::string_view kMagic = "MOCOLOG1";

enum Op : uint8_t {
  kNow = 1,
  kSend = 2,
  kReceive = 3,
  kRestart = 4,
  kOpen = 5,
  kSetEStop = 6,
  kSetLimit = 7,
  kSetGio = 8,
  kCanPress = 9,
  kPress = 10,
  kLinkLost = 11,
  kFirmwareStopped = 12,
  kFirmwareFaulted = 13,
  kBacktrace = 14,
  kPins = 15,
  kCaveats = 16,
};

const char* OpName(uint8_t op) {
  switch (op) {
    case kNow:
      return "read the clock";
    case kSend:
      return "sent bytes";
    case kReceive:
      return "waited for bytes";
    case kRestart:
      return "restarted the device";
    case kOpen:
      return "opened the device";
    case kSetEStop:
      return "set the e-stop";
    case kSetLimit:
      return "set a limit input";
    case kSetGio:
      return "set an I/O input";
    case kCanPress:
      return "asked for a button";
    case kPress:
      return "pressed a button";
    case kLinkLost:
      return "asked whether the link was lost";
    case kFirmwareStopped:
    case kFirmwareFaulted:
    case kBacktrace:
      return "asked whether the firmware stopped";
    case kPins:
      return "read the pins";
    case kCaveats:
      return "asked for the target's caveats";
    default:
      return "made an unknown call";
  }
}

void PutVarint(std::string& s, uint64_t v) {
  while (v >= 0x80) {
    s.push_back(static_cast<char>((v & 0x7F) | 0x80));
    v >>= 7;
  }
  s.push_back(static_cast<char>(v));
}
void PutSigned(std::string& s, int64_t v) {
  PutVarint(s, (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63));
}
void PutString(std::string& s, std::string_view v) {
  PutVarint(s, v.size());
  s.append(v);
}
void PutOptional(std::string& s, const std::optional<std::string>& v) {
  s.push_back(v ? 1 : 0);
  if (v) PutString(s, *v);
}
void PutStrings(std::string& s, const std::vector<std::string>& v) {
  PutVarint(s, v.size());
  for (const std::string& one : v) PutString(s, one);
}

// a + b, wrapping: a crafted log's deltas never overflow (and never make the
// sanitizers stop verify).
TimeNs Plus(TimeNs a, int64_t b) {
  return static_cast<TimeNs>(static_cast<uint64_t>(a) + static_cast<uint64_t>(b));
}
int64_t Minus(TimeNs a, TimeNs b) {
  return static_cast<int64_t>(static_cast<uint64_t>(a) - static_cast<uint64_t>(b));
}

// "3 bytes: 68 69 0d" (at most the first 24 bytes shown).
std::string Shown(std::string_view bytes) {
  std::string s = std::to_string(bytes.size()) + (bytes.size() == 1 ? " byte" : " bytes");
  if (!bytes.empty()) s += ":";
  for (size_t i = 0; i < bytes.size() && i < 24; ++i) {
    char hex[4];
    std::snprintf(hex, sizeof hex, " %02x", static_cast<unsigned char>(bytes[i]));
    s += hex;
  }
  if (bytes.size() > 24) s += " ...";
  return s;
}

// Reads entries from a log; every read is bounds-checked, and a damaged log
// leaves ok() false (reads then give zeros and empty strings).
class Reader {
 public:
  Reader(std::string_view log, size_t& at) : log_(log), at_(at) {}
  bool ok() const { return ok_; }
  bool AtEnd() const { return at_ >= log_.size(); }
  uint8_t Byte() {
    if (at_ >= log_.size()) return Bad();
    return static_cast<uint8_t>(log_[at_++]);
  }
  uint64_t Varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      const uint8_t b = Byte();
      if (!ok_) return 0;
      v |= static_cast<uint64_t>(b & 0x7F) << shift;
      if ((b & 0x80) == 0) return v;
    }
    return Bad();
  }
  int64_t Signed() {
    const uint64_t z = Varint();
    return static_cast<int64_t>((z >> 1) ^ (~(z & 1) + 1));
  }
  std::string_view String() {
    const uint64_t n = Varint();
    if (!ok_ || n > log_.size() - at_) {
      Bad();
      return {};
    }
    const std::string_view v = log_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::optional<std::string> Optional() {
    if (Byte() == 0) return std::nullopt;
    return std::string(String());
  }
  std::vector<std::string> Strings() {
    const uint64_t n = Varint();
    std::vector<std::string> v;
    for (uint64_t i = 0; i < n && ok_; ++i) v.emplace_back(String());
    return v;
  }

 private:
  uint8_t Bad() {
    ok_ = false;
    at_ = log_.size();
    return 0;
  }
  std::string_view log_;
  size_t& at_;
  bool ok_ = true;
};

}  // namespace

// --- recording ---------------------------------------------------------------------------

RecordingTarget::RecordingTarget(std::unique_ptr<Target> inner) : inner_(std::move(inner)) {
  virtual_clock_ = inner_->VirtualClock();
  can_restart_ = inner_->CanRestart();
  log_.append(kMagic);
  PutString(log_, inner_->Name());
  log_.push_back(virtual_clock_ ? 1 : 0);
  log_.push_back(can_restart_ ? 1 : 0);
}

std::optional<std::string> RecordingTarget::Open() {
  auto r = inner_->Open();
  log_.push_back(kOpen);
  PutOptional(log_, r);
  return r;
}

void RecordingTarget::Restart() {
  inner_->Restart();
  log_.push_back(kRestart);
  pins_logged_.clear();
}

TimeNs RecordingTarget::Now() const {
  const TimeNs t = inner_->Now();
  log_.push_back(kNow);
  PutSigned(log_, Minus(t, last_now_));
  last_now_ = t;
  return t;
}

bool RecordingTarget::Send(wire::ByteView bytes) {
  const bool r = inner_->Send(bytes);
  log_.push_back(kSend);
  PutString(log_, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  log_.push_back(r ? 1 : 0);
  return r;
}

bool RecordingTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  const size_t before = out.size();
  const bool r = inner_->Receive(deadline_ns, out);
  log_.push_back(kReceive);
  PutSigned(log_, Minus(deadline_ns, last_now_));
  log_.push_back(r ? 1 : 0);
  PutString(log_, std::string_view(reinterpret_cast<const char*>(out.data()) + before,
                                   out.size() - before));
  return r;
}

bool RecordingTarget::SetEStop(bool engaged) {
  const bool r = inner_->SetEStop(engaged);
  log_.push_back(kSetEStop);
  log_.push_back(engaged ? 1 : 0);
  log_.push_back(r ? 1 : 0);
  return r;
}

bool RecordingTarget::SetLimitInput(int set, bool high, bool active) {
  const bool r = inner_->SetLimitInput(set, high, active);
  log_.push_back(kSetLimit);
  PutSigned(log_, set);
  log_.push_back(static_cast<char>((high ? 1 : 0) | (active ? 2 : 0)));
  log_.push_back(r ? 1 : 0);
  return r;
}

bool RecordingTarget::SetGioInput(int bit, bool level) {
  const bool r = inner_->SetGioInput(bit, level);
  log_.push_back(kSetGio);
  PutSigned(log_, bit);
  log_.push_back(level ? 1 : 0);
  log_.push_back(r ? 1 : 0);
  return r;
}

bool RecordingTarget::CanPressButton(std::string_view button) const {
  const bool r = inner_->CanPressButton(button);
  log_.push_back(kCanPress);
  PutString(log_, button);
  log_.push_back(r ? 1 : 0);
  return r;
}

bool RecordingTarget::PressButton(std::string_view button) {
  const bool r = inner_->PressButton(button);
  log_.push_back(kPress);
  PutString(log_, button);
  log_.push_back(r ? 1 : 0);
  return r;
}

std::optional<std::string> RecordingTarget::LinkLost() const {
  auto r = inner_->LinkLost();
  log_.push_back(kLinkLost);
  PutOptional(log_, r);
  return r;
}

std::optional<std::string> RecordingTarget::FirmwareStopped() const {
  auto r = inner_->FirmwareStopped();
  log_.push_back(kFirmwareStopped);
  PutOptional(log_, r);
  return r;
}

std::optional<FirmwareFault> RecordingTarget::FirmwareFaulted() const {
  auto r = inner_->FirmwareFaulted();
  log_.push_back(kFirmwareFaulted);
  log_.push_back(r ? 1 : 0);
  if (r) {
    log_.push_back(static_cast<char>(r->kind));
    PutString(log_, r->what);
    PutStrings(log_, r->backtrace);
  }
  return r;
}

std::vector<std::string> RecordingTarget::FirmwareBacktrace() const {
  auto r = inner_->FirmwareBacktrace();
  log_.push_back(kBacktrace);
  PutStrings(log_, r);
  return r;
}

const PinTrace* RecordingTarget::Pins() const {
  const PinTrace* t = inner_->Pins();
  log_.push_back(kPins);
  if (t == nullptr) {
    log_.push_back(0);
    return t;
  }
  // The edges new since the last read; all of them after a restart (or when
  // the trace shrank: the target began a new one).
  bool full = pins_logged_.size() != t->signals.size();
  for (size_t i = 0; !full && i < t->signals.size(); ++i) {
    full = t->signals[i].edges.size() < pins_logged_[i];
  }
  if (full) pins_logged_.assign(t->signals.size(), 0);
  log_.push_back(full ? 2 : 1);
  PutVarint(log_, t->signals.size());
  for (size_t i = 0; i < t->signals.size(); ++i) {
    const PinSignal& s = t->signals[i];
    if (full) log_.push_back(s.initial ? 1 : 0);
    PutVarint(log_, s.edges.size() - pins_logged_[i]);
    TimeNs prev = pins_logged_[i] == 0 ? 0 : s.edges[pins_logged_[i] - 1].t_ns;
    for (size_t k = pins_logged_[i]; k < s.edges.size(); ++k) {
      PutSigned(log_, Minus(s.edges[k].t_ns, prev));
      PutVarint(log_, s.edges[k].cycle);
      log_.push_back(s.edges[k].level ? 1 : 0);
      prev = s.edges[k].t_ns;
    }
    pins_logged_[i] = s.edges.size();
  }
  PutSigned(log_, t->complete_until_ns);
  return t;
}

std::vector<std::string> RecordingTarget::Caveats() const {
  auto r = inner_->Caveats();
  log_.push_back(kCaveats);
  PutStrings(log_, r);
  return r;
}

// --- playback ----------------------------------------------------------------------------

std::unique_ptr<PlaybackTarget> PlaybackTarget::FromLog(std::string log, std::string* error) {
  if (log.compare(0, kMagic.size(), kMagic) != 0) {
    *error = "not a call log (it does not start with " + std::string(kMagic) + ")";
    return nullptr;
  }
  std::unique_ptr<PlaybackTarget> t(new PlaybackTarget());
  t->log_ = std::move(log);
  t->at_ = kMagic.size();
  Reader r(t->log_, t->at_);
  t->name_ = std::string(r.String());
  t->virtual_clock_ = r.Byte() != 0;
  t->can_restart_ = r.Byte() != 0;
  if (!r.ok()) {
    *error = "the call log's header is cut short";
    return nullptr;
  }
  return t;
}

void PlaybackTarget::Diverge(std::string what) const {
  if (!divergence_.empty()) return;
  divergence_ = "call " + std::to_string(calls_) + ": " + std::move(what);
  at_ = log_.size();
}

bool PlaybackTarget::Expect(uint8_t op, const char* what) const {
  if (!divergence_.empty()) return false;
  ++calls_;
  if (at_ >= log_.size()) {
    Diverge(std::string("the run ") + what + " after the recorded run's last call");
    return false;
  }
  const uint8_t recorded = static_cast<uint8_t>(log_[at_]);
  if (recorded != op) {
    Diverge(std::string("the run ") + what + " where the recorded run " + OpName(recorded));
    return false;
  }
  ++at_;
  return true;
}

std::optional<std::string> PlaybackTarget::Open() {
  if (!Expect(kOpen, OpName(kOpen))) return "the recorded run " + divergence_;
  Reader r(log_, at_);
  auto v = r.Optional();
  if (!r.ok()) Diverge("the call log is cut short");
  return v;
}

void PlaybackTarget::Restart() {
  if (!Expect(kRestart, OpName(kRestart))) return;
  if (board_) pins_ = PinTrace::For(*board_);
}

TimeNs PlaybackTarget::Now() const {
  if (!Expect(kNow, OpName(kNow))) return last_now_;
  Reader r(log_, at_);
  last_now_ = Plus(last_now_, r.Signed());
  if (!r.ok()) Diverge("the call log is cut short");
  return last_now_;
}

bool PlaybackTarget::Send(wire::ByteView bytes) {
  const std::string_view sent(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  const size_t entry = at_;
  if (!Expect(kSend, OpName(kSend))) return false;
  Reader r(log_, at_);
  const std::string_view recorded = r.String();
  const bool result = r.Byte() != 0;
  if (!r.ok()) {
    Diverge("the call log is cut short");
    return false;
  }
  if (recorded != sent) {
    at_ = entry;
    Diverge("the run sent " + Shown(sent) + " where the recorded run sent " + Shown(recorded));
    return false;
  }
  return result;
}

bool PlaybackTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  if (!Expect(kReceive, OpName(kReceive))) return false;
  Reader r(log_, at_);
  const TimeNs recorded_deadline = Plus(last_now_, r.Signed());
  const bool result = r.Byte() != 0;
  const std::string_view bytes = r.String();
  if (!r.ok()) {
    Diverge("the call log is cut short");
    return false;
  }
  if (recorded_deadline != deadline_ns) {
    Diverge("the run waited until " + std::to_string(deadline_ns) +
            " ns where the recorded run waited until " + std::to_string(recorded_deadline) + " ns");
    return false;
  }
  out.insert(out.end(), bytes.begin(), bytes.end());
  return result;
}

bool PlaybackTarget::SetEStop(bool engaged) {
  if (!Expect(kSetEStop, OpName(kSetEStop))) return false;
  Reader r(log_, at_);
  const bool arg = r.Byte() != 0;
  const bool result = r.Byte() != 0;
  if (arg != engaged) Diverge("the e-stop was set another way than in the recorded run");
  return r.ok() && result;
}

bool PlaybackTarget::SetLimitInput(int set, bool high, bool active) {
  if (!Expect(kSetLimit, OpName(kSetLimit))) return false;
  Reader r(log_, at_);
  const int64_t rec_set = r.Signed();
  const uint8_t flags = r.Byte();
  const bool result = r.Byte() != 0;
  if (rec_set != set || flags != ((high ? 1 : 0) | (active ? 2 : 0))) {
    Diverge("another limit input was set than in the recorded run");
  }
  return r.ok() && result;
}

bool PlaybackTarget::SetGioInput(int bit, bool level) {
  if (!Expect(kSetGio, OpName(kSetGio))) return false;
  Reader r(log_, at_);
  const int64_t rec_bit = r.Signed();
  const bool rec_level = r.Byte() != 0;
  const bool result = r.Byte() != 0;
  if (rec_bit != bit || rec_level != level) {
    Diverge("another I/O input was set than in the recorded run");
  }
  return r.ok() && result;
}

bool PlaybackTarget::CanPressButton(std::string_view button) const {
  if (!Expect(kCanPress, OpName(kCanPress))) return false;
  Reader r(log_, at_);
  const std::string_view rec = r.String();
  const bool result = r.Byte() != 0;
  if (rec != button) Diverge("the run asked for another button than the recorded run");
  return r.ok() && result;
}

bool PlaybackTarget::PressButton(std::string_view button) {
  if (!Expect(kPress, OpName(kPress))) return false;
  Reader r(log_, at_);
  const std::string_view rec = r.String();
  const bool result = r.Byte() != 0;
  if (rec != button) Diverge("the run pressed another button than the recorded run");
  return r.ok() && result;
}

std::optional<std::string> PlaybackTarget::LinkLost() const {
  if (!Expect(kLinkLost, OpName(kLinkLost))) {
    return "the certificate's traffic does not fit the installed rules: " + divergence_;
  }
  Reader r(log_, at_);
  auto v = r.Optional();
  if (!r.ok()) Diverge("the call log is cut short");
  return v;
}

std::optional<std::string> PlaybackTarget::FirmwareStopped() const {
  if (!Expect(kFirmwareStopped, OpName(kFirmwareStopped))) return std::nullopt;
  Reader r(log_, at_);
  return r.Optional();
}

std::optional<FirmwareFault> PlaybackTarget::FirmwareFaulted() const {
  if (!Expect(kFirmwareFaulted, OpName(kFirmwareFaulted))) return std::nullopt;
  Reader r(log_, at_);
  if (r.Byte() == 0) return std::nullopt;
  FirmwareFault f;
  f.kind = static_cast<FirmwareFaultKind>(
      std::min<uint8_t>(r.Byte(), static_cast<uint8_t>(FirmwareFaultKind::kReset)));
  f.what = std::string(r.String());
  f.backtrace = r.Strings();
  if (!r.ok()) Diverge("the call log is cut short");
  return f;
}

std::vector<std::string> PlaybackTarget::FirmwareBacktrace() const {
  if (!Expect(kBacktrace, OpName(kBacktrace))) return {};
  Reader r(log_, at_);
  return r.Strings();
}

std::optional<std::string> PlaybackTarget::WatchPins(const Board& board) {
  board_ = board;
  pins_ = PinTrace::For(board);
  return std::nullopt;
}

const PinTrace* PlaybackTarget::Pins() const {
  if (!Expect(kPins, OpName(kPins))) return nullptr;
  Reader r(log_, at_);
  const uint8_t kind = r.Byte();
  if (kind == 0) return nullptr;
  if (!pins_) {
    Diverge("the recorded run watched pins, and no board was given to watch them with");
    return nullptr;
  }
  const uint64_t n = r.Varint();
  if (n != pins_->signals.size()) {
    Diverge("the recorded run watched " + std::to_string(n) + " pins, the board names " +
            std::to_string(pins_->signals.size()));
    return nullptr;
  }
  for (PinSignal& s : pins_->signals) {
    if (kind == 2) {
      s.edges.clear();
      s.initial = r.Byte() != 0;
    }
    const uint64_t count = r.Varint();
    TimeNs prev = s.edges.empty() ? 0 : s.edges.back().t_ns;
    for (uint64_t k = 0; k < count && r.ok(); ++k) {
      PinEdge e;
      e.t_ns = Plus(prev, r.Signed());
      e.cycle = r.Varint();
      e.level = r.Byte() != 0;
      s.edges.push_back(e);
      prev = e.t_ns;
    }
  }
  pins_->complete_until_ns = r.Signed();
  if (!r.ok()) {
    Diverge("the call log is cut short");
    return nullptr;
  }
  return &*pins_;
}

std::vector<std::string> PlaybackTarget::Caveats() const {
  if (!Expect(kCaveats, OpName(kCaveats))) return {};
  Reader r(log_, at_);
  return r.Strings();
}

// --- reading a log without a runner ------------------------------------------------------

namespace {

// Walks every entry of `log`, calling `chunk` for traffic; false when the log
// is damaged (`error` says where).
template <typename OnChunk>
bool WalkLog(std::string_view log, CallLogSummary& sum, std::string* error, OnChunk&& chunk) {
  if (log.substr(0, kMagic.size()) != kMagic) {
    *error = "not a call log (it does not start with " + std::string(kMagic) + ")";
    return false;
  }
  size_t at = kMagic.size();
  Reader r(log, at);
  sum.target = std::string(r.String());
  sum.virtual_clock = r.Byte() != 0;
  sum.can_restart = r.Byte() != 0;
  TimeNs now = 0;
  while (r.ok() && !r.AtEnd()) {
    const uint8_t op = r.Byte();
    ++sum.calls;
    switch (op) {
      case kNow:
        now = Plus(now, r.Signed());
        break;
      case kSend: {
        const std::string_view b = r.String();
        r.Byte();
        sum.host_bytes += b.size();
        chunk(LoggedChunk{now, true, false, std::string(b)});
        break;
      }
      case kReceive: {
        r.Signed();
        r.Byte();
        const std::string_view b = r.String();
        sum.device_bytes += b.size();
        if (!b.empty()) chunk(LoggedChunk{now, false, false, std::string(b)});
        break;
      }
      case kRestart:
        ++sum.restarts;
        chunk(LoggedChunk{now, true, true, {}});
        break;
      case kOpen:
      case kLinkLost:
      case kFirmwareStopped:
        r.Optional();
        break;
      case kSetEStop:
        r.Byte(), r.Byte();
        break;
      case kSetLimit:
      case kSetGio:
        r.Signed(), r.Byte(), r.Byte();
        break;
      case kCanPress:
      case kPress:
        r.String(), r.Byte();
        break;
      case kFirmwareFaulted:
        if (r.Byte() != 0) r.Byte(), r.String(), r.Strings();
        break;
      case kBacktrace:
      case kCaveats:
        r.Strings();
        break;
      case kPins: {
        const uint8_t kind = r.Byte();
        if (kind == 0) break;
        const uint64_t n = r.Varint();
        for (uint64_t i = 0; i < n && r.ok(); ++i) {
          if (kind == 2) r.Byte();
          const uint64_t count = r.Varint();
          for (uint64_t k = 0; k < count && r.ok(); ++k) r.Signed(), r.Varint(), r.Byte();
        }
        r.Signed();
        break;
      }
      default:
        *error = "unknown entry " + std::to_string(op) + " at byte " + std::to_string(at - 1);
        return false;
    }
    sum.last_ns = now;
  }
  if (!r.ok()) {
    *error = "the call log is cut short or damaged";
    return false;
  }
  return true;
}

}  // namespace

std::optional<CallLogSummary> SummarizeCallLog(std::string_view log, std::string* error) {
  CallLogSummary sum;
  if (!WalkLog(log, sum, error, [](const LoggedChunk&) {})) return std::nullopt;
  return sum;
}

std::vector<LoggedChunk> TrafficOfCallLog(std::string_view log, std::string* error) {
  CallLogSummary sum;
  std::vector<LoggedChunk> out;
  if (!WalkLog(log, sum, error, [&](const LoggedChunk& c) { out.push_back(c); })) return {};
  return out;
}

}  // namespace moco::conformance
