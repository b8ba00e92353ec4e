// The emulated Cognisys StackShot 3X (see stackshot3x.h; stackshot-protocol.txt
// sections 1-3, ERRATA.md part 3, FACTS.md "StackShot").
#include "devices/stackshot3x/stackshot3x.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

#include "wire/protocol.h"
#include "wire/stackshot_timing.h"

namespace moco::devices {
namespace {

using stackshot::Action;
using stackshot::Command;
using stackshot::Units;

constexpr uint16_t Cmd(Command c) { return static_cast<uint16_t>(c); }

std::unique_ptr<sim::Planner> MakeStackshotPlanner() {
  return std::make_unique<sim::StackshotPlanner>();
}

}  // namespace

sim::TimeNs Stackshot3x::SecondsToNs(double s) {
  if (!(s > 0)) return 0;
  // Timers run on whole microseconds (0.1f s is 100000 us, not 100000001 ns).
  return static_cast<sim::TimeNs>(std::llround(s * 1e6)) * sim::kNsPerUs;
}

Stackshot3x::Stackshot3x(sim::Scheduler& scheduler, ByteSink& sink, Stackshot3xProfile profile,
                         StateStore* store)
    : scheduler_(scheduler),
      sink_(sink),
      profile_(std::move(profile)),
      own_store_(store == nullptr ? std::make_unique<MemoryStateStore>() : nullptr),
      store_(store != nullptr ? store : own_store_.get()),
      rig_(scheduler, kAxes, 0, this, &MakeStackshotPlanner),
      decoder_(/*from_device=*/false, profile_.checksum),
      framer_(dfmoco::FramerOptions{dfmoco::LineTermination::kLenient, dfmoco::kMaxLineBytes}),
      dialect_(dfmoco::StackShot3x()),
      config_(Stackshot3xConfig::Defaults(profile_)) {
  dialect_.firmware_version = profile_.dfmoco_version;
  for (int a = 0; a < kAxes; ++a) {
    auto planner = std::make_unique<sim::StackshotPlanner>(config_.axes[Index(a)].ramp_time_s);
    planners_[Index(a)] = planner.get();
    Motor(a).SetPlanner(std::move(planner));
  }
  nvm_.assign(static_cast<size_t>(profile_.nvm_registers), stackshot::kUnprogrammed);
}

Stackshot3x::~Stackshot3x() {
  powered_ = false;
  CancelTimers();
  rig_.SetObserver(nullptr);
}

DeviceLine Stackshot3x::Line() const { return {wire::Info(Speaking()).line, profile_.usb_bridge}; }

wire::Protocol Stackshot3x::Speaking() const {
  return SpeaksDfmoco() ? wire::Protocol::kStackshotDfmoco : wire::Protocol::kStackshot;
}

void Stackshot3x::AnnounceSpeaking() {
  if (Speaking() == announced_) return;
  announced_ = Speaking();
  AnnounceLineSwitch(announced_);
}

bool Stackshot3x::InDfmocoMode() const {
  return config_.global_mode == stackshot::GlobalMode::kMotionDfMoco;
}

// Section 3: "To enable the DfMoco interface (which runs over USB)". Over
// Wi-Fi the unit keeps the binary API of section 4.2 ("The commands are
// identical when sent over WiFi") whatever the mode.
bool Stackshot3x::SpeaksDfmoco() const { return InDfmocoMode() && host_link_ == HostLink::kSerial; }

void Stackshot3x::SetHostLink(HostLink link) {
  if (link == host_link_) return;
  const bool was = SpeaksDfmoco();
  host_link_ = link;
  scheduler_.Cancel(gap_timer_);
  gap_timer_ = sim::Scheduler::kNoTimer;
  if (was != SpeaksDfmoco()) {
    decoder_.Flush();
    framer_.Reset();
  }
  if (powered_) AnnounceSpeaking();
}

// ---------------------------------------------------------------------------
// Lifecycle and NVM

void Stackshot3x::PowerOn() {
  if (powered_) return;
  powered_ = true;
  ++generation_;
  ResetVolatile();
  LoadNvm();
  config_ = slots_[0].value_or(Stackshot3xConfig::Defaults(profile_));
  AddLog("power on");
  // The power-on mode is slot 0's: a unit set to DfMoco mode on its panel
  // powers on speaking DfMoco (stackshot-protocol.txt section 3).
  AnnounceSpeaking();
  if (profile_.boot_delay_ms == 0) {
    Boot();
  } else {
    boot_timer_ = scheduler_.After(profile_.boot_delay_ms * sim::kNsPerMs, [this] {
      boot_timer_ = sim::Scheduler::kNoTimer;
      Boot();
    });
  }
}

void Stackshot3x::Boot() { ready_ = true; }

void Stackshot3x::PowerOff() {
  if (!powered_) return;
  ResetVolatile();
  powered_ = false;
  ready_ = false;
}

void Stackshot3x::CancelTimers() {
  for (sim::Scheduler::TimerId* t : {&busy_timer_, &gap_timer_, &boot_timer_, &stack_.timer}) {
    scheduler_.Cancel(*t);
    *t = sim::Scheduler::kNoTimer;
  }
  for (ShutterRun& r : shutter_runs_) scheduler_.Cancel(r.timer);
  for (AxisState& s : axes_) scheduler_.Cancel(s.dfmoco_timer);
}

void Stackshot3x::ResetVolatile() {
  CancelTimers();
  shutter_runs_ = {};
  stack_ = StackRun{};
  motion_ = MotionRun{};
  const bool was_powered = powered_;
  powered_ = false;  // halts below must not drive the state machines
  for (int a = 0; a < kAxes; ++a) {
    Motor(a).EmergencyHalt();
    Motor(a).ResetPosition(0);
  }
  powered_ = was_powered;
  axes_ = {};
  ready_ = false;
  queue_.clear();
  busy_ = false;
  decoder_.Flush();
  framer_.Reset();
  pulses_.clear();
  for (int a = 0; a < kAxes; ++a) {
    dfmoco_rate_[Index(a)] = static_cast<int32_t>(
        std::min<double>(profile_.axes[Index(a)].max_speed_steps_per_s, dfmoco::kDefaultPulseRate));
  }
}

void Stackshot3x::LoadNvm() {
  serial_number_ = profile_.serial_number;
  // store_ is never null (own_store_ stands in for a missing one).
  nvm_.assign(static_cast<size_t>(profile_.nvm_registers), stackshot::kUnprogrammed);
  slots_ = {};
  log_.clear();
  store_error_.clear();
  if (store_ == nullptr) return;
  const StateLoad loaded = store_->Load();
  if (loaded.status == StateLoad::Status::kCorrupt ||
      loaded.status == StateLoad::Status::kUnsupported) {
    store_error_ = loaded.message;
    AddLog("nvm: " + loaded.message);
    return;
  }
  if (loaded.status != StateLoad::Status::kLoaded) return;
  const nlohmann::json& j = loaded.state;
  std::vector<std::string> ignored;
  if (const auto it = j.find("serial_number"); it != j.end()) {
    if (it->is_number_unsigned() && it->get<uint64_t>() <= 0xFFFFFFFFu) {
      serial_number_ = it->get<uint32_t>();
    } else {
      ignored.push_back("serial_number");
    }
  }
  if (const auto it = j.find("nvm"); it != j.end()) {
    if (it->is_object()) {
      for (const auto& [key, value] : it->items()) {
        char* end = nullptr;
        const unsigned long reg = std::strtoul(key.c_str(), &end, 10);
        if (end == key.c_str() || *end != '\0' || reg >= nvm_.size() ||
            !value.is_number_unsigned() || value.get<uint64_t>() > 0xFFFFFFFFu) {
          ignored.push_back("nvm." + key);
          continue;
        }
        nvm_[reg] = value.get<uint32_t>();
      }
    } else {
      ignored.push_back("nvm");
    }
  }
  if (const auto it = j.find("slots"); it != j.end()) {
    if (it->is_object()) {
      for (const auto& [key, value] : it->items()) {
        char* end = nullptr;
        const unsigned long slot = std::strtoul(key.c_str(), &end, 10);
        std::optional<Stackshot3xConfig> c = Stackshot3xConfig::FromJson(value);
        if (end == key.c_str() || *end != '\0' || slot > stackshot::kConfigSlotMax || !c) {
          ignored.push_back("slots." + key);
          continue;
        }
        slots_[slot] = std::move(c);
      }
    } else {
      ignored.push_back("slots");
    }
  }
  if (const auto it = j.find("log"); it != j.end()) {
    if (it->is_array()) {
      for (const nlohmann::json& e : *it) {
        if (e.is_string() && log_.size() < kMaxLogEntries) log_.push_back(e.get<std::string>());
      }
    } else {
      ignored.push_back("log");
    }
  }
  if (!ignored.empty()) {
    std::string text = "nvm: unreadable fields ignored:";
    for (const std::string& f : ignored) text += " " + f;
    store_error_ = text;
    AddLog(text);
  }
}

nlohmann::json Stackshot3x::NvmJson() const {
  nlohmann::json nvm = nlohmann::json::object();
  for (size_t i = 0; i < nvm_.size(); ++i) {
    if (nvm_[i] != stackshot::kUnprogrammed) nvm[std::to_string(i)] = nvm_[i];
  }
  nlohmann::json slots = nlohmann::json::object();
  for (size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i]) slots[std::to_string(i)] = slots_[i]->ToJson();
  }
  return nlohmann::json{{"format", "stackshot3x-nvm"},
                        {"version", 1},
                        {"serial_number", serial_number_},
                        {"nvm", nvm},
                        {"slots", slots},
                        {"log", log_}};
}

