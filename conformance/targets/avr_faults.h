// Fault oracles for AVR firmware under simavr, watched instruction by
// instruction (the simavr target calls Before() and After() around each
// avr_run()): what a fuzzer reports as a finding even when the serial stream
// still looks right.
//
//  - A return address overwritten (kStackSmash): a shadow call stack keeps the
//    bytes every CALL, RCALL, ICALL, EICALL and interrupt entry pushed, and
//    where. The innermost frame's address is checked after every instruction:
//    a store that overwrites it (an overflow of that function's own arrays)
//    is caught where it happens. A RET or RETI through any other slot whose
//    bytes have changed since is caught before it jumps; a RET whose changed
//    address still follows a call instruction (a longjmp restoring a saved
//    frame) is let through, a RETI never is (an interrupt returns where it
//    struck).
//  - A division by zero (kDivisionByZero): the AVR has no divide instruction
//    and no trap; avr-gcc calls libgcc's __udivmod*/__divmod* routines, which
//    return all ones. Entering one of them (found by name in the ELF's symbols)
//    with a zero divisor in its argument registers is the finding.
//  - A jump to the reset vector after start (kReset): a runaway return or
//    pointer, or a watchdog reset.
//
// The shadow stack also gives the backtrace of any PC: the call sites of every
// frame still open, innermost first.
#ifndef MOCO_CONFORMANCE_TARGETS_AVR_FAULTS_H_
#define MOCO_CONFORMANCE_TARGETS_AVR_FAULTS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "conformance/targets/avr_elf.h"
#include "conformance/targets/avr_stack.h"

namespace moco::conformance {

enum class AvrFaultKind { kStackSmash, kDivisionByZero, kReset };

struct AvrFault {
  AvrFaultKind kind = AvrFaultKind::kStackSmash;
  std::string what;  // one sentence, with the addresses involved
  uint32_t pc = 0;   // the instruction that faulted (byte address)
};

class AvrFaultWatch {
 public:
  // `symbols` must outlive the watch.
  explicit AvrFaultWatch(const AvrSymbols& symbols);

  // Forgets every frame (a fresh core).
  void Reset();
  // Around one avr_run(): Before() reads the instruction about to run (and
  // checks a RET or a division's entry), After() records what it pushed and
  // checks what a store, a call or an interrupt's entry wrote. Either returns
  // the first fault seen. Inline: most instructions need one table lookup.
  std::optional<AvrFault> Before(const avr_t* avr) {
    if (ops_.empty()) Classify(avr);
    pc_ = static_cast<uint32_t>(avr->pc);
    running_ = avr->interrupts.running_ptr;
    op_ = pc_ / 2 < ops_.size() ? ops_[pc_ / 2] : Op::kOther;
    if (op_ == Op::kOther || op_ == Op::kStore) return std::nullopt;
    return Checked(avr);
  }
  std::optional<AvrFault> After(const avr_t* avr) {
    if (op_ == Op::kOther && avr->interrupts.running_ptr <= running_ && avr->pc != 0) {
      started_ = true;
      return std::nullopt;
    }
    return Ran(avr);
  }

  // `pc`, then the call site of each open frame, innermost first, each as
  // AvrSymbols::Describe gives it (at most `max_frames`).
  std::vector<std::string> Backtrace(uint32_t pc, size_t max_frames = 16) const;

 private:
  // kStore: an instruction that writes the data memory (ST, STD, STS, PUSH,
  // XCH, LAS, LAC, LAT): only it, a call or an interrupt's entry can
  // overwrite a return address, so only after these is the frame checked.
  enum class Op : uint8_t { kOther, kCall, kRet, kReti, kDivision, kStore };
  struct Frame {
    uint32_t slot;   // the lowest stack byte of the pushed address
    uint32_t site;   // the call instruction, or the PC an interrupt struck (bit 31 set)
    uint32_t value;  // the word address pushed there
  };

  void Classify(const avr_t* avr);
  std::optional<AvrFault> Checked(const avr_t* avr);  // Before(), past the lookup
  std::optional<AvrFault> Ran(const avr_t* avr);      // After(), past the fast path

  void Push(const avr_t* avr, uint32_t slot, uint32_t site);
  std::optional<AvrFault> CheckReturn(const avr_t* avr, uint32_t sp);
  bool FollowsCall(const avr_t* avr, uint32_t byte_address) const;
  // The kStackSmash fault for frame `f`, saying `how` it shows.
  AvrFault Smash(const avr_t* avr, const Frame& f, const std::string& how) const;
  std::optional<AvrFault> CheckDivision(const avr_t* avr) const;

  const AvrSymbols& symbols_;
  // libgcc's division entries and the registers holding their divisors.
  struct Division {
    uint32_t address;
    uint8_t first_register, registers;
    const char* name;
  };
  std::vector<Division> divisions_;
  std::vector<Frame> frames_;  // the shadow stack, outermost first
  std::vector<Op> ops_;        // per flash word (Classify, on the first instruction)
  // Of the instruction Before() saw:
  uint32_t pc_ = 0, sp_ = 0;
  uint8_t running_ = 0;  // simavr's count of interrupts being served
  Op op_ = Op::kOther;
  bool started_ = false;  // an instruction has run since Reset()
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_AVR_FAULTS_H_
