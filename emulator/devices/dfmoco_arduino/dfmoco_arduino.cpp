// The DFMoco Arduino sketch in virtual time (dfmoco-protocol.txt "Messages",
// ERRATA part 2, FACTS.md "DFMoco"); the model is described in dfmoco_arduino.h.
#include "devices/dfmoco_arduino/dfmoco_arduino.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "sim/planner_dfmoco.h"
#include "wire/dfmoco_sketch_reader.h"
#include "wire/dfmoco_timing.h"

namespace moco::devices {
namespace {

using sim::TimeNs;

std::unique_ptr<sim::Planner> MakeDfmocoPlanner() { return std::make_unique<sim::DfmocoPlanner>(); }

// Floor division for a possibly negative numerator.
TimeNs FloorDiv(TimeNs a, TimeNs b) {
  const TimeNs q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

// The sketch keeps positions in int32_t.
int32_t Saturate32(int64_t v) {
  return static_cast<int32_t>(std::clamp<int64_t>(v, std::numeric_limits<int32_t>::min(),
                                                  std::numeric_limits<int32_t>::max()));
}

bool FitsInt32(double v) {
  return std::isfinite(v) && v >= std::numeric_limits<int32_t>::min() &&
         v <= std::numeric_limits<int32_t>::max();
}

// Time of the first 25 us step-timer tick at or after `t`.
TimeNs NextTick(TimeNs t) {
  return FloorDiv(t + sim::kDfmocoTickNs - 1, sim::kDfmocoTickNs) * sim::kDfmocoTickNs;
}

// Drives a motor through the sketch's chunks: `positions[i]` is the absolute
// step position at chunk boundary first_boundary_ns + i * 50 ms; each chunk
// moves at the constant velocity between two of them, and the time up to the
// first boundary continues the chunk in progress. kStop requests (only a
// go-motion's stop asks for them) are planned as DfmocoPlanner does.
class SketchChunkPlanner final : public sim::Planner {
 public:
  SketchChunkPlanner(TimeNs first_boundary_ns, std::vector<int64_t> positions)
      : first_boundary_ns_(first_boundary_ns), positions_(std::move(positions)) {}

  std::vector<sim::Segment> Plan(const sim::PlanRequest& req) override {
    if (req.kind != sim::PlanRequest::Kind::kMoveTo) return fallback_.Plan(req);
    std::vector<sim::Segment> out;
    const int64_t origin = positions_.back() - req.target_steps;
    double x = req.start.x_steps;
    TimeNs t = req.now_ns;
    TimeNs b = first_boundary_ns_;
    for (const int64_t p : positions_) {
      if (b > t) {
        sim::Segment s;
        s.duration_s = static_cast<double>(b - t) / 1e9;
        s.v0_steps_per_s = (static_cast<double>(p - origin) - x) / s.duration_s;
        out.push_back(s);
        x = static_cast<double>(p - origin);
        t = b;
      }
      b += sim::kDfmocoChunkNs;
    }
    return out;
  }
  TimeNs StepQuantumNs() const override { return sim::kDfmocoTickNs; }

 private:
  TimeNs first_boundary_ns_;
  std::vector<int64_t> positions_;
  sim::DfmocoPlanner fallback_;
};

}  // namespace

DfmocoArduino::DfmocoArduino(sim::Scheduler& scheduler, ByteSink& sink, DfmocoProfile profile,
                             DfmocoFaults faults)
    : scheduler_(scheduler),
      sink_(sink),
      profile_(std::move(profile)),
      faults_(std::move(faults)),
      dialect_(profile_.Dialect()),
      rig_(scheduler, profile_.MotorCount(), 0, nullptr, &MakeDfmocoPlanner),
      framer_(dfmoco::FramerOptions{dfmoco::LineTermination::kSketch, dfmoco::kMaxLineBytes}),
      motors_(static_cast<size_t>(profile_.MotorCount())) {
  rig_.SetObserver(this);
  ResetVolatileState();
}

DfmocoArduino::~DfmocoArduino() {
  CancelTimers();
  rig_.SetObserver(nullptr);
}

// --- lifecycle ----------------------------------------------------------------------

void DfmocoArduino::PowerOn() {
  if (powered_) return;
  powered_ = true;
  ResetVolatileState();
  if (profile_.boot_delay_ms <= 0) {
    Boot();
  } else {
    boot_timer_ = scheduler_.After(profile_.boot_delay_ms * sim::kNsPerMs, [this] {
      boot_timer_ = sim::Scheduler::kNoTimer;
      Boot();
    });
  }
}

void DfmocoArduino::Boot() {
  running_ = true;
  start_ns_ = scheduler_.Now();
  uart_free_ns_ = start_ns_;
  Send(Msg::kHi);  // the sketch announces itself unprompted (FACTS)
}

void DfmocoArduino::PowerOff() {
  if (!powered_) return;
  powered_ = false;
  running_ = false;
  CancelTimers();
  ResetVolatileState();
}

void DfmocoArduino::CancelTimers() {
  for (sim::Scheduler::TimerId* t : {&boot_timer_, &uart_timer_, &report_timer_}) {
    scheduler_.Cancel(*t);
    *t = sim::Scheduler::kNoTimer;
  }
  for (MotorState& s : motors_) {
    scheduler_.Cancel(s.extend_timer);
    s.extend_timer = sim::Scheduler::kNoTimer;
  }
}

void DfmocoArduino::ResetVolatileState() {
  const bool was_running = running_;
  running_ = false;  // halting below must not queue reports
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    sim::StepperMotor& motor = Motor(m);
    motor.EmergencyHalt();
    motor.SetPlanner(MakeDfmocoPlanner());
    (void)motor.ResetPosition(0);
    scheduler_.Cancel(motors_[Index(m)].extend_timer);
    motors_[Index(m)] = MotorState{};
    SetPulseRate(m, profile_.pulse_rate_steps_per_s);
  }
  running_ = was_running;
  go_ready_ = false;
  blur_reply_ = kBlurReady;
  ring_head_ = 0;
  ring_count_ = 0;
  dropped_ = 0;
  uart_free_ns_ = scheduler_.Now();
  burst_anchor_ns_ = uart_free_ns_;
  burst_bytes_ = 0;
  framer_.Reset();
}

void DfmocoArduino::OnHostLink(bool open) {
  if (open && profile_.reset_on_open && powered_) {
    PowerOff();
    PowerOn();
  }
}

// --- state ----------------------------------------------------------------------------

bool DfmocoArduino::MotorMoving(int motor) const {
  if (!motors_[Index(motor)].in_go_motion) {
    // The sketch's motorMoving bit.
    return SketchAt(motor, FloorDiv(scheduler_.Now(), sim::kDfmocoChunkNs)).moving();
  }
  const sim::StepperMotor& m = Motor(motor);
  return m.IsMoving() && m.CurrentPlan().EndNs() > scheduler_.Now();
}

int32_t DfmocoArduino::TargetOf(int motor) const {
  if (motors_[Index(motor)].in_go_motion) return Saturate32(Motor(motor).Target());
  return SketchAt(motor, FloorDiv(scheduler_.Now(), sim::kDfmocoChunkNs)).destination();
}

const SketchAxis& DfmocoArduino::SketchAt(int motor, int64_t k) const {
  const MotorState& s = motors_[Index(motor)];
  if (k <= s.base_k || s.window.empty()) return s.base;
  const auto i = static_cast<size_t>(k - s.base_k - 1);
  return i < s.window.size() ? s.window[i] : s.window.back();
}

int32_t DfmocoArduino::SketchPositionAfter(int motor, int64_t k) const {
  const MotorState& s = motors_[Index(motor)];
  if (k == s.base_k - 1) return s.position_before_base;
  return SketchAt(motor, k).position();
}

SketchAxis& DfmocoArduino::Begin(int motor) {
  MotorState& s = motors_[Index(motor)];
  const int64_t k = FloorDiv(scheduler_.Now(), sim::kDfmocoChunkNs);
  if (k != s.base_k || !s.window.empty()) {
    const SketchAxis now = SketchAt(motor, k);
    const int32_t before = SketchPositionAfter(motor, k - 1);
    s.base = now;
    s.position_before_base = before;
    s.base_k = k;
    s.window.clear();
  }
  scheduler_.Cancel(s.extend_timer);
  s.extend_timer = sim::Scheduler::kNoTimer;
  return s.base;
}

bool DfmocoArduino::Commit(int motor) {
  MotorState& s = motors_[Index(motor)];
  SketchAxis a = s.base;
  for (size_t i = 0; i < kWindowChunks && a.moving(); ++i) {
    (void)a.Update();
    s.window.push_back(a);
  }
  // Update k's chunk steps during [k + 1, k + 2): the motor is at
  // position_before_base at boundary base_k + 1, then follows the window.
  std::vector<int64_t> positions;
  positions.reserve(s.window.size() + 2);
  positions.push_back(s.position_before_base);
  positions.push_back(s.base.position());
  for (const SketchAxis& w : s.window) positions.push_back(w.position());
  while (positions.size() > 1 && positions.back() == positions[positions.size() - 2]) {
    positions.pop_back();
  }
  sim::StepperMotor& mo = Motor(motor);
  const int64_t target = positions.back();
  const bool still = positions.size() == 1 && target == mo.Position();
  if (!(still && !mo.IsMoving())) {
    mo.SetPlanner(std::make_unique<SketchChunkPlanner>((s.base_k + 1) * sim::kDfmocoChunkNs,
                                                       std::move(positions)));
    const sim::MoveStatus status = mo.MoveTo(target);
    mo.SetPlanner(MakeDfmocoPlanner());
    if (status != sim::MoveStatus::kOk) {
      mo.EmergencyHalt();
      s.base.Rest(Saturate32(mo.Position()));
      s.position_before_base = s.base.position();
      s.window.clear();
      return false;
    }
  }
  ArmExtendTimer(motor);
  return true;
}

void DfmocoArduino::ArmExtendTimer(int motor) {
  MotorState& s = motors_[Index(motor)];
  if (s.window.empty() || !s.window.back().moving()) return;
  // At the boundary of the window's last update, plan the next window.
  const TimeNs at = (s.base_k + static_cast<int64_t>(s.window.size())) * sim::kDfmocoChunkNs;
  s.extend_timer = scheduler_.At(at, [this, motor] {
    motors_[Index(motor)].extend_timer = sim::Scheduler::kNoTimer;
    (void)Begin(motor);
    (void)Commit(motor);
  });
}

bool DfmocoArduino::AnyMoving() const {
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    if (MotorMoving(m)) return true;
  }
  return false;
}