void Stackshot3x::SaveNvm() {
  if (store_ == nullptr) return;
  if (!store_->Save(NvmJson())) store_error_ = "nvm: " + store_->last_error();
}

void Stackshot3x::AddLog(std::string text) {
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.3f ",
                static_cast<double>(scheduler_.Now()) / static_cast<double>(sim::kNsPerSecond));
  std::string entry = stamp + std::move(text);
  // A log entry travels in one CC_LOG reply: keep it within a packet.
  if (entry.size() > kMaxLogEntryBytes) entry.resize(kMaxLogEntryBytes);
  std::replace(entry.begin(), entry.end(), '\0', ' ');
  if (log_.size() >= kMaxLogEntries) log_.erase(log_.begin());
  log_.push_back(std::move(entry));
  SaveNvm();
}

// ---------------------------------------------------------------------------
// Input

void Stackshot3x::OnHostBytes(wire::ByteView bytes) {
  if (!powered_ || !ready_) return;
  for (const uint8_t b : bytes) {
    // After CC_RESET the rest of the chunk reaches the restarted controller
    // once it is ready; bytes arriving while it boots are lost.
    if (!ready_) return;
    OnByte(b);
  }
  ArmGapTimer();
}

void Stackshot3x::ArmGapTimer() {
  scheduler_.Cancel(gap_timer_);
  gap_timer_ = sim::Scheduler::kNoTimer;
  // "Mandatory 2ms inter-frame delay for re-syncing to recover from partial
  // packet transmission": silence that long drops a partial packet. That is
  // the serial line's framing; TCP delivers a packet in segments whose gaps
  // say nothing about the packet (section 4.2: large commands are "broken
  // into smaller packet transmissions"), so on Wi-Fi no gap applies.
  if (host_link_ != HostLink::kSerial || SpeaksDfmoco() || decoder_.pending_bytes() == 0) return;
  gap_timer_ = scheduler_.After(stackshot::kInterFrameGapNs, [this] {
    gap_timer_ = sim::Scheduler::kNoTimer;
    decoder_.Flush();
  });
}

