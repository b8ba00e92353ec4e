// The AVR fault oracles (see avr_faults.h). Opcodes from the AVR Instruction Set
// Manual: CALL 1001 010k kkkk 111k (+16 bits), RCALL 1101 kkkk kkkk kkkk,
// ICALL 1001 0101 0000 1001, EICALL 1001 0101 0001 1001, RET 1001 0101 0000 1000,
// RETI 1001 0101 0001 1000; the data stores: 1001 001r rrrr xxxx (STS, ST
// through X, Y+, -Y, Z+, -Z, PUSH, XCH, LAS, LAC, LAT) and STD 10q0 qq1r rrrr
// xqqq (ST Y and ST Z are STD with q = 0). A call pushes its return address (a word address)
// one byte at a time, low byte first, at SP and downwards (simavr's
// _avr_push_addr, as the hardware): the pushed address's lowest stack byte,
// its slot, is SP + 1 afterwards and holds its highest byte.
#include "conformance/targets/avr_faults.h"

#include <algorithm>
#include <cstdio>

namespace moco::conformance {
namespace {

using avr_stack::Pushed;
using avr_stack::StackPointer;

uint16_t Word(const avr_t* avr, uint32_t byte_address) {
  if (byte_address + 1 > avr->flashend) return 0xFFFF;
  return static_cast<uint16_t>(avr->flash[byte_address] | (avr->flash[byte_address + 1] << 8));
}

bool IsLongCall(uint16_t w) { return (w & 0xFE0E) == 0x940E; }
bool IsStore(uint16_t w) { return (w & 0xFE00) == 0x9200 || (w & 0xD200) == 0x8200; }
// `rcall .+0` (0xD000) calls the next instruction: avr-gcc's way to take two
// bytes of stack for locals, not a call.
bool IsShortCall(uint16_t w) {
  return ((w & 0xF000) == 0xD000 && w != 0xD000) || w == 0x9509 || w == 0x9519;
}

std::string Hex(uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%04x", static_cast<unsigned>(v));
  return text;
}

}  // namespace

AvrFaultWatch::AvrFaultWatch(const AvrSymbols& symbols) : symbols_(symbols) {
  // libgcc's division routines (libgcc/config/avr/lib1funcs.S): the divisor's
  // registers, lowest first, and how many.
  static constexpr struct {
    const char* name;
    uint8_t first, count;
  } kDivisions[] = {
      {"__udivmodqi4", 22, 1}, {"__divmodqi4", 22, 1},   {"__udivmodhi4", 22, 2},
      {"__divmodhi4", 22, 2},  {"__udivmodpsi4", 18, 3}, {"__divmodpsi4", 18, 3},
      {"__udivmodsi4", 18, 4}, {"__divmodsi4", 18, 4},
  };
  for (const auto& d : kDivisions) {
    if (auto at = symbols_.Address(d.name)) divisions_.push_back({*at, d.first, d.count, d.name});
  }
}

void AvrFaultWatch::Reset() {
  frames_.clear();
  op_ = Op::kOther;
  started_ = false;
}

void AvrFaultWatch::Classify(const avr_t* avr) {
  // Every flash word as if an instruction started there: one lookup per
  // instruction instead of decoding it (the image does not change).
  ops_.assign((avr->flashend + 1) / 2, Op::kOther);
  for (uint32_t w = 0; w < ops_.size(); ++w) {
    const uint16_t op = Word(avr, 2 * w);
    if (IsStore(op)) ops_[w] = Op::kStore;
    if (IsLongCall(op) || IsShortCall(op)) ops_[w] = Op::kCall;
    if (op == 0x9508) ops_[w] = Op::kRet;
    if (op == 0x9518) ops_[w] = Op::kReti;
  }
  for (const Division& d : divisions_) {
    if (d.address / 2 < ops_.size()) ops_[d.address / 2] = Op::kDivision;
  }
}

std::optional<AvrFault> AvrFaultWatch::Checked(const avr_t* avr) {
  switch (op_) {
    case Op::kOther:
    case Op::kStore:
      return std::nullopt;
    case Op::kCall:
      sp_ = StackPointer(avr);
      return std::nullopt;
    case Op::kRet:
    case Op::kReti:
      return CheckReturn(avr, StackPointer(avr));
    case Op::kDivision:
      return CheckDivision(avr);
  }
  return std::nullopt;
}

std::optional<AvrFault> AvrFaultWatch::Ran(const avr_t* avr) {
  const uint8_t size = avr->address_size;
  if (op_ == Op::kCall && avr->pc != pc_) {
    // The call pushed at sp_ and below; an interrupt entered in the same step
    // pushed below that.
    Push(avr, sp_ + 1 - size, pc_);
  }
  const bool interrupted = avr->interrupts.running_ptr > running_;
  if (interrupted) {
    const uint32_t slot = StackPointer(avr) + 1;
    Push(avr, slot, Pushed(avr, slot) * 2);
    frames_.back().site |= 0x80000000u;  // marks an interrupt's frame
  }
  // A store that overwrote the innermost open frame's return address, caught
  // at the instruction that did it: an overflow of the frame's own arrays
  // reaches it before anything above it (the end of the data memory, where
  // simavr would stop the core first). Frames below the stack pointer were
  // left by a longjmp and are not checked.
  if (!frames_.empty() && (op_ == Op::kStore || op_ == Op::kCall || interrupted)) {
    const Frame& f = frames_.back();
    if (f.slot > StackPointer(avr) && Pushed(avr, f.slot) != f.value) {
      return Smash(avr, f, "the instruction at " + symbols_.Describe(pc_) + " wrote it");
    }
  }
  if (avr->pc == 0 && started_) {
    return AvrFault{AvrFaultKind::kReset,
                    "the firmware jumped to the reset vector (from " + symbols_.Describe(pc_) +
                        "): a runaway jump or return, or a watchdog reset",
                    pc_};
  }
  started_ = true;
  return std::nullopt;
}

void AvrFaultWatch::Push(const avr_t* avr, uint32_t slot, uint32_t site) {
  // Frames at or below the new slot were left without a return (longjmp, a
  // reset stack pointer): they are gone.
  while (!frames_.empty() && frames_.back().slot <= slot) frames_.pop_back();
  frames_.push_back(Frame{slot, site, Pushed(avr, slot)});
}

std::optional<AvrFault> AvrFaultWatch::CheckReturn(const avr_t* avr, uint32_t sp) {
  const uint32_t slot = sp + 1;
  while (!frames_.empty() && frames_.back().slot < slot) frames_.pop_back();
  // No frame there: an address the code pushed itself (a computed jump).
  if (frames_.empty() || frames_.back().slot != slot) return std::nullopt;
  const Frame f = frames_.back();
  const uint32_t now = Pushed(avr, slot);
  if (now == f.value || (op_ == Op::kRet && FollowsCall(avr, now * 2))) {
    frames_.pop_back();
    return std::nullopt;
  }
  // The frame stays: the backtrace names the call that made it.
  const bool interrupt = (f.site & 0x80000000u) != 0;
  return Smash(avr, f,
               std::string(interrupt ? "RETI" : "RET") + " at " + symbols_.Describe(pc_) +
                   " would jump there");
}

AvrFault AvrFaultWatch::Smash(const avr_t* avr, const Frame& f, const std::string& how) const {
  const bool interrupt = (f.site & 0x80000000u) != 0;
  const uint32_t site = f.site & 0x7FFFFFFFu;
  std::string what = "a return address was overwritten on the stack: ";
  what += interrupt ? "the interrupt that struck at " + symbols_.Describe(site)
                    : "the call at " + symbols_.Describe(site);
  what += " left " + Hex(f.value * 2) + " at " + Hex(f.slot) + ", which now holds " +
          Hex(Pushed(avr, f.slot) * 2) + "; " + how + " (a stack buffer overflow)";
  return AvrFault{AvrFaultKind::kStackSmash, std::move(what), pc_};
}

bool AvrFaultWatch::FollowsCall(const avr_t* avr, uint32_t byte_address) const {
  return (byte_address >= 4 && IsLongCall(Word(avr, byte_address - 4))) ||
         (byte_address >= 2 && IsShortCall(Word(avr, byte_address - 2)));
}

std::optional<AvrFault> AvrFaultWatch::CheckDivision(const avr_t* avr) const {
  for (const Division& d : divisions_) {
    if (d.address != pc_) continue;  // one of them is (ops_)
    uint32_t divisor = 0;
    for (uint8_t r = 0; r < d.registers; ++r) divisor |= avr->data[d.first_register + r];
    if (divisor != 0) return std::nullopt;
    // The caller is the innermost frame's call site (the routine is entered by a call).
    const std::string from =
        frames_.empty() ? std::string("?") : symbols_.Describe(frames_.back().site & 0x7FFFFFFFu);
    return AvrFault{AvrFaultKind::kDivisionByZero,
                    std::string("a division by zero: ") + d.name +
                        " entered with a zero divisor, " + "called from " + from +
                        " (the AVR has no trap; libgcc returns all ones)",
                    pc_};
  }
  return std::nullopt;
}

std::vector<std::string> AvrFaultWatch::Backtrace(uint32_t pc, size_t max_frames) const {
  std::vector<std::string> out{symbols_.Describe(pc)};
  for (auto it = frames_.rbegin(); it != frames_.rend() && out.size() < max_frames; ++it) {
    const bool interrupt = (it->site & 0x80000000u) != 0;
    out.push_back(symbols_.Describe(it->site & 0x7FFFFFFFu) + (interrupt ? " (interrupted)" : ""));
  }
  return out;
}

}  // namespace moco::conformance