int64_t DfmocoArduino::ReportedPosition(int motor) const {
  if (!motors_[Index(motor)].in_go_motion) {
    // The sketch's position counter: the end of the chunk it planned last.
    return SketchAt(motor, FloorDiv(scheduler_.Now(), sim::kDfmocoChunkNs)).position();
  }
  const sim::StepperMotor& m = Motor(motor);
  if (!m.IsMoving()) return m.Position();
  // The sketch's position counter runs one chunk ahead of the steps: it holds
  // the planned position at the end of the chunk being stepped (FACTS).
  const TimeNs phase = motors_[Index(motor)].chunk_phase_ns;
  const TimeNs k = FloorDiv(scheduler_.Now() - phase, sim::kDfmocoChunkNs);
  return m.PositionAt(phase + (k + 1) * sim::kDfmocoChunkNs);
}

size_t DfmocoArduino::OutstandingMessages() const {
  return ring_count_ + (scheduler_.Now() < uart_free_ns_ ? 1 : 0);
}

DfmocoArduino::GoMotionState DfmocoArduino::go_motion_state() const {
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    if (motors_[Index(m)].in_go_motion && Motor(m).IsMoving()) return GoMotionState::kRunning;
  }
  return go_ready_ ? GoMotionState::kArmed : GoMotionState::kIdle;
}