void Stackshot3x::OnByte(uint8_t byte) {
  if (SpeaksDfmoco()) {
    const char c = static_cast<char>(byte);
    framer_.Feed(std::string_view(&c, 1), [this](const dfmoco::FrameEvent& e) {
      if (e.kind == dfmoco::FrameEvent::Kind::kLine) OnDfmocoLine(e.text);
    });
    return;
  }
  scratch_.clear();
  decoder_.Feed(wire::ByteView(&byte, 1), scratch_);
  for (stackshot::DecodedPacket& d : scratch_) {
    stackshot::Packet p = std::move(d.packet);
    OnPacket(p);
  }
}

void Stackshot3x::OnPacket(const stackshot::Packet& packet) {
  if (busy_) {
    queue_.push_back(packet);
    return;
  }
  const auto decoded = stackshot::DecodeHostPacket(packet);
  if (!decoded) {
    Reply(packet, stackshot::ErrorReplyStatus(decoded.error()));
    return;
  }
  Handle(packet, *decoded);
}

void Stackshot3x::DrainQueue() {
  const uint64_t gen = generation_;
  while (!busy_ && !queue_.empty() && generation_ == gen && !SpeaksDfmoco()) {
    stackshot::Packet p = std::move(queue_.front());
    queue_.pop_front();
    OnPacket(p);
  }
}

