// The timer/counters of the ATmega328P and ATmega2560 run at their datasheet
// periods under libsimavr 1.6 (ATmega328P datasheet 7810D: 15 "8-bit
// Timer/Counter0 with PWM", 16 "16-bit Timer/Counter1 with PWM" (16.9 "Modes of
// Operation", 16.11 "Register Description", table 16-4), 17 "Timer/Counter0 and
// Timer/Counter1 Prescalers", 18 "8-bit Timer/Counter2 with PWM and Asynchronous
// Operation"; ATmega2560 datasheet 2549Q: 16, 17 (table 17-2), 18, 20 for
// Timer0, Timer1/3/4/5 and Timer2; FACTS "simavr (Debian 1.6)").
#ifndef MOCO_CONFORMANCE_TARGETS_AVR_TIMERS_H_
#define MOCO_CONFORMANCE_TARGETS_AVR_TIMERS_H_

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

struct avr_t;
struct avr_irq_t;
struct avr_timer_t;
struct avr_int_vector_t;

namespace moco::conformance {

// simavr 1.6 counts the dual-slope modes it knows single slope (ATmega328P
// Timer1 modes 8 and 9: interrupts twice as often as on the chip), has no
// entry for 16-bit modes 1-3 and 10-11 (and, on the ATmega2560, 8-9) nor for
// the 8-bit phase correct modes 1 and 5, so those never count, clears every
// flag of a timer on any write to TIFRn, and never pends an interrupt whose
// flag was already set when its TIMSKn bit is written. AvrTimers replaces
// simavr's timer arithmetic while keeping its register addresses and its
// interrupt vectors (so TIMSKn enables, TIFRn shows flags, and entering an
// interrupt clears its flag, as simavr's vector code does).
//
// The model, per timer n (Timer0 and Timer2: 8-bit, MAX 0xFF, compare units A
// and B; Timer1 (and 3, 4, 5 on the 2560): 16-bit, MAX 0xFFFF, units A and B
// (and C on the 2560), an input capture register ICRn):
//  - Clock: CSn2:0 select the prescaler N. Timer0/1/3/4/5: 0 stopped, 1, 8, 64,
//    256, 1024, 6/7 external pin Tn (not modelled: the timer stops and it is
//    named). Timer2: 0 stopped, 1, 8, 32, 64, 128, 256, 1024; ASSR.AS2 (TOSC
//    crystal) and EXCLK are not modelled (the timer stops, named). The
//    prescaler runs free from reset (17.2 "the prescaler is free running"): the
//    counter ticks at every CPU cycle c with c % N == 0 (c counted from the
//    core's reset). GTCCR (TSM, PSRSYNC, PSRASY) is not modelled (named).
//  - Mode: WGMn3:0 (16-bit, table 16-4) or WGMn2:0 (8-bit, table 15-8):
//      kind         16-bit modes (TOP)                        8-bit modes (TOP)
//      normal       0 (0xFFFF)                                0 (0xFF)
//      CTC          4 (OCRnA), 12 (ICRn)                      2 (OCRA)
//      fast PWM     5/6/7 (0xFF/0x1FF/0x3FF), 14 (ICRn), 15 (OCRnA)   3 (0xFF), 7 (OCRA)
//      phase corr.  1/2/3 (0xFF/0x1FF/0x3FF), 10 (ICRn), 11 (OCRnA)   1 (0xFF), 5 (OCRA)
//      phase+freq   8 (ICRn), 9 (OCRnA)                       -
//      reserved     13                                        4, 6 (the timer stops, named)
//  - Counting, one step per tick: single slope (normal, CTC, fast PWM) counts
//    0, 1, .., TOP, 0, ..; above TOP (TCNT or TOP written so) it counts on to
//    MAX and wraps to 0. Dual slope (phase correct, phase and frequency
//    correct) counts 0 up to TOP and down to 0; at or above TOP while counting
//    up it turns down; with TOP 0 it stays at 0.
//  - Flags: a flag belonging to counter value V is set on the tick that ends V
//    (16.10 "Timer/Counter Timing Diagrams": the flag rises as TCNT leaves the value).
//      TOVn: normal, CTC: V == MAX; fast PWM: V == TOP; dual slope: V == 0.
//      OCFnx: V == OCRnx, on the way up and (dual slope) on the way down;
//             not on the first tick after a CPU write to TCNTn (16.7 "compare
//             match blocking by TCNT1 write").
//      ICFn: when ICRn is TOP, V == TOP; otherwise from the ICPn pin (below).
//    Periods that follow: normal N*(MAX+1); CTC N*(TOP+1); fast PWM
//    N*(TOP+1); phase correct and phase and frequency correct 2*N*TOP.
//  - OCRnx is double buffered in the PWM modes: writes go to the buffer (what
//    reads return) and reach the compare unit (and TOP when OCRnA is TOP) on
//    the tick ending TOP (fast PWM, phase correct) or ending BOTTOM (phase and
//    frequency correct); in normal and CTC modes at once. ICRn as TOP is not
//    buffered.
//  - 16-bit access through the timer's TEMP byte (16.3): writing the high
//    byte stores TEMP, writing the low byte writes both; reading TCNTn or ICRn
//    low latches the high byte into TEMP. OCRnx reads are direct.
//  - TIFRn: writing 1 to a flag clears it (0 leaves it). TIMSKn: setting an
//    enable bit whose flag is already set pends that interrupt.
//  - Input capture: an edge on ICPn (ICESn: 1 rising, 0 falling; the pin's
//    level as simavr's port sees it, output or input) copies TCNTn into ICRn and
//    sets ICFn, except when ICRn is TOP. The noise canceler's 4-cycle delay
//    (ICNCn) is not modelled (named).
//  - Not modelled, named in Unmodelled() when firmware uses them: compare
//    output pins OCnx (COMnx bits; the pins are not driven), external clocks,
//    the asynchronous Timer2, reserved modes, GTCCR, ICNCn. A core reset
//    (watchdog) inside simavr is not followed (the target builds a fresh core
//    to restart). Not modelled and not named either: the analog comparator as
//    input capture source (ACIC), the power reduction bits (PRR PRTIMn: a
//    powered-down timer still counts here), FOCnx strobes.
class AvrTimers {
 public:
  // Takes over every timer simavr built for `avr`: their registers' write and
  // read callbacks in avr->io[] and the input capture pins' links.
  // REQUIRES: `avr` is initialised, its firmware loaded, no instruction run.
  // `avr` must outlive this object.
  explicit AvrTimers(avr_t* avr);
  ~AvrTimers();
  AvrTimers(const AvrTimers&) = delete;
  AvrTimers& operator=(const AvrTimers&) = delete;