nlohmann::json DfmocoArduino::State() const {
  nlohmann::json motors = nlohmann::json::array();
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    const sim::StepperMotor& motor = Motor(m);
    motors.push_back({{"motor", m},
                      {"position_steps", motor.Position()},
                      {"reported_position_steps", ReportedPosition(m)},
                      {"target_steps", TargetOf(m)},
                      {"moving", MotorMoving(m)},
                      {"pulse_rate_steps_per_s", motors_[Index(m)].pulse_rate_steps_per_s}});
  }
  nlohmann::json gomo = {{"state", "idle"}};
  switch (go_motion_state()) {
    case GoMotionState::kIdle:
      break;
    case GoMotionState::kArmed:
      gomo["state"] = "armed";
      break;
    case GoMotionState::kRunning:
      gomo["state"] = "running";
      break;
  }
  nlohmann::json channels = nlohmann::json::array();
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    const std::optional<BlurMove>& b = motors_[Index(m)].blur;
    if (!go_ready_ || !b) continue;
    channels.push_back({{"motor", m},
                        {"start_steps", std::llround(b->start_steps)},
                        {"exposure_start_steps", b->exposure_start_steps},
                        {"exposure_end_steps", b->exposure_end_steps},
                        {"end_steps", std::llround(b->end_steps)}});
  }
  gomo["channels"] = channels;
  gomo["last_bf_reply"] = blur_reply_;
  return {{"model", Model()},
          {"board", BoardName(profile_.board)},
          {"firmware", dialect_.firmware_version},
          {"powered", powered_},
          {"running", running_},
          {"motors", motors},
          {"go_motion", gomo},
          {"tx_queue",
           {{"outstanding", OutstandingMessages()},
            {"capacity", kMaxOutstanding},
            {"dropped", dropped_}}}};
}