void Stackshot3x::Reply(const stackshot::Packet& packet, Action status, stackshot::Payload payload,
                        bool read_response) {
  stackshot::DeviceReply r;
  r.command = packet.command;
  r.status = status;
  r.axis = packet.axis;
  r.sub_item = packet.sub_item;
  r.reserved_bit6 = packet.reserved_bit6;
  if (status != Action::kRspOk) {
    r.kind = stackshot::ReplyKind::kError;
    r.payload = stackshot::Raw{};
  } else {
    r.kind = read_response ? stackshot::ReplyKind::kReadResponse : stackshot::ReplyKind::kWriteAck;
    r.payload = std::move(payload);
  }
  stackshot::Packet out = stackshot::ToPacket(r, profile_.checksum);
  if (faults_.drop_reply_to != 0 && packet.command == faults_.drop_reply_to) return;
  if (faults_.misecho_reply_to != 0 && packet.command == faults_.misecho_reply_to) {
    ++out.command;
    stackshot::Seal(out, profile_.checksum);
  }
  if (faults_.bad_reply_checksum) ++out.checksum;
  wire::Bytes bytes;
  if (!stackshot::EncodePacket(out, bytes)) {
    // Data too long for one packet (cannot happen with the bounds kept on
    // names and log entries); answer FAILED rather than nothing.
    stackshot::Packet fail = out;
    fail.action = static_cast<uint8_t>(Action::kFailed);
    fail.data.clear();
    stackshot::Seal(fail, profile_.checksum);
    bytes.clear();
    stackshot::EncodePacket(fail, bytes);
  }
  sink_.Write(bytes);
}

void Stackshot3x::Handle(const stackshot::Packet& p, const stackshot::HostCommand& c) {
  if (std::holds_alternative<stackshot::Unknown>(c.payload)) {
    Reply(p, Action::kUnsupportedCmd);
    return;
  }
  if (std::holds_alternative<stackshot::PingRequest>(c.payload)) {
    // CC_PING, also at its table id 0x110A (see stackshot_constants.h).
    Reply(p, Action::kRspOk,
          stackshot::PingAnswer(std::get<stackshot::PingRequest>(c.payload).value), true);
    return;
  }
  const uint16_t id = c.command;
  if (id >= 0x1000 && id <= 0x100B) {
    HandleRail(p, c);
  } else if (id >= 0x1080 && id <= 0x10A0) {
    HandleConfig(p, c);
  } else if (id >= 0x1100 && id <= 0x110E) {
    HandleSystem(p, c);
  } else if (id == Cmd(Command::kMotionConfig) || id == Cmd(Command::kMotionStart)) {
    HandleMotion(p, c);
  } else {
    // CC_WAD has no documented layout (ERRATA 3.10).
    Reply(p, Action::kUnsupportedCmd);
  }
}

// ---------------------------------------------------------------------------
// Units

double Stackshot3x::StepsPerMm(int axis) const {
  return static_cast<double>(profile_.axes[Index(axis)].steps_per_rev) /
         config_.axes[Index(axis)].distance_per_rev_mm;
}

