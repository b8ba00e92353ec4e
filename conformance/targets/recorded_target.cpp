// The call log of a run, recorded and played back (recorded_target.h); its
// format and decoder are in call_log.h.
#include "conformance/targets/recorded_target.h"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "conformance/targets/call_log.h"

namespace moco::conformance {

using namespace call_log;  // NOLINT: the format's ops and primitives, used throughout

namespace {

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

}  // namespace

// --- recording ---------------------------------------------------------------------------

RecordingTarget::RecordingTarget(std::unique_ptr<Target> inner) : inner_(std::move(inner)) {
  virtual_clock_ = inner_->VirtualClock();
  can_restart_ = inner_->CanRestart();
  name_ = inner_->Name();
  log_.append(kMagic);
  PutString(log_, name_);
  log_.push_back(virtual_clock_ ? 1 : 0);
  log_.push_back(can_restart_ ? 1 : 0);
}

std::string RecordingTarget::Name() const {
  std::string name = inner_->Name();
  if (name != name_) {
    log_.push_back(kName);
    PutString(log_, name);
    name_ = name;
  }
  return name;
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

DeviceOutputs RecordingTarget::Outputs() const {
  // The runner reads through outputs_, which logs each read.
  OutputReads& reads = outputs_;
  reads.inner = inner_->Outputs();
  const uint8_t bits = static_cast<uint8_t>((reads.inner.dmx != nullptr ? kDmxBit : 0) |
                                            (reads.inner.gio != nullptr ? kGioBit : 0) |
                                            (reads.inner.camera != nullptr ? kCameraBit : 0));
  log_.push_back(kOutputs);
  log_.push_back(static_cast<char>(bits));
  return DeviceOutputs::Through(reads, (bits & kDmxBit) != 0, (bits & kGioBit) != 0,
                                (bits & kCameraBit) != 0);
}

int RecordingTarget::OutputReads::Value(int channel) const {
  const int v = inner.dmx->Value(channel);
  t_.log_.push_back(kDmxValue);
  PutSigned(t_.log_, channel);
  PutSigned(t_.log_, v);
  return v;
}

uint32_t RecordingTarget::OutputReads::outputs() const {
  const uint32_t v = inner.gio->outputs();
  t_.log_.push_back(kGioOutputs);
  PutVarint(t_.log_, v);
  return v;
}

std::vector<sim::CameraPort::Edge> RecordingTarget::OutputReads::Trace() const {
  std::vector<sim::CameraPort::Edge> v = inner.camera->Trace();
  t_.log_.push_back(kCameraTrace);
  PutVarint(t_.log_, v.size());
  TimeNs prev = 0;
  for (const sim::CameraPort::Edge& e : v) {
    PutSigned(t_.log_, Minus(e.time_ns, prev));
    t_.log_.push_back(static_cast<char>((e.line & 0x7F) | (e.level ? 0x80 : 0)));
    prev = e.time_ns;
  }
  return v;
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
    log_.push_back(kPinsNone);
    return t;
  }
  // The edges new since the last read; all of them after a restart (or when
  // the trace shrank: the target began a new one).
  bool full = pins_logged_.size() != t->signals.size();
  for (size_t i = 0; !full && i < t->signals.size(); ++i) {
    full = t->signals[i].edges.size() < pins_logged_[i];
  }
  if (full) pins_logged_.assign(t->signals.size(), 0);
  log_.push_back(full ? kPinsAllWithFrequency : kPinsSince);
  PutVarint(log_, t->signals.size());
  if (full) PutVarint(log_, t->frequency_hz);
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
  const size_t magic = MagicLength(log);
  if (magic == 0) {
    *error = NotALog();
    return nullptr;
  }
  std::unique_ptr<PlaybackTarget> t(new PlaybackTarget());
  t->log_ = std::move(log);
  t->at_ = magic;
  t->entry_ = std::make_unique<LogEntry>();
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

PlaybackTarget::~PlaybackTarget() = default;

void PlaybackTarget::Diverge(std::string what) const {
  if (!divergence_.empty()) return;
  divergence_ = "call " + std::to_string(calls_) + ": " + std::move(what);
  at_ = log_.size();
}

void PlaybackTarget::TakeNames() const {
  while (divergence_.empty() && at_ < log_.size() && static_cast<uint8_t>(log_[at_]) == kName) {
    Reader r(log_, at_);
    if (!DecodeEntry(r, *entry_)) {
      Diverge("the call log is cut short or damaged");
      return;
    }
    name_ = std::string(entry_->bytes);
  }
}

const LogEntry* PlaybackTarget::Next(uint8_t op) const {
  TakeNames();
  if (!divergence_.empty()) return nullptr;
  ++calls_;
  if (at_ >= log_.size()) {
    Diverge(std::string("the run ") + OpName(op) + " after the recorded run's last call");
    return nullptr;
  }
  const uint8_t recorded = static_cast<uint8_t>(log_[at_]);
  if (recorded != op) {
    Diverge(std::string("the run ") + OpName(op) + " where the recorded run " + OpName(recorded));
    return nullptr;
  }
  Reader r(log_, at_);
  if (!DecodeEntry(r, *entry_)) {
    Diverge("the call log is cut short or damaged");
    return nullptr;
  }
  return entry_.get();
}

std::string PlaybackTarget::Name() const {
  TakeNames();
  return name_;
}

std::optional<std::string> PlaybackTarget::Open() {
  const LogEntry* e = Next(kOpen);
  if (e == nullptr) return "the recorded run " + divergence_;
  return e->text;
}

void PlaybackTarget::Restart() {
  if (Next(kRestart) == nullptr) return;
  if (board_) pins_ = PinTrace::For(*board_);
}

TimeNs PlaybackTarget::Now() const {
  const LogEntry* e = Next(kNow);
  if (e == nullptr) return last_now_;
  last_now_ = Plus(last_now_, e->num);
  return last_now_;
}

bool PlaybackTarget::Send(wire::ByteView bytes) {
  const std::string_view sent(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  const LogEntry* e = Next(kSend);
  if (e == nullptr) return false;
  if (e->bytes != sent) {
    Diverge("the run sent " + Shown(sent) + " where the recorded run sent " + Shown(e->bytes));
    return false;
  }
  return e->ok;
}

bool PlaybackTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  const LogEntry* e = Next(kReceive);
  if (e == nullptr) return false;
  const TimeNs recorded_deadline = Plus(last_now_, e->num);
  if (recorded_deadline != deadline_ns) {
    Diverge("the run waited until " + std::to_string(deadline_ns) +
            " ns where the recorded run waited until " + std::to_string(recorded_deadline) + " ns");
    return false;
  }
  out.insert(out.end(), e->bytes.begin(), e->bytes.end());
  return e->ok;
}

bool PlaybackTarget::SetEStop(bool engaged) {
  const LogEntry* e = Next(kSetEStop);
  if (e == nullptr) return false;
  if ((e->flags != 0) != engaged)
    Diverge("the e-stop was set another way than in the recorded run");
  return e->ok;
}

bool PlaybackTarget::SetLimitInput(int set, bool high, bool active) {
  const LogEntry* e = Next(kSetLimit);
  if (e == nullptr) return false;
  if (e->num != set || e->flags != ((high ? 1 : 0) | (active ? 2 : 0))) {
    Diverge("another limit input was set than in the recorded run");
  }
  return e->ok;
}

bool PlaybackTarget::SetGioInput(int bit, bool level) {
  const LogEntry* e = Next(kSetGio);
  if (e == nullptr) return false;
  if (e->num != bit || (e->flags != 0) != level) {
    Diverge("another I/O input was set than in the recorded run");
  }
  return e->ok;
}

bool PlaybackTarget::CanPressButton(std::string_view button) const {
  const LogEntry* e = Next(kCanPress);
  if (e == nullptr) return false;
  if (e->bytes != button) Diverge("the run asked for another button than the recorded run");
  return e->ok;
}

bool PlaybackTarget::PressButton(std::string_view button) {
  const LogEntry* e = Next(kPress);
  if (e == nullptr) return false;
  if (e->bytes != button) Diverge("the run pressed another button than the recorded run");
  return e->ok;
}

DeviceOutputs PlaybackTarget::Outputs() const {
  const LogEntry* e = Next(kOutputs);
  if (e == nullptr) return {};
  return DeviceOutputs::Through(outputs_, (e->flags & kDmxBit) != 0, (e->flags & kGioBit) != 0,
                                (e->flags & kCameraBit) != 0);
}

int PlaybackTarget::OutputReads::Value(int channel) const {
  const LogEntry* e = t_.Next(kDmxValue);
  if (e == nullptr) return 0;
  if (e->num != channel) {
    t_.Diverge("the run read DMX channel " + std::to_string(channel) +
               " where the recorded run read channel " + std::to_string(e->num));
    return 0;
  }
  return static_cast<int>(std::clamp<int64_t>(e->value, 0, 255));
}

uint32_t PlaybackTarget::OutputReads::outputs() const {
  const LogEntry* e = t_.Next(kGioOutputs);
  return e == nullptr ? 0 : static_cast<uint32_t>(e->num);
}

std::vector<sim::CameraPort::Edge> PlaybackTarget::OutputReads::Trace() const {
  const LogEntry* e = t_.Next(kCameraTrace);
  return e == nullptr ? std::vector<sim::CameraPort::Edge>{} : e->camera;
}

std::optional<std::string> PlaybackTarget::LinkLost() const {
  const LogEntry* e = Next(kLinkLost);
  if (e == nullptr) {
    return "the certificate's traffic does not fit the installed rules: " + divergence_;
  }
  return e->text;
}

std::optional<std::string> PlaybackTarget::FirmwareStopped() const {
  const LogEntry* e = Next(kFirmwareStopped);
  return e == nullptr ? std::nullopt : e->text;
}

std::optional<FirmwareFault> PlaybackTarget::FirmwareFaulted() const {
  const LogEntry* e = Next(kFirmwareFaulted);
  if (e == nullptr || !e->ok) return std::nullopt;
  FirmwareFault f;
  f.kind = static_cast<FirmwareFaultKind>(
      std::min<uint8_t>(e->flags, static_cast<uint8_t>(FirmwareFaultKind::kReset)));
  f.what = std::string(e->bytes);
  f.backtrace = e->texts;
  return f;
}

std::vector<std::string> PlaybackTarget::FirmwareBacktrace() const {
  const LogEntry* e = Next(kBacktrace);
  return e == nullptr ? std::vector<std::string>{} : e->texts;
}

std::optional<std::string> PlaybackTarget::WatchPins(const Board& board) {
  board_ = board;
  pins_ = PinTrace::For(board);
  return std::nullopt;
}

const PinTrace* PlaybackTarget::Pins() const {
  const LogEntry* e = Next(kPins);
  if (e == nullptr || e->flags == kPinsNone) return nullptr;
  if (!pins_) {
    Diverge("the recorded run watched pins, and no board was given to watch them with");
    return nullptr;
  }
  if (e->pins.size() != pins_->signals.size()) {
    Diverge("the recorded run watched " + std::to_string(e->pins.size()) +
            " pins, the board names " + std::to_string(pins_->signals.size()));
    return nullptr;
  }
  const bool all = e->flags != kPinsSince;
  if (e->flags == kPinsAllWithFrequency) {
    pins_->frequency_hz = static_cast<uint32_t>(e->frequency_hz);
  }
  for (size_t i = 0; i < e->pins.size(); ++i) {
    PinSignal& s = pins_->signals[i];
    if (all) {
      s.edges.clear();
      s.initial = e->pins[i].initial;
    }
    TimeNs prev = s.edges.empty() ? 0 : s.edges.back().t_ns;
    for (const LogEntry::PinEdgeDelta& d : e->pins[i].edges) {
      PinEdge edge;
      edge.t_ns = Plus(prev, d.dt_ns);
      edge.cycle = d.cycle;
      edge.level = d.level;
      s.edges.push_back(edge);
      prev = edge.t_ns;
    }
  }
  pins_->complete_until_ns = e->num;
  return &*pins_;
}

std::vector<std::string> PlaybackTarget::Caveats() const {
  const LogEntry* e = Next(kCaveats);
  return e == nullptr ? std::vector<std::string>{} : e->texts;
}

// --- reading a log without a runner ------------------------------------------------------

namespace {

// Walks every entry of `log`, calling `chunk` for traffic; false when the log
// is damaged (`error` says where).
template <typename OnChunk>
bool WalkLog(std::string_view log, CallLogSummary& sum, std::string* error, OnChunk&& chunk) {
  size_t at = MagicLength(log);
  if (at == 0) {
    *error = NotALog();
    return false;
  }
  Reader r(log, at);
  sum.target = std::string(r.String());
  sum.virtual_clock = r.Byte() != 0;
  sum.can_restart = r.Byte() != 0;
  TimeNs now = 0;
  LogEntry e;
  while (r.ok() && !r.AtEnd()) {
    const size_t entry_at = at;
    if (!DecodeEntry(r, e)) {
      *error =
          r.ok() ? "unknown entry " + std::to_string(e.op) + " at byte " + std::to_string(entry_at)
                 : "the call log is cut short or damaged";
      return false;
    }
    switch (e.op) {
      case kName:
        sum.target = std::string(e.bytes);
        continue;  // not a call
      case kNow:
        now = Plus(now, e.num);
        break;
      case kSend:
        sum.host_bytes += e.bytes.size();
        chunk(LoggedChunk{now, true, false, std::string(e.bytes)});
        break;
      case kReceive:
        sum.device_bytes += e.bytes.size();
        if (!e.bytes.empty()) chunk(LoggedChunk{now, false, false, std::string(e.bytes)});
        break;
      case kRestart:
        ++sum.restarts;
        chunk(LoggedChunk{now, true, true, {}});
        break;
      default:
        break;
    }
    ++sum.calls;
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