  // What the firmware used that the model does not reproduce, one sentence
  // each, in the order first used (each once).
  const std::vector<std::string>& Unmodelled() const { return unmodelled_; }
  // For every timer interrupt enabled in TIMSKn now that has never fired:
  // which, and why it cannot or did not (stopped clock, unmodelled clock or
  // mode, a compare value the counter never reaches, a period longer than the
  // run so far, global interrupts off).
  std::vector<std::string> SilentInterrupts() const;
  // Which flag of a timer (index into a timer's vectors).
  enum Flag { kTov = 0, kOcfA, kOcfB, kOcfC, kIcf, kFlagCount };

 private:
  struct Timer;
  struct Hook;

  void TakeOver(Timer& t);
  void HookWrite(Timer& t, uint16_t addr, int reg);
  void HookRead(Timer& t, uint16_t addr, int reg);
  void Note(const std::string& text);
  void Reconfigure(Timer& t);
  void Sync(Timer& t, uint64_t now);
  void ProcessTick(Timer& t);
  uint64_t TicksToNextEvent(const Timer& t) const;
  uint64_t NextEventCycle(const Timer& t) const;
  void Reschedule(Timer& t);
  void Raise(Timer& t, int flag);

  static void OnWrite(avr_t* avr, uint16_t addr, uint8_t v, void* param);
  static uint8_t OnRead(avr_t* avr, uint16_t addr, void* param);
  static uint64_t OnCycle(avr_t* avr, uint64_t when, void* param);
  static void OnCapturePin(avr_irq_t* irq, uint32_t value, void* param);

  avr_t* avr_;
  std::vector<std::unique_ptr<Timer>> timers_;
  std::vector<std::unique_ptr<Hook>> hooks_;
  std::vector<std::string> unmodelled_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_AVR_TIMERS_H_