// --- input ----------------------------------------------------------------------------

void DfmocoArduino::OnHostBytes(wire::ByteView bytes) {
  if (!running_) return;  // powered off, or still booting: the bytes are lost
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  framer_.Feed(text, [this](const dfmoco::FrameEvent& e) {
    if (e.kind == dfmoco::FrameEvent::Kind::kLine) {
      OnLine(e.text);
      return;
    }
    // A line longer than any well-formed one: the sketch parses as it reads,
    // so only the 40-argument limit can still answer.
    if (dfmoco::ReadLineAsSketch(e.text).kind == dfmoco::SketchReading::Kind::kTooManyArgs) {
      SendDirect(dfmoco::TooManyArgsReply{});
    }
  });
}

void DfmocoArduino::OnLine(std::string_view line) {
  // The sketch's own byte-at-a-time reading (wire/dfmoco_sketch_reader.h):
  // "mm 1 --5" is -5, "mm 1 99999999999" wraps, "mm 1 x" has one argument.
  // What it reads is then judged as a canonical line (argument counts,
  // motors), which ParseHostLine reads the same way.
  const dfmoco::SketchReading sketch = dfmoco::ReadLineAsSketch(line);
  if (sketch.kind == dfmoco::SketchReading::Kind::kTooManyArgs) {
    SendDirect(dfmoco::TooManyArgsReply{});
    return;
  }
  if (sketch.kind == dfmoco::SketchReading::Kind::kNothing) return;  // no reply (FACTS)
  const wire::Result<dfmoco::HostCommand> r =
      dfmoco::ParseHostLine(sketch.CanonicalLine(), dialect_);
  if (!r.ok()) {
    SendDirect(dfmoco::ErrorReply(r.error()));
    return;
  }
  mute_ = !faults_.silent_word.empty() && dfmoco::CommandWord(*r) == faults_.silent_word;
  Handle(*r);
  mute_ = false;
  ArmReportTimer();
}