double Stackshot3x::StepsPerUnit(int axis, Units units) const {
  switch (units) {
    case Units::kMils:
      return StepsPerMm(axis) * kMmPerMil;
    case Units::kMm:
      return StepsPerMm(axis);
    case Units::kSteps:
    case Units::kDegrees:
      break;
  }
  return 1.0;
}

float Stackshot3x::ToUnits(int axis, double steps, Units units) const {
  return static_cast<float>(steps / StepsPerUnit(axis, units));
}

std::optional<double> Stackshot3x::ToMm(int axis, float value, Units units) const {
  if (!std::isfinite(value)) return std::nullopt;
  return static_cast<double>(value) * StepsPerUnit(axis, units) / StepsPerMm(axis);
}

double Stackshot3x::SpeedStepsPerS(int axis, double mm_per_s) const {
  return std::min(mm_per_s * StepsPerMm(axis), profile_.axes[Index(axis)].max_speed_steps_per_s);
}

// ---------------------------------------------------------------------------
// Motion

int64_t Stackshot3x::RailPosition(int axis) const {
  const AxisState& s = axes_[Index(axis)];
  const int64_t pos = Motor(axis).Position();
  int64_t done = 0;
  if (s.takeup.dir != 0) {
    done =
        std::clamp<int64_t>(s.takeup.dir * (pos - s.takeup.start_motor_steps), 0, s.takeup.steps);
  }
  return pos - s.offset_steps - s.takeup.dir * done;
}

bool Stackshot3x::AxisMoving(int axis) const {
  if (Motor(axis).IsMoving()) return true;
  if (faults_.busy_never_clears && axes_[Index(axis)].last_dir != 0) return true;
  if (stack_.active && (stack_.used[Index(axis)] || stack_.pano_axis == axis)) return true;
  return (motion_.pending && motion_.axes[Index(axis)]) || motion_.playing[Index(axis)];
}

void Stackshot3x::FinishTakeup(int axis) {
  AxisState& s = axes_[Index(axis)];
  if (s.takeup.dir == 0) return;
  const int64_t pos = Motor(axis).Position();
  const int64_t done =
      std::clamp<int64_t>(s.takeup.dir * (pos - s.takeup.start_motor_steps), 0, s.takeup.steps);
  s.offset_steps += s.takeup.dir * done;
  s.takeup = Takeup{};
}

sim::MoveStatus Stackshot3x::MoveAxisTo(int axis, int64_t target_rail, double max_v,
                                        bool backlash) {
  AxisState& s = axes_[Index(axis)];
  sim::StepperMotor& m = Motor(axis);
  FinishTakeup(axis);
  const int64_t cur = RailPosition(axis);
  const int dir = target_rail > cur ? 1 : (target_rail < cur ? -1 : 0);
  int64_t motor_target = target_rail + s.offset_steps;
  Takeup takeup;
  if (backlash && dir != 0 && s.last_dir != 0 && dir != s.last_dir) {
    const int64_t b = std::llround(config_.axes[Index(axis)].backlash_mm * StepsPerMm(axis));
    if (b > 0) {
      takeup = Takeup{dir, m.Position(), b};
      motor_target += dir * b;
    }
  }
  const float ramp_s = config_.axes[Index(axis)].ramp_time_s;
  planners_[Index(axis)]->SetRampTime(ramp_s);
  m.SetProfile(sim::RampProfile(std::max(max_v, 1.0), ramp_s));
  const sim::MoveStatus status = m.MoveTo(motor_target);
  if (status == sim::MoveStatus::kOk) {
    s.target_rail_steps = target_rail;
    s.takeup = takeup;
    if (dir != 0) s.last_dir = dir;
  }
  return status;
}

