// The ATmega328P/2560 timer/counters at their datasheet periods over libsimavr 1.6
// (ATmega328P datasheet sections 15-18, ATmega2560 sections 16-20; the model is
// defined in avr_timers.h).
#include "conformance/targets/avr_timers.h"

#include <algorithm>
#include <limits>

extern "C" {
#include "avr_ioport.h"
#include "avr_timer.h"
#include "sim_avr.h"
#include "sim_cycle_timers.h"
#include "sim_interrupts.h"
#include "sim_io.h"
#include "sim_irq.h"
#include "sim_regbit.h"
}

namespace moco::conformance {
namespace {

constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();

enum class Kind { kNormal, kCtc, kFast, kPhase, kPhaseFreq, kReserved };
enum class TopFrom { kFixed, kOcrA, kIcr };

struct ModeInfo {
  Kind kind;
  TopFrom top;
  uint16_t fixed_top;
};

// 16-bit Timer/Counter1 (3, 4, 5): ATmega328P table 16-4, ATmega2560 table 17-2.
constexpr ModeInfo kModes16[16] = {
    {Kind::kNormal, TopFrom::kFixed, 0xFFFF}, {Kind::kPhase, TopFrom::kFixed, 0x00FF},
    {Kind::kPhase, TopFrom::kFixed, 0x01FF},  {Kind::kPhase, TopFrom::kFixed, 0x03FF},
    {Kind::kCtc, TopFrom::kOcrA, 0},          {Kind::kFast, TopFrom::kFixed, 0x00FF},
    {Kind::kFast, TopFrom::kFixed, 0x01FF},   {Kind::kFast, TopFrom::kFixed, 0x03FF},
    {Kind::kPhaseFreq, TopFrom::kIcr, 0},     {Kind::kPhaseFreq, TopFrom::kOcrA, 0},
    {Kind::kPhase, TopFrom::kIcr, 0},         {Kind::kPhase, TopFrom::kOcrA, 0},
    {Kind::kCtc, TopFrom::kIcr, 0},           {Kind::kReserved, TopFrom::kFixed, 0},
    {Kind::kFast, TopFrom::kIcr, 0},          {Kind::kFast, TopFrom::kOcrA, 0},
};
// 8-bit Timer/Counter0 and 2: ATmega328P tables 15-8 and 18-8.
constexpr ModeInfo kModes8[8] = {
    {Kind::kNormal, TopFrom::kFixed, 0xFF}, {Kind::kPhase, TopFrom::kFixed, 0xFF},
    {Kind::kCtc, TopFrom::kOcrA, 0},        {Kind::kFast, TopFrom::kFixed, 0xFF},
    {Kind::kReserved, TopFrom::kFixed, 0},  {Kind::kPhase, TopFrom::kOcrA, 0},
    {Kind::kReserved, TopFrom::kFixed, 0},  {Kind::kFast, TopFrom::kOcrA, 0},
};
// CSn2:0 -> prescaler; 0 stopped, kExternal the Tn pin (table 15-9, 16-5, 18-9).
constexpr uint32_t kExternal = 0xFFFFFFFF;
constexpr uint32_t kDividers[8] = {0, 1, 8, 64, 256, 1024, kExternal, kExternal};
constexpr uint32_t kDividers2[8] = {0, 1, 8, 32, 64, 128, 256, 1024};

constexpr uint8_t kAs2 = 1 << 5;    // ASSR.AS2
constexpr uint8_t kExclk = 1 << 6;  // ASSR.EXCLK
constexpr uint8_t kIcnc = 1 << 7;   // TCCRnB.ICNCn
constexpr uint8_t kIces = 1 << 6;   // TCCRnB.ICESn
constexpr uint16_t kGtccr = 0x43;   // both MCUs

bool DualSlope(Kind k) { return k == Kind::kPhase || k == Kind::kPhaseFreq; }
bool Buffered(Kind k) { return k == Kind::kFast || DualSlope(k); }

// The counter's value and direction, and the shape it counts in.
struct Counter {
  uint32_t count = 0;
  bool up = true;
};
struct Shape {
  uint32_t top = 0;
  uint32_t max = 0;
  bool dual = false;
};

void Step(Counter& c, const Shape& s) {
  if (!s.dual) {
    c.count = c.count == s.top ? 0 : (c.count == s.max ? 0 : c.count + 1);
    return;
  }
  if (c.up) {
    if (c.count >= s.top) {
      if (c.count == 0) return;  // TOP 0: stays at 0
      --c.count;
      c.up = false;
    } else {
      ++c.count;
    }
  } else if (c.count == 0) {
    c.up = true;
    if (s.top > 0) c.count = 1;
  } else {
    --c.count;
  }
}

// Ticks until the counter holds `v` (0: it does now), kNever when it never will.
uint64_t Dist(const Counter& c, const Shape& s, uint32_t v) {
  if (!s.dual) {
    if (c.count <= s.top) {
      if (v > s.top) return kNever;
      return (v + s.top + 1 - c.count) % (uint64_t{s.top} + 1);
    }
    if (v >= c.count) return v - c.count;
    const uint64_t wrap = uint64_t{s.max} - c.count + 1;
    return v <= s.top ? wrap + v : kNever;
  }
  if (s.top == 0) return v <= c.count ? c.count - v : kNever;
  uint64_t pre = 0;
  uint64_t p;  // phase in 0 .. 2*TOP-1: up at count p, down at count 2*TOP-p
  if (c.count > s.top) {
    if (v > s.top) return v <= c.count ? c.count - v : kNever;
    pre = c.count - s.top;
    p = s.top;
  } else {
    if (v > s.top) return kNever;
    p = c.up ? c.count : (2 * uint64_t{s.top} - c.count) % (2 * uint64_t{s.top});
  }
  const uint64_t period = 2 * uint64_t{s.top};
  const uint64_t d1 = (v + period - p) % period;
  const uint64_t d2 = (2 * uint64_t{s.top} - v + period - p) % period;
  return pre + std::min(d1, d2);
}

void Advance(Counter& c, const Shape& s, uint64_t n) {
  if (n == 0) return;
  if (!s.dual) {
    if (c.count > s.top) {
      const uint64_t wrap = uint64_t{s.max} - c.count + 1;
      if (n < wrap) {
        c.count += static_cast<uint32_t>(n);
        return;
      }
      n -= wrap;
      c.count = 0;
    }
    c.count = static_cast<uint32_t>((c.count + n) % (uint64_t{s.top} + 1));
    return;
  }
  if (s.top == 0) {
    c.count = n >= c.count ? 0 : c.count - static_cast<uint32_t>(n);
    c.up = c.count == 0;
    return;
  }
  uint64_t p;
  if (c.count > s.top) {
    const uint64_t pre = c.count - s.top;
    if (n < pre) {
      c.count -= static_cast<uint32_t>(n);
      c.up = false;
      return;
    }
    n -= pre;
    p = s.top;
  } else {
    p = c.up ? c.count : (2 * uint64_t{s.top} - c.count) % (2 * uint64_t{s.top});
  }
  const uint64_t period = 2 * uint64_t{s.top};
  p = (p + n) % period;
  if (p <= s.top) {
    c.count = static_cast<uint32_t>(p);
    c.up = true;
  } else {
    c.count = static_cast<uint32_t>(period - p);
    c.up = false;
  }
}

enum Reg {
  kRegA,
  kRegB,
  kTcntL,
  kTcntH,
  kOcrL0,  // + unit
  kOcrH0 = kOcrL0 + 3,
  kIcrL = kOcrH0 + 3,
  kIcrH,
  kTifr,
  kTimsk,
  kAssr,
  kGtccrReg,
};

const char* const kFlagNames[AvrTimers::kFlagCount] = {
    "overflow", "compare match A", "compare match B", "compare match C", "input capture"};

}  // namespace

struct AvrTimers::Timer {
  AvrTimers* owner = nullptr;
  avr_timer_t* hw = nullptr;
  std::string name;  // "Timer1"
  char digit = '0';
  bool wide = false;
  bool timer2 = false;
  int units = 0;
  uint32_t max = 0xFF;
  uint16_t a_addr = 0, b_addr = 0;
  std::array<avr_int_vector_t*, kFlagCount> vectors{};