void DfmocoArduino::Handle(const dfmoco::HostCommand& command) {
  const std::optional<int32_t> addressed = dfmoco::AddressedMotor(command);
  if (addressed && !dfmoco::MotorInRange(*addressed, dialect_)) {
    SendDirect(dfmoco::ParseErrorReply{});
    return;
  }
  const int m = addressed.value_or(1);
  const auto idx = static_cast<int>(m - 1);
  std::visit(wire::Overloaded{
                 [&](const dfmoco::Hello&) { Send(Msg::kHi); },
                 [&](const dfmoco::MotorStatusQuery&) {
                   Send(Msg::kMs);
                   if (!faults_.extra_line_after_ms.empty() && !mute_) {
                     Transmit(faults_.extra_line_after_ms + "\r\n");
                   }
                 },
                 [&](const dfmoco::MoveMotor& c) { HandleMove(m, c.position_steps); },
                 [&](const dfmoco::PositionQuery&) { Send(Msg::kMp, idx); },
                 [&](const dfmoco::PositionQueryAll&) { SendDirect(dfmoco::ParseErrorReply{}); },
                 [&](const dfmoco::StopMotor&) {
                   StopSketchMotor(m);
                   Send(Msg::kSm, idx);
                   Send(Msg::kMp, idx);
                 },
                 [&](const dfmoco::StopAll&) {
                   for (int i = 1; i <= rig_.motor_count(); ++i) {
                     StopSketchMotor(i);
                   }
                   Send(Msg::kSa);
                 },
                 [&](const dfmoco::JogMotor& c) { HandleJog(c); },
                 [&](const dfmoco::InchMotor& c) { HandleInch(m, c.destination_steps); },
                 [&](const dfmoco::SetPulseRate& c) {
                   SetPulseRate(m, c.rate_steps_per_s);
                   Send(Msg::kPr, idx);
                 },
                 [&](const dfmoco::ZeroMotor&) {
                   SetPosition(m, 0);
                   Send(Msg::kMp, idx);
                   // The second `mp m 0` comes with the next periodic report (FACTS: sent twice).
                   motors_[Index(m)].report_pending = true;
                 },
                 [&](const dfmoco::NewPosition& c) {
                   SetPosition(m, c.position_steps);
                   Send(Msg::kMp, idx);  // FACTS: `mp`, not the protocol text's `np`
                 },
                 [&](const dfmoco::BlurFrame& c) { HandleBlur(c); },
                 [&](const dfmoco::Go&) { HandleGo(); },
                 [&](const dfmoco::UnknownCommand&) {},  // no reply at all (FACTS)
             },
             command);
}

void DfmocoArduino::SetPulseRate(int motor, int32_t rate_steps_per_s) {
  const int32_t rate = std::clamp(rate_steps_per_s, dfmoco::kMinPulseRate, dfmoco::kMaxPulseRate);
  motors_[Index(motor)].pulse_rate_steps_per_s = rate;
  sim::MotionProfile p = Motor(motor).profile();
  p.max_velocity_steps_per_s = rate;
  p.max_accel_steps_per_s2 = rate / 2.0;  // FACTS: acceleration is half the pulse rate
  (void)Motor(motor).SetProfile(p);
  // setPulsesPerSecond: later plans and stops use the new maxima; the
  // segments already planned stay.
  Begin(motor).SetPulseRate(rate);
  (void)Commit(motor);
}

void DfmocoArduino::SetPosition(int motor, int64_t steps) {
  LeaveGoMotion(motor);
  sim::StepperMotor& mo = Motor(motor);
  SketchAxis& axis = Begin(motor);
  if (axis.moving() || mo.IsMoving()) {
    // Reading: a moving motor stops dead where it is first.
    mo.EmergencyHalt();
    axis.Rest(Saturate32(mo.Position()));
  }
  (void)mo.ResetPosition(steps);
  motors_[Index(motor)].position_before_base = Saturate32(steps);
  axis.SetPosition(Saturate32(steps));  // `np`: the destination stays
}

void DfmocoArduino::LeaveGoMotion(int motor) {
  MotorState& s = motors_[Index(motor)];
  if (s.in_go_motion) {
    Motor(motor).EmergencyHalt();
    s.in_go_motion = false;
    Begin(motor).Rest(Saturate32(Motor(motor).Position()));
    s.position_before_base = s.base.position();
  }
  s.chunk_phase_ns = 0;
}