void Stackshot3x::OnMotionFinished(int motor_id, sim::TimeNs /*time_ns*/, int64_t /*steps*/) {
  if (!powered_) return;
  const int axis = motor_id - 1;
  if (axis < 0 || axis >= kAxes) return;
  FinishTakeup(axis);
  axes_[Index(axis)].target_rail_steps = RailPosition(axis);
  if (stack_.active && StackAxesAtRest() &&
      (stack_.phase == StackPhase::kToStart || stack_.phase == StackPhase::kMoving ||
       stack_.phase == StackPhase::kReturning || stack_.phase == StackPhase::kPanoNext)) {
    StackAdvance();
  }
  if (motion_.pending) {
    MotionAdvance();
  } else if (motion_.playing[Index(axis)]) {
    MotionAxisNext(axis);
  }
}

void Stackshot3x::OnEStop(bool engaged, sim::TimeNs /*time_ns*/) {
  if (!powered_ || !engaged) return;
  // The rig has halted every axis. A stack or a curve run in progress ends
  // there, as on the unit's stop button, and no frame is shot after it; a
  // shutter fired on its own (CC_RAIL_SHUTTER_FIRE) is not motion and runs on.
  AbortStack("stack aborted: e-stop");
  motion_ = MotionRun{};
  for (int a = 0; a < kAxes; ++a) axes_[Index(a)].target_rail_steps = RailPosition(a);
  AddLog("e-stop");
}

void Stackshot3x::UserAbort() {
  if (!powered_) return;
  const bool stack = stack_.active;
  const std::array<bool, 3> in_stack = stack_.used;
  if (stack) AbortStack("stack aborted by the user");
  motion_ = MotionRun{};
  for (int a = 0; a < kAxes; ++a) {
    if (Motor(a).IsMoving() || (stack && in_stack[Index(a)])) {
      axes_[Index(a)].user_aborted = true;
      Motor(a).EmergencyHalt();
    }
  }
  AddLog("user abort");
}

// ---------------------------------------------------------------------------
// Shutter

bool Stackshot3x::ShutterFiring() const {
  return std::any_of(shutter_runs_.begin(), shutter_runs_.end(),
                     [](const ShutterRun& r) { return r.active; });
}

bool Stackshot3x::FireShutter(int output, uint32_t pulses, std::array<float, 2> on_s,
                              std::array<float, 2> off_s, bool final_off) {
  ShutterRun& r = shutter_runs_[Index(output)];
  if (r.active || pulses == 0) return false;
  r = ShutterRun{};
  r.active = true;
  r.pulses_left = pulses;
  r.on_s = on_s;
  r.off_s = off_s;
  r.final_off = final_off;
  r.on_since_ns = scheduler_.Now();
  r.timer = scheduler_.After(SecondsToNs(on_s[0]), [this, output] { ShutterStep(output); });
  return true;
}

// Called at the end of each on time, and at the end of each off time.
void Stackshot3x::ShutterStep(int output) {
  ShutterRun& r = shutter_runs_[Index(output)];
  r.timer = sim::Scheduler::kNoTimer;
  const sim::TimeNs now = scheduler_.Now();
  if (r.on_since_ns >= 0) {
    // A pulse ends.
    pulses_.push_back(ShutterPulse{output, r.on_since_ns, now, config_.shutter_disable});
    const size_t k = r.pulse_index == 0 ? 0 : 1;
    ++r.pulse_index;
    --r.pulses_left;
    r.on_since_ns = -1;
    if (r.pulses_left > 0 || r.final_off) {
      r.timer = scheduler_.After(SecondsToNs(r.off_s[k]), [this, output] { ShutterStep(output); });
      return;
    }
  } else if (r.pulses_left > 0) {
    // The off time ends: the next pulse starts.
    r.on_since_ns = now;
    r.timer = scheduler_.After(SecondsToNs(r.on_s[1]), [this, output] { ShutterStep(output); });
    return;
  }
  r.active = false;
  if (stack_.active && stack_.phase == StackPhase::kShooting && !ShutterFiring()) {
    StackAdvance();
  }
}

void Stackshot3x::AbortShutters() {
  for (ShutterRun& r : shutter_runs_) {
    scheduler_.Cancel(r.timer);
    r = ShutterRun{};
  }
}

}  // namespace moco::devices