  // Configuration (from TCCRnA/B and ASSR).
  int wgm = 0;
  int cs = 0;
  ModeInfo mode = kModes8[0];
  uint32_t divider = 0;  // 0: not counting

  Counter counter;
  uint64_t ref_cycle = 0;  // `counter` holds since this cycle (its ticks done)
  bool block = false;      // TCNTn written: no compare match on the next tick
  std::array<uint32_t, 3> ocr{}, ocr_buf{};
  uint32_t icr = 0;
  uint8_t temp = 0;
  bool capture_level = false;
  avr_irq_t* capture_irq = nullptr;

  uint64_t scheduled = 0;  // the armed OnCycle's cycle, 0 when none
  bool in_callback = false;
  std::array<uint64_t, kFlagCount> fired{};

  uint32_t Top() const {
    switch (mode.top) {
      case TopFrom::kOcrA:
        return ocr[0];
      case TopFrom::kIcr:
        return icr;
      case TopFrom::kFixed:
        break;
    }
    return mode.fixed_top;
  }
  Shape GetShape() const { return Shape{Top(), max, DualSlope(mode.kind)}; }
  uint32_t TovValue() const {
    if (mode.kind == Kind::kFast) return Top();
    return DualSlope(mode.kind) ? 0 : max;
  }
  uint32_t UpdateValue() const { return mode.kind == Kind::kPhaseFreq ? 0 : Top(); }
  bool UpdatePending() const {
    for (int i = 0; i < units; ++i) {
      if (ocr[static_cast<size_t>(i)] != ocr_buf[static_cast<size_t>(i)]) return true;
    }
    return false;
  }
};

struct AvrTimers::Hook {
  AvrTimers* self;
  Timer* timer;  // null for GTCCR
  int reg;
};

AvrTimers::AvrTimers(avr_t* avr) : avr_(avr) {
  for (avr_io_t* io = avr->io_port; io != nullptr; io = io->next) {
    if (io->kind == nullptr || std::string(io->kind) != "timer") continue;
    auto* hw = reinterpret_cast<avr_timer_t*>(io);
    auto t = std::make_unique<Timer>();
    t->owner = this;
    t->hw = hw;
    t->digit = hw->name;
    t->name = std::string("Timer") + hw->name;
    t->wide = hw->r_tcnth != 0;
    t->timer2 = hw->name == '2';
    t->max = t->wide ? 0xFFFF : 0xFF;
    for (const avr_timer_comp_t& comp : hw->comp) {
      if (comp.r_ocr != 0) ++t->units;
    }
    t->a_addr = hw->wgm[0].reg;
    t->b_addr = hw->cs[0].reg;
    t->vectors[kTov] = &hw->overflow;
    for (int i = 0; i < t->units; ++i) t->vectors[kOcfA + i] = &hw->comp[i].interrupt;
    if (hw->icr.vector != 0) t->vectors[kIcf] = &hw->icr;
    TakeOver(*t);
    timers_.push_back(std::move(t));
  }
  const uint16_t gtccr_io = AVR_DATA_TO_IO(kGtccr);
  if (avr_->io[gtccr_io].w.c == nullptr) {
    hooks_.push_back(std::make_unique<Hook>(Hook{this, nullptr, kGtccrReg}));
    avr_->io[gtccr_io].w.c = &OnWrite;
    avr_->io[gtccr_io].w.param = hooks_.back().get();
  }
}

AvrTimers::~AvrTimers() {
  for (const auto& t : timers_) {
    avr_cycle_timer_cancel(avr_, &OnCycle, t.get());
    if (t->capture_irq != nullptr) {
      avr_irq_unregister_notify(t->capture_irq, &OnCapturePin, t.get());
    }
  }
}

void AvrTimers::HookWrite(Timer& t, uint16_t addr, int reg) {
  if (addr == 0) return;
  hooks_.push_back(std::make_unique<Hook>(Hook{this, &t, reg}));
  auto& slot = avr_->io[AVR_DATA_TO_IO(addr)].w;
  slot.c = &OnWrite;
  slot.param = hooks_.back().get();
}

void AvrTimers::HookRead(Timer& t, uint16_t addr, int reg) {
  if (addr == 0) return;
  hooks_.push_back(std::make_unique<Hook>(Hook{this, &t, reg}));
  auto& slot = avr_->io[AVR_DATA_TO_IO(addr)].r;
  slot.c = &OnRead;
  slot.param = hooks_.back().get();
}

// simavr's own timer callbacks are replaced, so its timer never starts: none of
// its cycle timers, its mode table or its TCNT arithmetic is used.
void AvrTimers::TakeOver(Timer& t) {
  avr_timer_t* hw = t.hw;
  HookWrite(t, t.a_addr, kRegA);
  HookWrite(t, t.b_addr, kRegB);
  HookWrite(t, hw->r_tcnt, kTcntL);
  HookRead(t, hw->r_tcnt, kTcntL);
  if (t.wide) {
    HookWrite(t, hw->r_tcnth, kTcntH);
    HookRead(t, hw->r_tcnth, kTcntH);
    HookWrite(t, hw->r_icr, kIcrL);
    HookRead(t, hw->r_icr, kIcrL);
    HookWrite(t, hw->r_icrh, kIcrH);
    HookRead(t, hw->r_icrh, kIcrH);
  }
  for (int i = 0; i < t.units; ++i) {
    HookWrite(t, hw->comp[i].r_ocr, kOcrL0 + i);
    if (t.wide) HookWrite(t, hw->comp[i].r_ocrh, kOcrH0 + i);
  }
  HookWrite(t, hw->overflow.raised.reg, kTifr);
  HookWrite(t, hw->overflow.enable.reg, kTimsk);
  if (t.timer2 && hw->as2.reg != 0) HookWrite(t, hw->as2.reg, kAssr);
  Reconfigure(t);

  // simavr links the ICPn pin to its own capture handler (which reads its own
  // TCNT); the pin is linked to this model's instead.
  if (t.vectors[kIcf] != nullptr && hw->icp.reg != 0) {
    avr_ioport_getirq_t req = {};
    req.bit = hw->icp;
    if (avr_ioctl(avr_, AVR_IOCTL_IOPORT_GETIRQ_REGBIT, &req) > 0 && req.irq[0] != nullptr) {
      avr_unconnect_irq(req.irq[0], hw->io.irq + TIMER_IRQ_IN_ICP);
      t.capture_irq = req.irq[0];
      t.capture_level = (req.irq[0]->value & 1) != 0;
      avr_irq_register_notify(req.irq[0], &OnCapturePin, &t);
    }
  }
}

void AvrTimers::Note(const std::string& text) {
  if (std::find(unmodelled_.begin(), unmodelled_.end(), text) == unmodelled_.end()) {
    unmodelled_.push_back(text);
  }
}

void AvrTimers::Reconfigure(Timer& t) {
  const uint8_t a = avr_->data[t.a_addr];
  const uint8_t b = avr_->data[t.b_addr];
  const std::string n(1, t.digit);
  if (t.wide) {
    t.wgm = (a & 3) | (((b >> 3) & 3) << 2);
    t.mode = kModes16[t.wgm];
  } else {
    t.wgm = (a & 3) | (((b >> 3) & 1) << 2);
    t.mode = kModes8[t.wgm];
  }
  t.cs = b & 7;
  t.divider = t.timer2 ? kDividers2[t.cs] : kDividers[t.cs];
  if (t.divider == kExternal) {
    Note(t.name + " external clock on pin T" + n + " (CS" + n + " = " + std::to_string(t.cs) +
         ") is not modelled: the timer does not count under simavr");
    t.divider = 0;
  }
  if (t.timer2 && t.hw->as2.reg != 0) {
    const uint8_t assr = avr_->data[t.hw->as2.reg];
    if ((assr & (kAs2 | kExclk)) != 0) {
      Note(t.name +
           " asynchronous clock (ASSR.AS2/EXCLK, TOSC1/TOSC2) is not modelled: the "
           "timer does not count under simavr");
      t.divider = 0;
    }
  }
  if (t.mode.kind == Kind::kReserved) {
    if (t.divider != 0) {
      Note(t.name + " WGM" + n + " = " + std::to_string(t.wgm) +
           " is a reserved mode: the timer does not count under simavr");
    }
    t.divider = 0;
  }
  for (int i = 0; i < t.units; ++i) {
    if (((a >> (6 - 2 * i)) & 3) != 0) {
      const std::string unit = n + static_cast<char>('A' + i);
      Note(t.name + " output compare pin OC" + unit + " (COM" + unit +
           " bits) is not driven under simavr");
    }
  }
  if (t.wide && (b & kIcnc) != 0) {
    Note(t.name + " input capture noise canceler (ICNC" + n +
         ", 4 cycles of delay) is not modelled");
  }
  if (!Buffered(t.mode.kind)) t.ocr = t.ocr_buf;
}

void AvrTimers::Sync(Timer& t, uint64_t now) {
  if (now < t.ref_cycle) return;
  if (t.divider == 0) {
    t.ref_cycle = now;
    return;
  }
  const uint64_t n = t.divider;
  for (;;) {
    const uint64_t k = TicksToNextEvent(t);
    if (k == kNever) break;
    const uint64_t event = (t.ref_cycle / n + k) * n;
    if (event > now) break;
    if (k > 1) {
      Advance(t.counter, t.GetShape(), k - 1);
      t.block = false;
    }
    ProcessTick(t);
    t.ref_cycle = event;
  }
  const uint64_t ticks = now / n - t.ref_cycle / n;
  if (ticks > 0) {
    Advance(t.counter, t.GetShape(), ticks);
    t.block = false;
  }
  t.ref_cycle = now;
}

// One tick from the value the counter holds: the flags of that value, the step,
// then the double-buffered compare registers when it ended their update point.
void AvrTimers::ProcessTick(Timer& t) {
  const uint32_t v = t.counter.count;
  const uint32_t top = t.Top();
  bool flags[kFlagCount] = {};
  flags[kTov] = v == t.TovValue();
  for (int i = 0; i < t.units; ++i) {
    flags[kOcfA + i] = !t.block && v == t.ocr[static_cast<size_t>(i)];
  }
  flags[kIcf] = t.mode.top == TopFrom::kIcr && v == top;
  const bool update = Buffered(t.mode.kind) && v == t.UpdateValue();
  Step(t.counter, t.GetShape());
  t.block = false;
  if (update) t.ocr = t.ocr_buf;
  for (int f = 0; f < kFlagCount; ++f) {
    if (flags[f]) Raise(t, f);
  }
}

uint64_t AvrTimers::TicksToNextEvent(const Timer& t) const {
  const Shape s = t.GetShape();
  uint64_t best = Dist(t.counter, s, t.TovValue());
  for (int i = 0; i < t.units; ++i) {
    const uint32_t v = t.ocr[static_cast<size_t>(i)];
    uint64_t d = Dist(t.counter, s, v);
    if (d == 0 && t.block) {
      Counter next = t.counter;
      Step(next, s);
      d = Dist(next, s, v);
      if (d != kNever) ++d;
    }
    best = std::min(best, d);
  }
  if (t.mode.top == TopFrom::kIcr) best = std::min(best, Dist(t.counter, s, s.top));
  if (Buffered(t.mode.kind) && t.UpdatePending()) {
    best = std::min(best, Dist(t.counter, s, t.UpdateValue()));
  }
  return best == kNever ? kNever : best + 1;
}

uint64_t AvrTimers::NextEventCycle(const Timer& t) const {
  if (t.divider == 0) return 0;
  const uint64_t k = TicksToNextEvent(t);
  if (k == kNever) return 0;
  return (t.ref_cycle / t.divider + k) * t.divider;
}

void AvrTimers::Reschedule(Timer& t) {
  if (t.in_callback) return;  // OnCycle returns the next cycle itself
  const uint64_t next = NextEventCycle(t);
  if (next == t.scheduled) return;
  avr_cycle_timer_cancel(avr_, &OnCycle, &t);
  t.scheduled = next;
  if (next != 0) {
    avr_cycle_timer_register(avr_, next > avr_->cycle ? next - avr_->cycle : 0, &OnCycle, &t);
  }
}

void AvrTimers::Raise(Timer& t, int flag) {
  ++t.fired[static_cast<size_t>(flag)];
  if (avr_int_vector_t* v = t.vectors[static_cast<size_t>(flag)]) avr_raise_interrupt(avr_, v);
}

uint64_t AvrTimers::OnCycle(avr_t* /*avr*/, uint64_t when, void* param) {
  auto* t = static_cast<Timer*>(param);
  t->in_callback = true;
  t->owner->Sync(*t, when);
  t->in_callback = false;
  t->scheduled = t->owner->NextEventCycle(*t);
  return t->scheduled;
}

void AvrTimers::OnWrite(avr_t* avr, uint16_t addr, uint8_t v, void* param) {
  auto* hook = static_cast<Hook*>(param);
  AvrTimers* self = hook->self;
  if (hook->timer == nullptr) {  // GTCCR
    avr->data[addr] = v;
    if (v != 0) {
      self->Note(
          "GTCCR (timer synchronization mode TSM, prescaler resets PSRSYNC/PSRASY) is "
          "not modelled");
    }
    return;
  }
  Timer& t = *hook->timer;
  const uint64_t now = avr->cycle;
  switch (hook->reg) {
    case kRegA:
    case kRegB:
    case kAssr: {
      self->Sync(t, now);
      uint8_t value = v;
      if (hook->reg == kRegB && !t.wide) value &= 0x3F;  // FOCnA/B: strobes, read as 0
      if (hook->reg == kAssr) value &= kAs2 | kExclk;    // busy flags stay 0
      avr->data[addr] = value;
      self->Reconfigure(t);
      self->Reschedule(t);
      return;
    }
    case kTcntH:
    case kIcrH:
      t.temp = v;
      return;
    case kTcntL:
      self->Sync(t, now);
      t.counter.count = t.wide ? (uint32_t{t.temp} << 8) | v : v;
      t.block = true;
      self->Reschedule(t);
      return;
    case kIcrL:
      self->Sync(t, now);
      t.icr = (uint32_t{t.temp} << 8) | v;
      self->Reschedule(t);
      return;
    case kTifr:
      for (avr_int_vector_t* vec : t.vectors) {
        if (vec == nullptr || (v & (1u << vec->raised.bit)) == 0) continue;
        if (avr_regbit_get(avr, vec->raised)) avr_clear_interrupt(avr, vec);
      }
      return;
    case kTimsk:
      avr->data[addr] = v;
      for (avr_int_vector_t* vec : t.vectors) {
        if (vec == nullptr || vec->pending) continue;
        if (avr_regbit_get(avr, vec->enable) && avr_regbit_get(avr, vec->raised)) {
          avr_raise_interrupt(avr, vec);
        }
      }
      return;
    default:
      break;
  }
  if (hook->reg >= kOcrH0 && hook->reg < kOcrH0 + 3) {
    t.temp = v;
    return;
  }
  if (hook->reg >= kOcrL0 && hook->reg < kOcrL0 + 3) {
    const auto unit = static_cast<size_t>(hook->reg - kOcrL0);
    self->Sync(t, now);
    const uint32_t value = t.wide ? (uint32_t{t.temp} << 8) | v : v;
    t.ocr_buf[unit] = value;
    avr->data[addr] = v;  // reads return the buffer (16.7.1); OCRnx reads need no TEMP
    if (t.wide) avr->data[t.hw->comp[unit].r_ocrh] = t.temp;
    if (!Buffered(t.mode.kind)) t.ocr[unit] = value;
    self->Reschedule(t);
  }
}

uint8_t AvrTimers::OnRead(avr_t* avr, uint16_t /*addr*/, void* param) {
  auto* hook = static_cast<Hook*>(param);
  Timer& t = *hook->timer;
  switch (hook->reg) {
    case kTcntL:
      hook->self->Sync(t, avr->cycle);
      hook->self->Reschedule(t);
      t.temp = static_cast<uint8_t>(t.counter.count >> 8);
      return static_cast<uint8_t>(t.counter.count);
    case kIcrL:
      t.temp = static_cast<uint8_t>(t.icr >> 8);
      return static_cast<uint8_t>(t.icr);
    case kTcntH:
    case kIcrH:
      return t.temp;
    default:
      return 0;
  }
}

// An edge on ICPn: TCNTn into ICRn and ICFn, unless ICRn is TOP (16.6).
void AvrTimers::OnCapturePin(avr_irq_t* /*irq*/, uint32_t value, void* param) {
  auto* t = static_cast<Timer*>(param);
  const bool level = (value & 1) != 0;
  if (level == t->capture_level) return;
  t->capture_level = level;
  AvrTimers* self = t->owner;
  const bool rising = (self->avr_->data[t->b_addr] & kIces) != 0;
  if (level != rising || t->mode.top == TopFrom::kIcr) return;
  self->Sync(*t, self->avr_->cycle);
  t->icr = t->counter.count;
  self->Raise(*t, kIcf);
  self->Reschedule(*t);
}

std::vector<std::string> AvrTimers::SilentInterrupts() const {
  std::vector<std::string> out;
  for (const auto& tp : timers_) {
    const Timer& t = *tp;
    const std::string n(1, t.digit);
    for (int f = 0; f < kFlagCount; ++f) {
      const avr_int_vector_t* vec = t.vectors[static_cast<size_t>(f)];
      if (vec == nullptr || t.fired[static_cast<size_t>(f)] != 0) continue;
      if (!avr_regbit_get(avr_, vec->enable)) continue;
      std::string why;
      const Shape s = t.GetShape();
      Counter now = t.counter;
      if (t.cs == 0) {
        why = "its clock is stopped (CS" + n + " = 0)";
      } else if (t.divider == 0) {
        why = "its clock or mode is not modelled (see the notes above)";
      } else if (f == kIcf && t.mode.top != TopFrom::kIcr) {
        why = "its input capture pin ICP" + n + " never had an edge";
      } else {
        uint32_t v = 0;
        if (f == kTov) v = t.TovValue();
        if (f >= kOcfA && f <= kOcfC) v = t.ocr[static_cast<size_t>(f - kOcfA)];
        if (f == kIcf) v = s.top;
        if (Dist(now, s, v) == kNever) {
          if (f == kTov && t.mode.kind == Kind::kCtc) {
            why = "in CTC mode (WGM" + n + " = " + std::to_string(t.wgm) +
                  ") the counter never reaches MAX, its TOP being " + std::to_string(s.top);
          } else {
            why = "the counter never reaches " + std::to_string(v) + " (TOP " +
                  std::to_string(s.top) + ")";
          }
        } else {
          why = "its next event is " + std::to_string(Dist(now, s, v) + 1) + " timer ticks of " +
                std::to_string(t.divider) + " cycles away; the run ended first";
        }
      }
      if (!avr_->sreg[S_I]) why += "; global interrupts are off";
      out.push_back(t.name + " " + kFlagNames[f] + " interrupt is enabled in TIMSK" + n +
                    " but never fired: " + why);
    }
  }
  return out;
}

}  // namespace moco::conformance