void DfmocoArduino::StopSketchMotor(int motor) {
  if (motors_[Index(motor)].in_go_motion) {
    Motor(motor).Stop();  // a go-motion decelerates on its own chunk clock
    return;
  }
  Begin(motor).Stop();
  (void)Commit(motor);
}

void DfmocoArduino::HandleMove(int motor, int32_t position_steps) {
  const auto idx = static_cast<int>(motor - 1);
  LeaveGoMotion(motor);
  SketchAxis& axis = Begin(motor);
  if (axis.position() == position_steps) {
    Send(Msg::kMp, idx);  // processGoPosition: already there
    return;
  }
  axis.MoveTo(position_steps);
  if (!Commit(motor)) {
    Send(Msg::kMp, idx);  // the rig refused (e.g. an e-stop): the motor stays
    return;
  }
  Send(Msg::kMm, idx);
}

void DfmocoArduino::HandleJog(const dfmoco::JogMotor& jog) {
  const int motor = jog.motor;
  LeaveGoMotion(motor);
  // jogMotor (FACTS): the destination is the position plus the distance of
  // at most 0.5 s of acceleration, the rest of the 0.5 s cruising, and the
  // braking, at vel/10000 of the pulse rate and its acceleration.
  Begin(motor).Jog(jog.destination_steps, jog.velocity ? *jog.velocity : dfmoco::kMaxJogVelocity);
  (void)Commit(motor);
  Send(Msg::kJm, static_cast<int>(motor - 1));
}

void DfmocoArduino::HandleInch(int motor, int32_t destination_steps) {
  LeaveGoMotion(motor);
  // inchMotor (FACTS): direction against the destination, 2 steps in 10 ms;
  // a motor whose loaded chunk steps is stopped instead.
  Begin(motor).Inch(destination_steps);
  (void)Commit(motor);
  Send(Msg::kIm, static_cast<int>(motor - 1));
}

void DfmocoArduino::HandleBlur(const dfmoco::BlurFrame& bf) {
  // Refused while moving (FACTS); the sketch also needs at least one channel.
  // Reading: an exposure <= 0 has no speed, so it is refused the same way.
  if (AnyMoving() || bf.channels.empty() || bf.exposure_ms <= 0) {
    SendDirect(dfmoco::ParseErrorReply{});
    return;
  }
  std::vector<std::optional<BlurMove>> moves(motors_.size());
  bool too_fast = false;
  bool out_of_range = false;
  for (const dfmoco::BlurChannel& ch : bf.channels) {
    if (!dfmoco::MotorInRange(ch.channel, dialect_)) {
      SendDirect(dfmoco::ParseErrorReply{});
      return;
    }
    const BlurMove move = PlanBlur(bf.exposure_ms, bf.blur, ch.p0_steps, ch.p1_steps, ch.p2_steps);
    too_fast = too_fast || move.MaxSpeed() > sim::kDfmocoMaxStepsPerS;
    out_of_range = out_of_range || !FitsInt32(move.start_steps) || !FitsInt32(move.end_steps);
    moves[Index(ch.channel)] = move;  // a repeated channel: the last one counts
  }
  if (too_fast && profile_.RefusesTooFastBlur()) {
    go_ready_ = false;
    blur_reply_ = dfmoco::kBlurRefused;  // `bf -1`, nothing moves
    Send(Msg::kBf);
    return;
  }
  if (out_of_range) {
    // The sketch's int32 position arithmetic would overflow.
    SendDirect(dfmoco::ParseErrorReply{});
    return;
  }
  go_ready_ = true;
  blur_reply_ = kBlurReady;
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    motors_[Index(m)].blur = moves[Index(m)];
    if (!moves[Index(m)]) continue;
    const int64_t start = std::llround(moves[Index(m)]->start_steps);
    LeaveGoMotion(m);
    SketchAxis& axis = Begin(m);
    if (axis.position() != start) {  // pre-position
      axis.MoveTo(Saturate32(start));
      (void)Commit(m);
    }
  }
  Send(Msg::kBf);
}

void DfmocoArduino::HandleGo() {
  if (AnyMoving() || !go_ready_) {
    SendDirect(dfmoco::ParseErrorReply{});
    return;
  }
  // The sketch restarts its chunk clock at `go`: the move starts at the next
  // step-timer tick, so the exposure opens 1 s later.
  const TimeNs start = NextTick(scheduler_.Now());
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    MotorState& s = motors_[Index(m)];
    if (!s.blur) continue;
    const int64_t target = std::llround(s.blur->end_steps);
    sim::StepperMotor& mo = Motor(m);
    mo.SetPlanner(std::make_unique<GoMotionPlanner>(*s.blur, start, target));
    const sim::MoveStatus status = mo.MoveTo(target);
    mo.SetPlanner(MakeDfmocoPlanner());
    if (status == sim::MoveStatus::kOk && mo.IsMoving()) {
      s.in_go_motion = true;
      s.chunk_phase_ns = start % sim::kDfmocoChunkNs;
    }
  }
  Send(Msg::kGo);
}

// --- output ---------------------------------------------------------------------------

void DfmocoArduino::Send(Msg msg, int motor_index, int32_t offset_steps) {
  if (!running_ || mute_) return;
  const TxMsg m{msg, static_cast<uint8_t>(motor_index), offset_steps};
  if (ring_count_ == 0 && scheduler_.Now() >= uart_free_ns_) {
    Transmit(Format(m));  // straight into the empty transmit buffer
    return;
  }
  if (ring_count_ >= kTxRingSlots - 1) {
    ++dropped_;  // the ring is full: dropped without a word (FACTS)
    return;
  }
  ring_[(ring_head_ + ring_count_) % kTxRingSlots] = m;
  ++ring_count_;
  ArmUartTimer();
}

void DfmocoArduino::SendDirect(const dfmoco::DeviceReply& reply) {
  if (!running_) return;
  Transmit(dfmoco::FormatDevice(reply));
  if (ring_count_ > 0) ArmUartTimer();
}

void DfmocoArduino::Transmit(const std::string& bytes) {
  const TimeNs now = scheduler_.Now();
  if (now > uart_free_ns_) {  // the line went idle: a new burst starts
    burst_anchor_ns_ = now;
    burst_bytes_ = 0;
  }
  burst_bytes_ += bytes.size();
  const auto bps = static_cast<uint64_t>(Line().serial.BytesPerSecond());
  const uint64_t burst_ns =
      (burst_bytes_ * static_cast<uint64_t>(sim::kNsPerSecond) + bps - 1) / bps;
  uart_free_ns_ = burst_anchor_ns_ + static_cast<TimeNs>(burst_ns);
  sink_.Write(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

std::string DfmocoArduino::Format(const TxMsg& m) const {
  const int motor = m.motor_index + 1;
  dfmoco::DeviceReply reply;
  switch (m.msg) {
    case Msg::kHi:
      reply = dfmoco::HelloFor(dialect_);
      break;
    case Msg::kMm:
      reply = dfmoco::MoveReply{motor, TargetOf(motor)};
      break;
    case Msg::kMp:
      reply = dfmoco::PositionReply{motor, Saturate32(ReportedPosition(motor) + m.offset_steps)};
      break;
    case Msg::kMs: {
      dfmoco::MotorStatusReply ms;
      for (int i = 1; i <= rig_.motor_count(); ++i) ms.moving.push_back(MotorMoving(i));
      ms.moving.resize(
          static_cast<size_t>(std::max(1, rig_.motor_count() + faults_.ms_width_delta)));
      reply = std::move(ms);
      break;
    }
    case Msg::kPr:
      reply = dfmoco::PulseRateReply{motor, motors_[Index(motor)].pulse_rate_steps_per_s};
      break;
    case Msg::kSm:
      reply = dfmoco::StopMotorReply{motor};
      break;
    case Msg::kSa:
      reply = dfmoco::StopAllReply{};
      break;
    case Msg::kBf:
      reply = dfmoco::BlurReply{blur_reply_};
      break;
    case Msg::kGo:
      reply = dfmoco::GoReply{};
      break;
    case Msg::kJm:
      reply = dfmoco::JogReply{motor};
      break;
    case Msg::kIm:
      reply = dfmoco::InchReply{motor};
      break;
  }
  return dfmoco::FormatDevice(reply);
}

void DfmocoArduino::ArmUartTimer() {
  if (uart_timer_ != sim::Scheduler::kNoTimer || ring_count_ == 0) return;
  uart_timer_ = scheduler_.At(uart_free_ns_, [this] { OnUartFree(); });
}

void DfmocoArduino::OnUartFree() {
  uart_timer_ = sim::Scheduler::kNoTimer;
  if (!running_ || ring_count_ == 0) return;
  if (scheduler_.Now() < uart_free_ns_) {  // a direct line went out meanwhile
    ArmUartTimer();
    return;
  }
  const TxMsg m = ring_[ring_head_];
  ring_head_ = (ring_head_ + 1) % kTxRingSlots;
  --ring_count_;
  Transmit(Format(m));
  ArmUartTimer();
}

// --- periodic position reports --------------------------------------------------------

TimeNs DfmocoArduino::NextReportTick(TimeNs after_ns) const {
  // The chunk clock runs from t = 0 (sim/planner_dfmoco.h); the first report
  // comes ten chunks after the first chunk boundary of the running sketch.
  const TimeNs first_boundary =
      FloorDiv(start_ns_ + sim::kDfmocoChunkNs - 1, sim::kDfmocoChunkNs) * sim::kDfmocoChunkNs;
  const TimeNs origin = first_boundary + dfmoco::kFirstReportNs;
  if (after_ns < origin) return origin;
  return origin + (FloorDiv(after_ns - origin, ReportPeriodNs()) + 1) * ReportPeriodNs();
}

TimeNs DfmocoArduino::ReportPeriodNs() const {
  return faults_.report_period_ms > 0 ? faults_.report_period_ms * sim::kNsPerMs
                                      : dfmoco::kReportPeriodNs;
}

void DfmocoArduino::ArmReportTimer() {
  if (!running_ || report_timer_ != sim::Scheduler::kNoTimer) return;
  bool needed = false;
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    needed = needed || MotorMoving(m) || Motor(m).IsMoving() || motors_[Index(m)].report_pending;
  }
  if (!needed) return;
  report_timer_ = scheduler_.At(NextReportTick(scheduler_.Now()), [this] { OnReportTick(); });
}

void DfmocoArduino::OnReportTick() {
  report_timer_ = sim::Scheduler::kNoTimer;
  const TimeNs now = scheduler_.Now();
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    MotorState& s = motors_[Index(m)];
    const bool moving = MotorMoving(m);
    if (!moving && !s.report_pending) continue;
    Send(Msg::kMp, m - 1, moving ? 0 : faults_.stop_report_offset_steps);
    s.report_pending = false;
    s.last_report_ns = now;
  }
  ArmReportTimer();
}

void DfmocoArduino::OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) {
  if (!running_ || !rig_.ValidMotor(motor_id)) return;
  MotorState& s = motors_[Index(motor_id)];
  const SketchAxis& last = s.window.empty() ? s.base : s.window.back();
  if (s.in_go_motion || last.moving() || last.position() != steps) {
    // A go-motion ended, or the rig stopped the motor (e-stop, limit): the
    // sketch rests where the motor is.
    s.in_go_motion = false;
    Begin(motor_id).Rest(Saturate32(steps));
    s.position_before_base = s.base.position();
  }
  s.chunk_phase_ns = 0;
  // One report after the stop, unless this instant's report already gave it.
  if (s.last_report_ns != time_ns) s.report_pending = true;
  ArmReportTimer();
}

}  // namespace moco::devices
